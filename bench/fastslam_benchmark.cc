// Landmark FastSLAM's maps at scale (white-box, on FastSlamModel): the cost of a scan's update
// per particle and observation against the number of landmarks, for each tree degree, the cost
// of unknown association against the map's size, and the memory of many particles sharing a big
// map.
//
// Every particle starts with the same map (particle 0's, shared after a resampling, as after a
// common history). Each iteration is one scan: a resampling that makes every odd particle a
// copy of its even neighbour (so half the updates meet shared paths and copy them), then
// FastSLAM 2.0's weighting and draw for every particle with 2 observations of landmarks drawn
// uniformly from the whole map.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/fastslam_model.h"
#include "engine/filter/filter_model.h"
#include "tools/sim/fastslam_simulator.h"

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
    GatherGeneration(*model, zeros, 64, workers);
    model->ReleaseDead(workers);
    for (uint32_t k = 0; k < particles; ++k) pairs.push_back(k & ~1u);
  }

  // One scan of 2 observations of random landmarks, after a resampling into pairs.
  void Scan(std::mt19937_64& rng) {
    GatherGeneration(*model, pairs, 64, workers);
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

// Unknown association against the map's size: the replicated webmap (its 35 landmarks in k x k
// tiles 300 m apart, 35 ... 20,160 landmarks, every particle sharing particle 0's map), 1,000
// particles, the vehicle at the origin of the central tile. Each iteration is a resampling into
// pairs, then FastSLAM 2.0's weighting, draw and updates with a scan that detects every landmark
// in view (so the existence evidence leaves the map as it is). Items: particle-detections.
struct UnknownFixture {
  FastSlamConfig config;
  WorkerPool workers{1};
  std::unique_ptr<fastslam::CellKeyedModel> model;  // unknown association's, as FastSlam's
  std::vector<double> log_w;
  std::vector<uint32_t> pairs;
  std::vector<LandmarkObservation> scan;
  uint64_t step = 0;

  UnknownFixture(int64_t tiles_per_side, int64_t particles) {
    config.particles = particles;
    config.threads = 1;
    config.association = FastSlamAssociation::kMaximumLikelihood;
    model = std::make_unique<fastslam::CellKeyedModel>(config, 1);
    log_w.assign(static_cast<size_t>(particles), 0.0);
    StatusOr<tools::BaileyMap> map = tools::ParseBaileyMap("webmap", tools::EmbeddedBaileyWebmap());
    if (!map.ok()) std::abort();
    const fastslam::SensorNoise noise{config.sigma_range_m, config.sigma_bearing_rad};
    const fastslam::VehiclePose origin{0, 0, 0};
    for (const tools::BaileyPoint& p : map->landmarks) {
      const fastslam::RangeBearing z = fastslam::Observe(origin, p.x_m, p.y_m);
      if (z.range_m <= config.sensor_range_m &&
          std::fabs(z.bearing_rad) <= 0.5 * std::numbers::pi) {
        scan.push_back({z.range_m, z.bearing_rad, -1});
      }
    }
    if (scan.empty()) std::abort();
    model->NoteScan(ScanStep{scan});
    const int64_t lo = -tiles_per_side / 2;
    for (int64_t tx = lo; tx < lo + tiles_per_side; ++tx) {
      for (int64_t ty = lo; ty < lo + tiles_per_side; ++ty) {
        for (const tools::BaileyPoint& p : map->landmarks) {
          // As first seen from 10 m away: the covariance of a new landmark at that range.
          const double x = p.x_m + 300.0 * static_cast<double>(tx);
          const double y = p.y_m + 300.0 * static_cast<double>(ty);
          const fastslam::VehiclePose from{x - 10, y, 0};
          const fastslam::Landmark l = fastslam::InitLandmark(from, {10, 0}, noise);
          if (!model->InsertLandmark(0, l, 0).ok()) std::abort();
        }
      }
    }
    std::vector<uint32_t> zeros(static_cast<size_t>(particles), 0);
    GatherGeneration(*model, zeros, 64, workers);
    model->ReleaseDead(workers);
    for (uint32_t k = 0; k < particles; ++k) pairs.push_back(k & ~1u);
  }

  void Scan() {
    GatherGeneration(*model, pairs, 64, workers);
    model->ReleaseDead(workers);
    const ScanStep s{scan};
    const size_t n = log_w.size();
    if (!model->Advance(s, step, 0, n, 0, log_w.data()).ok() ||
        !model->Complete(s, step, 0, n, 0).ok()) {
      std::abort();
    }
    ++step;
  }
};

void BM_UnknownAssociation(benchmark::State& state) {
  const int64_t particles = 1000;
  UnknownFixture f(state.range(0), particles);
  for (auto _ : state) f.Scan();
  state.SetItemsProcessed(state.iterations() * particles * static_cast<int64_t>(f.scan.size()));
  state.counters["landmarks"] = static_cast<double>(35 * state.range(0) * state.range(0));
  state.counters["detections"] = static_cast<double>(f.scan.size());
  state.counters["tree_height"] = fastslam::CellKeyedModel::Trie::Height(f.model->map(0));
  state.counters["map_MiB"] = f.model->map_memory().live_bytes / 1048576.0;
}
BENCHMARK(BM_UnknownAssociation)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->Arg(24);

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
