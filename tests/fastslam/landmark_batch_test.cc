// UpdateLandmarkBatch and LandmarkLikelihoodBatch (the EKF landmark update in SIMD lanes): the
// same bits on every Highway target, in any grouping and as UpdateLandmark() one at a time; a
// failing lane reported and left alone. LandmarkUpdates (a batch of particles' maps by a scan):
// the same maps and weights as particle-by-particle updates, and the lowest failing particle's
// error.
#include "engine/fastslam/landmark_batch.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/targets.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include "engine/fastslam/filter_steps.h"
#include "engine/fastslam/landmark_updates.h"
#include "engine/persistent/persistent_trie.h"
#include "tests/fastslam/matrix_testing.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;

// n poses and, for each, a landmark seen from it with a random covariance, and an observation
// of the landmark a little off its mean.
struct Batch {
  std::vector<VehiclePose> poses;
  std::vector<Landmark> leaves;
  RangeBearing z;
};

Batch RandomBatch(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-50, 50), angle(-kPi, kPi), off(-0.5, 0.5);
  Batch b;
  b.z = {20, 0.3};
  for (size_t i = 0; i < n; ++i) {
    const VehiclePose p{coord(rng), coord(rng), angle(rng)};
    Landmark l;
    l.x_m = p.x_m + 20 * std::cos(p.heading_rad + 0.3) + off(rng);
    l.y_m = p.y_m + 20 * std::sin(p.heading_rad + 0.3) + off(rng);
    SetCovariance(RandomSpd<2>(rng, 0.3), &l);
    b.poses.push_back(p);
    b.leaves.push_back(l);
  }
  return b;
}

// n observations anywhere within 1..40 m and any bearing (each against its own landmark).
std::vector<RangeBearing> RandomObservations(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> range(1, 40), angle(-kPi, kPi);
  std::vector<RangeBearing> zs;
  for (size_t k = 0; k < n; ++k) zs.push_back({range(rng), angle(rng)});
  return zs;
}

std::vector<uint64_t> Bits(const std::vector<Landmark>& leaves, const std::vector<double>& sums) {
  std::vector<uint64_t> bits;
  for (size_t i = 0; i < leaves.size(); ++i) {
    for (double v :
         {leaves[i].x_m, leaves[i].y_m, leaves[i].xx, leaves[i].xy, leaves[i].yy, sums[i]}) {
      bits.push_back(std::bit_cast<uint64_t>(v));
    }
  }
  return bits;
}

std::vector<Landmark*> Pointers(std::vector<Landmark>* leaves) {
  std::vector<Landmark*> p;
  for (Landmark& l : *leaves) p.push_back(&l);
  return p;
}

TEST(LandmarkBatchTest, SameBitsOnEveryTargetInAnyGroupingAndAsUpdateLandmark) {
  const uint64_t seed = 81;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  const Batch start = RandomBatch(23, seed);
  const SensorNoise noise{0.1, 0.02};
  const double r0 = 0.1 * 0.1, r1 = 0.02 * 0.02;  // as UpdateLandmark() squares them
  std::vector<uint64_t> first;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    std::vector<Landmark> all = start.leaves;
    std::vector<double> sums(23, 0.5);
    std::vector<Landmark*> pointers = Pointers(&all);
    ASSERT_EQ(
        UpdateLandmarkBatch(start.poses.data(), pointers.data(), start.z, r0, r1, sums.data(), 23),
        23u);
    // One at a time through UpdateLandmark(), which adds its log-likelihood to nothing.
    std::vector<Landmark> one = start.leaves;
    std::vector<double> one_sums(23, 0.5);
    for (size_t i = 0; i < 23; ++i) {
      double ll = 0;
      ASSERT_TRUE(UpdateLandmark(start.poses[i], start.z, noise, &one[i], &ll).ok());
      one_sums[i] += ll;
    }
    if (first.empty()) first = Bits(all, sums);
    EXPECT_EQ(Bits(all, sums), first);
    EXPECT_EQ(Bits(one, one_sums), first);
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(LandmarkBatchTest, LaneWithoutALeafOrFailingIsLeftAlone) {
  Batch b = RandomBatch(13, 82);
  b.leaves[5].x_m = b.poses[5].x_m;  // at the sensor: no bearing derivative
  b.leaves[5].y_m = b.poses[5].y_m;
  const std::vector<Landmark> before = b.leaves;
  std::vector<Landmark*> pointers = Pointers(&b.leaves);
  pointers[2] = nullptr;
  std::vector<double> sums(13, 1.0);
  EXPECT_EQ(
      UpdateLandmarkBatch(b.poses.data(), pointers.data(), b.z, 0.01, 0.0004, sums.data(), 13), 5u);
  for (size_t i : {size_t{2}, size_t{5}}) {
    EXPECT_EQ(std::memcmp(&b.leaves[i], &before[i], sizeof(Landmark)), 0) << i;
    EXPECT_EQ(sums[i], 1.0) << i;
  }
  for (size_t i : {size_t{0}, size_t{6}, size_t{12}}) {
    EXPECT_NE(b.leaves[i].xx, before[i].xx) << i;
    EXPECT_NE(sums[i], 1.0) << i;
  }
}

TEST(LandmarkBatchTest, LikelihoodIsTheUpdatesLogLikelihood) {
  const Batch b = RandomBatch(11, 83);
  std::vector<const Landmark*> pointers;
  for (const Landmark& l : b.leaves) pointers.push_back(&l);
  std::vector<double> ll(11), m2(11);
  ASSERT_EQ(LandmarkLikelihoodBatch(b.poses.data(), pointers.data(), b.z, 0.1 * 0.1, 0.02 * 0.02,
                                    ll.data(), m2.data(), 11),
            11u);
  for (size_t i = 0; i < 11; ++i) {
    double want = 0, want_m2 = 0;
    ASSERT_TRUE(
        ObservationLogLikelihood(b.poses[i], b.z, {0.1, 0.02}, b.leaves[i], &want, &want_m2).ok());
    EXPECT_EQ(ll[i], want) << i;
    EXPECT_EQ(m2[i], want_m2) << i;
    Landmark l = b.leaves[i];
    double updated = 0;
    ASSERT_TRUE(UpdateLandmark(b.poses[i], b.z, {0.1, 0.02}, &l, &updated).ok());
    EXPECT_EQ(updated, want) << i;
  }
}

// Pairs seen from one pose, each with its own observation: ObservationLogLikelihood()'s values
// bit for bit on every target, and on an error the first failing pair with its status.
TEST(LandmarkBatchTest, PairsFromOnePoseAreObservationLogLikelihoods) {
  const Batch b = RandomBatch(13, 84);
  const VehiclePose pose = b.poses[0];
  const std::vector<RangeBearing> zs = RandomObservations(13, 85);
  std::vector<const Landmark*> pointers;
  for (const Landmark& l : b.leaves) pointers.push_back(&l);
  const SensorNoise noise{0.1, 0.02};
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    std::vector<double> ll(13), m2(13);
    size_t failed = 99;
    ASSERT_TRUE(ObservationLogLikelihoods(pose, zs.data(), pointers.data(), noise, ll.data(),
                                          m2.data(), 13, &failed)
                    .ok());
    for (size_t k = 0; k < 13; ++k) {
      double want = 0, want_m2 = 0;
      ASSERT_TRUE(ObservationLogLikelihood(pose, zs[k], noise, b.leaves[k], &want, &want_m2).ok());
      EXPECT_EQ(std::bit_cast<uint64_t>(ll[k]), std::bit_cast<uint64_t>(want)) << k;
      EXPECT_EQ(std::bit_cast<uint64_t>(m2[k]), std::bit_cast<uint64_t>(want_m2)) << k;
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  // Pair 5's landmark at the sensor and pair 9's covariance not finite: pair 5's error.
  std::vector<Landmark> bad = b.leaves;
  bad[5].x_m = pose.x_m;
  bad[5].y_m = pose.y_m;
  bad[9].xx = NAN;
  std::vector<const Landmark*> bad_pointers;
  for (const Landmark& l : bad) bad_pointers.push_back(&l);
  std::vector<double> ll(13), m2(13);
  size_t failed = 99;
  const Status s = ObservationLogLikelihoods(pose, zs.data(), bad_pointers.data(), noise, ll.data(),
                                             m2.data(), 13, &failed);
  double unused = 0;
  const Status want = ObservationLogLikelihood(pose, zs[5], noise, bad[5], &unused, &unused);
  ASSERT_FALSE(want.ok());
  EXPECT_EQ(failed, 5u);
  EXPECT_EQ(s.code(), want.code());
  EXPECT_EQ(s.message(), want.message());
}

// Landmarks updated from one pose, each by its own observation: UpdateLandmark()'s results bit
// for bit (more than one chunk of the batch), and on an error the first failing landmark's.
TEST(LandmarkBatchTest, UpdatesFromOnePoseAreUpdateLandmarks) {
  const Batch b = RandomBatch(70, 86);
  const VehiclePose pose = b.poses[0];
  const std::vector<RangeBearing> zs = RandomObservations(70, 87);
  const SensorNoise noise{0.1, 0.02};
  std::vector<Landmark> together = b.leaves, alone = b.leaves;
  size_t failed = 99;
  ASSERT_TRUE(
      UpdateLandmarks(pose, zs.data(), Pointers(&together).data(), noise, 70, &failed).ok());
  for (size_t k = 0; k < 70; ++k) {
    ASSERT_TRUE(UpdateLandmark(pose, zs[k], noise, &alone[k], nullptr).ok());
  }
  const std::vector<double> zeros(70, 0.0);
  EXPECT_EQ(Bits(together, zeros), Bits(alone, zeros));
  // Landmark 66 (in the second chunk) at the sensor, landmark 68 not finite: 66's error.
  std::vector<Landmark> bad = b.leaves;
  bad[66].x_m = pose.x_m;
  bad[66].y_m = pose.y_m;
  Landmark want_leaf = bad[66];
  const Status want = UpdateLandmark(pose, zs[66], noise, &want_leaf, nullptr);
  ASSERT_FALSE(want.ok());
  bad[68].xx = NAN;
  const Status s = UpdateLandmarks(pose, zs.data(), Pointers(&bad).data(), noise, 70, &failed);
  EXPECT_EQ(failed, 66u);
  EXPECT_EQ(s.code(), want.code());
  EXPECT_EQ(s.message(), want.message());
  // Without the unusable one (checked before any update): the first failing pair alike.
  bad[68] = b.leaves[68];
  const Status t = UpdateLandmarks(pose, zs.data(), Pointers(&bad).data(), noise, 70, &failed);
  EXPECT_EQ(failed, 66u);
  EXPECT_EQ(t.message(), want.message());
}

// A bearing many turns off is the same observation: the update agrees to round-off.
TEST(LandmarkBatchTest, BearingsManyTurnsOffAreWrapped) {
  const Batch b = RandomBatch(9, 84);
  for (size_t i = 0; i < 9; ++i) {
    Landmark near = b.leaves[i], far = b.leaves[i];
    double ll_near = 0, ll_far = 0;
    ASSERT_TRUE(UpdateLandmark(b.poses[i], b.z, {0.1, 0.02}, &near, &ll_near).ok());
    ASSERT_TRUE(UpdateLandmark(b.poses[i], {b.z.range_m, b.z.bearing_rad + 6 * kPi}, {0.1, 0.02},
                               &far, &ll_far)
                    .ok());
    EXPECT_NEAR(near.x_m, far.x_m, 1e-9);
    EXPECT_NEAR(near.y_m, far.y_m, 1e-9);
    EXPECT_NEAR(ll_near, ll_far, 1e-9);
  }
}

// The proposal draws of a chunk of particles, their deviates drawn at once, are each particle's
// own Draw(): for both pose readings (a covariance, a factor), from a chunk not starting at 0.
TEST(FilterStepsTest, DeviatesDrawnAtOnceGiveEachParticlesDraw) {
  for (FastSlamFilter filter : {FastSlamFilter::kFastSlam2, FastSlamFilter::kSrcd}) {
    FastSlamConfig config;
    config.filter = filter;
    config.seed = 77;
    const FilterSteps steps(config);
    const Eigen::Vector3d mu(1.5, -2.0, 0.3);
    Eigen::Matrix3d sigma;
    sigma << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.01;
    if (filter == FastSlamFilter::kSrcd) sigma = Eigen::Matrix3d(sigma.llt().matrixL());
    const uint64_t step = 41, first = 1000;
    const size_t n = FilterSteps::kDrawChunk - 3;
    FilterSteps::Deviates d;
    steps.DrawDeviates(step, first, first + n, &d);
    for (size_t k = 0; k < n; ++k) {
      VehiclePose one, chunk;
      ASSERT_TRUE(steps.Draw(step, first + k, mu, sigma, &one).ok());
      ASSERT_TRUE(steps.DrawWith(d.of(k), first + k, mu, sigma, &chunk).ok());
      EXPECT_EQ(std::bit_cast<uint64_t>(one.x_m), std::bit_cast<uint64_t>(chunk.x_m)) << k;
      EXPECT_EQ(std::bit_cast<uint64_t>(one.y_m), std::bit_cast<uint64_t>(chunk.y_m)) << k;
      EXPECT_EQ(std::bit_cast<uint64_t>(one.heading_rad),
                std::bit_cast<uint64_t>(chunk.heading_rad))
          << k;
    }
  }
}

using Trie = PersistentTrie<Landmark, 3>;

// n particles sharing one map of landmarks 0..4 seen from the origin, the filter's FastSLAM 1.0
// steps, and a scan observing landmarks 1, 3 and 7 (7 new).
struct Maps {
  FastSlamConfig config;
  FilterSteps steps{Config()};
  Trie trie{1, 1};
  std::vector<Trie::Node*> roots;
  std::vector<VehiclePose> poses;
  std::vector<LandmarkObservation> z = {{20, 0.1, 1}, {15, -0.4, 3}, {12, 0.9, 7}};

  static FastSlamConfig Config() {
    FastSlamConfig c;
    c.filter = FastSlamFilter::kFastSlam1;
    return c;
  }
  explicit Maps(size_t n) {
    Trie::Node* root = nullptr;
    for (uint64_t id = 0; id < 5; ++id) {
      const Landmark l = InitLandmark({0, 0, 0}, {10.0 + 2 * id, 0.2 * id - 0.4}, {0.1, 0.02});
      EXPECT_TRUE(trie.Update(&root, id, 0, [&](Landmark& leaf, bool) { leaf = l; }));
    }
    for (size_t k = 0; k < n; ++k) {
      roots.push_back(k == 0 ? root : Trie::Share(root));
      poses.push_back({0.1 * k, -0.05 * k, 0.01 * k});
    }
  }
  ~Maps() {
    for (Trie::Node* r : roots) trie.Release(r, 0);
  }
  ScanStep scan() const { return ScanStep{z}; }
};

std::vector<double> MapValues(const Maps& m) {
  std::vector<double> v;
  for (Trie::Node* r : m.roots) {
    m.trie.ForEach(r, [&](uint64_t id, const Landmark& l) {
      v.insert(v.end(), {static_cast<double>(id), l.x_m, l.y_m, l.xx, l.xy, l.yy});
    });
  }
  return v;
}

TEST(LandmarkUpdatesTest, EqualsParticleByParticleUpdates) {
  const size_t n = 19;
  Maps batch(n), one(n);
  LandmarkUpdates<Trie> updates(1);
  std::vector<double> lw(n, -1.0), want_lw(n, -1.0);
  ASSERT_TRUE(updates
                  .Apply(batch.steps, &batch.trie, batch.roots.data(), batch.poses.data(), 0,
                         batch.scan(), n, 0, lw.data())
                  .ok());
  for (size_t k = 0; k < n; ++k) {
    double sum = 0;
    for (const LandmarkObservation& z : one.z) {
      ASSERT_TRUE(one.trie.Update(
          &one.roots[k], static_cast<uint64_t>(z.id), 0, [&](Landmark& l, bool existed) {
            const RangeBearing rb{z.range_m, z.bearing_rad};
            if (!existed) {
              ASSERT_TRUE(one.steps.NewLeaf(one.poses[k], rb, &l).ok());
              return;
            }
            double ll = 0;
            ASSERT_TRUE(one.steps.UpdateLeaf(one.poses[k], rb, &l, &ll).ok());
            sum += ll;
          }));
    }
    want_lw[k] += sum;
  }
  EXPECT_EQ(lw, want_lw);
  EXPECT_EQ(MapValues(batch), MapValues(one));
}

TEST(LandmarkUpdatesTest, ReportsTheLowestFailingParticle) {
  const size_t n = 12;
  Maps m(n);
  // Particle 8 sits on landmark 1 (its first observation fails); particle 4's landmark 3 has
  // an indefinite covariance (its second observation fails, by the checked path).
  m.poses[8] = {m.trie.Find(m.roots[8], 1)->x_m, m.trie.Find(m.roots[8], 1)->y_m, 0};
  ASSERT_TRUE(m.trie.Update(&m.roots[4], 3, 0, [](Landmark& l, bool) { l.xy = 10 * l.xx; }));
  LandmarkUpdates<Trie> updates(1);
  const Status s =
      updates.Apply(m.steps, &m.trie, m.roots.data(), m.poses.data(), 100, m.scan(), n, 0, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_NE(s.message().find("particle 104, landmark 3"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("landmark covariance"), std::string::npos) << s.message();
  // Without particle 4's fault, particle 8's.
  Maps m2(n);
  m2.poses[8] = {m2.trie.Find(m2.roots[8], 1)->x_m, m2.trie.Find(m2.roots[8], 1)->y_m, 0};
  const Status s2 = updates.Apply(m2.steps, &m2.trie, m2.roots.data(), m2.poses.data(), 100,
                                  m2.scan(), n, 0, nullptr);
  EXPECT_EQ(s2.code(), StatusCode::kFailedPrecondition) << s2.ToString();
  EXPECT_NE(s2.message().find("particle 108, landmark 1"), std::string::npos) << s2.message();
  EXPECT_NE(s2.message().find("sensor position"), std::string::npos) << s2.message();
}

}  // namespace
}  // namespace grove::fastslam
