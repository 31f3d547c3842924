// grove_ranks_benchmark: one FootSLAM filter across MPI ranks on the paper walk (its time, its
// communication and a digest of every particle's final state), started by mpirun or alone:
//   mpirun -np 2 grove_ranks_benchmark --out DIR [--particles N] [--minutes M] [--threads T]
//                                      [--islands I --exchange-steps k --exchange-fraction f]
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "bench/ranks/ranks_benchmark.h"
#include "tools/cli/mpi_world.h"
#include "tools/run/run_loop.h"

int main(int argc, char** argv) {
  try {
    CLI::App app{"One filter across MPI ranks on the paper walk: time, communication, digest"};
    grove::tools::RanksBenchOptions ranks_options;
    app.add_option("--out", ranks_options.out_dir, "Output directory")->required();
    app.add_option("--particles", ranks_options.particles, "Particles of the whole filter")
        ->capture_default_str()
        ->check(CLI::Range(int64_t{1}, int64_t{1} << 31));
    app.add_option("--minutes", ranks_options.minutes, "Walk length")
        ->capture_default_str()
        ->check(CLI::Range(0.1, 1440.0));
    app.add_option("--threads", ranks_options.threads, "Per rank; 0 = the rank's CPU set")
        ->capture_default_str()
        ->check(CLI::Range(0, 256));
    app.add_option("--seed", ranks_options.seed)->capture_default_str();
    app.add_option("--islands", ranks_options.islands,
                   "Island mode: islands of whole 4,096-particle blocks; 1: the global mode")
        ->capture_default_str()
        ->check(CLI::Range(1, 65536));
    app.add_option("--exchange-steps", ranks_options.exchange_steps,
                   "Island mode: steps between exchanges")
        ->capture_default_str()
        ->check(CLI::Range(int64_t{1}, int64_t{1} << 40));
    app.add_option("--exchange-fraction", ranks_options.exchange_fraction,
                   "Island mode: share of an island's particles sent at an exchange")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 0.5));

    CLI11_PARSE(app, argc, argv);
    grove::tools::MpiWorld world;  // one rank unless started by mpirun
    return grove::tools::RanksBenchCommand(ranks_options, world);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "grove_ranks_benchmark: internal error: %s\n", e.what());
    return grove::tools::kExitInternal;
  }
}
