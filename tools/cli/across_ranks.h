// A `run` command under mpirun: one filter across the ranks.
#ifndef GROVE_TOOLS_CLI_ACROSS_RANKS_H_
#define GROVE_TOOLS_CLI_ACROSS_RANKS_H_

#include "grove/status.h"
#include "tools/cli/mpi_world.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

// With more than one rank: checks the configuration for them (exit 2, one error line from rank
// 0, when it cannot run across that many), takes the threads per rank from the rank's CPU set
// unless given and points the run at the ranks. Returns -1 to go on, or the exit code.
template <typename Facade, typename Config>
int AcrossRanks(MpiWorld& world, Config* config, RunOptions* run) {
  if (!world.active() || world.size() == 1) return -1;
  if (Status s = Facade::CheckAcrossRanks(*config, world.size()); !s.ok()) {
    return world.rank() == 0 ? Fail(kExitUsage, s.message()) : kExitUsage;
  }
  if (config->threads == 0) config->threads = UsableCpus();
  run->ranks = &world;
  return -1;
}

// The end of a model's `run` command: `run_command` (RunFootSlamCommand, RunFastSlamCommand)
// with `config` and `options`, across the ranks under mpirun.
template <typename Facade, typename Config, typename Options>
int RunOnRanks(Config config, Options& options, int (*run_command)(const Config&, const Options&)) {
  MpiWorld world;  // one rank unless started by mpirun
  if (const int refused = AcrossRanks<Facade>(world, &config, &options.run); refused >= 0) {
    return refused;
  }
  return run_command(config, options);
}

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_ACROSS_RANKS_H_
