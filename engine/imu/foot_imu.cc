// FootImu: the detector stream, the alignment, the filter and the stance bookkeeping that cuts
// the walk into steps.
#include "grove/foot_imu.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <utility>

#include "engine/imu/zero_velocity_detector.h"
#include "engine/imu/zupt_filter.h"

namespace grove {
namespace {

struct Sample {
  double t_s = 0;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
};

imu::DetectorOptions DetectorOptionsOf(const FootImuConfig& c) {
  imu::DetectorOptions o;
  o.kind = c.detector;
  o.window = c.detector_window;
  o.threshold = c.Threshold();
  o.sigma_a = c.detector_accel_sigma_mps2;
  o.sigma_w = c.detector_gyro_sigma_radps;
  o.gravity = c.Gravity();
  o.gap = c.stance_gap_samples;
  return o;
}

imu::FilterNoise FilterNoiseOf(const FootImuConfig& c) {
  return {c.accel_noise_mps2_per_sqrt_hz, c.gyro_noise_radps_per_sqrt_hz,
          c.accel_bias_walk_mps3_per_sqrt_hz, c.gyro_bias_walk_radps2_per_sqrt_hz};
}

}  // namespace

class FootImu::Impl {
 public:
  explicit Impl(const FootImuConfig& config)
      : config_(config),
        gravity_(config.Gravity()),
        detector_(DetectorOptionsOf(config)),
        filter_(FilterNoiseOf(config), gravity_) {}

  const FootImuConfig& config() const { return config_; }

  Status AddSample(const ImuSample& s) {
    const auto start = std::chrono::steady_clock::now();
    if (finished_) return FailedPreconditionError("AddSample after Finish()");
    GROVE_RETURN_IF_ERROR(Check(s));
    Sample sample{s.t_s,
                  {s.accel_mps2[0], s.accel_mps2[1], s.accel_mps2[2]},
                  {s.gyro_radps[0], s.gyro_radps[1], s.gyro_radps[2]}};
    has_last_time_ = true;
    last_time_s_ = s.t_s;
    ++samples_;
    detector_.Push(sample.accel, sample.gyro);
    pending_.push_back(std::move(sample));
    Drain();
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return Status::Ok();
  }

  Status Finish() {
    if (finished_) return Status::Ok();
    const auto start = std::chrono::steady_clock::now();
    finished_ = true;
    detector_.Finish();
    Drain();
    if (in_run_ && aligned_) EndRun();
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return Status::Ok();
  }

  std::vector<FootStep> TakeSteps() { return std::exchange(steps_, {}); }

  FootImuState State() const {
    FootImuState s;
    s.t_s = processed_ > 0 ? previous_.t_s : 0;
    s.still = last_still_;
    if (!aligned_) return s;
    for (int i = 0; i < 3; ++i) {
      s.position_m[i] = filter_.position()[i];
      s.velocity_mps[i] = filter_.velocity()[i];
      s.accel_bias_mps2[i] = filter_.accel_bias()[i];
      s.gyro_bias_radps[i] = filter_.gyro_bias()[i];
    }
    const Eigen::Vector3d euler = imu::EulerFromRotation(filter_.attitude());
    s.roll_rad = euler[0];
    s.pitch_rad = euler[1];
    s.heading_rad = euler[2];
    return s;
  }

  FootImuSummary Summary() const {
    FootImuSummary s;
    s.samples = samples_;
    s.processed_samples = processed_;
    s.still_samples = still_samples_;
    s.stances = stances_;
    s.steps = step_count_;
    s.aligned = aligned_;
    s.alignment_t_s = alignment_t_s_;
    s.has_origin = has_origin_;
    s.origin_t_s = origin_t_s_;
    s.gravity_mps2 = gravity_;
    s.distance_m = distance_m_;
    s.seconds = seconds_;
    return s;
  }

 private:
  Status Check(const ImuSample& s) const {
    if (!std::isfinite(s.t_s))
      return InvalidArgumentError(fmt::format("t_s = {}: must be finite", s.t_s));
    for (int i = 0; i < 3; ++i) {
      for (auto [name, v, range, range_name] :
           {std::tuple{"accel_mps2", s.accel_mps2[i], config_.accel_range_mps2, "accel_range_mps2"},
            std::tuple{"gyro_radps", s.gyro_radps[i], config_.gyro_range_radps,
                       "gyro_range_radps"}}) {
        if (!std::isfinite(v)) {
          return InvalidArgumentError(
              fmt::format("t_s = {}: {}[{}] = {}: must be finite", s.t_s, name, i, v));
        }
        if (std::fabs(v) >= range) {
          return InvalidArgumentError(
              fmt::format("t_s = {}: {}[{}] = {}: saturated (|value| >= {} = {})", s.t_s, name, i,
                          v, range_name, range));
        }
      }
    }
    if (has_last_time_) {
      if (!(s.t_s > last_time_s_)) {
        return InvalidArgumentError(
            fmt::format("t_s = {}: not after the previous sample's {}", s.t_s, last_time_s_));
      }
      if (s.t_s - last_time_s_ > config_.max_sample_interval_s) {
        return InvalidArgumentError(fmt::format(
            "t_s = {}: {} s after the previous sample, more than max_sample_interval_s = {}", s.t_s,
            s.t_s - last_time_s_, config_.max_sample_interval_s));
      }
    }
    return Status::Ok();
  }

  // Processes every sample the detector has decided.
  void Drain() {
    for (std::optional<bool> still = detector_.Pop(); still; still = detector_.Pop()) {
      Process(pending_.front(), *still);
      pending_.pop_front();
    }
  }

  void Process(const Sample& s, bool still) {
    ++processed_;
    last_still_ = still;
    if (still) ++still_samples_;
    if (!aligned_) {
      Align(s, still);
      previous_ = s;
      return;
    }
    // A stance ends at its last still sample, before the filter moves on.
    if (!still && in_run_) EndRun();
    filter_.Propagate(previous_.accel, previous_.gyro, s.accel, s.gyro, s.t_s - previous_.t_s);
    previous_ = s;
    if (!still) return;
    filter_.UpdateZeroVelocity(config_.zupt_sigma_mps);
    if (config_.zaru_sigma_radps > 0)
      filter_.UpdateZeroAngularRate(s.gyro, config_.zaru_sigma_radps);
    NoteStill(s);
  }

  // Before the alignment: sums the still samples of a run until it has lasted alignment_s.
  void Align(const Sample& s, bool still) {
    if (!still) {
      in_run_ = false;
      rest_accel_.setZero();
      rest_gyro_.setZero();
      return;
    }
    NoteStill(s);
    rest_accel_ += s.accel;
    rest_gyro_ += s.gyro;
    if (s.t_s - run_begin_s_ < config_.alignment_s) return;
    const Eigen::Vector3d accel = rest_accel_ / static_cast<double>(run_samples_);
    const Eigen::Vector2d tilt = imu::TiltFromSpecificForce(accel);
    imu::InitialSigmas sigmas;
    sigmas.velocity = config_.zupt_sigma_mps;
    sigmas.tilt = config_.alignment_tilt_sigma_rad;
    sigmas.heading = config_.alignment_heading_sigma_rad;
    sigmas.accel_bias = config_.initial_accel_bias_sigma_mps2;
    sigmas.gyro_bias = config_.initial_gyro_bias_sigma_radps;
    filter_.Start(imu::RotationFromEuler(tilt[0], tilt[1], config_.alignment_heading_rad),
                  rest_gyro_ / static_cast<double>(run_samples_), sigmas);
    aligned_ = true;
    alignment_t_s_ = s.t_s;
  }

  void NoteStill(const Sample& s) {
    if (!in_run_) {
      in_run_ = true;
      run_begin_s_ = s.t_s;
      run_samples_ = 0;
    }
    ++run_samples_;
    run_end_s_ = s.t_s;
    run_end_sample_ = processed_ - 1;
  }

  // The run of still samples that ended at the sample processed last is a stance when long
  // enough: the first ends the alignment's stance (the origin), each later one a step.
  void EndRun() {
    in_run_ = false;
    if (run_samples_ < config_.min_stance_samples) return;
    ++stances_;
    const double mid_s = 0.5 * (run_begin_s_ + run_end_s_);
    if (!has_origin_) {
      has_origin_ = true;
      origin_t_s_ = mid_s;
      filter_.Clone();
      return;
    }
    const imu::StepDelta d = filter_.SinceClone();
    if (std::hypot(d.position.x(), d.position.y()) < config_.min_step_m) return;
    FootStep step;
    step.t_s = mid_s;
    step.dx_m = d.position.x();
    step.dy_m = d.position.y();
    step.dz_m = d.position.z();
    step.dheading_rad = d.heading;
    const Eigen::Matrix3d& c = d.covariance;
    // Variances clamped at zero against rounding.
    step.covariance = {std::max(0.0, c(0, 0)), c(0, 1), c(0, 2),
                       std::max(0.0, c(1, 1)), c(1, 2), std::max(0.0, c(2, 2))};
    step.stance_begin_s = run_begin_s_;
    step.stance_end_s = run_end_s_;
    step.stance_end_sample = run_end_sample_;
    steps_.push_back(step);
    ++step_count_;
    distance_m_ += std::hypot(step.dx_m, step.dy_m);
    filter_.Clone();
  }

  FootImuConfig config_;
  double gravity_;
  imu::ZeroVelocityDetectorStream detector_;
  imu::ZuptFilter filter_;
  std::deque<Sample> pending_;  // added, not yet decided
  bool finished_ = false;
  bool has_last_time_ = false;
  double last_time_s_ = 0;
  Sample previous_;  // the sample processed last
  bool last_still_ = false;
  bool aligned_ = false;
  double alignment_t_s_ = 0;
  Eigen::Vector3d rest_accel_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_gyro_ = Eigen::Vector3d::Zero();
  // The current run of still samples.
  bool in_run_ = false;
  double run_begin_s_ = 0;
  double run_end_s_ = 0;
  int64_t run_samples_ = 0;
  int64_t run_end_sample_ = 0;
  bool has_origin_ = false;
  double origin_t_s_ = 0;
  std::vector<FootStep> steps_;
  int64_t samples_ = 0;
  int64_t processed_ = 0;
  int64_t still_samples_ = 0;
  int64_t stances_ = 0;
  int64_t step_count_ = 0;
  double distance_m_ = 0;
  double seconds_ = 0;
};

StatusOr<std::unique_ptr<FootImu>> FootImu::Create(const FootImuConfig& config) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  try {
    return std::unique_ptr<FootImu>(new FootImu(std::make_unique<Impl>(config)));
  } catch (const std::bad_alloc&) {
    return ResourceExhaustedError("no memory for the foot IMU engine");
  }
}

FootImu::FootImu(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FootImu::~FootImu() = default;

Status FootImu::AddSample(const ImuSample& sample) {
  try {
    return impl_->AddSample(sample);
  } catch (const std::bad_alloc&) {
    return ResourceExhaustedError("no memory for a sample");
  }
}

Status FootImu::Finish() {
  try {
    return impl_->Finish();
  } catch (const std::bad_alloc&) {
    return ResourceExhaustedError("no memory to finish");
  }
}

std::vector<FootStep> FootImu::TakeSteps() { return impl_->TakeSteps(); }
const FootImuConfig& FootImu::config() const { return impl_->config(); }
FootImuState FootImu::State() const { return impl_->State(); }
FootImuSummary FootImu::Summary() const { return impl_->Summary(); }

}  // namespace grove
