// Value types shared by every model's public facade: poses, memory use and the filter's part of
// a run summary.
#ifndef GROVE_TYPES_H_
#define GROVE_TYPES_H_

#include <cstdint>
#include <string>
#include <string_view>

#include "grove/export.h"

namespace grove {

// A pose in the map frame.
struct Pose2 {
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;
};

// A pose's covariance (x and y in m, heading in rad), its upper triangle.
struct Pose2Covariance {
  double xx = 0, xy = 0, xh = 0, yy = 0, yh = 0, hh = 0;
};

struct StampedPose {
  double t_s = 0;
  Pose2 pose;
};

// Memory of one kind of node (map, trajectory), summed over the engine's node pools.
struct MemoryUse {
  int64_t live_nodes = 0;  // nodes in use now
  int64_t live_bytes = 0;
  int64_t peak_live_nodes = 0;  // highest seen (per node pool, summed)
  int64_t peak_live_bytes = 0;
  int64_t reserved_bytes = 0;  // obtained from the system by the node pools
};

// What a run asked for, what it used and what it cost, for every model (Ceres' Summary); each
// model's summary adds its own fields.
struct GROVE_EXPORT FilterSummary {
  int64_t particles = 0;
  int threads_requested = 0;
  int threads_used = 0;
  int64_t steps = 0;  // filter steps: weighting steps and predict-only steps
  int64_t resamplings = 0;
  double mean_ess = 0;       // over the weighting steps
  double advance_s = 0;      // propagate, weight and update maps
  double normalize_s = 0;    // log-sum-exp and effective sample size
  double resample_s = 0;     // drawing parents and gathering the new generation
  double release_s = 0;      // freeing the dead generation
  double bookkeeping_s = 0;  // weighted-mean pose per step
  // Across ranks, this rank's: the particles and bytes it sent to other ranks (resamplings,
  // island exchanges) and the seconds spent writing and reading them; 0 in one process.
  int64_t sent_particles = 0;
  int64_t sent_bytes = 0;
  double migrate_s = 0;
  // The parallel loops of this process's run (not kept in checkpoints): the driving thread's wall
  // time inside them, the threads' time running their bodies (summed over threads) and how many
  // ran. threads_used * loop_s - loop_busy_s is the time threads waited inside loops (arriving
  // late or done early); filter_s() - loop_s ran on the driving thread alone.
  double loop_s = 0;
  double loop_busy_s = 0;
  int64_t loops = 0;
  double filter_s() const {
    return advance_s + normalize_s + resample_s + release_s + bookkeeping_s;
  }
  // "MODEL: N particles x S steps on T thread(s) in X s (rate, ns per particle-step);
  // R resamplings, mean ESS E (P %); phases: ...": the sentence every model's report starts with.
  std::string BriefFilterReport(std::string_view model) const;
};

}  // namespace grove

#endif  // GROVE_TYPES_H_
