// White-box tests of the FootSLAM particle: weights by hand, maps against the odometry.
#include "engine/footslam/footslam_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/htree_map.h"
#include "engine/footslam/naive_map.h"
#include "grove/footslam.h"

namespace grove::footslam {
namespace {

FootSlamConfig ZeroNoise() {
  FootSlamConfig c;
  c.particles = 1;
  c.heading_drift_sigma_rad = 0;
  c.heading_sigma_rad = 0;
  c.step_length_sigma_m = 0;
  c.threads = 1;
  return c;
}

// Back and forth between the centres of hexagons (0,0) and (1,0): each step crosses one edge.
TEST(FootSlamModelTest, WeightsMatchHandComputedValues) {
  for (FootSlamWeighting weighting : {FootSlamWeighting::kPaper, FootSlamWeighting::kPriorRatio}) {
    SCOPED_TRACE(FootSlamWeightingName(weighting));
    FootSlamConfig config = ZeroNoise();
    config.weighting = weighting;
    config.prior_count = 0.5;
    HexGrid grid(config.hex_radius_m);
    HTreeLayout layout = *HTreeLayout::Create(64, 16);
    HTreeMap<4> map(layout, 1, 1, nullptr);
    FootSlamModel<HTreeMap<4>> model(config, &grid, &layout, &map, 1);
    ASSERT_TRUE(model.Init());
    const double a = 0.5;
    const double bias = weighting == FootSlamWeighting::kPriorRatio ? std::log(6.0) : 0.0;
    const double d = std::sqrt(3.0) * config.hex_radius_m;  // centre to centre
    // Step: +x (0,0)->(1,0) across e0; -x back across e3 of (1,0); +x again across e0.
    struct Expect {
      double dx;
      double factor;
    };
    const Expect steps[] = {
        {d, a / (6 * a)},             // (0,0) empty
        {-d, a / (6 * a)},            // (1,0) empty
        {d, (1 + a) / (1 + 6 * a)},   // (0,0): c0 = 1, total 1
        {-d, (1 + a) / (1 + 6 * a)},  // (1,0): c3 = 1, total 1
        {d, (2 + a) / (2 + 6 * a)},
        {0.2, 1.0},  // stays inside (1,0): no crossing, no weight
    };
    for (size_t k = 0; k < std::size(steps); ++k) {
      double lw = 0;
      ASSERT_TRUE(model.Advance(StepInput{steps[k].dx, 0}, k, 0, 1, 0, &lw).ok());
      double expected = steps[k].factor == 1.0 ? 0.0 : std::log(steps[k].factor) + bias;
      EXPECT_NEAR(lw, expected, 1e-12) << "step " << k;
    }
  }
}

// A prior that holds whole counts weighs a crossing bit for bit as a map holding the sum: a
// particle that walks W1 then W2 gets the same weight on every step of W2 as one that starts
// where W1 ended, with W1's map as its prior (the exactness that storing and restoring an area
// relies on).
TEST(FootSlamModelTest, AWholeCountPriorWeighsAsTheMapItCameFrom) {
  for (FootSlamWeighting weighting : {FootSlamWeighting::kPaper, FootSlamWeighting::kPriorRatio}) {
    SCOPED_TRACE(FootSlamWeightingName(weighting));
    FootSlamConfig config = ZeroNoise();
    config.weighting = weighting;
    HexGrid grid(config.hex_radius_m);
    HTreeLayout layout = *HTreeLayout::Create(256, 16);
    HTreeMap<4> map(layout, 1, 1, nullptr);
    FootSlamModel<HTreeMap<4>> whole(config, &grid, &layout, &map, 1);
    ASSERT_TRUE(whole.Init());
    std::mt19937_64 rng(5);
    std::normal_distribution<double> turn(0, 0.5);
    std::vector<StepInput> w2;
    double heading = 0, x = 0, y = 0;
    for (int k = 0; k < 600; ++k) {  // W1 (the first 300 steps), then W2, over the same area
      heading += turn(rng);
      // Within 8 m of the start: turn back when heading away beyond it.
      if (std::hypot(x, y) > 8 && std::cos(heading - std::atan2(-y, -x)) < 0) heading += M_PI;
      const StepInput in{0.7 * std::cos(heading), 0.7 * std::sin(heading)};
      x += in.dx_m;
      y += in.dy_m;
      if (k >= 300) w2.push_back(in);
      if (k < 300) {
        double lw = 0;
        Status s = whole.Advance(in, k, 0, 1, 0, &lw);
        ASSERT_TRUE(s.ok()) << s.ToString();
      }
    }
    // W1's map as a prior of whole counts, for a particle that starts where W1 ended.
    FootSlamConfig after = config;
    after.start_x_m = whole.x(0);
    after.start_y_m = whole.y(0);
    HTreeLayout after_layout = *HTreeLayout::Create(256, 16);
    HTreeMap<4> after_map(after_layout, 1, 1, nullptr);
    FootSlamModel<HTreeMap<4>> resumed(after, &grid, &after_layout, &after_map, 1);
    ASSERT_TRUE(resumed.Init());
    PriorMap prior;
    int hexes = 0;
    whole.map().ForEachHex(0, [&](uint64_t key, const Htc& h) {
      const Hex hex = whole.HexOfKey(key);
      uint64_t after_key;
      ASSERT_TRUE(resumed.KeyOf(hex, &after_key));
      PriorHex p{};
      for (int e = 0; e < 6; ++e) {
        p.edge[e] = h.c[e];
        p.total += h.c[e];
      }
      prior.Insert(after_key, p);
      ++hexes;
    });
    ASSERT_GT(hexes, 30);
    resumed.set_prior(&prior);
    int crossed_known = 0;
    for (size_t k = 0; k < w2.size(); ++k) {
      double lw_whole = 0, lw_resumed = 0;
      ASSERT_TRUE(whole.Advance(w2[k], 300 + k, 0, 1, 0, &lw_whole).ok());
      ASSERT_TRUE(resumed.Advance(w2[k], k, 0, 1, 0, &lw_resumed).ok());
      ASSERT_EQ(whole.x(0), resumed.x(0)) << "step " << k;
      ASSERT_EQ(lw_whole, lw_resumed) << "step " << k;
      crossed_known +=
          lw_whole != 0 &&
          lw_whole != std::log(1.0 / 6) +
                          (weighting == FootSlamWeighting::kPriorRatio ? std::log(6.0) : 0.0);
    }
    EXPECT_GT(crossed_known, 100);  // most of W2's crossings meet W1's counts
  }
}

// One particle without noise follows the odometry, so its map must hold exactly the edge
// crossings of the odometry polyline, computed here with the grid alone.
TEST(FootSlamModelTest, ZeroNoiseMapEqualsOdometryTransitions) {
  FootSlamConfig config = ZeroNoise();
  config.grid_size = 256;
  auto slam = FootSlam::Create(config);
  ASSERT_TRUE(slam.ok()) << slam.status().ToString();
  HexGrid grid(config.hex_radius_m);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> turn(0, 0.4);
  std::map<std::pair<int, int>, std::array<double, 6>> expected;
  double x = 0, y = 0, heading = 0;
  Hex hex = grid.HexAt(0, 0);
  for (int k = 0; k < 2000; ++k) {
    heading += turn(rng);
    double len = 0.3 + 0.6 * std::uniform_real_distribution<double>()(rng);
    double dx = len * std::cos(heading), dy = len * std::sin(heading);
    if (std::hypot(x + dx, y + dy) > 30) {  // stay in a 30 m disc: many revisits
      dx = -dx;
      dy = -dy;
      heading += M_PI;
    }
    ASSERT_TRUE((*slam)->Step(k + 1.0, dx, dy).ok());
    hex = grid.Traverse(hex, x, y, x + dx, y + dy, [&](const Crossing& c) {
      expected[{c.from.q, c.from.r}][c.edge] += 1;
    });
    x += dx;
    y += dy;
  }
  std::map<std::pair<int, int>, std::array<double, 6>> got;
  StatusOr<std::vector<HexCounts>> map = (*slam)->HeaviestMap();
  ASSERT_TRUE(map.ok());
  for (const HexCounts& h : *map) {
    for (int e = 0; e < 6; ++e) got[{h.q, h.r}][e] = h.counts[e];
  }
  EXPECT_EQ(got, expected);
  EXPECT_GT(expected.size(), 500u);
  Pose2 pose = (*slam)->HeaviestPose();
  EXPECT_NEAR(pose.x_m, x, 1e-9);
  EXPECT_NEAR(pose.y_m, y, 1e-9);
}

// Copies of a parent that cross the same edges in the same step share one new map (the
// previous particle's, or their own changed in place when they hold every reference to it)
// instead of copying the same path each: the weights, poses and maps stay those of NaiveMap,
// which copies whole tables and shares nothing. Batches as the workers cut them: a particle
// follows only the previous one of its batch. With `with_prior`, a prior map of whole counts on
// half the hexagons near the start, and the prior-ratio weighting.
template <typename Map>
void ExpectFollowersMatchNaive(const Alphabet* alphabet, bool with_prior) {
  FootSlamConfig config;
  config.particles = 64;
  config.threads = 1;
  config.hex_radius_m = 0.5;
  config.step_length_sigma_m = 0.02;  // small noise: many copies cross as their parent does
  config.heading_sigma_rad = 0.02;
  if (with_prior) config.weighting = FootSlamWeighting::kPriorRatio;
  const size_t n = 64;
  HexGrid grid(config.hex_radius_m);
  HTreeLayout layout = *HTreeLayout::Create(256, 16);
  Map shared(layout, 1, n, alphabet);
  NaiveMap naive(layout, 1, n, alphabet);
  FootSlamModel<Map> a(config, &grid, &layout, &shared, 1);
  FootSlamModel<NaiveMap> b(config, &grid, &layout, &naive, 1);
  ASSERT_TRUE(a.Init());
  ASSERT_TRUE(b.Init());
  PriorMap prior;
  if (with_prior) {
    const Hex start = grid.HexAt(config.start_x_m, config.start_y_m);
    for (int dq = -12; dq <= 12; ++dq) {
      for (int dr = -12; dr <= 12; ++dr) {
        uint64_t key;
        if ((dq + dr) % 2 != 0 || !a.KeyOf(Hex{start.q + dq, start.r + dr}, &key)) continue;
        PriorHex p{};
        for (int e = 0; e < 6; ++e) {
          p.edge[e] = (7 * dq + 3 * dr + e + 200) % 4;  // 0 to 3
          p.total += p.edge[e];
        }
        prior.Insert(key, p);
      }
    }
    a.set_prior(&prior);
    b.set_prior(&prior);
  }
  WorkerPool workers(1);
  std::vector<double> lw_a(n), lw_b(n);
  std::vector<uint32_t> parents(n);
  for (size_t i = 0; i < n; ++i) parents[i] = static_cast<uint32_t>(i / 8 * 8);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> turn(0, 0.5);
  double heading = 0, x = 0, y = 0;
  int crossed = 0, followed = 0;  // particle-steps that crossed an edge; of them, shared
  int in_place = 0;  // of those, by a map shared at the start of the step and changed in place
  std::vector<double> lw_before(n);
  std::vector<typename Map::Version> start(n);
  for (uint64_t k = 0; k < 300; ++k) {
    heading += turn(rng);
    if (std::hypot(x, y) > 8 && std::cos(heading - std::atan2(-y, -x)) < 0) heading += M_PI;
    const StepInput in{0.7 * std::cos(heading), 0.7 * std::sin(heading)};
    x += in.dx_m;
    y += in.dy_m;
    lw_before = lw_b;
    for (size_t i = 0; i < n; ++i) start[i] = shared.version(i);
    for (auto [begin, end] : {std::pair<size_t, size_t>{0, 27}, {27, n}}) {
      ASSERT_TRUE(a.Advance(in, k, begin, end, 0, lw_a.data()).ok());
      ASSERT_TRUE(b.Advance(in, k, begin, end, 0, lw_b.data()).ok());
    }
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(lw_a[i], lw_b[i]) << "step " << k << " particle " << i;
      ASSERT_EQ(a.x(i), b.x(i));
      ASSERT_EQ(a.y(i), b.y(i));
      if (lw_b[i] == lw_before[i]) continue;  // a crossing's weight is never 0
      ++crossed;
      followed += i != 0 && i != 27 && shared.version(i) == shared.version(i - 1);
      const bool was_shared =
          (i + 1 < n && start[i] == start[i + 1]) || (i > 0 && start[i] == start[i - 1]);
      in_place += was_shared && shared.version(i) == start[i];
    }
    if (k % 5 == 4) {
      a.Gather(parents, workers);
      b.Gather(parents, workers);
      a.ReleaseDead(workers);
      b.ReleaseDead(workers);
    }
  }
  for (size_t i = 0; i < n; ++i) {
    std::vector<std::pair<uint64_t, Htc>> got, want;
    shared.ForEachHex(i, [&](uint64_t key, const Htc& h) { got.push_back({key, h}); });
    naive.ForEachHex(i, [&](uint64_t key, const Htc& h) { want.push_back({key, h}); });
    ASSERT_EQ(got.size(), want.size()) << "particle " << i;
    for (size_t j = 0; j < got.size(); ++j) {
      EXPECT_EQ(got[j].first, want[j].first);
      EXPECT_TRUE(std::equal(got[j].second.c, got[j].second.c + 6, want[j].second.c));
    }
  }
  EXPECT_TRUE(a.CheckCounts().ok());
  // Without following, no two particles' new maps are one.
  EXPECT_GT(followed, crossed / 4) << followed << " of " << crossed;
  // A group that holds every reference to its map and crosses as one changes it in place
  // (without groups only the last holder of a shared map does: 280 of 16,754 here).
  EXPECT_GT(in_place, crossed / 4) << in_place << " of " << crossed;
}

TEST(FootSlamModelTest, CopiesThatCrossTheSameEdgesShareOneNewMap) {
  StatusOr<Alphabet> alphabet = Alphabet::Create(5);
  ASSERT_TRUE(alphabet.ok());
  for (bool with_prior : {false, true}) {
    SCOPED_TRACE(with_prior ? "with a prior map" : "without a prior map");
    ExpectFollowersMatchNaive<HTreeMap<4>>(nullptr, with_prior);
    ExpectFollowersMatchNaive<AlphabetHTreeMap<4>>(&*alphabet, with_prior);
  }
}

// ReleaseMany frees exactly what Release one by one frees, and leaves the other paths intact.
TEST(AncestryTest, ReleaseManyFreesWhatReleaseFrees) {
  PoseHistory one(2), many(2);
  std::mt19937_64 rng(3);
  constexpr int kPaths = 500;
  std::vector<PoseHistory::Node*> a(kPaths, nullptr), b(kPaths, nullptr);
  for (uint32_t step = 1; step <= 60; ++step) {
    // Resample: each path is replaced by a copy of a random one (shared, not copied).
    std::vector<PoseHistory::Node*> next_a(kPaths), next_b(kPaths);
    for (int k = 0; k < kPaths; ++k) {
      int from = rng() % kPaths;
      next_a[k] = PoseHistory::Share(a[from]);
      next_b[k] = PoseHistory::Share(b[from]);
    }
    for (PoseHistory::Node* n : a) one.Release(n, 1);
    many.ReleaseMany(b, 1);
    a.swap(next_a);
    b.swap(next_b);
    ASSERT_EQ(one.stats().live_nodes, many.stats().live_nodes) << "step " << step;
    for (int k = 0; k < kPaths; ++k) {
      const PathPose pose{static_cast<float>(k), static_cast<float>(step), 0};
      a[k] = one.Append(a[k], step, pose, 0);
      b[k] = many.Append(b[k], step, pose, 0);
    }
  }
  for (int k = 0; k < kPaths; ++k) {
    auto pa = PoseHistory::Path(a[k]);
    auto pb = PoseHistory::Path(b[k]);
    ASSERT_EQ(pa.size(), pb.size());
    for (size_t j = 0; j < pa.size(); ++j) {
      ASSERT_EQ(pa[j]->step, pb[j]->step);
      ASSERT_EQ(pa[j]->value.dx_m, pb[j]->value.dx_m);
    }
  }
  for (PoseHistory::Node* n : a) one.Release(n, 0);
  many.ReleaseMany(b, 0);
  EXPECT_EQ(one.stats().live_nodes, 0);
  EXPECT_EQ(many.stats().live_nodes, 0);
  EXPECT_TRUE(one.CheckCounts({}).ok());
}

// Smooth() against brute force: every path walked whole, its weight added at every step. The
// tree has resamplings (shared entries) and steps some paths skip (an entry standing for
// several steps).
TEST(AncestryTest, SmoothEqualsBruteForceOverEveryPath) {
  PoseHistory history(1);
  std::mt19937_64 rng(5);
  constexpr int kPaths = 200;
  constexpr uint32_t kSteps = 40;
  std::vector<PoseHistory::Node*> paths(kPaths, nullptr);
  for (uint32_t step = 0; step <= kSteps; ++step) {
    if (step % 3 == 1) {  // resample
      std::vector<PoseHistory::Node*> next(kPaths);
      for (int k = 0; k < kPaths; ++k) next[k] = PoseHistory::Share(paths[rng() % kPaths]);
      for (PoseHistory::Node* n : paths) history.Release(n, 0);
      paths.swap(next);
    }
    for (int k = 0; k < kPaths; ++k) {
      if (step > 0 && step < kSteps && rng() % 7 == 0) continue;  // no entry at this step
      const PathPose pose{static_cast<float>(rng() % 1000), static_cast<float>(k), 0};
      paths[k] = history.Append(paths[k], step, pose, 0);
    }
  }
  std::vector<double> weights(kPaths);
  double total = 0;
  for (double& w : weights) total += (w = static_cast<double>(rng() % 100 + 1));
  for (double& w : weights) w /= total;

  std::vector<double> fast(kSteps + 1, 0), fast_w(kSteps + 1, 0);
  std::vector<int> visits(kSteps + 1, 0);
  const std::vector<const PoseHistory::Node*> heads(paths.begin(), paths.end());
  PoseHistory::Smooth<double>(heads, weights, kSteps, [&](uint32_t k, double w, const PathPose& p) {
    fast[k] += w * p.dx_m;
    fast_w[k] += w;
    ++visits[k];
  });
  for (uint32_t k = 0; k <= kSteps; ++k) {
    double brute = 0;
    std::map<const PoseHistory::Node*, int> distinct;
    for (int i = 0; i < kPaths; ++i) {
      const PoseHistory::Node* n = paths[i];
      while (n->step > k) n = n->parent;  // the newest entry at or before step k
      brute += weights[i] * n->value.dx_m;
      ++distinct[n];
    }
    EXPECT_NEAR(fast[k], brute, 1e-9 * std::abs(brute)) << "step " << k;
    EXPECT_NEAR(fast_w[k], 1.0, 1e-12) << "step " << k;
    EXPECT_EQ(visits[k], static_cast<int>(distinct.size())) << "step " << k;
  }
  EXPECT_LT(visits[0], kPaths);  // resampling left fewer distinct roots than paths
  for (PoseHistory::Node* n : paths) history.Release(n, 0);
  EXPECT_EQ(history.stats().live_nodes, 0);
}

// The order of the visits and of the sums follows the paths' order and the tree's shape only:
// the same tree built at other addresses gives the same bits.
TEST(AncestryTest, SmoothDoesNotDependOnAddresses) {
  auto run = [](int padding) {
    PoseHistory history(1);
    std::vector<PoseHistory::Node*> pad;
    for (int k = 0; k < padding; ++k) pad.push_back(history.Append(nullptr, 0, {}, 0));
    std::mt19937_64 rng(9);
    std::vector<PoseHistory::Node*> paths(64, nullptr);
    for (uint32_t step = 0; step <= 20; ++step) {
      std::vector<PoseHistory::Node*> next(paths.size());
      for (auto& n : next) n = PoseHistory::Share(paths[rng() % paths.size()]);
      for (PoseHistory::Node* n : paths) history.Release(n, 0);
      paths.swap(next);
      for (auto& n : paths) {
        n = history.Append(n, step, {static_cast<float>(rng() % 97) * 0.37f, 0, 0}, 0);
      }
    }
    std::vector<double> weights(paths.size());
    for (size_t i = 0; i < weights.size(); ++i) weights[i] = 1.0 / (3.0 + static_cast<double>(i));
    std::vector<double> sums(21, 0);
    const std::vector<const PoseHistory::Node*> heads(paths.begin(), paths.end());
    PoseHistory::Smooth<double>(heads, weights, 20, [&](uint32_t k, double w, const PathPose& p) {
      sums[k] += w * p.dx_m;
    });
    for (PoseHistory::Node* n : paths) history.Release(n, 0);
    for (PoseHistory::Node* n : pad) history.Release(n, 0);
    return sums;
  };
  const std::vector<double> a = run(0), b = run(37);
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k], b[k]) << "step " << k;
}

}  // namespace
}  // namespace grove::footslam
