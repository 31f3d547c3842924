// A foot-mounted IMU walking the walk simulator's true path: a gait model gives the foot's
// motion (still stances, swings with toe off and heel strike), from which the sensor's specific
// force and angular rate follow analytically; a MEMS error model then corrupts them.
//
// Gait. The sensor is on one foot, which lands on every second true position of the walk (a
// stride is two of the walker's steps; the other foot takes the steps between). At each landing
// the foot is flat and still for stance_fraction of the mean stride period, centred on the true
// time; the walk starts and ends with rest_s of stillness. In a swing the foot moves along the
// straight line between its stances (velocity, acceleration and jerk zero at both ends), rises
// by clearance_m, pitches toes down by toe_off_pitch_rad after leaving the ground, turns quickly
// through level to toes up by heel_strike_pitch_rad before landing, and turns from one stance's
// heading to the next (each stance faces along the path there). No impact transients: every
// signal is smooth, so that an ideal sensor's samples integrate to the true path.
//
// Frames. The sensor frame is the foot's: x forward (towards the toes), y left, z up; it
// measures specific force (0, 0, +g) when still and level. The truth frame is the walk's, z up.
//
// MEMS errors (MemsModel): per axis a turn-on bias, a bias random walk, a scale factor error,
// cross-axis misalignment and white noise, then clipping at the range and rounding to the
// resolution. The defaults are typical values of the Bosch BMI160 (engine/imu/README.md lists
// each with its source); MemsModel::None() is an ideal sensor.
#ifndef GROVE_TOOLS_SIM_FOOT_IMU_SIMULATOR_H_
#define GROVE_TOOLS_SIM_FOOT_IMU_SIMULATOR_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/foot_imu.h"
#include "grove/status.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {

struct GaitModel {
  // Still (foot flat) share of the mean stride period. Range: [0.1, 0.8]. Default: 0.4.
  double stance_fraction = 0.4;
  // Stillness before the first stride and after the last, seconds. Range: [0.5, 60].
  // Default: 2.
  double rest_s = 2;
  // Peak height of the sensor in a swing, metres. Range: [0, 0.5]. Default: 0.12.
  double clearance_m = 0.12;
  // Peak pitch after toe off (toes down) and before heel strike (toes up), radians.
  // Range: [0, 1.5]. Defaults: 0.7 (40 degrees) and 0.35 (20 degrees).
  double toe_off_pitch_rad = 0.7;
  double heel_strike_pitch_rad = 0.35;
};

struct MemsModel {
  // White noise densities: m/s^2/sqrt(Hz) (BMI160: 180 ug/sqrt(Hz)) and rad/s/sqrt(Hz)
  // (0.007 deg/s/sqrt(Hz)).
  double accel_noise_mps2_per_sqrt_hz = 180e-6 * 9.80665;
  double gyro_noise_radps_per_sqrt_hz = 0.007 * 3.14159265358979323846 / 180;
  // Turn-on biases, one draw per axis and recording, standard deviations: m/s^2 and rad/s.
  // Default: the residual after a user calibration, a tenth of the data sheet's offsets
  // (40 mg and 3 deg/s).
  double accel_bias_mps2 = 0.004 * 9.80665;
  double gyro_bias_radps = 0.3 * 3.14159265358979323846 / 180;
  // Bias random walks (in-run instability): m/s^3/sqrt(Hz) and rad/s^2/sqrt(Hz).
  // Defaults: after 10 minutes about 0.1 mg and 15 deg/h (not in the data sheet: typical of
  // consumer MEMS in Allan variance studies).
  double accel_bias_walk_mps3_per_sqrt_hz = 5e-5;
  double gyro_bias_walk_radps2_per_sqrt_hz = 3e-6;
  // Scale factor errors and misalignment (each off-diagonal term of the axes' matrix),
  // standard deviations per axis. Defaults: 0.5 % and 1 mrad after calibration.
  double accel_scale_sigma = 0.005;
  double gyro_scale_sigma = 0.005;
  double accel_misalignment_rad = 0.001;
  double gyro_misalignment_rad = 0.001;
  // Ranges: values beyond are clipped (BMI160: 16 g, 2000 deg/s).
  double accel_range_mps2 = 16 * 9.80665;
  double gyro_range_radps = 2000 * 3.14159265358979323846 / 180;
  // Resolution: outputs are rounded to range / 2^(bits - 1); 0 keeps full precision.
  int bits = 16;

  // An ideal sensor: no error of any kind, full precision, unlimited range.
  static MemsModel None();
};

struct FootImuSimOptions {
  // Samples per second. Range: [50, 2000]. Default: 200.
  double rate_hz = 200;
  GaitModel gait;
  MemsModel mems;
  // Seeds the sensor errors (the walk has its own seed). Default: 1.
  uint64_t seed = 1;
  // Gravity the sensor feels, m/s^2: the foot IMU's default (FootImuConfig::Gravity()).
  double gravity_mps2 = FootImuConfig().Gravity();
};

// A stance of the instrumented foot: still from begin_s to end_s at a true position.
struct TrueStance {
  double begin_s = 0;
  double end_s = 0;
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;   // of the foot (the sensor's x axis), unwrapped across the walk
  int64_t truth_index = 0;  // the walk's truth point it stands on
};

struct SimulatedFootImu {
  std::vector<ImuSample> samples;
  std::vector<TrueStance> stances;  // the first is the start, where the walk begins
};

// The recording of `walk` (the walk simulator's output: its truth is what the foot follows).
// InvalidArgument naming the option when one is out of range or the walk's step period is too
// short for the stance fraction.
StatusOr<SimulatedFootImu> SimulateFootImu(const SimulatedWalk& walk,
                                           const FootImuSimOptions& options);

// "t,ax,ay,az,gx,gy,gz" then one row per sample, SI units; numbers with `digits` significant
// digits, or 0 for the shortest form that reads back to the same double.
std::string ImuCsv(const SimulatedFootImu& imu, int digits = 0);
// "begin,end,x,y,heading" then one row per stance.
std::string StancesCsv(const SimulatedFootImu& imu);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_FOOT_IMU_SIMULATOR_H_
