// TrackingModel (engine/tracking/tracking_model.h), white-box: the motion model, the range
// weighting, particles moving between ranks and checkpoints; and the Tracker across ranks.
#include "engine/tracking/tracking_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/io/checkpoint_io.h"
#include "tests/api/ranks_testing.h"

namespace grove::tracking {
namespace {

// A prior without spread: every particle at (3, 4) moving at (1, -2) m/s.
TrackerConfig Exact() {
  TrackerConfig c;
  c.particles = 10;
  c.start_x_m = 3;
  c.start_y_m = 4;
  c.start_vx_mps = 1;
  c.start_vy_mps = -2;
  c.initial_position_sigma_m = 0;
  c.initial_velocity_sigma_mps = 0;
  c.acceleration_sigma_mps2 = 0;
  return c;
}

TEST(TrackingModelTest, WithoutNoiseEveryParticleMovesAtItsVelocity) {
  const TrackerConfig config = Exact();
  TrackingModel model(config);
  std::vector<double> log_w(model.size(), 0.0);
  ASSERT_TRUE(model.Advance(RangeUpdate{0.5, {}}, 0, 0, model.size(), 0, log_w.data()).ok());
  for (size_t i = 0; i < model.size(); ++i) {
    EXPECT_EQ(model.state(i).x_m, 3.5);
    EXPECT_EQ(model.state(i).y_m, 3.0);
    EXPECT_EQ(model.state(i).vx_mps, 1.0);
    EXPECT_EQ(log_w[i], 0.0);
  }
  EXPECT_NEAR(model.pose(0).heading_rad, std::atan2(-2.0, 1.0), 1e-15);
}

TEST(TrackingModelTest, ARangeWeighsByItsGaussianError) {
  TrackerConfig config = Exact();
  config.range_sigma_m = 0.5;
  TrackingModel model(config);
  std::vector<double> log_w(model.size(), 0.0);
  // From (3, 4) the origin is 5 m away: a range of 5 costs nothing, one of 6 two sigmas.
  const RangeMeasurement z[] = {{0, 0, 5.0}, {0, 0, 6.0}};
  ASSERT_TRUE(model.Advance(RangeUpdate{0, z}, 0, 0, model.size(), 0, log_w.data()).ok());
  EXPECT_DOUBLE_EQ(log_w[0], -0.5 * (1.0 / 0.25));
}

TEST(TrackingModelTest, ThePriorDependsOnTheGlobalIndexOnly) {
  TrackerConfig config;
  config.particles = 8;
  TrackingModel all(config);
  TrackingModel second_half(config, ParticleShare{4, 4});
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(std::memcmp(&all.state(4 + i), &second_half.state(i), sizeof(TargetState)), 0) << i;
  }
}

TEST(TrackingModelTest, ExportedParticlesImportUnchanged) {
  TrackerConfig config;
  config.particles = 6;
  TrackingModel from(config), to(config);
  ByteWriter w;
  const uint32_t which[] = {1, 4};
  from.Export(which, &w);
  const std::string bytes = w.Take();
  ByteReader r(bytes, "exported");
  ASSERT_TRUE(to.Import(&r, 2, 0).ok());
  ASSERT_EQ(to.size(), 8u);
  EXPECT_EQ(std::memcmp(&to.state(6), &from.state(1), sizeof(TargetState)), 0);
  EXPECT_EQ(std::memcmp(&to.state(7), &from.state(4), sizeof(TargetState)), 0);
}

TEST(TrackingModelTest, ALoadRefusesANonFiniteState) {
  TrackerConfig config;
  config.particles = 2;
  TrackingModel model(config);
  ByteWriter w;
  w.Put<uint64_t>(2);
  w.Put(TargetState{1, 2, 3, 4});
  w.Put(TargetState{1, NAN, 3, 4});
  const std::string bytes = w.Take();
  ByteReader r(bytes, "bad");
  const Status s = model.Load(&r);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss) << s.ToString();
  EXPECT_NE(s.message().find("particle 1 is not finite"), std::string::npos) << s.message();
}

// A filter over 2 ranks (threads of this process) gives every rank the bits of one process.
TEST(TrackerAcrossRanksTest, TwoRanksGiveTheBitsOfOneProcess) {
  TrackerConfig config;
  config.particles = 3 * 4096;
  config.threads = 1;
  auto feed = [](Tracker& t) -> Status {
    for (int k = 1; k <= 20; ++k) {
      const double x = 0.5 * k, y = 0.2 * k;
      const RangeMeasurement z[] = {{-50, -50, std::hypot(x + 50, y + 50)},
                                    {50, -50, std::hypot(x - 50, y + 50)},
                                    {0, 50, std::hypot(x, y - 50)}};
      GROVE_RETURN_IF_ERROR(t.Update(k, z));
    }
    return Status::Ok();
  };
  auto one = Tracker::Create(config);
  ASSERT_TRUE(one.ok());
  ASSERT_TRUE(feed(**one).ok());
  const TargetState expected = (*one)->MeanState();
  const Pose2 heaviest = (*one)->HeaviestPose();
  std::vector<TargetState> got(2);
  std::vector<Pose2> got_heaviest(2);
  testing::OnRanks(2, [&](int r, Collective* c) {
    auto t = Tracker::Create(config, c);
    ASSERT_TRUE(t.ok()) << t.status().ToString();
    ASSERT_TRUE(feed(**t).ok());
    got[r] = (*t)->MeanState();
    got_heaviest[r] = (*t)->HeaviestPose();
  });
  for (int r = 0; r < 2; ++r) {
    EXPECT_TRUE(testing::SameBits(got[r].x_m, expected.x_m)) << r;
    EXPECT_TRUE(testing::SameBits(got[r].vy_mps, expected.vy_mps)) << r;
    EXPECT_TRUE(testing::SameBits(got_heaviest[r].x_m, heaviest.x_m)) << r;
  }
}

}  // namespace
}  // namespace grove::tracking
