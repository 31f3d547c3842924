// The cost of the embedding layers: the bundled walk fed through the C++ facade (a loop of
// Step()) and through the C API (one grove_footslam_steps() call over arrays), each iteration
// a whole run: create, 872 steps, read the cumulative map, destroy. The Python module's share
// is measured by bench/embedding_python.py against the C API in one process.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "grove/c_api.h"
#include "grove/footslam.h"
#include "tools/io/step_reader.h"

namespace grove {
namespace {

struct Walk {
  std::vector<double> t, dx, dy;
};

const Walk& BundledWalk() {
  static const Walk walk = [] {
    Walk w;
    const StatusOr<std::vector<tools::StepRecord>> steps = tools::ReadAllSteps(GROVE_WALK_CSV);
    for (const tools::StepRecord& s : steps.value()) {
      w.t.push_back(s.t_s);
      w.dx.push_back(s.dx_m);
      w.dy.push_back(s.dy_m);
    }
    return w;
  }();
  return walk;
}

void SetCounters(benchmark::State& state, int64_t particles) {
  const double particle_steps = static_cast<double>(BundledWalk().t.size()) * particles;
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * particle_steps));
  state.counters["time_per_particle_step"] = benchmark::Counter(
      particle_steps, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_WalkFacade(benchmark::State& state) {
  FootSlamConfig config;
  config.particles = state.range(0);
  config.threads = static_cast<int>(state.range(1));
  const Walk& walk = BundledWalk();
  for (auto _ : state) {
    std::unique_ptr<FootSlam> slam = std::move(FootSlam::Create(config).value());
    for (size_t i = 0; i < walk.t.size(); ++i) {
      if (!slam->Step(walk.t[i], walk.dx[i], walk.dy[i]).ok()) state.SkipWithError("step failed");
    }
    StatusOr<std::vector<HexCounts>> map = slam->CumulativeMap();
    benchmark::DoNotOptimize(map);
  }
  SetCounters(state, config.particles);
}

void BM_WalkCApi(benchmark::State& state) {
  grove_footslam_config config;
  grove_footslam_config_default(&config);
  config.particles = state.range(0);
  config.threads = static_cast<int>(state.range(1));
  const Walk& walk = BundledWalk();
  std::vector<grove_hex_counts> map;
  for (auto _ : state) {
    grove_footslam* slam = nullptr;
    if (grove_footslam_create(&config, &slam, nullptr, 0) != GROVE_OK) {
      state.SkipWithError("create failed");
      break;
    }
    if (grove_footslam_steps(slam, walk.t.data(), walk.dx.data(), walk.dy.data(), walk.t.size(),
                             nullptr) != GROVE_OK) {
      state.SkipWithError("steps failed");
    }
    size_t count = 0;
    if (grove_footslam_cumulative_map(slam, nullptr, 0, &count) == GROVE_OK) {
      map.resize(count);
      if (grove_footslam_cumulative_map(slam, map.data(), map.size(), &count) != GROVE_OK) {
        state.SkipWithError("map failed");
      }
    }
    benchmark::DoNotOptimize(map.data());
    grove_footslam_destroy(slam);
  }
  SetCounters(state, config.particles);
}

// Particles, threads. Run with --benchmark_repetitions and --benchmark_enable_random_interleaving
// so that the two alternate on a noisy machine.
BENCHMARK(BM_WalkFacade)
    ->ArgNames({"particles", "threads"})
    ->Args({3000, 1})
    ->Args({30000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_WalkCApi)
    ->ArgNames({"particles", "threads"})
    ->Args({3000, 1})
    ->Args({30000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace grove
