// The beacon tracker (grove/tracking.h) as an embedder sees it: it follows a target among
// beacons, gives the same bits at any thread count and after a checkpoint, and refuses bad
// input, configurations and checkpoints without changing anything.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "grove/footslam.h"
#include "grove/tracking.h"
#include "tests/api/status_testing.h"

namespace grove {
namespace {

constexpr double kBeacons[4][2] = {{-40, -40}, {40, -40}, {40, 40}, {-40, 40}};

struct Update {
  double t;
  std::vector<RangeMeasurement> ranges;
  double x, y;  // the truth
};

// A target on a circle of radius 15 m through the beacons' square, one update a second with
// ranges to every beacon, each off by up to +-`noise_m` (uniform, a fixed seed).
std::vector<Update> CircleTrack(int updates, double noise_m) {
  std::mt19937_64 random(7);
  std::vector<Update> out;
  for (int k = 1; k <= updates; ++k) {
    Update u{static_cast<double>(k), {}, 15 * std::sin(0.05 * k), 15 - 15 * std::cos(0.05 * k)};
    for (const auto& b : kBeacons) {
      const double e = noise_m * (2 * static_cast<double>(random() >> 11) * 0x1.0p-53 - 1);
      u.ranges.push_back({b[0], b[1], std::hypot(u.x - b[0], u.y - b[1]) + e});
    }
    out.push_back(u);
  }
  return out;
}

TrackerConfig Small(int threads = 1) {
  TrackerConfig c;
  c.particles = 1500;
  c.threads = threads;
  c.initial_position_sigma_m = 5;
  return c;
}

std::unique_ptr<Tracker> Track(const TrackerConfig& config, const std::vector<Update>& track) {
  auto t = Tracker::Create(config);
  EXPECT_TRUE(t.ok()) << t.status().ToString();
  if (!t.ok()) return nullptr;
  for (const Update& u : track) EXPECT_TRUE((*t)->Update(u.t, u.ranges).ok());
  return std::move(*t);
}

bool SameBits(const std::vector<StampedPose>& a, const std::vector<StampedPose>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

TEST(TrackerTest, FollowsATargetAmongFourBeacons) {
  const std::vector<Update> track = CircleTrack(60, 0.5);
  std::unique_ptr<Tracker> t = Track(Small(), track);
  ASSERT_NE(t, nullptr);
  double worst = 0;
  const std::vector<StampedPose>& mean = t->MeanTrajectory();
  ASSERT_EQ(mean.size(), track.size() + 1);  // the prior, then every update
  for (size_t k = 10; k < track.size(); ++k) {
    worst = std::max(
        worst, std::hypot(mean[k + 1].pose.x_m - track[k].x, mean[k + 1].pose.y_m - track[k].y));
  }
  EXPECT_LT(worst, 1.0);
  const TargetState s = t->MeanState();
  // The circle's velocity at t = 60: 0.75 m/s along (cos 3, sin 3).
  EXPECT_NEAR(s.vx_mps, 0.75 * std::cos(3.0), 0.3);
  EXPECT_NEAR(s.vy_mps, 0.75 * std::sin(3.0), 0.3);
  const TrackerSummary summary = t->Summary();
  EXPECT_EQ(summary.measurements, 240);
  EXPECT_EQ(summary.steps, 60);
  EXPECT_NE(summary.BriefReport().find("Tracker: 1500 particles"), std::string::npos);
}

// The bound is derived, not fitted: one update's four ranges alone, each with the configured
// noise sigma (0.5 m, above the true +-0.5 m uniform noise's 0.29 m), locate the target by least
// squares with mean squared error sigma^2 trace((H^T H)^-1), H the unit vectors from the beacons
// to the target. The filter uses those ranges and the motion before them, so its RMS error after
// the prior is forgotten must stay below that single-update RMS.
TEST(TrackerTest, TrackingErrorStaysBelowTheSingleUpdateLeastSquaresBound) {
  const std::vector<Update> track = CircleTrack(120, 0.5);
  const TrackerConfig config = Small();
  std::unique_ptr<Tracker> t = Track(config, track);
  ASSERT_NE(t, nullptr);
  const std::vector<StampedPose>& mean = t->MeanTrajectory();
  double error_sq = 0, bound_sq = 0;
  int n = 0;
  for (size_t k = 10; k < track.size(); ++k, ++n) {
    const Update& u = track[k];
    error_sq += std::pow(mean[k + 1].pose.x_m - u.x, 2) + std::pow(mean[k + 1].pose.y_m - u.y, 2);
    double a = 0, b = 0, c = 0;  // H^T H = [a b; b c]
    for (const auto& beacon : kBeacons) {
      const double d = std::hypot(u.x - beacon[0], u.y - beacon[1]);
      const double ux = (u.x - beacon[0]) / d, uy = (u.y - beacon[1]) / d;
      a += ux * ux;
      b += ux * uy;
      c += uy * uy;
    }
    bound_sq += config.range_sigma_m * config.range_sigma_m * (a + c) / (a * c - b * b);
  }
  const double rmse = std::sqrt(error_sq / n), bound = std::sqrt(bound_sq / n);
  EXPECT_LT(rmse, bound) << "RMS error " << rmse << " m, single-update bound " << bound << " m";
  EXPECT_GT(bound, 0.4);  // the geometry is as intended: about sigma near the square's centre
}

TEST(TrackerTest, SameSeedGivesTheSameBitsAtOneAndTwoThreads) {
  const std::vector<Update> track = CircleTrack(30, 0.5);
  std::unique_ptr<Tracker> one = Track(Small(1), track), two = Track(Small(2), track);
  ASSERT_TRUE(one != nullptr && two != nullptr);
  EXPECT_TRUE(SameBits(one->MeanTrajectory(), two->MeanTrajectory()));
  const TargetState a = one->MeanState(), b = two->MeanState();
  EXPECT_EQ(std::memcmp(&a, &b, sizeof(a)), 0);
  TrackerConfig other = Small(1);
  other.seed = 2;
  std::unique_ptr<Tracker> reseeded = Track(other, track);
  EXPECT_FALSE(SameBits(one->MeanTrajectory(), reseeded->MeanTrajectory()));
}

TEST(TrackerTest, BadInputIsRefusedAndChangesNothing) {
  const std::vector<Update> track = CircleTrack(3, 0);
  auto t = Tracker::Create(Small());
  ASSERT_TRUE(t.ok());
  ASSERT_TRUE((*t)->Update(track[0].t, track[0].ranges).ok());
  std::vector<RangeMeasurement> bad = track[1].ranges;
  bad[2].range_m = -1;
  Status s = (*t)->Update(track[1].t, bad);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("measurement 2"), std::string::npos) << s.message();
  bad[2].range_m = NAN;
  EXPECT_EQ((*t)->Update(track[1].t, bad).code(), StatusCode::kInvalidArgument);
  s = (*t)->Update(track[0].t, track[1].ranges);  // not after the previous update
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("strictly increasing"), std::string::npos) << s.message();
  EXPECT_EQ((*t)->SetStartTime(0).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ((*t)->steps(), 1);
  // What follows is what a tracker that never saw the refused calls gives.
  ASSERT_TRUE((*t)->Update(track[1].t, track[1].ranges).ok());
  std::unique_ptr<Tracker> clean = Track(Small(), {track[0], track[1]});
  EXPECT_TRUE(SameBits((*t)->MeanTrajectory(), clean->MeanTrajectory()));
}

TEST(TrackerTest, AnUpdateWithoutRangesOnlyPredicts) {
  TrackerConfig c = Small();
  c.acceleration_sigma_mps2 = 0;
  c.start_vx_mps = 2;
  c.initial_velocity_sigma_mps = 0;
  auto t = Tracker::Create(c);
  ASSERT_TRUE(t.ok());
  ASSERT_TRUE((*t)->SetStartTime(0).ok());
  const TargetState before = (*t)->MeanState();
  ASSERT_TRUE((*t)->Update(1.5, {}).ok());
  const TargetState after = (*t)->MeanState();
  EXPECT_NEAR(after.x_m - before.x_m, 3.0, 1e-9);
  EXPECT_NEAR(after.y_m - before.y_m, 0.0, 1e-9);
  EXPECT_EQ((*t)->MeanTrajectory().front().t_s, 0.0);
}

TEST(TrackerTest, ACheckpointResumesBitForBit) {
  const std::vector<Update> track = CircleTrack(40, 0.5);
  std::unique_ptr<Tracker> whole = Track(Small(2), track);
  std::unique_ptr<Tracker> first = Track(Small(1), {track.begin(), track.begin() + 25});
  StatusOr<std::string> bytes = first->Checkpoint("position 25");
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  std::string user;
  auto resumed = Tracker::Resume(Small(2), *bytes, "t.ckpt", &user);  // threads may differ
  ASSERT_TRUE(resumed.ok()) << resumed.status().ToString();
  EXPECT_EQ(user, "position 25");
  for (size_t k = 25; k < track.size(); ++k) {
    ASSERT_TRUE((*resumed)->Update(track[k].t, track[k].ranges).ok());
  }
  EXPECT_TRUE(SameBits(whole->MeanTrajectory(), (*resumed)->MeanTrajectory()));
  EXPECT_EQ((*resumed)->Summary().measurements, 160);
}

TEST(TrackerTest, ResumeRefusesAnotherConfigurationModelOrCorruptBytes) {
  std::unique_ptr<Tracker> t = Track(Small(), CircleTrack(5, 0.5));
  const std::string bytes = ValueOf(t->Checkpoint());
  TrackerConfig other = Small();
  other.range_sigma_m = 0.25;
  auto r = Tracker::Resume(other, bytes, "t.ckpt", nullptr);
  EXPECT_EQ(r.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("range_sigma_m = 0.5"), std::string::npos)
      << r.status().message();
  std::string corrupt = bytes;
  corrupt[corrupt.size() / 2] ^= 1;
  EXPECT_EQ(Tracker::Resume(Small(), corrupt, "t.ckpt", nullptr).status().code(),
            StatusCode::kDataLoss);
  FootSlamConfig foot;
  foot.particles = 50;
  auto slam = FootSlam::Create(foot);
  ASSERT_TRUE(slam.ok());
  r = Tracker::Resume(Small(), ValueOf((*slam)->Checkpoint()), "f.ckpt", nullptr);
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(r.status().message().find("is not a Tracker checkpoint"), std::string::npos)
      << r.status().message();
}

TEST(TrackerConfigTest, EveryFieldHasARowAndItsDefaultIsInRange) {
  const TrackerConfig defaults;
  EXPECT_EQ(defaults.particles, 2000);
  EXPECT_EQ(defaults.resample_threshold, 0.5);
  EXPECT_EQ(TrackerConfigFields().size(), 14u)
      << "a field added to TrackerConfig needs a row in TrackerConfigFields()";
  for (const auto& f : TrackerConfigFields()) {
    EXPECT_TRUE(CheckFieldValue(f.info, f.get(defaults)).ok()) << f.info.name;
  }
  EXPECT_TRUE(defaults.Validate().ok());
  TrackerConfig bad;
  bad.range_sigma_m = 0;
  EXPECT_EQ(bad.Validate().message(), "range_sigma_m = 0: must be in (0, 1000000]");
  EXPECT_EQ(Tracker::Create(bad).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace grove
