// The flags every model's `grove ... run` takes besides its inputs, written once: --out,
// --config, one flag per configuration field, --memory-budget, --checkpoint-every,
// --checkpoint, --resume, --print-config and --no-progress; and what they mean: the file's
// values first, flags over them, --print-config printing the result.
#ifndef GROVE_TOOLS_CLI_RUN_FLAGS_H_
#define GROVE_TOOLS_CLI_RUN_FLAGS_H_

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "grove/config_fields.h"
#include "grove/config_json.h"
#include "tools/cli/config_flags.h"
#include "tools/cli/typed_flags.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

// --memory-budget SIZE, as every command that predicts its memory takes it.
inline void AddMemoryBudgetFlag(CLI::App* app, std::string* text) {
  Document(app->add_option("--memory-budget", *text,
                           "Refuse runs predicted to need more memory, e.g. 512M or 8G"),
           {"SIZE", "", {}, "the memory available"});
}

// The bytes of --memory-budget's `text` (0 when not given) into *bytes. Returns -1 to go on, or
// the exit code after printing the error.
inline int ParseMemoryBudgetFlag(const std::string& text, int64_t* bytes) {
  *bytes = 0;
  if (text.empty()) return -1;
  StatusOr<int64_t> parsed = ParseMemorySize(text);
  if (!parsed.ok()) return Fail(kExitUsage, parsed.status().message());
  *bytes = *parsed;
  return -1;
}

// Refuses a path option given empty (never "use the default"). Returns -1 to go on, or the
// exit code after printing the error.
inline int RefuseEmptyPaths(const std::vector<std::pair<CLI::Option*, const char*>>& paths) {
  for (const auto& [option, name] : paths) {
    if (*option && option->template as<std::string>().empty()) {
      return Fail(kExitUsage, fmt::format("{}: the path is empty", name));
    }
  }
  return -1;
}

// Sets *config from the --config file at `path`. Returns -1 to go on, or the exit code after
// printing the error: a file that cannot be read is an input error, a bad value a usage error.
template <typename Config>
int LoadConfigFlag(const std::vector<ConfigField<Config>>& fields, const std::string& path,
                   Config* config) {
  Status s = LoadConfigFile(fields, path, config);
  if (s.ok()) return -1;
  return Fail(s.code() == StatusCode::kNotFound || s.code() == StatusCode::kIoError ? kExitInput
                                                                                    : kExitUsage,
              s.message());
}

template <typename Config>
class RunFlags {
 public:
  // `defaults`: the configuration the help page gives the defaults of.
  RunFlags(CLI::App* app, const std::vector<ConfigField<Config>>& fields,
           const Config& defaults = Config())
      : fields_(fields), config_flags_(app, fields, defaults), run_flags_(app) {
    AddPath(app, "--out", &options_.out_dir, "Output directory");
    config_option_ = AddPath(app, "--config", &config_path_, "JSON file setting any parameter");
    AddMemoryBudgetFlag(app, &memory_budget_);
    run_flags_.Integer("--checkpoint-every", &options_.checkpoint_every, 0,
                       std::numeric_limits<int64_t>::max(),
                       "Write a checkpoint every N steps (0: only when stopped by SIGINT or "
                       "SIGTERM)");
    checkpoint_option_ = AddPath(app, "--checkpoint", &options_.checkpoint_path, "Checkpoint file",
                                 "OUT/checkpoint.grove");
    resume_option_ = AddPath(app, "--resume", &options_.resume_path,
                             "Continue from this checkpoint; give the same inputs and "
                             "configuration as the interrupted run (threads may differ)");
    app->add_flag("--print-config", print_config_, "Print the effective configuration and exit");
    app->add_flag("--no-progress", no_progress_, "No progress output");
  }

  // After parsing: sets *config (the --config file, then the flags) and *options. Returns -1 to
  // go on with the run, or the exit code to return (--print-config printed, or an error).
  // `input_paths`: the model's own path options, refused when given empty.
  int Prepare(Config* config, RunOptions* options,
              const std::vector<std::pair<CLI::Option*, const char*>>& input_paths) const {
    std::vector<std::pair<CLI::Option*, const char*>> paths = input_paths;
    paths.insert(paths.end(), {{config_option_, "--config"},
                               {resume_option_, "--resume"},
                               {checkpoint_option_, "--checkpoint"}});
    if (const int code = RefuseEmptyPaths(paths); code >= 0) return code;
    if (*config_option_) {
      if (const int code = LoadConfigFlag(fields_, config_path_, config); code >= 0) return code;
    }
    if (Status s = config_flags_.Apply(config); !s.ok()) return Fail(kExitUsage, s.message());
    if (Status s = run_flags_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    if (print_config_) {
      std::printf("%s\n", ConfigToJson(fields_, *config, 2).c_str());
      return kExitOk;
    }
    if (options_.out_dir.empty()) return Fail(kExitUsage, "--out: an output directory is required");
    *options = options_;
    options->progress = !no_progress_;
    return ParseMemoryBudgetFlag(memory_budget_, &options->memory_budget_bytes);
  }

 private:
  const std::vector<ConfigField<Config>>& fields_;
  ConfigFlags<Config> config_flags_;
  TypedFlags run_flags_;
  RunOptions options_;
  std::string config_path_;
  std::string memory_budget_;
  bool print_config_ = false;
  bool no_progress_ = false;
  CLI::Option* config_option_ = nullptr;
  CLI::Option* checkpoint_option_ = nullptr;
  CLI::Option* resume_option_ = nullptr;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_RUN_FLAGS_H_
