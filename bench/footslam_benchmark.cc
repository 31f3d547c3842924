// End-to-end FootSLAM steps through the public API, on the paper-scale walk (a simulated 13-minute
// open-area walk), parameterised by map kind, degree, alphabet, particles and threads.
// Items are particle-steps; counters give ns per particle-step and the live map size at the end.
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "grove/footslam.h"
#include "tools/sim/walk_simulator.h"

namespace grove {
namespace {

const std::vector<tools::StepRecord>& PaperWalk() {
  static const std::vector<tools::StepRecord> steps = *tools::PaperWalk(13);
  return steps;
}

void BM_FootSlamStep(benchmark::State& state) {
  FootSlamConfig config;
  config.map = state.range(0) == 0 ? FootSlamMapKind::kHTree : FootSlamMapKind::kNaive;
  config.degree = static_cast<int>(state.range(1));
  config.grid_size = config.degree == 64 ? 512 : 256;
  config.alphabet = static_cast<int>(state.range(2));
  config.particles = state.range(3);
  config.threads = static_cast<int>(state.range(4));
  const auto& walk = PaperWalk();
  std::unique_ptr<FootSlam> slam;
  size_t next = walk.size();
  for (auto _ : state) {
    if (next == walk.size()) {  // start (again) at the beginning of the walk, untimed
      state.PauseTiming();
      slam.reset();
      slam = std::move(FootSlam::Create(config).value());
      next = 0;
      state.ResumeTiming();
    }
    const tools::StepRecord& s = walk[next++];
    if (!slam->Step(s.t_s, s.dx_m, s.dy_m).ok()) {
      state.SkipWithError("step failed");
      break;
    }
  }
  state.SetItemsProcessed(state.iterations() * config.particles);
  // Seconds per particle-step (printed with an SI prefix, e.g. 350n).
  state.counters["time_per_particle_step"] = benchmark::Counter(
      static_cast<double>(config.particles),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  if (slam) {
    FootSlamSummary summary = slam->Summary();
    state.counters["live_map_nodes"] = static_cast<double>(summary.map_memory.live_nodes);
    state.counters["live_map_MiB"] = summary.map_memory.live_bytes / 1048576.0;
    state.counters["walk_step"] = static_cast<double>(next);
  }
}

BENCHMARK(BM_FootSlamStep)
    ->ArgNames({"naive", "degree", "alphabet", "particles", "threads"})
    ->Args({0, 16, 5, 30000, 1})
    ->Args({0, 16, 5, 30000, 2})
    ->Args({0, 16, 0, 30000, 2})
    ->Args({0, 4, 5, 30000, 2})
    ->Args({0, 64, 5, 30000, 2})
    ->Args({0, 16, 5, 1000, 2})
    ->Args({0, 16, 5, 1000000, 2})
    ->Args({1, 16, 0, 30000, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace grove
