// `grove footslam batch`: many walks, one FootSLAM filter each, from a manifest, run side by side
// in one process, each through the run loop (tools/run/run_loop.h) into its own directory.
//
// The manifest is JSON Lines: one object per non-empty line,
//   {"name": "walk-7", "steps": "walks/7.csv", "prior_map": "maps/a.csv", "config": {...}}
// name (required; letters, digits, '.', '_' and '-', not starting with '.'; unique) names the
// output directory OUT/name; steps (required) and prior_map (optional) are paths, relative ones
// from the manifest's directory; config (optional) sets configuration keys over the batch's
// (--config and flags). Every line is checked before any walk runs.
//
// Idempotent and resumable: a walk whose OUT/name/summary.json exists and whose OUT/name/
// batch_walk.json records the same digest (CRC-32 of its steps file, prior map and effective
// configuration) is skipped; a walk stopped part-way (a signal, a kill) with a checkpoint of the
// same digest is resumed from it. Each walk's result is a JSON line on stdout as it ends, and
// all of them, in manifest order, in OUT/batch_summary.jsonl (written atomically at the end).
// Under mpirun the walks are dealt to the ranks (every rank checks the manifest, and the ranks
// must agree on it and on the configuration); rank 0 writes batch_summary.jsonl.
#ifndef GROVE_TOOLS_RUN_FOOTSLAM_BATCH_H_
#define GROVE_TOOLS_RUN_FOOTSLAM_BATCH_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "grove/footslam.h"

namespace grove::tools {

struct FootSlamBatchOptions {
  std::string manifest_path;
  std::string out_dir;
  // Walks run side by side. Each gets T / jobs worker threads (at least 1) unless its own
  // configuration sets threads, T being the batch configuration's threads or, when that is 0,
  // the CPUs in the process's affinity mask (a scheduler's CPU set).
  int jobs = 1;
  int64_t checkpoint_every = 0;  // per walk, as `run --checkpoint-every`
  // MPI ranks (tools/cli/mpi_world.h): walk i runs on rank i % ranks; all_gather(mine) returns
  // every rank's string in rank order on every rank (collective). Unset: one rank.
  int rank = 0;
  int ranks = 1;
  std::function<std::vector<std::string>(const std::string&)> all_gather;
};

// Exit codes: 0 every walk ran or was skipped; 2 a bad manifest or option (nothing ran); 3 the
// manifest cannot be read; 4 some
// walk failed for a reason a retry will not change (its input, its configuration, the run
// itself: exit codes 2, 3, 4 of `run`); 75 (EX_TEMPFAIL) some walk failed for a reason a retry
// may fix (memory, writing outputs, an internal error) and none of the former; 128 + the
// signal when SIGINT or SIGTERM stopped the batch (running walks wrote checkpoints; run the
// same command again to go on).
int RunFootSlamBatch(const FootSlamConfig& base, const FootSlamBatchOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_FOOTSLAM_BATCH_H_
