// Range-only beacon tracking: a target moving in the plane at nearly constant velocity, measured
// by its distances to beacons at known positions, tracked by a bootstrap particle filter (Gordon,
// Salmond and Smith, "Novel approach to nonlinear/non-Gaussian Bayesian state estimation", 1993):
// Monte Carlo localisation with a known map, so the particles carry no map.
//
//   grove::TrackerConfig config;  // 2,000 particles around the origin
//   config.particles = 500;
//   auto tracker = grove::Tracker::Create(config);  // validates; nothing built on error
//   if (!tracker.ok()) return tracker.status();
//   const grove::RangeMeasurement z[] = {{0, 0, 5.0}, {10, 0, 7.0}, {0, 10, 7.0}};
//   GROVE_RETURN_IF_ERROR((*tracker)->Update(1.0, z));  // beacon x, y and range, metres
//   grove::TargetState state = (*tracker)->MeanState();  // weighted mean position and velocity
//   if (!(state.x_m > -10 && state.x_m < 10)) return grove::InternalError("off the beacons");
//
// Model: the state is the position (x, y) and velocity (vx, vy); between updates dt apart each
// particle moves x += vx dt + a_x dt^2 / 2, vx += a_x dt (and so for y), with a_x, a_y drawn from
// N(0, acceleration_sigma_mps2^2) (the discrete white-noise acceleration model); a measurement
// of range r to a beacon at b weighs a particle at p by N(r; |p - b|, range_sigma_m^2).
//
// Thread safety and ownership: as FootSlam's (grove/footslam.h): one thread drives a Tracker at a
// time; it runs its own worker threads inside Update(); read-outs that return containers return
// copies.
#ifndef GROVE_TRACKING_H_
#define GROVE_TRACKING_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "grove/config_fields.h"
#include "grove/export.h"
#include "grove/filter_config.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove {

// The filter's fields come from FilterConfig (grove/filter_config.h): particles (Default: 2000),
// seed, resampling, resample_threshold (Default: 0.5), threads and batch (Default: 512).
struct GROVE_EXPORT TrackerConfig : FilterConfig {
  TrackerConfig() { particles = 2000; }

  // Options that change results

  // The prior: position and velocity at the start, metres and m/s. Range: |position| <= 1e9,
  // |velocity| <= 1e6. Default: at rest at the origin.
  double start_x_m = 0, start_y_m = 0;
  double start_vx_mps = 0, start_vy_mps = 0;
  // The prior's spread per axis: position (m) and velocity (m/s). Range: [0, 1e6].
  // Defaults: 20 m and 1 m/s.
  double initial_position_sigma_m = 20, initial_velocity_sigma_mps = 1;
  // Acceleration noise of the motion model per axis, m/s^2. Range: [0, 1e4]. Default: 0.5.
  double acceleration_sigma_mps2 = 0.5;
  // Range noise, metres. Range: (0, 1e6]. Default: 0.5.
  double range_sigma_m = 0.5;

  // Checks every field; the message names the field, its value and the rule it breaks.
  Status Validate() const;
};

// Every field of TrackerConfig: name, type, range, effect and meaning.
GROVE_EXPORT const std::vector<ConfigField<TrackerConfig>>& TrackerConfigFields();

// One range: the beacon's position (metres, in the frame of the track) and the measured
// distance to it (metres, >= 0).
struct RangeMeasurement {
  double beacon_x_m = 0, beacon_y_m = 0, range_m = 0;
};

// The target's position (m) and velocity (m/s).
struct TargetState {
  double x_m = 0, y_m = 0, vx_mps = 0, vy_mps = 0;
};

struct GROVE_EXPORT TrackerSummary : FilterSummary {
  int64_t measurements = 0;  // ranges over all updates
  TargetState mean_state;    // after the last update
  // One paragraph for a terminal.
  std::string BriefReport() const;
};

class Collective;

// A tracker is an interface (LevelDB's DB): Create() and Resume() return its implementation.
class GROVE_EXPORT Tracker {
 public:
  // Validates `config` and builds the tracker; nothing is built when the config is invalid.
  // With `ranks` (grove/collective.h), one rank's tracker of a filter whose config.particles are
  // split over the ranks, as FootSlam::Create's (null: one process).
  static StatusOr<std::unique_ptr<Tracker>> Create(const TrackerConfig& config,
                                                   Collective* ranks = nullptr);
  // What Create(config, ranks) checks of a configuration for `ranks` ranks beyond Validate().
  static Status CheckAcrossRanks(const TrackerConfig& config, int ranks);
  // A tracker continuing from `checkpoint`, as FootSlam::Resume (across ranks: collective, every
  // rank with its own file).
  static StatusOr<std::unique_ptr<Tracker>> Resume(const TrackerConfig& config,
                                                   std::string_view checkpoint,
                                                   const std::string& name, std::string* user_data,
                                                   Collective* ranks = nullptr);
  virtual ~Tracker();

  // The time of the prior; the first update must come after it. Without it the prior takes the
  // first update's time (that update then only weights). InvalidArgument for a non-finite
  // time, FailedPrecondition after the first update.
  virtual Status SetStartTime(double t_s) = 0;
  // Moves every particle to t_s, then weights it by `measurements` (none: a prediction).
  // InvalidArgument, the tracker unchanged, for a time not finite or not after the previous
  // one, or a measurement that is not finite or has a negative range (named by its index);
  // FailedPrecondition when every weight became zero: the tracker must then not be updated again.
  virtual Status Update(double t_s, std::span<const RangeMeasurement> measurements) = 0;

  virtual const TrackerConfig& config() const = 0;
  // Updates so far.
  virtual int64_t steps() const = 0;
  // The weighted mean pose and the heaviest particle's, the heading the direction of motion
  // (atan2(vy, vx); 0 at rest).
  virtual Pose2 MeanPose() const = 0;
  virtual Pose2 HeaviestPose() const = 0;
  // The weighted mean pose at the start and after every update.
  virtual const std::vector<StampedPose>& MeanTrajectory() const = 0;
  // The weighted mean position and velocity after the last update.
  virtual TargetState MeanState() const = 0;
  virtual TrackerSummary Summary() const = 0;
  // The whole state as the bytes of a checkpoint file, as FootSlam::Checkpoint.
  virtual StatusOr<std::string> Checkpoint(std::string_view user_data = {}) const = 0;
};

}  // namespace grove

#endif  // GROVE_TRACKING_H_
