#include "tools/sim/tracking_simulator.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <numbers>

#include "tools/io/atomic_file.h"
#include "tools/io/filter_outputs.h"
#include "tools/run/run_loop.h"
#include "tools/sim/normal_source.h"

namespace grove::tools {
namespace {

constexpr double kOmega = 2 * std::numbers::pi / 120;
constexpr double kBeacons[4][2] = {{-50, -50}, {50, -50}, {50, 50}, {-50, 50}};

// The truth at t: position, and the direction of the velocity as the heading.
StampedPose TruthAt(double t) {
  const double vx = 30 * kOmega * std::cos(kOmega * t);
  const double vy = 40 * kOmega * std::cos(2 * kOmega * t);
  return {t, Pose2{30 * std::sin(kOmega * t), 20 * std::sin(2 * kOmega * t), std::atan2(vy, vx)}};
}

}  // namespace

Interval TrackingSecondsRange() { return Interval::LeftOpen(0, 86400); }
Interval TrackingRateRange() { return Interval::LeftOpen(0, 100); }
Interval TrackingRangeSigmaRange() { return Interval::Closed(0, 100); }

TrackingSimulation SimulateTracking(const TrackingSimOptions& o) {
  TrackingSimulation sim;
  sim.beacons_csv = "id,x,y\n";
  for (int b = 0; b < 4; ++b) {
    fmt::format_to(std::back_inserter(sim.beacons_csv), "{},{},{}\n", b, kBeacons[b][0],
                   kBeacons[b][1]);
  }
  sim.measurements_csv = "t,beacon,range\n";
  NormalSource noise(o.seed, 1);
  sim.truth.push_back(TruthAt(0));
  const auto updates = static_cast<int64_t>(std::floor(o.seconds * o.rate_hz));
  for (int64_t k = 1; k <= updates; ++k) {
    const StampedPose p = TruthAt(static_cast<double>(k) / o.rate_hz);
    sim.truth.push_back(p);
    for (int b = 0; b < 4; ++b) {
      const double d = std::hypot(p.pose.x_m - kBeacons[b][0], p.pose.y_m - kBeacons[b][1]);
      fmt::format_to(std::back_inserter(sim.measurements_csv), "{:.6f},{},{:.6f}\n", p.t_s, b,
                     std::max(0.0, d + o.range_sigma_m * noise.Next()));
    }
  }
  return sim;
}

int TrackingSimulateCommand(const TrackingSimOptions& options, const std::string& out_dir) {
  if (out_dir.empty()) return Fail(kExitUsage, "--out: the path is empty");
  const TrackingSimulation sim = SimulateTracking(options);
  if (sim.truth.size() < 2) {
    return Fail(kExitUsage, fmt::format("--seconds = {}: shorter than one update at --rate {}",
                                        options.seconds, options.rate_hz));
  }
  Status s = EnsureDirectory(out_dir);
  if (s.ok()) s = WriteFileAtomically(out_dir + "/beacons.csv", sim.beacons_csv);
  if (s.ok()) s = WriteFileAtomically(out_dir + "/measurements.csv", sim.measurements_csv);
  if (s.ok()) s = WriteFileAtomically(out_dir + "/truth.csv", TrajectoryCsv(sim.truth));
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::fprintf(stderr, "wrote %s/{beacons,measurements,truth}.csv: %zu updates of 4 ranges\n",
               out_dir.c_str(), sim.truth.size() - 1);
  return kExitOk;
}

}  // namespace grove::tools
