// The landmark FastSLAM facade: the engine on the generic FilterDriver, its inputs, read-outs
// and checkpoints (the run itself: fastslam_impl.h).
#include "grove/fastslam.h"

#include <algorithm>
#include <thread>

#include "engine/fastslam/fastslam_impl.h"

namespace grove {

using fastslam_facade::kFastSlamCheckpoint;

namespace {

// The model whose map layout suits the association's keys.
std::unique_ptr<FastSlam::Impl> MakeImpl(const FastSlamConfig& config, int threads,
                                         Collective* ranks) {
  if (config.association == FastSlamAssociation::kKnown) {
    return fastslam_facade::MakeIdKeyedImpl(config, threads, ranks);
  }
  return fastslam_facade::MakeCellKeyedImpl(config, threads, ranks);
}

}  // namespace

FastSlam::FastSlam(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FastSlam::~FastSlam() = default;

Status FastSlam::CheckAcrossRanks(const FastSlamConfig& config, int ranks) {
  return CheckRankShares(static_cast<uint64_t>(config.particles), ranks, kSumBlock);
}

int64_t FastSlam::EstimatePeakBytes(const FastSlamConfig& config, const FastSlamWorkload& work) {
  // Calibrated on 2-thread runs of `grove fastslam victoria-park` (unknown association, about
  // 10 detections a scan; 5,000 and 20,000 particles, fastslam1 and fastslam2, 20 s and 60 s)
  // and of the webmap's `run` (known association, 1.4 detections a scan; 5,000 and 50,000
  // particles): the peak RSS grew by 12.9 and 4.3 KB a particle, most of it the map paths the
  // scans copied; the prediction stays 26 to 74 % above (engine/fastslam/README.md).
  const double fixed = 48.0 * 1048576;  // the process, its pools and the worker slots
  // State, weights, parents and the pose path's nodes of a particle.
  const double state = 4096;
  // The trie path one detection's update copies, in two generations, with the allocator's slack.
  const double per_detection = 1536;
  const double detections_per_scan =
      work.scans > 0 ? static_cast<double>(work.observations) / static_cast<double>(work.scans) : 0;
  const double n = static_cast<double>(config.particles);
  // The driver's time and mean pose of every step (a scan takes two).
  const double records = 256.0 * static_cast<double>(work.controls + 2 * work.scans);
  const double bytes = fixed + n * (state + per_detection * detections_per_scan) + records;
  return static_cast<int64_t>(std::min(bytes, 9e18));
}

StatusOr<std::unique_ptr<FastSlam>> FastSlam::Create(const FastSlamConfig& config) {
  return Create(config, nullptr);
}

StatusOr<std::unique_ptr<FastSlam>> FastSlam::Create(const FastSlamConfig& config,
                                                     Collective* ranks) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  if (ranks != nullptr && ranks->size() > 1) {
    GROVE_RETURN_IF_ERROR(CheckAcrossRanks(config, ranks->size()));
  } else {
    ranks = nullptr;
  }
  return NoThrow([&]() -> StatusOr<std::unique_ptr<FastSlam>> {
    const int threads = config.threads > 0
                            ? config.threads
                            : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    return std::unique_ptr<FastSlam>(new FastSlam(MakeImpl(config, threads, ranks)));
  });
}

Status FastSlam::Control(double t_s, double speed_mps, double steer_rad) {
  return NoThrow([&] { return impl_->Control(t_s, speed_mps, steer_rad); });
}
Status FastSlam::Scan(double t_s, std::span<const LandmarkObservation> observations) {
  return NoThrow([&] { return impl_->Scan(t_s, observations); });
}
const FastSlamConfig& FastSlam::config() const { return impl_->config(); }
// Every read-out first runs the deferred predictions (Impl::Settle()).
int64_t FastSlam::steps() const {
  impl_->SettleQuietly();
  return impl_->steps();
}
Pose2 FastSlam::MeanPose() const {
  impl_->SettleQuietly();
  return impl_->MeanPose();
}
Pose2 FastSlam::HeaviestPose() const {
  impl_->SettleQuietly();
  return impl_->HeaviestPose();
}
const std::vector<StampedPose>& FastSlam::MeanTrajectory() const {
  impl_->SettleQuietly();
  return impl_->MeanTrajectory();
}
Pose2Covariance FastSlam::PoseCovariance() const {
  impl_->SettleQuietly();
  return impl_->PoseCovariance();
}
StatusOr<std::vector<StampedPose>> FastSlam::HeaviestTrajectory() const {
  return NoThrow([&]() -> StatusOr<std::vector<StampedPose>> {
    GROVE_RETURN_IF_ERROR(impl_->Settle());
    return impl_->HeaviestTrajectory();
  });
}
StatusOr<std::vector<LandmarkEstimate>> FastSlam::HeaviestLandmarks() const {
  return NoThrow([&]() -> StatusOr<std::vector<LandmarkEstimate>> {
    GROVE_RETURN_IF_ERROR(impl_->Settle());
    return impl_->HeaviestLandmarks();
  });
}
FastSlamSummary FastSlam::Summary() const {
  impl_->SettleQuietly();
  return impl_->Summary();
}
Status FastSlam::CheckInvariants() const {
  GROVE_RETURN_IF_ERROR(impl_->Settle());
  return impl_->CheckInvariants();
}

StatusOr<std::string> FastSlam::Checkpoint(std::string_view user_data) const {
  return NoThrow([&]() -> StatusOr<std::string> {
    GROVE_RETURN_IF_ERROR(impl_->Settle());
    return impl_->Checkpoint(user_data);
  });
}

StatusOr<std::unique_ptr<FastSlam>> FastSlam::Resume(const FastSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data) {
  return Resume(config, checkpoint, name, user_data, nullptr);
}

StatusOr<std::unique_ptr<FastSlam>> FastSlam::Resume(const FastSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data, Collective* ranks) {
  return ResumeFacade<FastSlam>(kFastSlamCheckpoint, FastSlamConfigFields(), config, checkpoint,
                                name, user_data, ranks,
                                [](FastSlam& slam, ByteReader* r) { return slam.impl_->Load(r); });
}

}  // namespace grove
