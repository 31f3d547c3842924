// FootImu: steps from a foot-mounted IMU, the odometry FootSLAM walks on. A zero-velocity-aided
// strapdown inertial navigation system (Foxlin 2005; Skog, Händel, Nilsson and Rantakokko,
// "Zero-velocity detection - an algorithm evaluation", IEEE TBME 2010; Nilsson et al., OpenShoe):
// the samples are integrated in a local level frame, a detector finds the stance phases, where
// the foot is still, and an error-state Kalman filter corrects the navigation state and the
// sensor biases with zero-velocity (and optionally zero-angular-rate) pseudo-measurements. Each
// stance ends a step: the displacement since the previous stance, the heading change and their
// covariance. Frames, units and signs: engine/imu/README.md.
//
//   grove::FootImuConfig config;  // SHOE detector, 5-sample window, a sensor at about 200 Hz
//   auto imu = grove::FootImu::Create(config);  // validates; nothing built on error
//   if (!imu.ok()) return imu.status();
//   for (int k = 0; k < 400; ++k) {  // 2 s of a still, level sensor: the first stance
//     const grove::ImuSample sample{0.005 * k, {0.0, 0.0, 9.80665}, {0.0, 0.0, 0.0}};
//     GROVE_RETURN_IF_ERROR((*imu)->AddSample(sample));  // on error the engine is unchanged
//   }
//   GROVE_RETURN_IF_ERROR((*imu)->Finish());  // decides the samples held back by the detector
//   for (const grove::FootStep& step : (*imu)->TakeSteps()) {
//     (void)step;  // step.t_s, step.dx_m, step.dy_m: one FootSlam::Step
//   }
//
// Thread safety: a FootImu is driven by one thread at a time (no two calls overlap, const
// read-outs included). Two engines in one process share nothing. It starts no threads.
#ifndef GROVE_FOOT_IMU_H_
#define GROVE_FOOT_IMU_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/export.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove {

// The zero-velocity detectors of Skog et al. (2010). Each computes a statistic T over a window of
// detector_window samples centred on a sample and declares the sample still when T is below
// detector_threshold. a: specific force, w: angular rate, g: gravity, N the window's samples,
// a_mean their mean specific force, sigma_a and sigma_w the detector's noise levels.
enum class ZeroVelocityDetector {
  // SHOE, the generalised likelihood ratio test: T = 1/N sum (|a - g a_mean/|a_mean||^2 / sigma_a^2
  // + |w|^2 / sigma_w^2).
  kShoe,
  // ARE, angular rate energy: T = 1/N sum |w|^2 / sigma_w^2.
  kAre,
  // MV, acceleration moving variance: T = 1/N sum |a - a_mean|^2 / sigma_a^2.
  kMv,
  // MAG, acceleration magnitude: T = 1/N sum (|a| - g)^2 / sigma_a^2.
  kMag,
};

struct GROVE_EXPORT FootImuConfig {
  // Every option below changes results.

  // Zero-velocity detection. The window and threshold suit about 200 Hz; scale the window with
  // the rate (e.g. 10 at 400 Hz).
  ZeroVelocityDetector detector = ZeroVelocityDetector::kShoe;
  // Samples in the detector's window, centred on the sample decided (one more after it than
  // before it when even). Range: 1..1001. Default: 5.
  int detector_window = 5;
  // The detector's threshold on T. 0: the detector's own default (SHOE 3e4, as OpenShoe's;
  // ARE 3e4, MV 50, MAG 100: engine/imu/README.md says how they were chosen). Range: >= 0.
  // Default: 0.
  double detector_threshold = 0;
  // sigma_a and sigma_w of the statistics (OpenShoe's values). Range: (0, 100] and (0, 10].
  // Defaults: 0.01 m/s^2 and 0.1 deg/s.
  double detector_accel_sigma_mps2 = 0.01;
  double detector_gyro_sigma_radps = 0.1 * 3.14159265358979323846 / 180;
  // A run of at most this many moving samples between still ones is taken as still (a stance
  // does not break in two on a twitch). Range: 0..1000. Default: 2.
  int stance_gap_samples = 2;
  // A run of still samples ends a step only when it is at least this long; shorter runs still
  // get zero-velocity updates. Range: 1..100000. Default: 5.
  int min_stance_samples = 5;
  // A stance less than this far (horizontally) from the previous step's end does not end a
  // step: the foot twitched within one stance, and the walk on from there joins the next step.
  // Range: [0, 10] m. Default: 0.15.
  double min_step_m = 0.15;

  // Error-state Kalman filter. Process noise as densities (the sensor's white noise, raised to
  // cover what the model leaves out: impacts, vibration, a foot that is not quite still).
  // Accelerometer, m/s^2/sqrt(Hz). Range: [0, 100]. Default: 0.02.
  double accel_noise_mps2_per_sqrt_hz = 0.02;
  // Gyroscope, rad/s/sqrt(Hz). Range: [0, 10]. Default: 5e-4.
  double gyro_noise_radps_per_sqrt_hz = 5e-4;
  // Random walk of the accelerometer biases, m/s^3/sqrt(Hz). Range: [0, 100]. Default: 1e-4.
  double accel_bias_walk_mps3_per_sqrt_hz = 1e-4;
  // Random walk of the gyroscope biases, rad/s^2/sqrt(Hz). Range: [0, 10]. Default: 1e-5.
  double gyro_bias_walk_radps2_per_sqrt_hz = 1e-5;
  // Standard deviation of a zero-velocity pseudo-measurement, m/s. Range: (0, 100].
  // Default: 0.01.
  double zupt_sigma_mps = 0.01;
  // Standard deviation of a zero-angular-rate pseudo-measurement, rad/s, applied in every still
  // sample with the zero-velocity one; 0 switches it off. Range: [0, 10]. Default: 0.005.
  double zaru_sigma_radps = 0.005;

  // Initial alignment, from the first stance: the first run of still samples lasting
  // alignment_s sets roll and pitch from the mean specific force and the gyroscope biases to
  // the mean angular rate; heading is alignment_heading_rad. Samples before it are skipped.
  // Range: (0, 3600] s. Default: 0.5.
  double alignment_s = 0.5;
  // Heading of the sensor's x axis at the alignment, radians counter-clockwise from the
  // odometry frame's x axis. Range: [-10, 10]. Default: 0.
  double alignment_heading_rad = 0;
  // Standard deviations after the alignment: roll and pitch (rad), heading (rad), accelerometer
  // biases (m/s^2), gyroscope biases (rad/s). Ranges: [0, 10], [0, 10], [0, 100], [0, 10].
  // Defaults: 0.01, 0, 0.05, 0.002.
  double alignment_tilt_sigma_rad = 0.01;
  double alignment_heading_sigma_rad = 0;
  double initial_accel_bias_sigma_mps2 = 0.05;
  double initial_gyro_bias_sigma_radps = 0.002;

  // Gravity, m/s^2; 0 takes the normal gravity of the WGS-84 ellipsoid (Somigliana) at
  // latitude_deg and height_m. Range: 0 or [9.7, 9.9]. Default: 0.
  double gravity_mps2 = 0;
  // Range: [-90, 90] degrees and [-1000, 10000] m. Defaults: 45, 0.
  double latitude_deg = 45;
  double height_m = 0;

  // Input checks. A sample whose specific force or angular rate reaches the sensor's range on
  // any axis is saturated and refused. Range: (0, 1e4] m/s^2 and (0, 1e3] rad/s. Defaults: 16 g
  // and 2000 deg/s.
  double accel_range_mps2 = 16 * 9.80665;
  double gyro_range_radps = 2000 * 3.14159265358979323846 / 180;
  // The longest accepted time between two samples; a longer gap is refused. Range: (0, 10] s.
  // Default: 0.05.
  double max_sample_interval_s = 0.05;

  // Checks every field; the message names the field, its value and the rule it breaks.
  Status Validate() const;
  // gravity_mps2, or the normal gravity at latitude_deg and height_m.
  double Gravity() const;
  // detector_threshold, or the detector's default.
  double Threshold() const;
};

// "shoe", "are", "mv", "mag".
GROVE_EXPORT const char* ZeroVelocityDetectorName(ZeroVelocityDetector detector);
GROVE_EXPORT bool ParseZeroVelocityDetector(const std::string& name,
                                            ZeroVelocityDetector* detector);

// Every field of FootImuConfig, as FootSlamConfigFields(): Validate() checks these ranges; the
// grove command's flags, JSON keys and --print-config come from this table. No name is also a
// FootSlamConfig field's, so both sets of flags fit on one command line.
GROVE_EXPORT const std::vector<ConfigField<FootImuConfig>>& FootImuConfigFields();

// One sample of the sensor: specific force (what an accelerometer measures: +g upwards at rest)
// and angular rate, both in the sensor frame, right-handed.
struct ImuSample {
  double t_s = 0;
  double accel_mps2[3] = {0, 0, 0};
  double gyro_radps[3] = {0, 0, 0};
};

// One step: from the end of one stance to the end of the next, in the odometry frame (the local
// level frame of the alignment: x along alignment_heading_rad = 0, y to its left, z up; origin
// where the sensor was aligned).
struct FootStep {
  double t_s = 0;  // the middle of the stance that ends the step
  double dx_m = 0;
  double dy_m = 0;
  double dz_m = 0;
  // Change of the sensor's heading (the yaw of a z-y-x Euler sequence), in (-pi, pi].
  double dheading_rad = 0;
  // Covariance of (dx, dy, dheading) by the filter (x and y in m, heading in rad).
  Pose2Covariance covariance;
  // The first and last still samples of the stance that ends the step, and the index of the
  // last (0-based over every sample added).
  double stance_begin_s = 0;
  double stance_end_s = 0;
  int64_t stance_end_sample = 0;
};

// The navigation state after the last sample the filter has processed (it runs
// detector_window / 2 + stance_gap_samples samples behind AddSample).
struct FootImuState {
  double t_s = 0;
  double position_m[3] = {0, 0, 0};  // odometry frame
  double velocity_mps[3] = {0, 0, 0};
  double roll_rad = 0;  // z-y-x Euler angles of the sensor frame in the odometry frame
  double pitch_rad = 0;
  double heading_rad = 0;
  double accel_bias_mps2[3] = {0, 0, 0};  // the filter's estimates, sensor frame
  double gyro_bias_radps[3] = {0, 0, 0};
  bool still = false;  // the detector's decision for this sample
};

// What a run read, what it found and what it cost.
struct GROVE_EXPORT FootImuSummary {
  int64_t samples = 0;            // added
  int64_t processed_samples = 0;  // through the detector and, once aligned, the filter
  int64_t still_samples = 0;      // decided still (zero-velocity updates once aligned)
  int64_t stances = 0;            // runs of at least min_stance_samples still samples
  int64_t steps = 0;              // finished steps (stances after the first)
  bool aligned = false;
  double alignment_t_s = 0;  // the sample at which the filter started
  // The end of the first stance: the start of the first step, the odometry's start time.
  bool has_origin = false;
  double origin_t_s = 0;
  double gravity_mps2 = 0;  // in use
  double distance_m = 0;    // summed horizontal step lengths
  double seconds = 0;       // time spent in AddSample and Finish
  // One paragraph for a terminal.
  std::string BriefReport() const;
};

class GROVE_EXPORT FootImu {
 public:
  // Validates `config` and builds the engine; nothing is built when the config is invalid.
  static StatusOr<std::unique_ptr<FootImu>> Create(const FootImuConfig& config);
  virtual ~FootImu();

  // Adds the next sample. InvalidArgument, the engine unchanged, for a value that is not finite,
  // a saturated axis (accel_range_mps2, gyro_range_radps), a time not after the previous
  // sample's or more than max_sample_interval_s after it; FailedPrecondition after Finish().
  // A step is finished when the sample after its stance is decided (TakeSteps).
  Status AddSample(const ImuSample& sample);
  // The end of the recording: decides the samples held back by the detector window and ends a
  // stance still open as a step. Later AddSample calls fail; a second Finish() does nothing.
  Status Finish();
  // The steps finished since the last call, oldest first; the engine keeps none of them.
  std::vector<FootStep> TakeSteps();

  const FootImuConfig& config() const;
  FootImuState State() const;
  FootImuSummary Summary() const;

  class Impl;

 private:
  explicit FootImu(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace grove

#endif  // GROVE_FOOT_IMU_H_
