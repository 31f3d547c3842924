// The foot IMU front end (grove/foot_imu.h) on a simulated 10-minute walk at 200 Hz with the
// default MEMS errors, per detector and with zero-angular-rate updates on or off. Items are
// samples; real_time_factor is the recording's length over the time taken (the target: at least
// 1,000 on one core).
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "grove/foot_imu.h"
#include "tools/sim/foot_imu_simulator.h"
#include "tools/sim/walk_simulator.h"

namespace grove {
namespace {

constexpr double kRateHz = 200;

const std::vector<ImuSample>& Recording() {
  static const std::vector<ImuSample> samples = [] {
    tools::SimulatorOptions walk_options;
    walk_options.minutes = 10;
    walk_options.seed = 1;
    tools::FootImuSimOptions options;
    options.rate_hz = kRateHz;
    options.seed = 1;
    return tools::SimulateFootImu(*tools::SimulateWalk(walk_options), options)->samples;
  }();
  return samples;
}

void BM_FootImuRecording(benchmark::State& state) {
  FootImuConfig config;
  config.detector = static_cast<ZeroVelocityDetector>(state.range(0));
  if (state.range(1) == 0) config.zaru_sigma_radps = 0;
  const std::vector<ImuSample>& samples = Recording();
  int64_t steps = 0;
  for (auto _ : state) {
    std::unique_ptr<FootImu> imu = std::move(FootImu::Create(config).value());
    for (const ImuSample& s : samples) {
      if (!imu->AddSample(s).ok()) {
        state.SkipWithError("a sample was refused");
        return;
      }
    }
    if (!imu->Finish().ok()) {
      state.SkipWithError("Finish failed");
      return;
    }
    steps = static_cast<int64_t>(imu->TakeSteps().size());
  }
  const double n = static_cast<double>(samples.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(samples.size()));
  state.counters["real_time_factor"] =
      benchmark::Counter(n / kRateHz, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["steps"] = static_cast<double>(steps);
}

BENCHMARK(BM_FootImuRecording)
    ->ArgNames({"detector", "zaru"})
    ->Args({static_cast<int>(ZeroVelocityDetector::kShoe), 1})
    ->Args({static_cast<int>(ZeroVelocityDetector::kShoe), 0})
    ->Args({static_cast<int>(ZeroVelocityDetector::kAre), 1})
    ->Args({static_cast<int>(ZeroVelocityDetector::kMv), 1})
    ->Args({static_cast<int>(ZeroVelocityDetector::kMag), 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace grove
