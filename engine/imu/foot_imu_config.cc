// FootImuConfig's field table, its validation, the detectors' names and the summary's report.
#include <fmt/format.h>

#include <cmath>

#include "engine/imu/zupt_filter.h"
#include "grove/foot_imu.h"

namespace grove {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

const std::vector<ConfigField<FootImuConfig>>& FootImuConfigFields() {
  using C = FootImuConfig;
  using I = Interval;
  // Never destroyed: read-outs of it may run during static destruction.
  static const auto* fields = new std::vector<ConfigField<C>>{
      ChoiceField("detector", &C::detector, {"shoe", "are", "mv", "mag"}, kChangesResults,
                  "Zero-velocity detector: shoe (likelihood ratio), are (angular rate energy), "
                  "mv (acceleration variance) or mag (acceleration magnitude)"),
      IntegerField("detector_window", &C::detector_window, 1, 1001, kChangesResults,
                   "Samples in the detector's window"),
      RealField("detector_threshold", &C::detector_threshold, I::AtLeast(0), kChangesResults,
                "Threshold on the detector's statistic; 0: the detector's default"),
      RealField("detector_accel_sigma_mps2", &C::detector_accel_sigma_mps2, I::LeftOpen(0, 100),
                kChangesResults, "Accelerometer noise of the detector's statistic, m/s^2"),
      RealField("detector_gyro_sigma_radps", &C::detector_gyro_sigma_radps, I::LeftOpen(0, 10),
                kChangesResults, "Gyroscope noise of the detector's statistic, rad/s"),
      IntegerField("stance_gap_samples", &C::stance_gap_samples, 0, 1000, kChangesResults,
                   "Moving runs this short between still samples are still"),
      IntegerField("min_stance_samples", &C::min_stance_samples, 1, 100000, kChangesResults,
                   "Still samples a stance needs to end a step"),
      RealField("min_step_m", &C::min_step_m, I::Closed(0, 10), kChangesResults,
                "Stances closer than this to the previous step's end do not end a step, metres"),
      RealField("accel_noise_mps2_per_sqrt_hz", &C::accel_noise_mps2_per_sqrt_hz, I::Closed(0, 100),
                kChangesResults, "Filter: accelerometer noise density, m/s^2/sqrt(Hz)"),
      RealField("gyro_noise_radps_per_sqrt_hz", &C::gyro_noise_radps_per_sqrt_hz, I::Closed(0, 10),
                kChangesResults, "Filter: gyroscope noise density, rad/s/sqrt(Hz)"),
      RealField("accel_bias_walk_mps3_per_sqrt_hz", &C::accel_bias_walk_mps3_per_sqrt_hz,
                I::Closed(0, 100), kChangesResults,
                "Filter: accelerometer bias random walk, m/s^3/sqrt(Hz)"),
      RealField("gyro_bias_walk_radps2_per_sqrt_hz", &C::gyro_bias_walk_radps2_per_sqrt_hz,
                I::Closed(0, 10), kChangesResults,
                "Filter: gyroscope bias random walk, rad/s^2/sqrt(Hz)"),
      RealField("zupt_sigma_mps", &C::zupt_sigma_mps, I::LeftOpen(0, 100), kChangesResults,
                "Zero-velocity pseudo-measurement sigma, m/s"),
      RealField("zaru_sigma_radps", &C::zaru_sigma_radps, I::Closed(0, 10), kChangesResults,
                "Zero-angular-rate pseudo-measurement sigma, rad/s; 0: off"),
      RealField("alignment_s", &C::alignment_s, I::LeftOpen(0, 3600), kChangesResults,
                "Still time at the start that aligns the filter, seconds"),
      RealField("alignment_heading_rad", &C::alignment_heading_rad, I::Closed(-10, 10),
                kChangesResults, "Heading of the sensor's x axis at the alignment, radians"),
      RealField("alignment_tilt_sigma_rad", &C::alignment_tilt_sigma_rad, I::Closed(0, 10),
                kChangesResults, "Roll and pitch sigma after the alignment, radians"),
      RealField("alignment_heading_sigma_rad", &C::alignment_heading_sigma_rad, I::Closed(0, 10),
                kChangesResults, "Heading sigma after the alignment, radians"),
      RealField("initial_accel_bias_sigma_mps2", &C::initial_accel_bias_sigma_mps2,
                I::Closed(0, 100), kChangesResults, "Accelerometer bias sigma at the start, m/s^2"),
      RealField("initial_gyro_bias_sigma_radps", &C::initial_gyro_bias_sigma_radps,
                I::Closed(0, 10), kChangesResults,
                "Gyroscope bias sigma after the alignment's estimate, rad/s"),
      RealField("gravity_mps2", &C::gravity_mps2, I::Closed(0, 9.9), kChangesResults,
                "Gravity, m/s^2; 0: normal gravity at latitude_deg and height_m"),
      RealField("latitude_deg", &C::latitude_deg, I::Closed(-90, 90), kChangesResults,
                "Latitude for normal gravity, degrees"),
      RealField("height_m", &C::height_m, I::Closed(-1000, 10000), kChangesResults,
                "Height above the ellipsoid for normal gravity, metres"),
      RealField("accel_range_mps2", &C::accel_range_mps2, I::LeftOpen(0, 1e4), kChangesResults,
                "Accelerometer range: samples reaching it are saturated, m/s^2"),
      RealField("gyro_range_radps", &C::gyro_range_radps, I::LeftOpen(0, 1e3), kChangesResults,
                "Gyroscope range: samples reaching it are saturated, rad/s"),
      RealField("max_sample_interval_s", &C::max_sample_interval_s, I::LeftOpen(0, 10),
                kChangesResults, "Longest accepted time between samples, seconds"),
  };
  return *fields;
}

Status FootImuConfig::Validate() const {
  GROVE_RETURN_IF_ERROR(CheckFieldRanges(FootImuConfigFields(), *this));
  if (gravity_mps2 != 0 && gravity_mps2 < 9.7) {
    return InvalidArgumentError(fmt::format(
        "gravity_mps2 = {}: must be 0 (normal gravity) or in [9.7, 9.9]", gravity_mps2));
  }
  return Status::Ok();
}

double FootImuConfig::Gravity() const {
  return gravity_mps2 > 0 ? gravity_mps2 : imu::NormalGravity(latitude_deg * kPi / 180, height_m);
}

double FootImuConfig::Threshold() const {
  if (detector_threshold > 0) return detector_threshold;
  switch (detector) {
    case ZeroVelocityDetector::kShoe:
      return 3e4;
    case ZeroVelocityDetector::kAre:
      return 3e4;
    case ZeroVelocityDetector::kMv:
      return 50;
    case ZeroVelocityDetector::kMag:
      return 100;
  }
  return 3e4;
}

const char* ZeroVelocityDetectorName(ZeroVelocityDetector detector) {
  switch (detector) {
    case ZeroVelocityDetector::kShoe:
      return "shoe";
    case ZeroVelocityDetector::kAre:
      return "are";
    case ZeroVelocityDetector::kMv:
      return "mv";
    case ZeroVelocityDetector::kMag:
      return "mag";
  }
  return "shoe";
}

bool ParseZeroVelocityDetector(const std::string& name, ZeroVelocityDetector* detector) {
  for (ZeroVelocityDetector d : {ZeroVelocityDetector::kShoe, ZeroVelocityDetector::kAre,
                                 ZeroVelocityDetector::kMv, ZeroVelocityDetector::kMag}) {
    if (name == ZeroVelocityDetectorName(d)) {
      *detector = d;
      return true;
    }
  }
  return false;
}

std::string FootImuSummary::BriefReport() const {
  if (!aligned) {
    return fmt::format(
        "Foot IMU: {} samples, never aligned: no still run at the start lasted alignment_s ({} "
        "still samples).",
        samples, still_samples);
  }
  return fmt::format(
      "Foot IMU: {} samples in {:.3f} s ({:.0f} samples/s), aligned at t = {:.3f} s; {} stances, "
      "{} steps, {:.2f} m walked; {:.1f} % of samples still; gravity {:.5f} m/s^2.",
      samples, seconds, seconds > 0 ? samples / seconds : 0.0, alignment_t_s, stances, steps,
      distance_m, processed_samples > 0 ? 100.0 * still_samples / processed_samples : 0.0,
      gravity_mps2);
}

}  // namespace grove
