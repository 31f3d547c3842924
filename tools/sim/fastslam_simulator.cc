#include "tools/sim/fastslam_simulator.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <memory>
#include <random>
#include <sstream>
#include <utility>

#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/run/run_loop.h"
#include "tools/sim/normal_source.h"

namespace grove::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180;

// Stream purposes of the two noise engines. Part of the results: never renumber.
constexpr uint32_t kControlNoise = 1;
constexpr uint32_t kObservationNoise = 2;

// Wraps to (-pi, pi]. std::remainder is exact, so an angle already in range is returned as is.
double WrapAngle(double a) {
  if (a > kPi || a <= -kPi) {
    a = std::remainder(a, 2 * kPi);
    if (a <= -kPi) a += 2 * kPi;
  }
  return a;
}

// "field = value: rule".
Status RangeError(std::string_view field, double value, std::string_view rule) {
  return InvalidArgumentError(fmt::format("{} = {}: {}", field, value, rule));
}

// (0, max] and finite.
Status CheckPositive(std::string_view field, double value, double max) {
  if (!(value > 0) || !(value <= max)) {
    return RangeError(field, value, fmt::format("must be > 0 and <= {:g}", max));
  }
  return Status::Ok();
}

// [0, max] and finite.
Status CheckSigma(std::string_view field, double value, double max, std::string_view max_text) {
  if (!(value >= 0) || !(value <= max)) {
    return RangeError(field, value, fmt::format("must be >= 0 and <= {}", max_text));
  }
  return Status::Ok();
}

void AppendObservations(const BaileyMap& map, const BaileySimOptions& o, double t,
                        const BaileyPose& pose, NormalSource* noise, BaileySimulation* sim) {
  const double range2 = o.max_range_m * o.max_range_m;
  const double half_view = o.field_of_view_rad / 2;
  const bool all_around = o.field_of_view_rad >= 2 * kPi;
  for (size_t id = 0; id < map.landmarks.size(); ++id) {
    const double dx = map.landmarks[id].x_m - pose.x_m;
    const double dy = map.landmarks[id].y_m - pose.y_m;
    const double d2 = dx * dx + dy * dy;
    // Strict, as Bailey's (dx^2 + dy^2) < rmax^2; a landmark at the sensor has no bearing.
    if (!(d2 < range2) || d2 == 0) continue;
    const double bearing = WrapAngle(std::atan2(dy, dx) - pose.heading_rad);
    if (!all_around && !(std::fabs(bearing) < half_view)) continue;
    // Both draws are made even when the detection is dropped, so that a drop does not shift
    // the noise of the rest of the run.
    const double range = std::sqrt(d2) + o.sigma_range_m * noise->Next();
    const double noisy_bearing = WrapAngle(bearing + o.sigma_bearing_rad * noise->Next());
    if (!(range > 0)) continue;
    sim->observations.push_back({t, range, noisy_bearing, static_cast<int32_t>(id)});
  }
}

}  // namespace

Status BaileySimOptions::Validate() const {
  GROVE_RETURN_IF_ERROR(CheckPositive("speed_mps", speed_mps, 100));
  GROVE_RETURN_IF_ERROR(CheckPositive("wheelbase_m", wheelbase_m, 100));
  if (!(max_steer_rad > 0) || !(max_steer_rad <= kPi / 2)) {
    return RangeError("max_steer_rad", max_steer_rad, "must be > 0 and <= pi/2");
  }
  GROVE_RETURN_IF_ERROR(CheckPositive("max_steer_rate_radps", max_steer_rate_radps, 100));
  GROVE_RETURN_IF_ERROR(CheckPositive("at_waypoint_m", at_waypoint_m, 1e6));
  if (loops < 1 || loops > 1000) {
    return InvalidArgumentError(fmt::format("loops = {}: must be in [1, 1000]", loops));
  }
  GROVE_RETURN_IF_ERROR(CheckPositive("dt_control_s", dt_control_s, 10));
  if (!(dt_observe_s > 0) || !std::isfinite(dt_observe_s)) {
    return RangeError("dt_observe_s", dt_observe_s, "must be > 0 and finite");
  }
  const double ratio = dt_observe_s / dt_control_s;
  const double steps = std::round(ratio);
  if (!(steps >= 1 && steps <= 1e6) || !(std::fabs(ratio - steps) <= 1e-9 * steps)) {
    return RangeError("dt_observe_s", dt_observe_s,
                      fmt::format("must be a whole multiple n of dt_control_s = {} with 1 <= n "
                                  "<= 1e6 (it is {:.6g} times dt_control_s)",
                                  dt_control_s, ratio));
  }
  GROVE_RETURN_IF_ERROR(CheckPositive("max_range_m", max_range_m, 1e6));
  if (!(field_of_view_rad > 0) || !(field_of_view_rad <= 2 * kPi)) {
    return RangeError("field_of_view_rad", field_of_view_rad, "must be > 0 and <= 2 pi");
  }
  GROVE_RETURN_IF_ERROR(CheckSigma("sigma_speed_mps", sigma_speed_mps, 100, "100"));
  GROVE_RETURN_IF_ERROR(CheckSigma("sigma_steer_rad", sigma_steer_rad, kPi, "pi"));
  GROVE_RETURN_IF_ERROR(CheckSigma("sigma_range_m", sigma_range_m, 1e4, "1e4"));
  GROVE_RETURN_IF_ERROR(CheckSigma("sigma_bearing_rad", sigma_bearing_rad, kPi, "pi"));
  if (!(std::fabs(start_x_m) <= kBaileyMaxCoordinateM)) {
    return RangeError("start_x_m", start_x_m, "must be within +-1e9");
  }
  if (!(std::fabs(start_y_m) <= kBaileyMaxCoordinateM)) {
    return RangeError("start_y_m", start_y_m, "must be within +-1e9");
  }
  if (!(start_heading_rad > -kPi) || !(start_heading_rad <= kPi)) {
    return RangeError("start_heading_rad", start_heading_rad, "must be in (-pi, pi]");
  }
  if (max_steps < 1 || max_steps > 100'000'000) {
    return InvalidArgumentError(fmt::format("max_steps = {}: must be in [1, 1e8]", max_steps));
  }
  return Status::Ok();
}

BaileySimOptions WebmapPreset() { return BaileySimOptions(); }

BaileySimOptions Simulation1Preset() {
  BaileySimOptions o;
  // "vehicle speed of 3 m/s, wheelbase of 4 m, and control frequency of 40 Hz".
  o.speed_mps = 3.0;
  o.wheelbase_m = 4.0;
  o.dt_control_s = 1.0 / 40;
  // Eq. (33) is extracted as "Q = [ 1.02 0 0 [10× (π/180)]2 ]": the lone "2" after the bracket
  // can only be a lost superscript, so every trailing 2 is one: Q = diag(1.0^2,
  // (10 pi/180)^2), not a variance of 1.02 (which would give sigma 1.00995).
  o.sigma_speed_mps = 1.0;
  o.sigma_steer_rad = 10 * kDegree;
  // Eq. (34), "R = [ 1.22 0 0 [12× (π/180)]2 ]", read the same way: R = diag(1.2^2,
  // (12 pi/180)^2), not a range variance of 1.22 (sigma 1.1045).
  o.sigma_range_m = 1.2;
  o.sigma_bearing_rad = 12 * kDegree;
  // "maximum laser range of 30 m and vehicle scanning frequency between observations of 5 Hz".
  o.max_range_m = 30.0;
  o.dt_observe_s = 1.0 / 5;
  // Not stated: Bailey's simulator, which the section says it uses, observes the half plane.
  o.field_of_view_rad = kPi;
  return o;
}

BaileySimOptions Simulation2Preset() { return Simulation1Preset(); }

BaileySimOptions Simulation3Preset() {
  BaileySimOptions o;
  // "Vehicle wheelbase was set as 0.26 m with 0.8 m/s vehicle velocity. The control frequency
  // was 40 Hz and sensor frequency was 5 Hz."
  o.wheelbase_m = 0.26;
  o.speed_mps = 0.8;
  o.dt_control_s = 1.0 / 40;
  o.dt_observe_s = 1.0 / 5;
  // "Control noises were 0.4 m/s in velocity and 4° in steering angle".
  o.sigma_speed_mps = 0.4;
  o.sigma_steer_rad = 4 * kDegree;
  // "measurement noises were 0.2 m/s in range and 2° in bearing": a range noise in m/s is a
  // slip of the text; read as 0.2 m.
  o.sigma_range_m = 0.2;
  o.sigma_bearing_rad = 2 * kDegree;
  // "The maximum sensor range was 5 m, with 180° frontal field of view (FOV)."
  o.max_range_m = 5.0;
  o.field_of_view_rad = kPi;
  return o;
}

StatusOr<BaileySimOptions> BaileyPreset(std::string_view name) {
  if (name == "webmap") return WebmapPreset();
  if (name == "sim1") return Simulation1Preset();
  if (name == "sim2") return Simulation2Preset();
  if (name == "sim3") return Simulation3Preset();
  std::string names;
  for (std::string_view n : kBaileyPresetNames)
    names += (names.empty() ? "" : ", ") + std::string(n);
  return InvalidArgumentError(
      fmt::format("preset {}: must be one of {}", QuoteForMessage(name), names));
}

StatusOr<BaileySimulation> SimulateBailey(const BaileyMap& map, const BaileySimOptions& o) {
  GROVE_RETURN_IF_ERROR(o.Validate());
  if (map.waypoints.empty()) return InvalidArgumentError("the map has no waypoint");
  if (map.landmarks.size() > static_cast<size_t>(INT32_MAX)) {
    return InvalidArgumentError("the map has more than 2^31 - 1 landmarks");
  }
  for (const auto* points : {&map.landmarks, &map.waypoints}) {
    for (const BaileyPoint& p : *points) {
      if (!(std::fabs(p.x_m) <= kBaileyMaxCoordinateM) ||
          !(std::fabs(p.y_m) <= kBaileyMaxCoordinateM)) {
        return InvalidArgumentError(
            fmt::format("the map has a {} at ({}, {}): coordinates must be within +-1e9 m",
                        points == &map.landmarks ? "landmark" : "waypoint", p.x_m, p.y_m));
      }
    }
  }

  // Waypoints that all lie within reach of the start would end the run before its first step.
  const double at_waypoint2 = o.at_waypoint_m * o.at_waypoint_m;
  const bool drives = std::any_of(map.waypoints.begin(), map.waypoints.end(), [&](const auto& p) {
    const double dx = p.x_m - o.start_x_m;
    const double dy = p.y_m - o.start_y_m;
    return dx * dx + dy * dy >= at_waypoint2;
  });
  if (!drives) {
    return InvalidArgumentError(fmt::format(
        "wp: every waypoint lies within at_waypoint_m = {} m of the start ({}, {}), so the "
        "vehicle would not move: the path needs a waypoint farther from the start",
        o.at_waypoint_m, o.start_x_m, o.start_y_m));
  }

  const int64_t observe_every = std::llround(o.dt_observe_s / o.dt_control_s);
  const double max_delta = o.max_steer_rate_radps * o.dt_control_s;
  const auto n_waypoints = static_cast<int32_t>(map.waypoints.size());
  NormalSource control_noise(o.seed, kControlNoise);
  NormalSource observation_noise(o.seed, kObservationNoise);

  BaileySimulation sim;
  sim.landmarks = map.landmarks;
  BaileyPose pose{0, o.start_x_m, o.start_y_m, o.start_heading_rad};
  sim.truth.push_back(pose);
  double steer = 0;  // Bailey's G = 0 at the start
  int32_t target = 0;
  int32_t loop = 0;
  int64_t k = 0;
  for (;;) {
    const BaileyPoint& goal = map.waypoints[static_cast<size_t>(target)];
    const double gx = goal.x_m - pose.x_m;
    const double gy = goal.y_m - pose.y_m;
    if (gx * gx + gy * gy < at_waypoint2) {
      sim.visits.push_back({k, target, loop});
      if (++target == n_waypoints) {
        target = 0;
        if (++loop == o.loops) break;
      }
      continue;  // steer towards the new target from the same pose, in the same step
    }
    if (k == o.max_steps) {
      return InvalidArgumentError(fmt::format(
          "the vehicle did not reach waypoint {} ({}, {}) of loop {} within max_steps = {} "
          "control steps: a waypoint nearer the path than the turning radius wheelbase_m / "
          "sin(max_steer_rad) = {:.3g} m may be circled for ever",
          target, goal.x_m, goal.y_m, loop + 1, o.max_steps,
          o.wheelbase_m / std::sin(o.max_steer_rad)));
    }

    // compute_steering: turn towards the target, rate- then angle-limited.
    const double wanted = WrapAngle(std::atan2(gy, gx) - pose.heading_rad - steer);
    steer = std::clamp(steer + std::clamp(wanted, -max_delta, max_delta), -o.max_steer_rad,
                       o.max_steer_rad);

    const double t = static_cast<double>(k) * o.dt_control_s;
    const double t_next = static_cast<double>(k + 1) * o.dt_control_s;
    const double dt = t_next - t;
    sim.true_controls.push_back({t, o.speed_mps, steer});
    const double noisy_speed = o.speed_mps + o.sigma_speed_mps * control_noise.Next();
    const double noisy_steer = steer + o.sigma_steer_rad * control_noise.Next();
    sim.controls.push_back({t, noisy_speed, noisy_steer});

    // predict_true: one Euler step, heading from before the step.
    const double step = o.speed_mps * dt;
    pose.t_s = t_next;
    pose.x_m += step * std::cos(steer + pose.heading_rad);
    pose.y_m += step * std::sin(steer + pose.heading_rad);
    pose.heading_rad = WrapAngle(pose.heading_rad + step * std::sin(steer) / o.wheelbase_m);
    sim.truth.push_back(pose);
    ++k;

    if (k % observe_every == 0) {
      sim.scan_times_s.push_back(t_next);
      AppendObservations(map, o, t_next, pose, &observation_noise, &sim);
    }
  }
  // The stop: holds for ever, moves nothing.
  const BaileyControl stop{sim.truth.back().t_s, 0, steer};
  sim.true_controls.push_back(stop);
  sim.controls.push_back(stop);
  return sim;
}

std::string BaileyControlsCsv(const BaileySimulation& sim) {
  std::string out = "t,v,steer\n";
  auto it = std::back_inserter(out);
  for (const BaileyControl& c : sim.controls) {
    fmt::format_to(it, "{},{},{}\n", c.t_s, c.speed_mps, c.steer_rad);
  }
  return out;
}

std::string BaileyObservationsCsv(const BaileySimulation& sim) {
  std::string out = "t,range,bearing,id\n";
  auto it = std::back_inserter(out);
  for (const BaileyObservation& z : sim.observations) {
    fmt::format_to(it, "{},{},{},{}\n", z.t_s, z.range_m, z.bearing_rad, z.id);
  }
  return out;
}

std::string BaileyTruthCsv(const BaileySimulation& sim) {
  std::string out = "t,x,y,heading\n";
  auto it = std::back_inserter(out);
  for (const BaileyPose& p : sim.truth) {
    fmt::format_to(it, "{},{},{},{}\n", p.t_s, p.x_m, p.y_m, p.heading_rad);
  }
  return out;
}

std::string BaileyLandmarksCsv(const BaileySimulation& sim) {
  std::string out = "id,x,y\n";
  auto it = std::back_inserter(out);
  for (size_t id = 0; id < sim.landmarks.size(); ++id) {
    fmt::format_to(it, "{},{},{}\n", id, sim.landmarks[id].x_m, sim.landmarks[id].y_m);
  }
  return out;
}

int FastSlamSimulateCommand(const std::string& map_path, const std::string& preset,
                            const std::string& out_dir, uint64_t seed) {
  if (out_dir.empty()) return Fail(kExitUsage, "--out: the path is empty");
  StatusOr<BaileySimOptions> options = BaileyPreset(preset.empty() ? "webmap" : preset);
  if (!options.ok()) return Fail(kExitUsage, options.status().message());
  options->seed = seed;
  if (Status s = options->Validate(); !s.ok()) return Fail(kExitUsage, s.message());

  const std::string map_name = map_path.empty() ? EmbeddedBaileyWebmapName() : map_path;
  StatusOr<BaileyMap> map =
      map_path.empty() ? ParseBaileyMap(map_name, EmbeddedBaileyWebmap()) : ReadBaileyMap(map_path);
  if (!map.ok()) return Fail(kExitInput, map.status().message());
  StatusOr<BaileySimulation> sim = SimulateBailey(*map, *options);
  if (!sim.ok()) return Fail(kExitInput, fmt::format("{}: {}", map_name, sim.status().message()));

  Status s = EnsureDirectory(out_dir);
  if (s.ok()) s = WriteFileAtomically(out_dir + "/controls.csv", BaileyControlsCsv(*sim));
  if (s.ok()) s = WriteFileAtomically(out_dir + "/observations.csv", BaileyObservationsCsv(*sim));
  if (s.ok()) s = WriteFileAtomically(out_dir + "/truth.csv", BaileyTruthCsv(*sim));
  if (s.ok()) s = WriteFileAtomically(out_dir + "/landmarks_truth.csv", BaileyLandmarksCsv(*sim));
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::fprintf(stderr,
               "wrote %s/{controls,observations,truth,landmarks_truth}.csv: %lld control steps, "
               "%zu scans, %zu observations of %zu landmarks, %d loops of %zu waypoints\n",
               out_dir.c_str(), static_cast<long long>(sim->control_steps()),
               sim->scan_times_s.size(), sim->observations.size(), sim->landmarks.size(),
               options->loops, map->waypoints.size());
  return kExitOk;
}

Status FeedSimulation(const BaileySimulation& sim, FastSlam* slam, size_t controls,
                      FeedTimes* times, const std::function<Status(double t_s)>& after_scan) {
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  controls = std::min(controls, sim.controls.size());
  size_t z = 0;
  std::vector<LandmarkObservation> scan;
  for (size_t k = 0; k < controls; ++k) {
    const BaileyControl& c = sim.controls[k];
    auto t0 = Clock::now();
    Status s = slam->Control(c.t_s, c.speed_mps, c.steer_rad);
    if (times != nullptr) times->control_s += seconds(Clock::now() - t0);
    if (!s.ok()) return Status(s.code(), fmt::format("control {}: {}", k, s.message()));
    const double upper = k + 1 < sim.controls.size() ? sim.controls[k + 1].t_s : INFINITY;
    while (z < sim.observations.size() && sim.observations[z].t_s < c.t_s) ++z;
    while (z < sim.observations.size() && sim.observations[z].t_s < upper) {
      const double t = sim.observations[z].t_s;
      scan.clear();
      for (; z < sim.observations.size() && sim.observations[z].t_s == t; ++z) {
        const BaileyObservation& o = sim.observations[z];
        scan.push_back({o.range_m, o.bearing_rad, o.id});
      }
      t0 = Clock::now();
      s = slam->Scan(t, scan);
      if (times != nullptr) times->scan_s += seconds(Clock::now() - t0);
      if (!s.ok()) return Status(s.code(), fmt::format("scan at t = {}: {}", t, s.message()));
      if (after_scan) GROVE_RETURN_IF_ERROR(after_scan(t));
    }
  }
  return Status::Ok();
}

}  // namespace grove::tools
