// ModelRunCli: a model's `grove MODEL run` command whose inputs are files: one required path flag
// per input, the flags of every run (RunFlags: --out, --config, the configuration's fields,
// checkpoints, --print-config) and the run itself, across the ranks under mpirun.
#ifndef GROVE_TOOLS_CLI_MODEL_RUN_CLI_H_
#define GROVE_TOOLS_CLI_MODEL_RUN_CLI_H_

#include <CLI/CLI.hpp>
#include <initializer_list>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "grove/config_fields.h"
#include "tools/cli/across_ranks.h"
#include "tools/cli/run_flags.h"
#include "tools/cli/typed_flags.h"

namespace grove::tools {

// Options: the model's run options, with `run` (RunOptions) and a path member per input.
template <typename Facade, typename Options>
class ModelRunCli {
 public:
  using Config = std::decay_t<decltype(std::declval<const Facade&>().config())>;
  using RunFunction = int (*)(const Config&, const Options&);
  // An input file: its flag, where its path goes and the help text.
  struct Input {
    const char* flag;
    std::string Options::*path;
    const char* help;
  };

  ModelRunCli(CLI::App* app, const std::vector<ConfigField<Config>>& fields,
              std::initializer_list<Input> inputs, RunFunction run)
      : run_(run) {
    for (const Input& in : inputs) {
      inputs_.push_back(
          {AddPath(app, in.flag, &(options_.*in.path), in.help)->required(), in.flag});
    }
    flags_.emplace(app, fields);  // after the inputs on the help page
  }

  int Run() {
    Config config;
    const int code = flags_->Prepare(&config, &options_.run, inputs_);
    if (code >= 0) return code;
    return RunOnRanks<Facade>(config, options_, run_);
  }

 private:
  Options options_;
  std::vector<std::pair<CLI::Option*, const char*>> inputs_;
  std::optional<RunFlags<Config>> flags_;
  RunFunction run_;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_MODEL_RUN_CLI_H_
