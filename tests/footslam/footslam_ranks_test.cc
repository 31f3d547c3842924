// The FootSLAM facade across ranks (threads of this process, joined by InProcessCollective): every
// read-out of a filter split over 2 and 3 ranks is, on every rank, bit for bit what one process
// gives; what does not run across ranks yet is refused with a clear error.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "engine/collective.h"
#include "grove/footslam.h"
#include "tests/api/test_walk.h"

namespace grove {
namespace {

using testing::Step;
using testing::Walk;

struct ReadOuts {
  Status status;
  std::vector<StampedPose> heaviest, mean, smoothed;
  std::vector<HexCounts> cumulative, best;
  Pose2 heaviest_pose;
  double mean_scale = 0, mean_heading_error = 0;
  int64_t particles = 0, resamplings = 0;
};

template <typename T>
Status Take(StatusOr<T> v, T* out) {
  if (!v.ok()) return v.status();
  *out = std::move(v).value();
  return Status::Ok();
}

ReadOuts RunOne(const FootSlamConfig& config, const std::vector<Step>& steps, Collective* ranks) {
  ReadOuts r;
  StatusOr<std::unique_ptr<FootSlam>> slam = FootSlam::Create(config, ranks);
  if (!slam.ok()) {
    r.status = slam.status();
    return r;
  }
  FootSlam& s = **slam;
  for (const Step& step : steps) {
    r.status = s.Step(step.t, step.dx, step.dy);
    if (!r.status.ok()) return r;
  }
  r.heaviest_pose = s.HeaviestPose();
  r.mean = s.MeanTrajectory();
  if (r.status = Take(s.HeaviestTrajectory(), &r.heaviest); !r.status.ok()) return r;
  if (r.status = Take(s.SmoothedTrajectory(), &r.smoothed); !r.status.ok()) return r;
  if (r.status = Take(s.CumulativeMap(), &r.cumulative); !r.status.ok()) return r;
  if (r.status = Take(s.HeaviestMap(), &r.best); !r.status.ok()) return r;
  const FootSlamSummary summary = s.Summary();
  r.mean_scale = summary.mean_scale;
  r.mean_heading_error = summary.mean_heading_error_rad;
  r.particles = summary.particles;
  r.resamplings = summary.resamplings;
  return r;
}

std::vector<ReadOuts> RunRanks(const FootSlamConfig& config, const std::vector<Step>& steps,
                               int ranks) {
  std::vector<ReadOuts> out(static_cast<size_t>(ranks));
  std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r) {
    threads.emplace_back([&, r] {
      out[static_cast<size_t>(r)] = RunOne(config, steps, endpoints[static_cast<size_t>(r)].get());
    });
  }
  for (std::thread& t : threads) t.join();
  return out;
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

void ExpectSamePaths(const std::vector<StampedPose>& a, const std::vector<StampedPose>& b,
                     const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_TRUE(SameBits(a[k].t_s, b[k].t_s) && SameBits(a[k].pose.x_m, b[k].pose.x_m) &&
                SameBits(a[k].pose.y_m, b[k].pose.y_m) &&
                SameBits(a[k].pose.heading_rad, b[k].pose.heading_rad))
        << what << " pose " << k << ": " << a[k].pose.x_m << " " << b[k].pose.x_m;
  }
}

void ExpectSameMaps(const std::vector<HexCounts>& a, const std::vector<HexCounts>& b,
                    const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t h = 0; h < a.size(); ++h) {
    ASSERT_EQ(a[h].q, b[h].q) << what << " hexagon " << h;
    ASSERT_EQ(a[h].r, b[h].r) << what << " hexagon " << h;
    for (int e = 0; e < 6; ++e) {
      ASSERT_TRUE(SameBits(a[h].counts[e], b[h].counts[e]))
          << what << " hexagon " << h << " edge " << e << ": " << a[h].counts[e] << " "
          << b[h].counts[e];
    }
  }
}

FootSlamConfig RanksConfig() {
  FootSlamConfig c;
  c.particles = 12805;  // 3 whole blocks and a part
  c.threads = 1;
  c.grid_size = 256;
  c.seed = 17;
  return c;
}

TEST(FootSlamRanksTest, EveryReadOutIsOneProcessesOnEveryRank) {
  const std::vector<Step> steps = Walk(150, 5);
  for (int degree : {16, 4}) {
    FootSlamConfig config = RanksConfig();
    config.degree = degree;
    config.alphabet = degree == 16 ? 5 : 0;
    SCOPED_TRACE(::testing::Message() << "degree " << degree);
    const ReadOuts one = RunOne(config, steps, nullptr);
    ASSERT_TRUE(one.status.ok()) << one.status.ToString();
    ASSERT_GT(one.resamplings, 10);
    for (int ranks : {2, 3}) {
      SCOPED_TRACE(::testing::Message() << ranks << " ranks");
      const std::vector<ReadOuts> all = RunRanks(config, steps, ranks);
      for (int r = 0; r < ranks; ++r) {
        SCOPED_TRACE(::testing::Message() << "rank " << r);
        const ReadOuts& got = all[static_cast<size_t>(r)];
        ASSERT_TRUE(got.status.ok()) << got.status.ToString();
        ExpectSamePaths(one.heaviest, got.heaviest, "heaviest path");
        ExpectSamePaths(one.mean, got.mean, "mean path");
        ExpectSamePaths(one.smoothed, got.smoothed, "smoothed path");
        ExpectSameMaps(one.cumulative, got.cumulative, "cumulative map");
        ExpectSameMaps(one.best, got.best, "heaviest map");
        EXPECT_TRUE(SameBits(one.heaviest_pose.x_m, got.heaviest_pose.x_m));
        EXPECT_TRUE(SameBits(one.mean_scale, got.mean_scale));
        EXPECT_TRUE(SameBits(one.mean_heading_error, got.mean_heading_error));
        EXPECT_EQ(got.particles, config.particles);
        EXPECT_EQ(got.resamplings, one.resamplings);
      }
    }
  }
}

TEST(FootSlamRanksTest, WhatDoesNotRunAcrossRanksIsRefused) {
  const std::vector<Step> steps = Walk(5, 5);
  FootSlamConfig config = RanksConfig();
  config.particles = 4096;  // one block: not enough for 2 ranks
  for (const ReadOuts& r : RunRanks(config, steps, 2)) {
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status.message().find("particles = 4096: across 2 ranks"), std::string::npos)
        << r.status.ToString();
  }
  config = RanksConfig();
  config.store_distance_m = 30;
  for (const ReadOuts& r : RunRanks(config, steps, 2)) {
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status.message().find("store_distance_m = 30"), std::string::npos)
        << r.status.ToString();
  }
  // A checkpoint of one rank's share is refused on every rank.
  std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(2);
  std::vector<Status> saved(2);
  std::vector<std::thread> threads;
  for (int r = 0; r < 2; ++r) {
    threads.emplace_back([&, r] {
      StatusOr<std::unique_ptr<FootSlam>> slam =
          FootSlam::Create(RanksConfig(), endpoints[static_cast<size_t>(r)].get());
      if (!slam.ok()) {
        saved[static_cast<size_t>(r)] = slam.status();
        return;
      }
      for (const Step& s : steps) (void)(*slam)->Step(s.t, s.dx, s.dy);
      saved[static_cast<size_t>(r)] = (*slam)->Checkpoint().status();
    });
  }
  for (std::thread& t : threads) t.join();
  for (const Status& s : saved) {
    EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  }
}

}  // namespace
}  // namespace grove
