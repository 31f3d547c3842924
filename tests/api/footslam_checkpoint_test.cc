// Checkpoints through the public API: a resumed engine continues bit for bit, at any thread
// count; corrupt, truncated and incompatible checkpoints are refused with a clear status.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"
#include "tests/api/test_walk.h"

namespace grove {
namespace {

using testing::Step;
using testing::Walk;

void RunSteps(FootSlam* slam, const std::vector<Step>& steps, size_t begin, size_t end) {
  for (size_t k = begin; k < end; ++k) {
    Status s = slam->Step(steps[k].t, steps[k].dx, steps[k].dy);
    ASSERT_TRUE(s.ok()) << s.ToString();
  }
}

std::unique_ptr<FootSlam> Make(const FootSlamConfig& config) {
  auto slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok()) << slam.status().ToString();
  return std::move(*slam);
}

std::unique_ptr<FootSlam> ResumeOrDie(const FootSlamConfig& config, const std::string& bytes,
                                      std::string* user = nullptr) {
  auto slam = FootSlam::Resume(config, bytes, "test.ckpt", user);
  EXPECT_TRUE(slam.ok()) << slam.status().ToString();
  return slam.ok() ? std::move(*slam) : nullptr;
}

// Every output of the engine, compared field by field with exact equality.
void ExpectSameResults(const FootSlam& a, const FootSlam& b) {
  ASSERT_EQ(a.steps(), b.steps());
  auto ta = ValueOf(a.HeaviestTrajectory()), tb = ValueOf(b.HeaviestTrajectory());
  ASSERT_EQ(ta.size(), tb.size());
  for (size_t k = 0; k < ta.size(); ++k) {
    ASSERT_EQ(ta[k].t_s, tb[k].t_s) << k;
    ASSERT_EQ(ta[k].pose.x_m, tb[k].pose.x_m) << k;
    ASSERT_EQ(ta[k].pose.y_m, tb[k].pose.y_m) << k;
    ASSERT_EQ(ta[k].pose.heading_rad, tb[k].pose.heading_rad) << k;
  }
  const auto& ma = a.MeanTrajectory();
  const auto& mb = b.MeanTrajectory();
  ASSERT_EQ(ma.size(), mb.size());
  for (size_t k = 0; k < ma.size(); ++k) {
    ASSERT_EQ(ma[k].t_s, mb[k].t_s) << k;
    ASSERT_EQ(ma[k].pose.x_m, mb[k].pose.x_m) << k;
    ASSERT_EQ(ma[k].pose.heading_rad, mb[k].pose.heading_rad) << k;
  }
  for (auto [ca, cb] : {std::pair{ValueOf(a.CumulativeMap()), ValueOf(b.CumulativeMap())},
                        std::pair{ValueOf(a.HeaviestMap()), ValueOf(b.HeaviestMap())}}) {
    ASSERT_EQ(ca.size(), cb.size());
    for (size_t k = 0; k < ca.size(); ++k) {
      ASSERT_EQ(ca[k].q, cb[k].q);
      ASSERT_EQ(ca[k].r, cb[k].r);
      for (int e = 0; e < 6; ++e) ASSERT_EQ(ca[k].counts[e], cb[k].counts[e]) << k << " " << e;
    }
  }
  FootSlamSummary sa = a.Summary(), sb = b.Summary();
  EXPECT_EQ(sa.resamplings, sb.resamplings);
  EXPECT_EQ(sa.mean_ess, sb.mean_ess);
  EXPECT_EQ(sa.mean_scale, sb.mean_scale);
  EXPECT_EQ(sa.mean_heading_error_rad, sb.mean_heading_error_rad);
}

FootSlamConfig Small() {
  FootSlamConfig c;
  c.particles = 1000;
  c.threads = 2;
  c.initial_heading_sigma_rad = 0.05;
  return c;
}

struct Variant {
  const char* name;
  FootSlamConfig config;
};

std::vector<Variant> Variants() {
  std::vector<Variant> v;
  v.push_back({"htree s16 T5", Small()});
  FootSlamConfig c = Small();
  c.degree = 4;
  c.alphabet = 0;
  v.push_back({"htree s4 T0", c});
  c = Small();
  c.degree = 64;
  c.grid_size = 512;
  c.alphabet = 3;
  c.resampling = ResamplingScheme::kResidual;
  v.push_back({"htree s64 T3 residual", c});
  c = Small();
  c.map = FootSlamMapKind::kNaive;
  v.push_back({"naive", c});
  c = Small();
  c.weighting = FootSlamWeighting::kPriorRatio;
  c.scale_sigma = 0.05;
  c.scale_drift_sigma = 0.002;
  c.resample_threshold = 1.0;
  v.push_back({"prior ratio, free scale, resample every step", c});
  // The walk leaves a 16 x 16 grid: maps of several heights, shared across heights.
  c = Small();
  c.grid_size = 16;
  v.push_back({"growing grid from 16", c});
  c.map = FootSlamMapKind::kNaive;
  v.push_back({"naive, growing grid from 16", c});
  return v;
}

TEST(FootSlamCheckpointTest, ResumedRunIsBitIdenticalAtAnyThreadCount) {
  const std::vector<Step> steps = Walk(160, 7);
  for (const Variant& v : Variants()) {
    SCOPED_TRACE(v.name);
    auto reference = Make(v.config);
    RunSteps(reference.get(), steps, 0, steps.size());

    for (size_t cut : {size_t{0}, size_t{1}, size_t{70}}) {
      SCOPED_TRACE(cut);
      auto first = Make(v.config);
      RunSteps(first.get(), steps, 0, cut);
      auto bytes = first->Checkpoint("position");
      ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
      first.reset();  // nothing of the first engine is needed to resume
      FootSlamConfig other = v.config;
      other.threads = cut == 70 ? 1 : 3;
      other.batch = 97;
      std::string user;
      auto resumed = ResumeOrDie(other, *bytes, &user);
      ASSERT_NE(resumed, nullptr);
      EXPECT_EQ(user, "position");
      EXPECT_EQ(resumed->steps(), static_cast<int64_t>(cut));
      RunSteps(resumed.get(), steps, cut, steps.size());
      ExpectSameResults(*reference, *resumed);
    }
  }
}

// The prior map is in the checkpoint: a resumed run needs no prior map and continues
// bit-identically.
TEST(FootSlamCheckpointTest, APriorMapIsCarriedThroughACheckpoint) {
  const std::vector<Step> steps = Walk(160, 7);
  auto first = Make(Small());
  RunSteps(first.get(), Walk(160, 8), 0, 160);
  const std::vector<HexCounts> prior = ValueOf(first->CumulativeMap());
  auto reference = Make(Small());
  ASSERT_TRUE(reference->SetPriorMap(prior).ok());
  RunSteps(reference.get(), steps, 0, steps.size());
  auto cut = Make(Small());
  ASSERT_TRUE(cut->SetPriorMap(prior).ok());
  RunSteps(cut.get(), steps, 0, 70);
  auto bytes = cut->Checkpoint();
  ASSERT_TRUE(bytes.ok());
  cut.reset();
  std::string user;
  auto resumed = ResumeOrDie(Small(), *bytes, &user);
  ASSERT_NE(resumed, nullptr);
  EXPECT_EQ(resumed->Summary().prior_hexagons, static_cast<int64_t>(prior.size()));
  RunSteps(resumed.get(), steps, 70, steps.size());
  ExpectSameResults(*reference, *resumed);
}

TEST(FootSlamCheckpointTest, CheckpointOfAResumedEngineHasTheSameBytes) {
  // One thread: the sharing between particles is then deterministic too.
  FootSlamConfig config = Small();
  config.threads = 1;
  auto slam = Make(config);
  RunSteps(slam.get(), Walk(90, 3), 0, 90);
  auto a = slam->Checkpoint("x");
  ASSERT_TRUE(a.ok());
  auto resumed = ResumeOrDie(config, *a);
  ASSERT_NE(resumed, nullptr);
  auto b = resumed->Checkpoint("x");
  ASSERT_TRUE(b.ok());
  EXPECT_TRUE(*a == *b) << a->size() << " vs " << b->size() << " bytes";
}

TEST(FootSlamCheckpointTest, SizeFollowsTheDistinctNodes) {
  FootSlamConfig config = Small();
  config.particles = 5000;
  config.alphabet = 0;
  auto slam = Make(config);
  RunSteps(slam.get(), Walk(200, 5), 0, 200);
  auto bytes = slam->Checkpoint();
  ASSERT_TRUE(bytes.ok());
  // Without sharing every particle would store its whole map: at least 24 bytes of counters
  // per hexagon it visited.
  const double unshared =
      static_cast<double>(config.particles) * ValueOf(slam->HeaviestMap()).size() * 24;
  EXPECT_LT(static_cast<double>(bytes->size()), unshared / 4)
      << bytes->size() << " bytes; unshared maps alone would take " << unshared;
}

class CorruptCheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_ = Small();
    config_.particles = 12;
    config_.threads = 1;
    auto slam = Make(config_);
    RunSteps(slam.get(), Walk(25, 11), 0, 25);
    auto bytes = slam->Checkpoint("user");
    ASSERT_TRUE(bytes.ok());
    good_ = *bytes;
  }
  Status ResumeStatus(const std::string& bytes, const FootSlamConfig& config) {
    auto slam = FootSlam::Resume(config, bytes, "run.ckpt", nullptr);
    return slam.ok() ? Status::Ok() : slam.status();
  }

  FootSlamConfig config_;
  std::string good_;
};

TEST_F(CorruptCheckpointTest, EveryFlippedByteIsRefused) {
  ASSERT_TRUE(ResumeStatus(good_, config_).ok());
  for (size_t k = 0; k < good_.size(); k += (k < 64 ? 1 : 13)) {
    std::string bad = good_;
    bad[k] = static_cast<char>(bad[k] ^ (1 << (k % 8)));
    Status s = ResumeStatus(bad, config_);
    ASSERT_FALSE(s.ok()) << "byte " << k;
    EXPECT_TRUE(s.code() == StatusCode::kDataLoss || s.code() == StatusCode::kFailedPrecondition)
        << s.ToString();
    EXPECT_EQ(s.message().rfind("run.ckpt: ", 0), 0u) << s.ToString();
  }
}

TEST_F(CorruptCheckpointTest, TruncatedOrExtendedFilesAreRefused) {
  for (size_t len = 0; len < good_.size(); len += (len < 64 ? 1 : 17)) {
    Status s = ResumeStatus(good_.substr(0, len), config_);
    ASSERT_EQ(s.code(), StatusCode::kDataLoss) << len << ": " << s.ToString();
    if (len >= 24) {
      EXPECT_NE(s.message().find("truncated"), std::string::npos) << s.ToString();
    }
  }
  Status s = ResumeStatus(good_ + "x", config_);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_NE(s.message().find("trailing bytes"), std::string::npos) << s.ToString();
}

TEST_F(CorruptCheckpointTest, OtherFilesAndVersionsAreRefused) {
  Status s = ResumeStatus("t,dx,dy\n1,0.7,0\n", config_);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_NE(s.message().find("not a grove checkpoint"), std::string::npos) << s.ToString();
  // Another format version (the header's u32 at offset 8, outside the body's checksum), newer
  // or older, is refused once the kind shows it is FootSLAM's.
  for (uint8_t version : {5, 7}) {
    std::string other = good_;
    other[8] = static_cast<char>(version);
    s = ResumeStatus(other, config_);
    EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
    EXPECT_NE(s.message().find("FootSLAM checkpoint format version " + std::to_string(version) +
                               " cannot be read by this grove, which reads version 6"),
              std::string::npos)
        << s.ToString();
  }
}

TEST_F(CorruptCheckpointTest, ADifferentConfigurationIsRefusedNamingTheField) {
  FootSlamConfig other = config_;
  other.particles = 13;
  Status s = ResumeStatus(good_, other);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("particles = 12"), std::string::npos) << s.ToString();
  EXPECT_NE(s.message().find("particles = 13"), std::string::npos) << s.ToString();
  other = config_;
  other.heading_sigma_rad = 0.031;
  s = ResumeStatus(good_, other);
  EXPECT_NE(s.message().find("heading_sigma_rad = 0.03,"), std::string::npos) << s.ToString();
  other = config_;
  other.degree = 4;
  EXPECT_EQ(ResumeStatus(good_, other).code(), StatusCode::kFailedPrecondition);
  other = config_;
  other.particles = 0;
  EXPECT_EQ(ResumeStatus(good_, other).code(), StatusCode::kInvalidArgument);
  // Threads and batch change neither results nor the layout.
  other = config_;
  other.threads = 4;
  other.batch = 3;
  EXPECT_TRUE(ResumeStatus(good_, other).ok());
}

// A step of any allowed length ends: the walk stops where the particle leaves the grid (it used
// to walk every hexagon of a 1e9 m step), and stops the engine, saying so. A longer step breaks
// grove/input_rules.h: refused, the engine unchanged.
TEST(FootSlamStepTest, AHugeStepLeavesTheGridAndReturns) {
  FootSlamConfig config = Small();
  config.particles = 10;
  config.grid = FootSlamGrid::kFixed;
  for (double d : {1e3, 1e6}) {
    auto slam = Make(config);
    Status s = slam->Step(1, d, -d);
    EXPECT_EQ(s.code(), StatusCode::kOutOfRange) << s.ToString();
    EXPECT_NE(s.message().find("left the 256 x 256 hexagon grid"), std::string::npos);
    EXPECT_NE(s.message().find("the engine stopped here"), std::string::npos) << s.message();
    EXPECT_EQ(slam->Step(2, 0.5, 0).code(), StatusCode::kFailedPrecondition);
  }
  for (double d : {1e9, 1e200, 1e307}) {
    auto slam = Make(config);
    Status s = slam->Step(1, d, -d);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.ToString();
    EXPECT_NE(s.message().find("must be within +-1e6 m"), std::string::npos) << s.message();
    EXPECT_EQ(slam->steps(), 0);
    EXPECT_TRUE(slam->Step(2, 0.5, 0).ok());
  }
}

TEST(FootSlamCheckpointTest, AStoppedEngineHasNoCheckpoint) {
  FootSlamConfig config = Small();
  config.particles = 10;
  config.grid_size = 16;
  config.grid = FootSlamGrid::kFixed;
  auto slam = Make(config);
  Status s;
  for (int k = 1; k < 100 && s.ok(); ++k) s = slam->Step(k, 0.7, 0);  // walks off the grid
  ASSERT_EQ(s.code(), StatusCode::kOutOfRange);
  EXPECT_EQ(slam->Checkpoint().status().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace grove
