// MoveSampled and MoveLinearized (FastSLAM 1.0's and 2.0's particle steps in SIMD lanes): the
// same bits on every Highway target and in any grouping of the particles, the vehicle model's
// step and covariance propagation to round-off, the wrap of the heading, and the first unusable
// particle reported.
#include "engine/fastslam/sampled_motion.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/targets.h>

#include <Eigen/Core>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "concurrency/sin_cos.h"
#include "engine/fastslam/vehicle_model.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;

struct Particles {
  std::vector<VehiclePose> poses;
  std::vector<HeadingUnit> units;
  std::vector<double> nv, ng;
  std::vector<PoseCovariance> covs;
};

// n particles anywhere, headings across (-pi, pi] (units SinCos of them) and standard normals.
Particles RandomParticles(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-500, 500), angle(-kPi, kPi);
  std::normal_distribution<double> normal(0, 1);
  Particles p;
  for (size_t i = 0; i < n; ++i) {
    VehiclePose pose{coord(rng), coord(rng), angle(rng)};
    HeadingUnit u;
    SinCosReference(&pose.heading_rad, 1, &u.s, &u.c);
    p.poses.push_back(pose);
    p.units.push_back(u);
    p.nv.push_back(normal(rng));
    p.ng.push_back(normal(rng));
    // A covariance: A A^T of a random A.
    Eigen::Matrix3d a;
    for (int k = 0; k < 9; ++k) a(k / 3, k % 3) = normal(rng);
    const Eigen::Matrix3d c = a * a.transpose();
    p.covs.push_back({c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2)});
  }
  return p;
}

SampledControl Control(FastSlamVehicle vehicle) {
  SampledControl u;
  u.geometry.kind = vehicle;
  u.geometry.wheelbase_m = vehicle == FastSlamVehicle::kBailey ? 4 : 2.83;
  u.geometry.encoder_offset_m = 0.76;
  u.geometry.laser_forward_m = 3.78;
  u.geometry.laser_left_m = 0.5;
  u.v_mps = 3;
  u.steer_rad = 0.3;
  u.dt_s = 0.025;
  u.sigma_speed_mps = 0.3;
  u.sigma_steer_rad = 0.05;
  return u;
}

MotionResult Move(const SampledControl& u, Particles* p, bool from_headings, size_t begin,
                  size_t end) {
  const double* noise[2] = {p->nv.data() + begin, p->ng.data() + begin};
  return MoveSampled(u, noise, from_headings, p->poses.data() + begin, p->units.data() + begin,
                     end - begin);
}

constexpr double kQSpeed = 0.09, kQSteer = 0.0027;

MotionResult MoveEkf(const SampledControl& u, Particles* p, bool from_headings, size_t begin,
                     size_t end) {
  return MoveLinearized(u, kQSpeed, kQSteer, from_headings, p->poses.data() + begin,
                        p->units.data() + begin, p->covs.data() + begin, end - begin);
}

std::vector<uint64_t> Bits(const Particles& p) {
  std::vector<uint64_t> bits;
  for (size_t i = 0; i < p.poses.size(); ++i) {
    const PoseCovariance& c = p.covs[i];
    for (double v : {p.poses[i].x_m, p.poses[i].y_m, p.poses[i].heading_rad, p.units[i].c,
                     p.units[i].s, c.xx, c.xy, c.xh, c.yy, c.yh, c.hh}) {
      bits.push_back(std::bit_cast<uint64_t>(v));
    }
  }
  return bits;
}

// Moves particles [begin, end) of *p with control u (MoveSampled or MoveLinearized).
using Mover = std::function<MotionResult(const SampledControl& u, Particles* p, bool from_headings,
                                         size_t begin, size_t end)>;
// Moves a copy of the start another way, given the particles `all` moved at once.
using Variant = std::function<void(const SampledControl& u, bool from_headings,
                                   const Particles& all, Particles* p)>;

// The particles' bits after `move` are the same on every Highway target and in any grouping
// (all 37 at once, one at a time, in groups of 5: every particle in a partial vector), for both
// vehicles, with the unit vectors loaded or recomputed; and after `variant`, if given.
void ExpectSameBitsOnEveryTargetAndInAnyGrouping(const Mover& move, uint64_t seed,
                                                 const Variant& variant = nullptr) {
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  for (FastSlamVehicle vehicle : {FastSlamVehicle::kBailey, FastSlamVehicle::kGuivantNebot}) {
    for (bool from_headings : {false, true}) {
      SCOPED_TRACE(testing::Message() << "vehicle " << static_cast<int>(vehicle)
                                      << " units from headings " << from_headings);
      const SampledControl u = Control(vehicle);
      const Particles start = RandomParticles(37, seed);
      std::vector<uint64_t> first;
      for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
        hwy::SetSupportedTargetsForTest(target);
        SCOPED_TRACE(hwy::TargetName(target));
        Particles all = start;
        ASSERT_EQ(move(u, &all, from_headings, 0, 37).first_failed, 37u);
        Particles one = start;
        for (size_t i = 0; i < 37; ++i) move(u, &one, from_headings, i, i + 1);
        Particles groups = start;
        for (size_t b = 0; b < 37; b += 5)
          move(u, &groups, from_headings, b, std::min<size_t>(b + 5, 37));
        if (first.empty()) first = Bits(all);
        EXPECT_EQ(Bits(all), first);
        EXPECT_EQ(Bits(one), first);
        EXPECT_EQ(Bits(groups), first);
        if (variant) {
          Particles other = start;
          variant(u, from_headings, all, &other);
          EXPECT_EQ(Bits(other), first);
        }
      }
      hwy::SetSupportedTargetsForTest(0);
    }
  }
}

TEST(SampledMotionTest, SameBitsOnEveryTargetAndInAnyGrouping) {
  ExpectSameBitsOnEveryTargetAndInAnyGrouping(Move, 71);
}

TEST(SampledMotionTest, AgreesWithTheVehicleModel) {
  for (FastSlamVehicle vehicle : {FastSlamVehicle::kBailey, FastSlamVehicle::kGuivantNebot}) {
    const SampledControl u = Control(vehicle);
    Particles p = RandomParticles(50, 72);
    const Particles before = p;
    ASSERT_EQ(Move(u, &p, false, 0, 50).first_failed, 50u);
    for (size_t i = 0; i < 50; ++i) {
      const double v = u.v_mps + u.sigma_speed_mps * before.nv[i];
      const double g = u.steer_rad + u.sigma_steer_rad * before.ng[i];
      const VehiclePose want = MoveVehicle(u.geometry, before.poses[i], v, g, u.dt_s);
      EXPECT_NEAR(p.poses[i].x_m, want.x_m, 1e-12) << i;
      EXPECT_NEAR(p.poses[i].y_m, want.y_m, 1e-12) << i;
      EXPECT_NEAR(WrapAngle(p.poses[i].heading_rad - want.heading_rad), 0, 1e-14) << i;
      EXPECT_NEAR(p.units[i].c, std::cos(want.heading_rad), 1e-15) << i;
      EXPECT_NEAR(p.units[i].s, std::sin(want.heading_rad), 1e-15) << i;
    }
  }
}

TEST(SampledMotionTest, OnlyTheSteeringNoiseIsDrawnWhenTheSpeedIsExact) {
  SampledControl u = Control(FastSlamVehicle::kBailey);
  u.sigma_speed_mps = 0;
  ASSERT_EQ(u.normals(), 1);
  Particles p = RandomParticles(9, 73);
  const Particles before = p;
  const double* noise[1] = {p.ng.data()};  // the one normal is the steering's
  ASSERT_EQ(MoveSampled(u, noise, false, p.poses.data(), p.units.data(), 9).first_failed, 9u);
  for (size_t i = 0; i < 9; ++i) {
    const double g = u.steer_rad + u.sigma_steer_rad * before.ng[i];
    const VehiclePose want = MoveVehicle(u.geometry, before.poses[i], u.v_mps, g, u.dt_s);
    EXPECT_NEAR(p.poses[i].x_m, want.x_m, 1e-12) << i;
  }
}

// Headings next to +-pi and turns beyond one wrap: WrapAngle()'s result bit for bit, and the unit
// vector of it.
TEST(SampledMotionTest, WrapsTheHeadingAsWrapAngle) {
  SampledControl u = Control(FastSlamVehicle::kBailey);
  u.sigma_speed_mps = u.sigma_steer_rad = 0;
  // Turns of 0.0022 rad (one add of 2 pi next to +-pi), and of 29.5 and -33.2 rad (WrapAngle()).
  for (double v : {3.0, 800.0, -900.0}) {
    u.v_mps = v;
    u.dt_s = std::fabs(v) > 100 ? 0.5 : 0.025;
    std::vector<VehiclePose> poses;
    for (double h : {kPi, -kPi + 1e-12, kPi - 1e-3, -3.0, 3.1, 0.0}) poses.push_back({1, 2, h});
    std::vector<HeadingUnit> units(poses.size());
    const std::vector<VehiclePose> before = poses;
    ASSERT_EQ(MoveSampled(u, nullptr, true, poses.data(), units.data(), poses.size()).first_failed,
              poses.size());
    for (size_t i = 0; i < poses.size(); ++i) {
      const double turn = u.v_mps * u.dt_s * std::sin(u.steer_rad) / u.geometry.wheelbase_m;
      SCOPED_TRACE(testing::Message() << "heading " << before[i].heading_rad << " turn " << turn);
      const double want = WrapAngle(before[i].heading_rad + turn);
      EXPECT_NEAR(poses[i].heading_rad, want, 1e-15);
      EXPECT_GT(poses[i].heading_rad, -kPi);
      EXPECT_LE(poses[i].heading_rad, kPi);
      HeadingUnit w;
      SinCosReference(&poses[i].heading_rad, 1, &w.s, &w.c);
      EXPECT_EQ(std::bit_cast<uint64_t>(units[i].c), std::bit_cast<uint64_t>(w.c));
      EXPECT_EQ(std::bit_cast<uint64_t>(units[i].s), std::bit_cast<uint64_t>(w.s));
    }
  }
}

TEST(SampledMotionTest, ReportsTheFirstUnusableParticle) {
  // Guivant-Nebot: steering near pi/2 makes 1 - tan(G) H / L negative for some particles.
  SampledControl u = Control(FastSlamVehicle::kGuivantNebot);
  u.steer_rad = 1.3;
  u.sigma_steer_rad = 0.2;
  Particles p = RandomParticles(40, 74);
  size_t want = 40;
  for (size_t i = 0; i < 40 && want == 40; ++i) {
    if (!SteeringUsable(u.geometry, u.steer_rad + u.sigma_steer_rad * p.ng[i])) want = i;
  }
  ASSERT_LT(want, 40u) << "the case needs an unusable particle";
  const MotionResult r = Move(u, &p, false, 0, 40);
  EXPECT_EQ(r.first_failed, want);
  EXPECT_EQ(r.why, MotionFailure::kSteering);
}

// A pose that overflows is not finite, in either step.
TEST(SampledMotionTest, APoseThatOverflowsIsNotFiniteInEitherStep) {
  SampledControl fast = Control(FastSlamVehicle::kBailey);
  fast.v_mps = 1e308;
  fast.dt_s = 10;
  for (const Mover& move : {Mover(Move), Mover(MoveEkf)}) {
    Particles p = RandomParticles(3, 75);
    const MotionResult r = move(fast, &p, false, 0, 3);
    EXPECT_EQ(r.first_failed, 0u);
    EXPECT_EQ(r.why, MotionFailure::kNotFinite);
  }
}

TEST(LinearizedMotionTest, SameBitsOnEveryTargetAndInAnyGrouping) {
  // Without covariances (a replay): the same poses and units.
  auto poses_only = [](const SampledControl& u, bool from_headings, const Particles& all,
                       Particles* p) {
    ASSERT_EQ(MoveLinearized(u, kQSpeed, kQSteer, from_headings, p->poses.data(), p->units.data(),
                             nullptr, p->poses.size())
                  .first_failed,
              p->poses.size());
    p->covs = all.covs;
  };
  ExpectSameBitsOnEveryTargetAndInAnyGrouping(MoveEkf, 76, poses_only);
}

// The step with the control itself, and Gv Sigma Gv^T + Gu Q Gu^T with VehicleJacobians()'s
// Jacobians, in Eigen.
TEST(LinearizedMotionTest, AgreesWithTheVehicleModelAndItsJacobians) {
  for (FastSlamVehicle vehicle : {FastSlamVehicle::kBailey, FastSlamVehicle::kGuivantNebot}) {
    SCOPED_TRACE(testing::Message() << "vehicle " << static_cast<int>(vehicle));
    const SampledControl u = Control(vehicle);  // its sigmas are not used
    Particles p = RandomParticles(50, 77);
    const Particles before = p;
    ASSERT_EQ(MoveEkf(u, &p, false, 0, 50).first_failed, 50u);
    const Eigen::Matrix2d q = Eigen::Vector2d(kQSpeed, kQSteer).asDiagonal();
    for (size_t i = 0; i < 50; ++i) {
      const VehiclePose want =
          MoveVehicle(u.geometry, before.poses[i], u.v_mps, u.steer_rad, u.dt_s);
      EXPECT_NEAR(p.poses[i].x_m, want.x_m, 1e-12) << i;
      EXPECT_NEAR(p.poses[i].y_m, want.y_m, 1e-12) << i;
      EXPECT_NEAR(WrapAngle(p.poses[i].heading_rad - want.heading_rad), 0, 1e-14) << i;
      EXPECT_NEAR(p.units[i].c, std::cos(want.heading_rad), 1e-15) << i;
      Eigen::Matrix3d gv;
      Eigen::Matrix<double, 3, 2> gu;
      VehicleJacobians(u.geometry, before.poses[i], u.v_mps, u.steer_rad, u.dt_s, &gv, &gu);
      const PoseCovariance& b = before.covs[i];
      Eigen::Matrix3d sigma;
      sigma << b.xx, b.xy, b.xh, b.xy, b.yy, b.yh, b.xh, b.yh, b.hh;
      const Eigen::Matrix3d w = gv * sigma * gv.transpose() + gu * q * gu.transpose();
      const PoseCovariance& c = p.covs[i];
      const double tol = 1e-12 * (1 + w.cwiseAbs().maxCoeff());
      EXPECT_NEAR(c.xx, w(0, 0), tol) << i;
      EXPECT_NEAR(c.xy, w(0, 1), tol) << i;
      EXPECT_NEAR(c.xh, w(0, 2), tol) << i;
      EXPECT_NEAR(c.yy, w(1, 1), tol) << i;
      EXPECT_NEAR(c.yh, w(1, 2), tol) << i;
      EXPECT_NEAR(c.hh, w(2, 2), tol) << i;
    }
  }
}

}  // namespace
}  // namespace grove::fastslam
