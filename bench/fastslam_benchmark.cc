// Landmark FastSLAM's maps at scale (white-box, on FastSlamModel): the cost of a scan's update
// per particle and observation against the number of landmarks, for each tree degree, and the
// memory of many particles sharing a big map.
//
// Every particle starts with the same map (particle 0's, shared after a resampling, as after a
// common history). Each iteration is one scan: a resampling that makes every odd particle a
// copy of its even neighbour (so half the updates meet shared paths and copy them), then
// FastSLAM 2.0's weighting and draw for every particle with 2 observations of landmarks drawn
// uniformly from the whole map.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <random>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/fastslam_model.h"

namespace grove {
namespace {

using fastslam::FastSlamModel;
using fastslam::ScanStep;

// Landmark `id` on a 10 m grid around the origin, `side` landmarks a row.
LandmarkObservation Sighting(int64_t id, int64_t side) {
  const double x = static_cast<double>(id % side) * 10.0 - static_cast<double>(side) * 5.0 + 3.0;
  const double y = static_cast<double>(id / side) * 10.0 - static_cast<double>(side) * 5.0 + 7.0;
  return {std::hypot(x, y), std::atan2(y, x), id};
}

template <int kLog2>
struct MapFixture {
  FastSlamConfig config;
  WorkerPool workers{1};
  std::unique_ptr<FastSlamModel<kLog2>> model;
  std::vector<double> log_w;
  std::vector<uint32_t> pairs;
  int64_t landmarks, side;
  uint64_t step = 0;

  MapFixture(int64_t landmarks_, int64_t particles) : landmarks(landmarks_) {
    config.particles = particles;
    config.threads = 1;
    model = std::make_unique<FastSlamModel<kLog2>>(config, 1);
    log_w.assign(static_cast<size_t>(particles), 0.0);
    side = static_cast<int64_t>(std::ceil(std::sqrt(static_cast<double>(landmarks))));
    // Particle 0 maps every landmark, then every particle takes its map.
    std::vector<LandmarkObservation> all;
    for (int64_t id = 0; id < landmarks; ++id) all.push_back(Sighting(id, side));
    const ScanStep fill{all};
    if (!model->Advance(fill, step, 0, 1, 0, log_w.data()).ok() ||
        !model->Complete(fill, step, 0, 1, 0).ok()) {
      std::abort();
    }
    ++step;
    std::vector<uint32_t> zeros(static_cast<size_t>(particles), 0);
    model->Gather(zeros, workers);
    model->ReleaseDead(workers);
    for (uint32_t k = 0; k < particles; ++k) pairs.push_back(k & ~1u);
  }

  // One scan of 2 observations of random landmarks, after a resampling into pairs.
  void Scan(std::mt19937_64& rng) {
    model->Gather(pairs, workers);
    model->ReleaseDead(workers);
    const LandmarkObservation z[2] = {Sighting(static_cast<int64_t>(rng() % landmarks), side),
                                      Sighting(static_cast<int64_t>(rng() % landmarks), side)};
    const ScanStep scan{z};
    const size_t n = log_w.size();
    if (!model->Advance(scan, step, 0, n, 0, log_w.data()).ok() ||
        !model->Complete(scan, step, 0, n, 0).ok()) {
      std::abort();
    }
    ++step;
  }
};

template <int kLog2>
void BM_ScanUpdate(benchmark::State& state) {
  const int64_t particles = 1000;
  MapFixture<kLog2> f(state.range(0), particles);
  std::mt19937_64 rng(1);
  for (auto _ : state) f.Scan(rng);
  // Items: particle-observations; the time per item is the cost of one observation's update.
  state.SetItemsProcessed(state.iterations() * particles * 2);
  state.counters["landmarks"] = static_cast<double>(state.range(0));
  state.counters["tree_height"] = FastSlamModel<kLog2>::Trie::HeightFor(state.range(0) - 1);
  state.counters["map_MiB"] = f.model->map_memory().live_bytes / 1048576.0;
}

void MapSizes(benchmark::internal::Benchmark* b) {
  for (int64_t n : {35, 140, 560, 2240, 8960, 20160}) b->Arg(n);
}
BENCHMARK(BM_ScanUpdate<1>)->Apply(MapSizes)->Name("BM_ScanUpdate/degree:2");
BENCHMARK(BM_ScanUpdate<2>)->Apply(MapSizes)->Name("BM_ScanUpdate/degree:4");
BENCHMARK(BM_ScanUpdate<3>)->Apply(MapSizes)->Name("BM_ScanUpdate/degree:8");
BENCHMARK(BM_ScanUpdate<4>)->Apply(MapSizes)->Name("BM_ScanUpdate/degree:16");

// 10,000 particles on a 20,000-landmark map: the live map bytes after 100 scans against a deep
// copy per particle. Run it alone (--benchmark_filter=BM_MapMemory) for a peak RSS of its own.
void BM_MapMemory(benchmark::State& state) {
  const int64_t particles = state.range(0), landmarks = state.range(1);
  double live = 0;
  for (auto _ : state) {
    MapFixture<3> f(landmarks, particles);
    std::mt19937_64 rng(1);
    for (int k = 0; k < 100; ++k) f.Scan(rng);
    live = static_cast<double>(f.model->map_memory().live_bytes);
  }
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  state.counters["map_live_MiB"] = live / 1048576.0;
  state.counters["deep_copy_MiB"] =
      static_cast<double>(particles) * landmarks * sizeof(fastslam::Landmark) / 1048576.0;
  state.counters["peak_rss_MiB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
}
BENCHMARK(BM_MapMemory)->Args({10000, 20000})->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace grove
