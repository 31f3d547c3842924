// grove/collective.h: one filter across ranks, the ranks here threads of one process.
#include "grove/collective.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "grove/footslam.h"
#include "grove/status.h"
#include "tests/api/ranks_testing.h"
#include "tests/api/status_testing.h"
#include "tests/api/test_walk.h"

namespace grove {
namespace {

using testing::OnRanks;

TEST(CollectiveTest, SharesAreContiguousAndCoverEveryParticleOnce) {
  for (int ranks : {1, 2, 3, 5}) {
    for (uint64_t total : {uint64_t{20000}, uint64_t{100001}}) {
      std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(ranks);
      uint64_t next = 0;
      for (const std::unique_ptr<Collective>& c : endpoints) {
        const ParticleShare share = ShareOf(total, c.get());
        EXPECT_EQ(share.first, next) << "rank " << c->rank() << " of " << ranks;
        EXPECT_GT(share.count, 0u) << "rank " << c->rank() << " of " << ranks;
        next = share.first + share.count;
      }
      EXPECT_EQ(next, total) << ranks << " ranks";
    }
  }
}

TEST(CollectiveTest, WithoutRanksTheShareIsEveryParticle) {
  const ParticleShare share = ShareOf(1234, nullptr);
  EXPECT_EQ(share.first, 0u);
  EXPECT_EQ(share.count, 1234u);
}

TEST(CollectiveTest, AgreeStatusGivesEveryRankTheLowestFailingRanksError) {
  std::vector<Status> agreed(3);
  OnRanks(3, [&](int rank, Collective* c) {
    const Status mine =
        rank == 0 ? Status::Ok() : InvalidArgumentError("bad on " + std::to_string(rank));
    agreed[static_cast<size_t>(rank)] = AgreeStatus(*c, mine);
  });
  EXPECT_EQ(agreed[0].message(), "rank 1: bad on 1");
  EXPECT_EQ(agreed[1].message(), "bad on 1");
  EXPECT_EQ(agreed[2].message(), "rank 1: bad on 1");
  for (const Status& s : agreed) EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
}

bool SameBits(const Pose2& a, const Pose2& b) {
  return testing::SameBits(a.x_m, b.x_m) && testing::SameBits(a.y_m, b.y_m) &&
         testing::SameBits(a.heading_rad, b.heading_rad);
}

TEST(CollectiveTest, FootSlamOnTwoRanksGivesTheBitsOfOneProcess) {
  FootSlamConfig config;
  config.particles = 8192;  // a block of 4,096 on each rank
  config.threads = 1;
  const std::vector<testing::Step> steps = testing::Walk(40, 7);
  auto alone = FootSlam::Create(config);
  ASSERT_TRUE(alone.ok()) << alone.status().ToString();
  for (const testing::Step& s : steps) ASSERT_TRUE((*alone)->Step(s.t, s.dx, s.dy).ok());

  std::vector<Pose2> mean(2);
  std::vector<size_t> hexagons(2);
  OnRanks(2, [&](int rank, Collective* c) {
    auto slam = FootSlam::Create(config, c);
    ASSERT_TRUE(slam.ok()) << slam.status().ToString();
    for (const testing::Step& s : steps) ASSERT_TRUE((*slam)->Step(s.t, s.dx, s.dy).ok());
    mean[static_cast<size_t>(rank)] = (*slam)->MeanPose();
    hexagons[static_cast<size_t>(rank)] = ValueOf((*slam)->CumulativeMap()).size();
  });
  for (int rank = 0; rank < 2; ++rank) {
    EXPECT_TRUE(SameBits(mean[static_cast<size_t>(rank)], (*alone)->MeanPose())) << rank;
    EXPECT_EQ(hexagons[static_cast<size_t>(rank)], ValueOf((*alone)->CumulativeMap()).size());
  }
}

}  // namespace
}  // namespace grove
