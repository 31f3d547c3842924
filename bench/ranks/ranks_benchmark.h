// `grove bench ranks`: one FootSLAM filter across the ranks of a Collective (the MPI ranks under
// mpirun, or this process alone) on the paper walk (H-tree s = 16, T = 5, the fixed 256 x 256
// grid). Reports the run time, each rank's time in collectives (waiting for the others and
// moving bytes) against its own work, its time writing and reading the particles that move, the
// bytes of particles sent per resampling, and a digest
// of every particle's final state (weight, pose, error states, path, map) that must be the same
// at any rank and thread count (in island mode, for one island count).
#ifndef GROVE_BENCH_RANKS_RANKS_BENCHMARK_H_
#define GROVE_BENCH_RANKS_RANKS_BENCHMARK_H_

#include <cstdint>
#include <string>

#include "engine/ranks/collective.h"

namespace grove::tools {

struct RanksBenchOptions {
  std::string out_dir;
  int64_t particles = 30000;
  double minutes = 4;
  int threads = 0;  // per rank; 0: the rank's CPU set
  uint64_t seed = 1;
  // Island mode (FootSlamConfig::islands and its exchange); 1: the global mode.
  int islands = 1;
  int64_t exchange_steps = 10;
  double exchange_fraction = 0.1;
};

// Rank 0 writes OUT/ranks.json and prints one line; returns an exit code, the same on every rank.
int RanksBenchCommand(const RanksBenchOptions& options, Collective& world);

}  // namespace grove::tools

#endif  // GROVE_BENCH_RANKS_RANKS_BENCHMARK_H_
