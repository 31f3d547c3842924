// The flags of a benchmark on the user's own input (`grove bench footslam|fastslam`): --out,
// the sweep's lists --particles and --threads (comma or space separated), --repeat,
// --memory-budget, --config and one flag per configuration field but particles and threads,
// which the lists replace; the configuration is built as a run builds it (the file's values,
// then the flags).
#ifndef GROVE_TOOLS_CLI_SWEEP_FLAGS_H_
#define GROVE_TOOLS_CLI_SWEEP_FLAGS_H_

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "grove/config_fields.h"
#include "tools/bench/sweep_bench.h"
#include "tools/cli/config_flags.h"
#include "tools/cli/run_flags.h"
#include "tools/cli/typed_flags.h"

namespace grove::tools {

template <typename Config>
class SweepFlags {
 public:
  SweepFlags(CLI::App* app, const std::vector<ConfigField<Config>>& fields)
      : fields_(fields), typed_(app) {
    AddPath(app, "--out", &options_.out_dir,
            "Output directory: bench.md, bench.csv, bench_summary.csv, threads.png, "
            "particles.png, summary.json")
        ->required();
    const FieldInfo& particles = FindField(fields, "particles")->info;
    typed_
        .IntegerList("--particles", &options_.particles, particles.min_integer,
                     particles.max_integer,
                     "Particle counts, e.g. 1000,10000; each runs at every "
                     "thread count")
        ->default_str("the configuration's particles");
    const FieldInfo& threads = FindField(fields, "threads")->info;
    typed_
        .IntegerList("--threads", &options_.threads, 1, threads.max_integer,
                     "Thread counts, e.g. 1,2,4")
        ->default_str("1, 2, 4, ... below the CPUs this process may use, then that count");
    typed_.Integer("--repeat", &options_.repeat, 1, 1000,
                   "Runs per (particles, threads) pair, each in a fresh process");
    AddMemoryBudgetFlag(app, &memory_budget_);
    config_option_ = AddPath(app, "--config", &config_path_,
                             "JSON file setting any parameter (particles and threads: the lists)");
    config_flags_.emplace(app, fields, Config(), std::vector<std::string>{"particles", "threads"});
  }

  // After parsing: sets *config (the --config file, then the flags) and *options, whose
  // particles are the configuration's when --particles was not given. Returns -1 to go on, or
  // the exit code after printing the error. `input_paths`: the model's own path options.
  int Prepare(Config* config, SweepBenchOptions* options,
              std::vector<std::pair<CLI::Option*, const char*>> input_paths) const {
    input_paths.emplace_back(config_option_, "--config");
    if (const int code = RefuseEmptyPaths(input_paths); code >= 0) return code;
    if (Status s = typed_.Apply(); !s.ok()) return Fail(kExitUsage, s.message());
    if (*config_option_) {
      if (const int code = LoadConfigFlag(fields_, config_path_, config); code >= 0) return code;
    }
    if (Status s = config_flags_->Apply(config); !s.ok()) return Fail(kExitUsage, s.message());
    for (const auto& [flag, list] :
         {std::pair{"--particles", &options_.particles}, {"--threads", &options_.threads}}) {
      for (auto it = list->begin(); it != list->end(); ++it) {
        if (std::find(list->begin(), it, *it) != it) {
          return Fail(
              kExitUsage,
              fmt::format("{}: {} is given twice: each count must be given once", flag, *it));
        }
      }
    }
    *options = options_;
    if (options->particles.empty()) options->particles = {config->particles};
    return ParseMemoryBudgetFlag(memory_budget_, &options->memory_budget_bytes);
  }

 private:
  const std::vector<ConfigField<Config>>& fields_;
  TypedFlags typed_;
  SweepBenchOptions options_;
  std::string config_path_;
  std::string memory_budget_;
  CLI::Option* config_option_ = nullptr;
  std::optional<ConfigFlags<Config>> config_flags_;  // after the sweep's flags on the help page
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_SWEEP_FLAGS_H_
