// The FootSLAM facade across ranks (threads of this process, joined by InProcessCollective): every
// read-out of a filter split over 2 and 3 ranks is, on every rank, bit for bit what one process
// gives, with storage of diversity too, and so is a run resumed from each rank's checkpoint; too
// few particles for the ranks is refused with a clear error.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "engine/ranks/collective.h"
#include "grove/footslam.h"
#include "tests/api/ranks_testing.h"
#include "tests/api/test_walk.h"

namespace grove {
namespace {

using testing::OnRanks;
using testing::SameBits;
using testing::Step;
using testing::Walk;

struct ReadOuts {
  Status status;
  std::vector<StampedPose> heaviest, mean, smoothed;
  std::vector<HexCounts> cumulative, best, stored;
  Pose2 heaviest_pose;
  double mean_scale = 0, mean_heading_error = 0;
  int64_t particles = 0, resamplings = 0, stored_blocks = 0, stored_blocks_exact = 0;
};

template <typename T>
Status Take(StatusOr<T> v, T* out) {
  if (!v.ok()) return v.status();
  *out = std::move(v).value();
  return Status::Ok();
}

// Every read-out of `s` (collective across ranks).
ReadOuts ReadAll(FootSlam& s) {
  ReadOuts r;
  r.heaviest_pose = s.HeaviestPose();
  r.mean = s.MeanTrajectory();
  if (r.status = Take(s.HeaviestTrajectory(), &r.heaviest); !r.status.ok()) return r;
  if (r.status = Take(s.SmoothedTrajectory(), &r.smoothed); !r.status.ok()) return r;
  if (r.status = Take(s.CumulativeMap(), &r.cumulative); !r.status.ok()) return r;
  if (r.status = Take(s.HeaviestMap(), &r.best); !r.status.ok()) return r;
  if (r.status = Take(s.StoredMap(), &r.stored); !r.status.ok()) return r;
  const FootSlamSummary summary = s.Summary();
  r.mean_scale = summary.mean_scale;
  r.mean_heading_error = summary.mean_heading_error_rad;
  r.particles = summary.particles;
  r.resamplings = summary.resamplings;
  r.stored_blocks = summary.stored_blocks;
  r.stored_blocks_exact = summary.stored_blocks_exact;
  return r;
}

ReadOuts RunOne(const FootSlamConfig& config, const std::vector<Step>& steps, Collective* ranks) {
  StatusOr<std::unique_ptr<FootSlam>> slam = FootSlam::Create(config, ranks);
  ReadOuts r;
  if (!slam.ok()) {
    r.status = slam.status();
    return r;
  }
  for (const Step& step : steps) {
    r.status = (*slam)->Step(step.t, step.dx, step.dy);
    if (!r.status.ok()) return r;
  }
  return ReadAll(**slam);
}

// Each rank's checkpoint after the first `cut` steps.
std::vector<std::string> CheckpointsAfter(const FootSlamConfig& config,
                                          const std::vector<Step>& steps, size_t cut, int ranks) {
  std::vector<std::string> files(static_cast<size_t>(ranks));
  OnRanks(ranks, [&](int r, Collective* c) {
    StatusOr<std::unique_ptr<FootSlam>> slam = FootSlam::Create(config, c);
    ASSERT_TRUE(slam.ok()) << slam.status().ToString();
    for (size_t k = 0; k < cut; ++k) {
      ASSERT_TRUE((*slam)->Step(steps[k].t, steps[k].dx, steps[k].dy).ok());
    }
    StatusOr<std::string> bytes = (*slam)->Checkpoint("user");
    ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
    files[static_cast<size_t>(r)] = *bytes;
  });
  return files;
}

// Each rank resumes from files[rank] and takes the steps after `cut`.
std::vector<ReadOuts> ResumeRanks(const FootSlamConfig& config, const std::vector<Step>& steps,
                                  size_t cut, const std::vector<std::string>& files) {
  const int ranks = static_cast<int>(files.size());
  std::vector<ReadOuts> out(files.size());
  OnRanks(ranks, [&](int r, Collective* c) {
    ReadOuts& got = out[static_cast<size_t>(r)];
    std::string user;
    StatusOr<std::unique_ptr<FootSlam>> slam =
        FootSlam::Resume(config, files[static_cast<size_t>(r)], "c.ckpt", &user, c);
    if (!slam.ok()) {
      got.status = slam.status();
      return;
    }
    EXPECT_EQ(user, "user");
    for (size_t k = cut; k < steps.size(); ++k) {
      got.status = (*slam)->Step(steps[k].t, steps[k].dx, steps[k].dy);
      if (!got.status.ok()) return;
    }
    got = ReadAll(**slam);
  });
  return out;
}

std::vector<ReadOuts> RunRanks(const FootSlamConfig& config, const std::vector<Step>& steps,
                               int ranks) {
  std::vector<ReadOuts> out(static_cast<size_t>(ranks));
  OnRanks(ranks,
          [&](int r, Collective* c) { out[static_cast<size_t>(r)] = RunOne(config, steps, c); });
  return out;
}

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

TEST(FootSlamRanksTest, TooFewParticlesForTheRanksAreRefused) {
  const std::vector<Step> steps = Walk(5, 5);
  FootSlamConfig config = RanksConfig();
  config.particles = 4096;  // one block: not enough for 2 ranks
  for (const ReadOuts& r : RunRanks(config, steps, 2)) {
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status.message().find("particles = 4096: across 2 ranks"), std::string::npos)
        << r.status.ToString();
  }
}

// Storage of diversity across ranks: the ranks fold the far blocks of every rank's particles
// into one stored map, one process's to the bit.
TEST(FootSlamRanksTest, StorageOfDiversityIsOneProcessesOnEveryRank) {
  // Out 42 m and back: the start's area is stored on the way out.
  std::vector<Step> steps;
  for (int k = 1; k <= 120; ++k) steps.push_back({0.5 * k, k <= 60 ? 0.7 : -0.7, 0.01});
  for (int degree : {16, 4}) {
    FootSlamConfig config = RanksConfig();
    config.degree = degree;
    config.alphabet = degree == 16 ? 5 : 0;
    config.store_distance_m = 10;
    config.particles = 8200;  // 2 blocks and a part
    SCOPED_TRACE(::testing::Message() << "degree " << degree);
    const ReadOuts one = RunOne(config, steps, nullptr);
    ASSERT_TRUE(one.status.ok()) << one.status.ToString();
    ASSERT_GT(one.stored_blocks, 0);
    ASSERT_FALSE(one.stored.empty());
    for (int ranks : {2, 3}) {
      SCOPED_TRACE(::testing::Message() << ranks << " ranks");
      const std::vector<ReadOuts> all = RunRanks(config, steps, ranks);
      for (const ReadOuts& got : all) {
        ASSERT_TRUE(got.status.ok()) << got.status.ToString();
        ExpectSameMaps(one.stored, got.stored, "stored map");
        ExpectSameMaps(one.cumulative, got.cumulative, "cumulative map");
        ExpectSameMaps(one.best, got.best, "heaviest map");
        ExpectSamePaths(one.heaviest, got.heaviest, "heaviest path");
        EXPECT_EQ(got.stored_blocks, one.stored_blocks);
        EXPECT_EQ(got.stored_blocks_exact, one.stored_blocks_exact);
      }
    }
  }
}

// Each rank checkpoints its share; resumed on as many ranks, the filter goes on as if never
// stopped, in island mode too.
TEST(FootSlamRanksTest, ACheckpointPerRankResumesBitIdentically) {
  const std::vector<Step> steps = Walk(120, 5);
  for (int islands : {1, 2}) {
    FootSlamConfig config = RanksConfig();
    config.islands = islands;
    config.island_exchange_steps = 7;
    SCOPED_TRACE(::testing::Message() << islands << " islands");
    const ReadOuts one = RunOne(config, steps, nullptr);
    ASSERT_TRUE(one.status.ok()) << one.status.ToString();
    const std::vector<ReadOuts> resumed =
        ResumeRanks(config, steps, 61, CheckpointsAfter(config, steps, 61, 2));
    for (const ReadOuts& got : resumed) {
      ASSERT_TRUE(got.status.ok()) << got.status.ToString();
      ExpectSamePaths(one.heaviest, got.heaviest, "heaviest path");
      ExpectSamePaths(one.mean, got.mean, "mean path");
      ExpectSamePaths(one.smoothed, got.smoothed, "smoothed path");
      ExpectSameMaps(one.cumulative, got.cumulative, "cumulative map");
      EXPECT_EQ(got.resamplings, one.resamplings);
    }
  }
}

// Files of other ranks, of another rank count, or of two different steps are refused on every
// rank.
TEST(FootSlamRanksTest, CheckpointFilesMustBeEachRanksOwnOfOneStep) {
  const std::vector<Step> steps = Walk(40, 5);
  const FootSlamConfig config = RanksConfig();
  const std::vector<std::string> at20 = CheckpointsAfter(config, steps, 20, 2);
  const std::vector<std::string> at30 = CheckpointsAfter(config, steps, 30, 2);
  auto expect_refused = [&](const std::vector<std::string>& files, const std::string& want) {
    for (const ReadOuts& r : ResumeRanks(config, steps, 20, files)) {
      EXPECT_EQ(r.status.code(), StatusCode::kFailedPrecondition) << r.status.ToString();
      EXPECT_NE(r.status.message().find(want), std::string::npos) << r.status.ToString();
    }
  };
  expect_refused({at20[1], at20[0]},
                 "the checkpoint holds rank 1 of 2's particles, and this is "
                 "rank 0 of 2");
  expect_refused({at20[0], at30[1]},
                 "rank 1's checkpoint was made after step 30, rank 0's after step 20");
  // One process cannot take a rank's file.
  std::string user;
  StatusOr<std::unique_ptr<FootSlam>> alone = FootSlam::Resume(config, at20[0], "c.ckpt", &user);
  EXPECT_EQ(alone.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(alone.status().message().find("rank 0 of 2"), std::string::npos)
      << alone.status().ToString();
}

}  // namespace
}  // namespace grove
