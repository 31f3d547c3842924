// Storage of diversity (FootSlamConfig::store_distance_m) on the simulator's campus walks: three
// buildings 100 m apart, an hour long.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

SimulatedWalk CampusWalk(uint64_t seed, double minutes) {
  SimulatorOptions sim;
  sim.scenario = Scenario::kCampus;
  sim.minutes = minutes;
  sim.seed = seed;
  StatusOr<SimulatedWalk> walk = SimulateWalk(sim);
  EXPECT_TRUE(walk.ok()) << walk.status().ToString();
  return std::move(*walk);
}

std::unique_ptr<FootSlam> Create(const FootSlamConfig& config) {
  StatusOr<std::unique_ptr<FootSlam>> slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok()) << slam.status().ToString();
  return std::move(*slam);
}

void RunSteps(FootSlam* slam, const SimulatedWalk& walk, size_t begin, size_t end) {
  for (size_t k = begin; k < end; ++k) {
    const StepRecord& s = walk.steps[k];
    ASSERT_TRUE(slam->Step(s.t_s, s.dx_m, s.dy_m).ok()) << "step " << k + 1;
  }
}

void ExpectSameTrajectories(const FootSlam& a, const FootSlam& b) {
  const std::vector<StampedPose>& ma = a.MeanTrajectory();
  const std::vector<StampedPose>& mb = b.MeanTrajectory();
  ASSERT_EQ(ma.size(), mb.size());
  for (size_t k = 0; k < ma.size(); ++k) {
    ASSERT_EQ(ma[k].pose.x_m, mb[k].pose.x_m) << "step " << k;
    ASSERT_EQ(ma[k].pose.y_m, mb[k].pose.y_m) << "step " << k;
    ASSERT_EQ(ma[k].pose.heading_rad, mb[k].pose.heading_rad) << "step " << k;
  }
  const std::vector<StampedPose> ha = ValueOf(a.HeaviestTrajectory());
  const std::vector<StampedPose> hb = ValueOf(b.HeaviestTrajectory());
  ASSERT_EQ(ha.size(), hb.size());
  for (size_t k = 0; k < ha.size(); ++k) {
    ASSERT_EQ(ha[k].pose.x_m, hb[k].pose.x_m) << "step " << k;
    ASSERT_EQ(ha[k].pose.y_m, hb[k].pose.y_m) << "step " << k;
  }
}

void ExpectSameMaps(const std::vector<HexCounts>& a, const std::vector<HexCounts>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].q, b[i].q) << i;
    ASSERT_EQ(a[i].r, b[i].r) << i;
    for (int e = 0; e < 6; ++e) ASSERT_EQ(a[i].counts[e], b[i].counts[e]) << i;
  }
}

// The documented exactness case: a block whose every particle holds the same counters (their
// lineages met before the walk left it, so they share its one version) folds into exactly those
// counters, and a particle that comes back is weighted as if nothing had been stored. With few
// particles resampled at every step the lineages meet quickly, and every fold of this walk is
// exact: the filter's results are then those of never storing, bit for bit.
TEST(StorageOfDiversityTest, RestoringExactFoldsGivesTheResultsOfNeverStoring) {
  const SimulatedWalk walk = CampusWalk(1, 60);
  FootSlamConfig config;
  config.particles = 20;
  config.resample_threshold = 1;
  config.threads = 1;
  auto plain = Create(config);
  config.store_distance_m = 60;
  auto storing = Create(config);
  RunSteps(plain.get(), walk, 0, walk.steps.size());
  RunSteps(storing.get(), walk, 0, walk.steps.size());
  const FootSlamSummary s = storing->Summary();
  std::printf(
      "stored %lld blocks (%lld exact), %lld hexagons\n", static_cast<long long>(s.stored_blocks),
      static_cast<long long>(s.stored_blocks_exact), static_cast<long long>(s.stored_hexagons));
  ASSERT_GT(s.stored_blocks, 0);
  ASSERT_EQ(s.stored_blocks_exact, s.stored_blocks) << "the case this test is about";
  // The walk came back to stored areas: the heaviest particle's own map (its map minus the
  // stored map) has counts in hexagons the stored map holds.
  std::map<std::pair<int32_t, int32_t>, const HexCounts*> stored;
  const std::vector<HexCounts> stored_map = ValueOf(storing->StoredMap());
  for (const HexCounts& h : stored_map) stored[{h.q, h.r}] = &h;
  int revisited = 0;
  for (const HexCounts& h : ValueOf(storing->HeaviestMap())) {
    auto it = stored.find({h.q, h.r});
    if (it == stored.end()) continue;
    double own = 0;
    for (int e = 0; e < 6; ++e) own += h.counts[e] - it->second->counts[e];
    revisited += own > 0.5 ? 1 : 0;
  }
  std::printf("%d stored hexagons crossed again\n", revisited);
  ASSERT_GT(revisited, 0) << "the walk never returned to a stored area";
  ExpectSameTrajectories(*plain, *storing);
  // The maps agree to rounding: the stored counters are whole, the particles' sum of weights
  // is 1 only to rounding.
  const std::vector<HexCounts> a = ValueOf(plain->CumulativeMap());
  const std::vector<HexCounts> b = ValueOf(storing->CumulativeMap());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].q, b[i].q);
    ASSERT_EQ(a[i].r, b[i].r);
    for (int e = 0; e < 6; ++e) ASSERT_NEAR(a[i].counts[e], b[i].counts[e], 1e-9) << i;
  }
}

// What storage is for: the particles' maps hold only the area near the particles. After an hour
// across three buildings the heaviest particle's own map (its map minus the stored map) lies
// within the store distance plus a block of where it stands; without storage it spans the walk.
TEST(StorageOfDiversityTest, TheParticlesMapsKeepOnlyTheAreaNearThem) {
  const SimulatedWalk walk = CampusWalk(1, 60);
  const size_t steps = walk.steps.size() / 50 * 50;  // ends with a store
  FootSlamConfig config;
  config.particles = 300;
  config.threads = 2;
  auto plain = Create(config);
  config.store_distance_m = 30;
  auto storing = Create(config);
  RunSteps(plain.get(), walk, 0, steps);
  RunSteps(storing.get(), walk, 0, steps);
  auto farthest = [](const FootSlam& slam, const std::vector<HexCounts>& stored_map) {
    std::map<std::pair<int32_t, int32_t>, const HexCounts*> stored;
    for (const HexCounts& h : stored_map) stored[{h.q, h.r}] = &h;
    const Pose2 at = slam.HeaviestPose();
    double far = 0;
    for (const HexCounts& h : ValueOf(slam.HeaviestMap())) {
      double own = 0;
      auto it = stored.find({h.q, h.r});
      for (int e = 0; e < 6; ++e) {
        own += h.counts[e] - (it == stored.end() ? 0 : it->second->counts[e]);
      }
      if (own > 0.5) far = std::max(far, std::hypot(h.x_m - at.x_m, h.y_m - at.y_m));
    }
    return far;
  };
  const double far_without = farthest(*plain, {});
  const double far_with = farthest(*storing, ValueOf(storing->StoredMap()));
  const FootSlamSummary with = storing->Summary();
  const FootSlamSummary without = plain->Summary();
  std::printf(
      "own map reaches %.1f m (without storage %.1f m); live map %lld bytes (without %lld), "
      "peak %lld (without %lld); stored %lld blocks (%lld exact), %lld hexagons\n",
      far_with, far_without, static_cast<long long>(with.map_memory.live_bytes),
      static_cast<long long>(without.map_memory.live_bytes),
      static_cast<long long>(with.map_memory.peak_live_bytes),
      static_cast<long long>(without.map_memory.peak_live_bytes),
      static_cast<long long>(with.stored_blocks), static_cast<long long>(with.stored_blocks_exact),
      static_cast<long long>(with.stored_hexagons));
  EXPECT_GT(far_without, 100) << "the walk (ending in the middle building) should span the campus";
  // A kept block is within 30 m of the particles' bounding box and at most 14 m wide (level 1
  // blocks of degree 16: 16 hexagons of 0.87 m); the box is a few metres across.
  EXPECT_LT(far_with, 30 + 2 * 14 + 10);
  EXPECT_GT(with.stored_hexagons, 1000);
}

// Storing happens between steps, on the state a step left: a checkpoint holds the stored map,
// and a resumed run goes on bit for bit, storing what the uninterrupted run stores.
TEST(StorageOfDiversityTest, ResumingFromACheckpointContinuesBitIdentically) {
  const SimulatedWalk walk = CampusWalk(2, 20);
  FootSlamConfig config;
  config.particles = 200;
  config.threads = 2;
  config.store_distance_m = 20;
  auto whole = Create(config);
  RunSteps(whole.get(), walk, 0, walk.steps.size());
  auto first = Create(config);
  const size_t cut = 1234;
  RunSteps(first.get(), walk, 0, cut);
  ASSERT_GT(first->Summary().stored_blocks, 0) << "the checkpoint should hold stored blocks";
  const std::string checkpoint = ValueOf(first->Checkpoint());
  config.threads = 1;
  StatusOr<std::unique_ptr<FootSlam>> resumed =
      FootSlam::Resume(config, checkpoint, "run.ckpt", nullptr);
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  RunSteps(resumed->get(), walk, cut, walk.steps.size());
  const FootSlamSummary a = whole->Summary(), b = (*resumed)->Summary();
  EXPECT_GT(a.stored_blocks, first->Summary().stored_blocks) << "more stored after the cut";
  EXPECT_EQ(a.stored_blocks, b.stored_blocks);
  EXPECT_EQ(a.stored_blocks_exact, b.stored_blocks_exact);
  EXPECT_EQ(a.stored_hexagons, b.stored_hexagons);
  ExpectSameTrajectories(*whole, **resumed);
  ExpectSameMaps(ValueOf(whole->StoredMap()), ValueOf((*resumed)->StoredMap()));
  ExpectSameMaps(ValueOf(whole->CumulativeMap()), ValueOf((*resumed)->CumulativeMap()));
  EXPECT_TRUE((*resumed)->CheckInvariants().ok());
}

// With a prior map and stored blocks both in use, at 1 and 2 threads: the same bits, the
// stored map read back from the checkpoint.
TEST(StorageOfDiversityTest, WithAPriorMapAnyThreadCountGivesTheSameResults) {
  const SimulatedWalk walk = CampusWalk(3, 15);
  FootSlamConfig config;
  config.particles = 300;
  config.store_distance_m = 20;
  std::vector<std::unique_ptr<FootSlam>> runs;
  std::vector<HexCounts> prior;
  {
    FootSlamConfig first = config;
    first.store_distance_m = 0;
    auto earlier = Create(first);
    RunSteps(earlier.get(), walk, 0, 600);
    prior = ValueOf(earlier->CumulativeMap());
  }
  for (int threads : {1, 2}) {
    config.threads = threads;
    runs.push_back(Create(config));
    ASSERT_TRUE(runs.back()->SetPriorMap(prior).ok());
    RunSteps(runs.back().get(), walk, 0, walk.steps.size());
    EXPECT_TRUE(runs.back()->CheckInvariants().ok());
  }
  EXPECT_GT(runs[0]->Summary().stored_blocks, 0);
  EXPECT_EQ(runs[0]->Summary().prior_hexagons, static_cast<int64_t>(prior.size()));
  ExpectSameTrajectories(*runs[0], *runs[1]);
  ExpectSameMaps(ValueOf(runs[0]->StoredMap()), ValueOf(runs[1]->StoredMap()));
  ExpectSameMaps(ValueOf(runs[0]->CumulativeMap()), ValueOf(runs[1]->CumulativeMap()));
}

TEST(StorageOfDiversityTest, ConfigurationsThatCannotStoreAreRefused) {
  FootSlamConfig config;
  config.store_distance_m = 30;
  config.map = FootSlamMapKind::kNaive;
  Status s = config.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("store_distance_m = 30: storage of diversity needs map = htree"),
            std::string::npos)
      << s.ToString();
  config.map = FootSlamMapKind::kHTree;
  config.grid_size = 4;  // one level: no block below the root
  s = config.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("grid_size >= degree (grid_size = 4, degree = 16)"), std::string::npos)
      << s.ToString();
  config.grid_size = 16;
  EXPECT_TRUE(config.Validate().ok());
  config.store_distance_m = -1;
  EXPECT_EQ(config.Validate().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace grove::tools
