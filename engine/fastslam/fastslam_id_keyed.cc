// The FastSLAM run of fastslam::IdKeyedModel (known association, maps keyed by landmark id;
// fastslam_impl.h).
#include "engine/fastslam/fastslam_impl.h"

namespace grove::fastslam_facade {

std::unique_ptr<FastSlam::Impl> MakeIdKeyedImpl(const FastSlamConfig& config, int threads,
                                                Collective* ranks) {
  return std::make_unique<ImplOf<fastslam::IdKeyedModel>>(config, threads, ranks);
}

}  // namespace grove::fastslam_facade
