// FootSlam::Impl: what the FootSlam facade calls of its engine, and MakeFootSlamEngine, which
// builds the engine of the configured map kind (FootSlamEngine, footslam_engine.cc: the filter
// and its stepping, the prior map and storage of diversity the weighting reads, the read-outs
// and checkpoints).
#ifndef GROVE_ENGINE_FOOTSLAM_FOOTSLAM_ENGINE_H_
#define GROVE_ENGINE_FOOTSLAM_FOOTSLAM_ENGINE_H_

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/filter/filter_facade.h"
#include "engine/footslam/htree_layout.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/footslam.h"
#include "grove/status.h"

namespace grove {

// Thread safety: one thread drives an engine (see FilterDriver).
class FootSlam::Impl {
 public:
  virtual ~Impl() = default;
  virtual Status Init() = 0;
  virtual Status Step(double t_s, double dx_m, double dy_m) = 0;
  virtual Status SetStartTime(double t_s) = 0;
  virtual Status SetPriorMap(const std::vector<HexCounts>& map) = 0;
  virtual const FootSlamConfig& config() const = 0;
  virtual int64_t steps() const = 0;
  virtual Pose2 HeaviestPose() const = 0;
  virtual Pose2 MeanPose() const = 0;
  virtual StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const = 0;
  virtual StatusOr<std::vector<StampedPose>> SmoothedTrajectory() const = 0;
  virtual const std::vector<StampedPose>& MeanTrajectory() const = 0;
  virtual StatusOr<std::vector<HexCounts>> CumulativeMap() const = 0;
  virtual StatusOr<std::vector<HexCounts>> HeaviestMap() const = 0;
  virtual std::vector<HexCounts> StoredMap() const = 0;
  virtual FootSlamSummary Summary() const = 0;
  // The whole state as a checkpoint file (SaveCheckpoint).
  virtual StatusOr<std::string> Checkpoint(std::string_view user_data) const = 0;
  // Replaces the state of a freshly created engine with the rest of a checkpoint body, after
  // its head (LoadCheckpoint).
  virtual Status Load(ByteReader* r) = 0;
  virtual Status CheckInvariants() const = 0;
};

namespace footslam {

// FootSLAM's checkpoints. The body layout's version is bumped whenever it changes. 2: path
// positions relative to the start, the filter's count of weighting steps. 3: the grid field,
// maps grown past the first grid. 4: the stored map of storage of diversity. 5: the island
// fields. 6: the alphabet's symbol tree with bottom nodes of two H-tree levels (degrees 4 and
// 16).
inline constexpr CheckpointFormat kFootSlamCheckpoint = {"grove footslam", "FootSLAM", 6};

// The engine of config.map and config.degree on `threads` workers over the grid `layout`, a
// rank's share of the particles across `ranks` (null: all of them). Call Init() before stepping
// it. REQUIRES: config.Validate() is ok; `layout` is config's.
std::unique_ptr<FootSlam::Impl> MakeFootSlamEngine(const FootSlamConfig& config, int threads,
                                                   HTreeLayout layout, Collective* ranks);

}  // namespace footslam
}  // namespace grove

#endif  // GROVE_ENGINE_FOOTSLAM_FOOTSLAM_ENGINE_H_
