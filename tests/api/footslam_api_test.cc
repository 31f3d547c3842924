// The embedder's view: only the public headers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"
#include "tests/api/test_walk.h"

namespace grove {
namespace {

using testing::Step;
using testing::Walk;

struct Result {
  std::vector<StampedPose> trajectory;
  std::vector<StampedPose> mean;
  std::vector<StampedPose> smoothed;
  std::vector<HexCounts> cumulative;
  std::vector<HexCounts> best;
  int64_t resamplings;
};

Result RunWith(FootSlamConfig config, const std::vector<Step>& steps) {
  auto slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok()) << slam.status().ToString();
  for (const Step& s : steps) {
    Status st = (*slam)->Step(s.t, s.dx, s.dy);
    EXPECT_TRUE(st.ok()) << st.ToString();
  }
  return {ValueOf((*slam)->HeaviestTrajectory()), (*slam)->MeanTrajectory(),
          ValueOf((*slam)->SmoothedTrajectory()), ValueOf((*slam)->CumulativeMap()),
          ValueOf((*slam)->HeaviestMap()),        (*slam)->Summary().resamplings};
}

FootSlamConfig Small() {
  FootSlamConfig c;
  c.particles = 2000;
  c.threads = 2;
  c.grid_size = 256;
  return c;
}

void ExpectSame(const Result& a, const Result& b) {
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t k = 0; k < a.trajectory.size(); ++k) {
    ASSERT_EQ(a.trajectory[k].pose.x_m, b.trajectory[k].pose.x_m) << "pose " << k;
    ASSERT_EQ(a.trajectory[k].pose.y_m, b.trajectory[k].pose.y_m) << "pose " << k;
    ASSERT_EQ(a.mean[k].pose.x_m, b.mean[k].pose.x_m) << "mean pose " << k;
    ASSERT_EQ(a.mean[k].pose.heading_rad, b.mean[k].pose.heading_rad) << "mean pose " << k;
    ASSERT_EQ(a.smoothed[k].pose.x_m, b.smoothed[k].pose.x_m) << "smoothed pose " << k;
    ASSERT_EQ(a.smoothed[k].pose.heading_rad, b.smoothed[k].pose.heading_rad) << "smoothed " << k;
  }
  // Maps come in key order, which depends on the degree: compare them in (q, r) order.
  auto same_map = [](std::vector<HexCounts> x, std::vector<HexCounts> y) {
    auto by_hex = [](const HexCounts& a, const HexCounts& b) {
      return std::pair(a.q, a.r) < std::pair(b.q, b.r);
    };
    std::sort(x.begin(), x.end(), by_hex);
    std::sort(y.begin(), y.end(), by_hex);
    ASSERT_EQ(x.size(), y.size());
    for (size_t i = 0; i < x.size(); ++i) {
      ASSERT_EQ(x[i].q, y[i].q);
      ASSERT_EQ(x[i].r, y[i].r);
      for (int e = 0; e < 6; ++e) ASSERT_EQ(x[i].counts[e], y[i].counts[e]) << "hex " << i;
    }
  };
  same_map(a.cumulative, b.cumulative);
  same_map(a.best, b.best);
  EXPECT_EQ(a.resamplings, b.resamplings);
}

TEST(FootSlamApiTest, NaiveAndHTreeGiveTheSameParticlesAndMaps) {
  auto steps = Walk(400, 1);
  FootSlamConfig htree = Small();
  FootSlamConfig naive = Small();
  naive.map = FootSlamMapKind::kNaive;
  Result a = RunWith(htree, steps);
  EXPECT_GT(a.resamplings, 5);
  ExpectSame(a, RunWith(naive, steps));
}

TEST(FootSlamApiTest, AlphabetOnAndOffGiveTheSameResult) {
  auto steps = Walk(400, 2);
  FootSlamConfig on = Small();
  FootSlamConfig off = Small();
  off.alphabet = 0;
  for (int t : {1, 3, 5}) {
    on.alphabet = t;
    ExpectSame(RunWith(on, steps), RunWith(off, steps));
  }
}

TEST(FootSlamApiTest, EveryDegreeGivesTheSameResult) {
  auto steps = Walk(300, 3);
  FootSlamConfig c = Small();
  c.degree = 16;
  Result reference = RunWith(c, steps);
  for (auto [degree, grid] : {std::pair{4, 256}, std::pair{64, 512}, std::pair{256, 256}}) {
    SCOPED_TRACE(degree);
    c.degree = degree;
    c.grid_size = grid;
    ExpectSame(reference, RunWith(c, steps));
  }
}

TEST(FootSlamApiTest, SameSeedIsBitIdenticalAtOneTwoAndFourThreads) {
  auto steps = Walk(300, 4);
  FootSlamConfig c = Small();
  c.threads = 1;
  c.batch = 64;
  Result one = RunWith(c, steps);
  for (int threads : {2, 4}) {
    c.threads = threads;
    ExpectSame(one, RunWith(c, steps));
  }
}

TEST(FootSlamApiTest, DifferentSeedsGiveDifferentPaths) {
  auto steps = Walk(200, 5);
  FootSlamConfig c = Small();
  Result a = RunWith(c, steps);
  c.seed = 2;
  Result b = RunWith(c, steps);
  EXPECT_NE(a.trajectory.back().pose.x_m, b.trajectory.back().pose.x_m);
}

TEST(FootSlamApiTest, CumulativeMapSumsToTheWeightedCrossings) {
  auto steps = Walk(200, 6);
  FootSlamConfig c = Small();
  c.heading_drift_sigma_rad = 0;
  c.heading_sigma_rad = 0;
  c.step_length_sigma_m = 0;
  // Without noise every particle has the same map, so the weighted sum is that map.
  Result r = RunWith(c, steps);
  ASSERT_EQ(r.cumulative.size(), r.best.size());
  for (size_t i = 0; i < r.best.size(); ++i) {
    for (int e = 0; e < 6; ++e) EXPECT_NEAR(r.cumulative[i].counts[e], r.best[i].counts[e], 1e-9);
  }
}

TEST(FootSlamApiTest, ConfigErrorsNameFieldValueAndRule) {
  struct Case {
    void (*set)(FootSlamConfig*);
    const char* message;
  };
  const Case cases[] = {
      {[](FootSlamConfig* c) { c->particles = 0; }, "particles = 0: must be in 1.."},
      {[](FootSlamConfig* c) { c->heading_sigma_rad = -1; },
       "heading_sigma_rad = -1: must be in [0, 10]"},
      {[](FootSlamConfig* c) { c->resample_threshold = 1.5; },
       "resample_threshold = 1.5: must be in (0, 1]"},
      {[](FootSlamConfig* c) { c->resample_threshold = 0; },
       "resample_threshold = 0: must be in (0, 1]"},
      {[](FootSlamConfig* c) { c->degree = 8; }, "degree = 8"},
      {[](FootSlamConfig* c) { c->grid_size = 100; }, "grid_size = 100"},
      {[](FootSlamConfig* c) { c->alphabet = 6; }, "alphabet = 6: must be in 0..5"},
      {[](FootSlamConfig* c) { c->threads = -1; }, "threads = -1: must be in 0..256"},
      {[](FootSlamConfig* c) { c->hex_radius_m = 0; }, "hex_radius_m = 0: must be in (0, 1000]"},
      {[](FootSlamConfig* c) { c->prior_count = std::nan(""); },
       "prior_count = nan: must be in (0, 1000000]"},
  };
  for (const Case& k : cases) {
    FootSlamConfig c;
    k.set(&c);
    Status s = c.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << k.message;
    EXPECT_NE(s.message().find(k.message), std::string::npos) << s.message();
    EXPECT_FALSE(FootSlam::Create(c).ok());
  }
  EXPECT_TRUE(FootSlamConfig().Validate().ok());
}

TEST(FootSlamApiTest, BadStepIsRejectedAndLeavesTheEngineUnchanged) {
  FootSlamConfig c = Small();
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  ASSERT_TRUE((*slam)->Step(1.0, 0.7, 0).ok());
  Pose2 before = (*slam)->HeaviestPose();
  Status s = (*slam)->Step(2.0, std::nan(""), 0);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  s = (*slam)->Step(1.0, 0.7, 0);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("strictly increasing"), std::string::npos) << s.message();
  EXPECT_EQ((*slam)->steps(), 1);
  EXPECT_EQ((*slam)->HeaviestPose().x_m, before.x_m);
  EXPECT_TRUE((*slam)->Step(2.0, 0.7, 0).ok());
}

TEST(FootSlamApiTest, LeavingTheGridIsAnErrorNamingStepAndPosition) {
  FootSlamConfig c = Small();
  c.grid_size = 16;  // 16 hexagons of 0.87 m: about 14 m across
  c.grid = FootSlamGrid::kFixed;
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  Status s;
  int k = 0;
  while (s.ok() && k < 100) {
    ++k;
    s = (*slam)->Step(k, 0.7, 0);
  }
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange);
  EXPECT_NE(s.message().find("step " + std::to_string(k)), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("left the 16 x 16 hexagon grid"), std::string::npos) << s.message();
  EXPECT_EQ((*slam)->Step(k + 1, 0.7, 0).code(), StatusCode::kFailedPrecondition);
}

// The growing grid (paper §VIII): a walk far beyond its first 16 x 16 grid runs, and gives
// the particles, paths and maps of a fixed grid large enough for it, for every map kind.
TEST(FootSlamGridTest, AGrowingGridGivesTheResultsOfAFixedGridLargeEnough) {
  const auto steps = Walk(500, 3, 60);  // about 120 m across: 140 hexagons
  FootSlamConfig growing = Small();
  growing.particles = 500;  // eight runs: kept short for the sanitizer build
  growing.grid_size = 16;
  FootSlamConfig fixed = growing;
  fixed.grid_size = 1024;
  fixed.grid = FootSlamGrid::kFixed;
  for (int variant = 0; variant < 4; ++variant) {
    SCOPED_TRACE(variant);
    FootSlamConfig g = growing, f = fixed;
    if (variant == 1) g.alphabet = f.alphabet = 0;
    if (variant == 2) g.map = f.map = FootSlamMapKind::kNaive;
    if (variant == 3) {
      g.degree = f.degree = 4;
      f.grid_size = 512;
    }
    ExpectSame(RunWith(g, steps), RunWith(f, steps));
  }
}

TEST(FootSlamGridTest, TheSummaryReportsTheGridTheMapsGrewTo) {
  FootSlamConfig c = Small();
  c.particles = 100;
  c.grid_size = 16;
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  EXPECT_EQ((*slam)->Summary().grid_size, 16);
  for (const Step& s : Walk(500, 3, 60)) ASSERT_TRUE((*slam)->Step(s.t, s.dx, s.dy).ok());
  // 16 hexagons nest in 64, then 256: the walk reaches 70 hexagons from the start.
  EXPECT_EQ((*slam)->Summary().grid_size, 256);
  // A first grid of one level, 4 x 4 hexagons, inside one bottom node of the alphabet's symbol
  // tree (16 x 16 at s = 16): a step into the next hexagon stays in it.
  c.grid_size = 4;
  auto small = FootSlam::Create(c);
  ASSERT_TRUE(small.ok());
  ASSERT_TRUE((*small)->Step(1, 0.9, 0).ok());  // one hexagon east: a crossing
  EXPECT_GT((*small)->Summary().map_memory.live_nodes, 0);
  EXPECT_EQ((*small)->Summary().grid_size, 4);
}

// A growing grid bounds the work of one step instead: a step may not cross more hexagons than
// eight times the first grid's side.
TEST(FootSlamGridTest, AStepLongerThanTheFirstGridIsAnError) {
  FootSlamConfig c = Small();
  c.particles = 10;
  c.grid_size = 16;
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  Status ok = (*slam)->Step(1, 40, 0);  // 46 hexagons
  ASSERT_TRUE(ok.ok()) << ok.ToString();
  Status s = (*slam)->Step(2, 1e6, -1e6);  // the longest step grove/input_rules.h allows
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange);
  EXPECT_NE(s.message().find("crosses more than 128 hexagons, 8 x grid_size"), std::string::npos)
      << s.message();
}

// A prior map: its errors name the row and leave the engine as it was; confidence 0 gives the
// results of no prior, bit for bit; hexagons outside a fixed grid are left out and counted.
TEST(FootSlamPriorMapTest, BadRowsAreRefusedNamingTheRow) {
  auto slam = FootSlam::Create(Small());
  ASSERT_TRUE(slam.ok());
  std::vector<HexCounts> map(3);
  map[1].q = 4;
  map[2].q = 5;
  map[2].counts[2] = -1;
  Status s = (*slam)->SetPriorMap(map);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "prior map row 2 (q = 5, r = 0): c2 = -1: counts must be finite and >= 0");
  map[2].counts[2] = std::nan("");
  EXPECT_EQ((*slam)->SetPriorMap(map).code(), StatusCode::kInvalidArgument);
  map[2].counts[2] = 1;
  map[2].q = 4;
  s = (*slam)->SetPriorMap(map);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "prior map row 2: hexagon (q = 4, r = 0) is given twice");
  EXPECT_EQ((*slam)->Summary().prior_hexagons, 0);
  map[2].q = 5;
  ASSERT_TRUE((*slam)->SetPriorMap(map).ok());
  EXPECT_EQ((*slam)->Summary().prior_hexagons, 3);
  ASSERT_TRUE((*slam)->Step(1, 0.7, 0).ok());
  EXPECT_EQ((*slam)->SetPriorMap(map).code(), StatusCode::kFailedPrecondition);
}

TEST(FootSlamPriorMapTest, ConfidenceZeroGivesTheResultsOfNoPrior) {
  const auto steps = Walk(300, 5);
  FootSlamConfig c = Small();
  c.prior_map_confidence = 0;
  // A prior with counts on the walk's hexagons: the map of a first run.
  const std::vector<HexCounts> prior = RunWith(Small(), Walk(300, 6)).cumulative;
  ASSERT_GT(prior.size(), 50u);
  auto with = FootSlam::Create(c);
  ASSERT_TRUE(with.ok());
  ASSERT_TRUE((*with)->SetPriorMap(prior).ok());
  for (const Step& s : steps) ASSERT_TRUE((*with)->Step(s.t, s.dx, s.dy).ok());
  const Result without = RunWith(c, steps);
  ExpectSame(Result{ValueOf((*with)->HeaviestTrajectory()), (*with)->MeanTrajectory(),
                    ValueOf((*with)->SmoothedTrajectory()), ValueOf((*with)->CumulativeMap()),
                    ValueOf((*with)->HeaviestMap()), (*with)->Summary().resamplings},
             without);
  // With confidence 1 the same prior changes the weights.
  c.prior_map_confidence = 1;
  auto strong = FootSlam::Create(c);
  ASSERT_TRUE((*strong)->SetPriorMap(prior).ok());
  for (const Step& s : steps) ASSERT_TRUE((*strong)->Step(s.t, s.dx, s.dy).ok());
  EXPECT_NE((*strong)->MeanTrajectory().back().pose.x_m, without.mean.back().pose.x_m);
}

TEST(FootSlamPriorMapTest, HexagonsOutsideAFixedGridAreLeftOut) {
  FootSlamConfig c = Small();
  c.grid_size = 16;
  c.grid = FootSlamGrid::kFixed;
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  std::vector<HexCounts> map(3);
  map[0].counts[0] = 2;
  map[1].q = 100;
  map[2].r = -9;
  ASSERT_TRUE((*slam)->SetPriorMap(map).ok());
  EXPECT_EQ((*slam)->Summary().prior_hexagons, 1);
  EXPECT_EQ((*slam)->Summary().prior_hexagons_outside, 2);
}

TEST(FootSlamApiTest, TrajectoryHasTheStartAndOnePosePerStep) {
  auto steps = Walk(50, 7);
  FootSlamConfig c = Small();
  auto slam = FootSlam::Create(c);
  ASSERT_TRUE(slam.ok());
  ASSERT_TRUE((*slam)->SetStartTime(0.0).ok());
  EXPECT_EQ((*slam)->SetStartTime(std::nan("")).code(), StatusCode::kInvalidArgument);
  for (const Step& s : steps) ASSERT_TRUE((*slam)->Step(s.t, s.dx, s.dy).ok());
  EXPECT_EQ((*slam)->SetStartTime(0.0).code(), StatusCode::kFailedPrecondition);
  auto path = ValueOf((*slam)->HeaviestTrajectory());
  ASSERT_EQ(path.size(), steps.size() + 1);
  EXPECT_EQ(path[0].t_s, 0.0);
  EXPECT_EQ(path[0].pose.x_m, 0.0);
  for (size_t k = 0; k < steps.size(); ++k) EXPECT_EQ(path[k + 1].t_s, steps[k].t);
  EXPECT_EQ((*slam)->MeanTrajectory().size(), steps.size() + 1);
}

// The smoothed path has the start and one pose per step, ends at the filtered mean (to the
// history's single precision) and, for one particle, is that particle's path.
TEST(FootSlamApiTest, SmoothedPathEndsAtTheMeanAndIsThePathOfALoneParticle) {
  auto steps = Walk(300, 8);
  FootSlamConfig c = Small();
  Result r = RunWith(c, steps);
  ASSERT_EQ(r.smoothed.size(), steps.size() + 1);
  for (size_t k = 0; k < r.smoothed.size(); ++k) {
    ASSERT_EQ(r.smoothed[k].t_s, r.mean[k].t_s) << "pose " << k;
  }
  const Pose2& last = r.smoothed.back().pose;
  EXPECT_NEAR(last.x_m, r.mean.back().pose.x_m, 1e-4);
  EXPECT_NEAR(last.y_m, r.mean.back().pose.y_m, 1e-4);
  EXPECT_NEAR(last.heading_rad, r.mean.back().pose.heading_rad, 1e-5);
  EXPECT_EQ(r.smoothed[0].pose.x_m, 0.0);  // every particle starts at the start
  // Resampling happened, so the smoothed past differs from the filtered one somewhere.
  ASSERT_GT(r.resamplings, 0);
  double most = 0;
  for (size_t k = 0; k < r.mean.size(); ++k) {
    most = std::max(most, std::hypot(r.smoothed[k].pose.x_m - r.mean[k].pose.x_m,
                                     r.smoothed[k].pose.y_m - r.mean[k].pose.y_m));
  }
  EXPECT_GT(most, 1e-3);

  c.particles = 1;
  Result one = RunWith(c, steps);
  ASSERT_EQ(one.smoothed.size(), one.trajectory.size());
  for (size_t k = 0; k < one.smoothed.size(); ++k) {
    EXPECT_EQ(one.smoothed[k].pose.x_m, one.trajectory[k].pose.x_m) << "pose " << k;
    EXPECT_EQ(one.smoothed[k].pose.y_m, one.trajectory[k].pose.y_m) << "pose " << k;
    EXPECT_NEAR(
        std::remainder(one.smoothed[k].pose.heading_rad - one.trajectory[k].pose.heading_rad,
                       2 * M_PI),
        0, 1e-12)
        << "pose " << k;
  }
}

TEST(FootSlamEstimateTest, PredictionGrowsWithParticlesAndTheNaiveMapWithSteps) {
  FootSlamConfig c;
  auto at = [&](int64_t particles) {
    c.particles = particles;
    return FootSlam::EstimatePeakBytes(c, 1000);
  };
  // A fixed overhead plus the same cost for every particle.
  EXPECT_GT(at(60000), at(30000));
  EXPECT_EQ(at(90000) - at(60000), at(60000) - at(30000));
  c.particles = 300000;
  // The H-tree's prediction grows with the walk only by what every step adds once (times, the
  // common path, the area mapped): 99,000 more steps cost far less than 300,000 particles.
  const int64_t longer =
      FootSlam::EstimatePeakBytes(c, 100000) - FootSlam::EstimatePeakBytes(c, 1000);
  EXPECT_GT(longer, 99000 * 100);
  EXPECT_LT(longer, 99000 * 400);
  c.map = FootSlamMapKind::kNaive;
  EXPECT_GT(FootSlam::EstimatePeakBytes(c, 100000), 50 * FootSlam::EstimatePeakBytes(c, 1000));
  // The alphabet's 2-byte leaves make a smaller prediction than 24-byte counters.
  FootSlamConfig alphabet, full;
  full.alphabet = 0;
  EXPECT_LT(FootSlam::EstimatePeakBytes(alphabet, 1000), FootSlam::EstimatePeakBytes(full, 1000));
}

}  // namespace
}  // namespace grove
