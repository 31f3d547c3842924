// Tim Bailey's FastSLAM simulator (Bailey and Nieto's MATLAB FastSLAM 1.0/2.0 package, 2004-2006:
// fastslam*_sim.m, compute_steering.m, predict_true.m, get_observations.m), rewritten for grove.
// A car-like vehicle drives NUMBER_LOOPS times through a list of waypoints among point landmarks;
// it gives the noisy controls a filter gets, range-bearing observations with the landmark's id
// (known association) and the truth. The files it writes are the inputs of `grove fastslam run`.
//
// Models (as Bailey's):
// - Control law: steer towards the current waypoint, the change per step limited to
//   max_steer_rate_radps * dt and the angle to +-max_steer_rad; switch to the next waypoint when
//   closer than at_waypoint_m (Bailey switches at most once a step; grove goes on switching
//   while the next waypoint is that close too, which the webmap never needs).
// - Vehicle: one Euler step per control interval dt, with speed V and steering angle G:
//     x += V dt cos(G + phi),  y += V dt sin(G + phi),  phi = wrap(phi + V dt sin(G) / wheelbase).
//   (sin(G) / wheelbase, not sin(G / wheelbase) as several C++ ports write.)
// - Sensor: every landmark with range < max_range_m and |bearing| < field_of_view_rad / 2, where
//   range is the distance from the vehicle's reference point and bearing its angle in the vehicle
//   frame, counter-clockwise from the heading. With the default field of view of pi this is
//   Bailey's forward half plane (dx cos phi + dy sin phi > 0).
// - Noise: the filter's controls are the true ones plus N(0, sigma_speed_mps^2) and
//   N(0, sigma_steer_rad^2), independent per step; each observation is the true range and bearing
//   plus N(0, sigma_range_m^2) and N(0, sigma_bearing_rad^2). Angles are wrapped to (-pi, pi].
//
// Times (what a filter must do to reproduce the truth with zero noise):
// - t_k = k * dt_control_s for k = 0 ... K, computed by multiplication (never by summing dt).
// - Control row k, k < K, is at t_k and holds over [t_k, t_{k+1}) (zero-order hold). It moves the
//   true pose of row k of truth.csv (at t_k) to row k + 1 (at t_{k+1}) by one Euler step of
//   dt_k = t_{k+1} - t_k, computed in double from the written times, so a reader that differences
//   the times it reads gets the same dt bit for bit.
// - Row K of controls.csv, at t_K, is the stop: speed 0 and the last true steering angle,
//   noise-free; it moves nothing. So controls.csv and truth.csv have the same K + 1 times, truth
//   row 0 being the start pose at t = 0.
// - Scans are at t_k for k = n, 2n, 3n, ... <= K with n = round(dt_observe_s / dt_control_s),
//   never at t = 0: a scan at t_k observes truth row k, the pose reached by holding control k - 1
//   over [t_{k-1}, t_k], before control k starts. A filter that predicts from its last time to
//   the scan's t with the held control, then updates, sees the scan from the true pose.
//
// Decision (Bailey's 0.225 s): Bailey's loop sums dtsum += 0.025 and observes when
// dtsum >= DT_OBSERVE = 0.2; in double the eighth sum is 0.19999999999999998, so his scans come
// every 9 steps (0.225 s, 4.44 Hz). grove counts control steps instead and observes every
// n = round(dt_observe_s / dt_control_s) steps (8: exactly every 0.2 s), because that is what
// his configuration means (his configfile.m writes DT_OBSERVE = 8*DT_CONTROLS and the paper of
// Simulations I-III says 5 Hz), and a count cannot drift with round-off. The webmap therefore
// has about 9/8 of Bailey's scans (about 2,170 instead of about 1,930).
//
// Other differences from Bailey's loop, each one control step: at the wrap from the last
// waypoint to the first, Bailey's compute_steering returns before steering, so one step keeps
// the previous angle (grove steers towards the new waypoint at once); after the final waypoint
// Bailey's loop moves once more before it stops (grove stops there). Landmark ids are 0-based
// (the row in the lm block), Bailey's ftag 1-based.
//
// Random numbers: two std::mt19937_64 engines, one for the control noise and one for the
// observation noise, each seeded by std::seed_seq from (seed, purpose) (both algorithms are fixed
// by the C++ standard); normal deviates by our own Box-Muller on the raw 64-bit output, never by
// an implementation-defined std:: distribution. The result depends only on the map and the
// options (libm's sin, cos, atan2, log may differ in the last bit between platforms). Two
// engines keep the control noise unchanged when only the sensor options change.
//
// Thread safety: all functions are thread-safe (no shared state).
#ifndef GROVE_TOOLS_SIM_FASTSLAM_SIMULATOR_H_
#define GROVE_TOOLS_SIM_FASTSLAM_SIMULATOR_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/sim/bailey_map.h"

namespace grove::tools {

// Every parameter of Bailey's example_webmap.ini that the simulator uses, with his defaults.
// Parameters of the .ini that belong to the filter, not the simulator: sigmaT and
// SWITCH_HEADING_KNOWN (heading observed by the particles), GATE_REJECT, GATE_AUGMENT,
// NPARTICLES, NEFFECTIVE and the other SWITCH_ flags. SWITCH_CONTROL_NOISE = 0 or
// SWITCH_SENSOR_NOISE = 0 are the sigmas set to 0 here.
struct BaileySimOptions {
  // Fields that change the results.

  // Constant true speed V of the vehicle. Range: (0, 100]. Default: 3 (V).
  double speed_mps = 3.0;
  // Distance between the axles, B in the vehicle model. Range: (0, 100]. Default: 4 (WHEELBASE).
  double wheelbase_m = 4.0;
  // Largest true steering angle: -max <= G <= max. Range: (0, pi/2]. Default: 30 degrees,
  // 0.523598775598299 (MAXG).
  double max_steer_rad = 0.523598775598299;
  // Largest rate of change of the true steering angle: |G_k - G_{k-1}| <= this * dt_control_s.
  // Range: (0, 100]. Default: 20 degrees/s, 0.349065850398866 (RATEG).
  double max_steer_rate_radps = 0.349065850398866;
  // A waypoint counts as reached when the vehicle is closer to it than this.
  // Range: (0, 1e6]. Default: 1 (AT_WAYPOINT).
  double at_waypoint_m = 1.0;
  // Times the vehicle drives through the whole waypoint list; it stops at the last waypoint of
  // the last loop. Range: [1, 1000]. Default: 2 (NUMBER_LOOPS).
  int32_t loops = 2;
  // Time between controls, the Euler step of the vehicle model. Range: (0, 10].
  // Default: 0.025, 40 Hz (DT_CONTROLS).
  double dt_control_s = 0.025;
  // Time between scans. Range: a whole multiple n of dt_control_s (to 1e-9 relative), 1 <= n <=
  // 1e6; scans come every n control steps. Default: 0.2, 5 Hz (DT_OBSERVE).
  double dt_observe_s = 0.2;
  // Landmarks closer than this are observed. Range: (0, 1e6]. Default: 30 (MAX_RANGE).
  double max_range_m = 30.0;
  // Full angular width of the sensor's view, centred on the heading: a landmark is observed when
  // |true bearing| < field_of_view_rad / 2. Range: (0, 2 pi]; 2 pi observes all around.
  // Default: pi, Bailey's forward half plane (get_observations.m; not a parameter of his .ini).
  double field_of_view_rad = 3.14159265358979323846;
  // Standard deviation of the noise added to the speed the filter gets. Range: [0, 100].
  // Default: 0.3 (sigmaV).
  double sigma_speed_mps = 0.3;
  // Standard deviation of the noise added to the steering angle the filter gets (the true angle
  // stays within max_steer_rad, the noisy one need not). Range: [0, pi]. Default: 3 degrees,
  // 0.052359877559830 (sigmaG).
  double sigma_steer_rad = 0.052359877559830;
  // Standard deviation of the range noise. A detection whose noisy range is not > 0 is dropped
  // (a sensor reports no negative range; with the defaults only a landmark within about 0.5 m
  // could be). Range: [0, 1e4]. Default: 0.1 (sigmaR).
  double sigma_range_m = 0.1;
  // Standard deviation of the bearing noise. Range: [0, pi]. Default: 1 degree,
  // 0.017453292519943 (sigmaB).
  double sigma_bearing_rad = 0.017453292519943;
  // Seeds the control and the observation noise. Any value. Default: 1 (Bailey's
  // SWITCH_SEED_RANDOM = 0 draws an unseeded run; grove always seeds).
  uint64_t seed = 1;
  // True pose at t = 0. Ranges: |x|, |y| <= 1e9; heading in (-pi, pi]. Default: (0, 0, 0),
  // Bailey's xtrue = zeros(3,1).
  double start_x_m = 0;
  double start_y_m = 0;
  double start_heading_rad = 0;

  // A guard, not a model parameter: the run fails (InvalidArgument) instead of driving on when
  // the last waypoint is not reached within this many control steps (a waypoint inside the
  // turning circle can be circled for ever). Range: [1, 1e8]. Default: 1,000,000 (6.9 h at
  // 40 Hz; the webmap needs about 17,400).
  int64_t max_steps = 1'000'000;

  // Ok, or InvalidArgument naming the first field that breaks its range:
  // "speed_mps = -1: must be > 0 and finite".
  Status Validate() const;
};

// The presets. Fields a source does not give keep Bailey's webmap values (max_steer_rad,
// max_steer_rate_radps, at_waypoint_m, loops, field of view when not stated, seed 1).
//
// Bailey's example_webmap.ini: the defaults above.
BaileySimOptions WebmapPreset();
// Ankışhan et al. (2016), Section 4.1, Simulation I: V = 3 m/s, wheelbase 4 m, controls
// at 40 Hz, observations at 5 Hz, maximum range 30 m, and Q (Eq. 33) and R (Eq. 34). Readings of
// the PDF's flattened text (each written down in the .cc): Q = diag(1.0^2, (10 pi/180)^2), so
// sigma_speed_mps = 1.0 and sigma_steer_rad = 10 degrees; R = diag(1.2^2, (12 pi/180)^2), so
// sigma_range_m = 1.2 and sigma_bearing_rad = 12 degrees. No field of view is stated: Bailey's
// half plane (pi).
BaileySimOptions Simulation1Preset();
// Section 4.2, Simulation II: "system and observation parameters ... similar to Simulation I and
// the knowledge of control and measurement noise is the same": Simulation I's options. What
// differs (unknown association, another map, 30 and 3 particles) is the filter's or the map's.
BaileySimOptions Simulation2Preset();
// Section 4.3, Simulation III: wheelbase 0.26 m, V = 0.8 m/s, controls at 40 Hz, sensor at 5 Hz,
// sigma_speed 0.4 m/s, sigma_steer 4 degrees, sigma_range 0.2 m (the text says "0.2 m/s in
// range": read as metres), sigma_bearing 2 degrees, maximum range 5 m, 180 degree frontal field
// of view. The paper's map (its Figure 7) is not published: run it on a map of its scale.
BaileySimOptions Simulation3Preset();

// The preset names accepted by BaileyPreset: "webmap", "sim1", "sim2", "sim3".
inline constexpr std::string_view kBaileyPresetNames[] = {"webmap", "sim1", "sim2", "sim3"};
// The preset called `name`, or InvalidArgument listing the names.
StatusOr<BaileySimOptions> BaileyPreset(std::string_view name);

struct BaileyControl {
  double t_s = 0;
  double speed_mps = 0;
  double steer_rad = 0;
};

struct BaileyPose {
  double t_s = 0;
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;
};

struct BaileyObservation {
  double t_s = 0;
  double range_m = 0;
  double bearing_rad = 0;  // in (-pi, pi]
  int32_t id = 0;          // index of the landmark in BaileyMap::landmarks
};

// The vehicle was closer than at_waypoint_m to `waypoint` (0-based) in loop `loop` (0-based) at
// truth row `step`, and switched to the next one there.
struct BaileyWaypointVisit {
  int64_t step = 0;
  int32_t waypoint = 0;
  int32_t loop = 0;
};

struct BaileySimulation {
  // K + 1 true poses at t_0 = 0 ... t_K (see Times above); truth[0] is the start.
  std::vector<BaileyPose> truth;
  // K + 1 rows each at the times of `truth`; the last is the stop (speed 0, noise-free).
  std::vector<BaileyControl> true_controls;  // what drove the vehicle
  std::vector<BaileyControl> controls;       // with noise: what the filter gets
  // Every scan time, including scans in which no landmark was in view (they have no rows).
  std::vector<double> scan_times_s;
  // One row per detection, in scan order and, within a scan, by id.
  std::vector<BaileyObservation> observations;
  // Every waypoint reached, in order: loops * waypoints visits.
  std::vector<BaileyWaypointVisit> visits;
  std::vector<BaileyPoint> landmarks;  // the map's, for landmarks_truth.csv

  // K, the number of control steps that moved the vehicle.
  int64_t control_steps() const { return static_cast<int64_t>(truth.size()) - 1; }
};

// Runs the simulator. InvalidArgument when the options fail Validate(), the map has no waypoint
// or a non-finite point, or the last waypoint is not reached within max_steps.
StatusOr<BaileySimulation> SimulateBailey(const BaileyMap& map, const BaileySimOptions& options);

// The output files as text, numbers in the shortest form that reads back to the same double.
// "t,v,steer": the noisy controls (K + 1 rows, t strictly increasing).
std::string BaileyControlsCsv(const BaileySimulation& sim);
// "t,range,bearing,id": one detection a row; rows with the same t are one scan.
std::string BaileyObservationsCsv(const BaileySimulation& sim);
// "t,x,y,heading": the true poses (K + 1 rows).
std::string BaileyTruthCsv(const BaileySimulation& sim);
// "id,x,y": the true landmarks.
std::string BaileyLandmarksCsv(const BaileySimulation& sim);

// Seconds spent in the engine's Control() and Scan() calls.
struct FeedTimes {
  double control_s = 0;
  double scan_s = 0;
};

// Feeds the first `controls` control rows of `sim` into `slam`, each followed by the scans from
// its time until the next row's (a control first at a shared time), as `grove fastslam run`
// merges its files, and calls after_scan(t) (when given) after each scan. The first error stops
// it (the message names the row), and so does an error after_scan returns (returned as it is).
// `times` may be null.
Status FeedSimulation(const BaileySimulation& sim, FastSlam* slam, size_t controls = SIZE_MAX,
                      FeedTimes* times = nullptr,
                      const std::function<Status(double t_s)>& after_scan = nullptr);

// `grove fastslam simulate`: reads the map (the bundled webmap when map_path is empty), takes the
// preset (empty: "webmap") with `seed`, simulates and writes controls.csv, observations.csv,
// truth.csv and landmarks_truth.csv into out_dir (created if missing), each atomically. Returns
// 0 and prints a one-line summary on stderr, or prints "grove: error: ..." on stderr and returns
// 2 (bad option or preset), 3 (bad map file, or a waypoint the vehicle cannot reach) or 5 (an
// output cannot be written).
int FastSlamSimulateCommand(const std::string& map_path, const std::string& preset,
                            const std::string& out_dir, uint64_t seed);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_FASTSLAM_SIMULATOR_H_
