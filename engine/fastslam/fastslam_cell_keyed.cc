// The FastSLAM run of fastslam::CellKeyedModel (unknown association, maps keyed by cell;
// fastslam_impl.h).
#include "engine/fastslam/fastslam_impl.h"

namespace grove::fastslam_facade {

std::unique_ptr<FastSlam::Impl> MakeCellKeyedImpl(const FastSlamConfig& config, int threads,
                                                  Collective* ranks) {
  return std::make_unique<ImplOf<fastslam::CellKeyedModel>>(config, threads, ranks);
}

}  // namespace grove::fastslam_facade
