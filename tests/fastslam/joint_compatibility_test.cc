// Joint compatibility branch and bound (association = jcbb): the chi-square gates, hand-built
// matches whose best hypothesis is known, the node budget's fallback, and a scan through the
// facade where nearest neighbour pairs wrongly and the joint test pairs right.
#include "engine/fastslam/joint_compatibility.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "grove/fastslam.h"

namespace grove::fastslam {
namespace {

Match M(uint32_t detection, uint64_t key, double d2) { return {detection, key, -d2, d2}; }

TEST(ChiSquareEvenQuantile, MatchesTables) {
  EXPECT_NEAR(ChiSquareEvenQuantile(1, 0.05), 5.991465, 1e-6);   // 2 degrees of freedom
  EXPECT_NEAR(ChiSquareEvenQuantile(2, 0.05), 9.487729, 1e-6);   // 4
  EXPECT_NEAR(ChiSquareEvenQuantile(5, 0.01), 23.209251, 1e-6);  // 10
  EXPECT_NEAR(ChiSquareEvenQuantile(50, 0.05), 124.342113, 1e-5);
}

TEST(ExtendJointGates, FirstGateIsTheRejectGateAndTheRestGrow) {
  std::vector<double> gates;
  ExtendJointGates(4, 3, &gates);
  ASSERT_EQ(gates.size(), 3u);
  EXPECT_EQ(gates[0], 4);
  // P(chi2_4 > x) = exp(-x/2) (1 + x/2) = exp(-2) at the reject gate's confidence.
  EXPECT_NEAR(std::exp(-gates[1] / 2) * (1 + gates[1] / 2), std::exp(-2.0), 1e-12);
  EXPECT_GT(gates[2], gates[1]);
  ExtendJointGates(4, 2, &gates);  // never shrinks
  EXPECT_EQ(gates.size(), 3u);
}

class JointCompatibilityTest : public ::testing::Test {
 protected:
  void SetUp() override { ExtendJointGates(4, 8, &gates_); }
  std::vector<double> gates_;
  JointCompatibility jcbb_;
  std::vector<Decision> out_;
};

// Detection 0's nearest landmark is 1, but detection 1 has only landmark 1: pairing detection 0
// with landmark 2 pairs both (nearest neighbour would give landmark 1 to both).
TEST_F(JointCompatibilityTest, MorePairsBeatNearerOnes) {
  std::vector<Match> m = {M(0, 1, 0.1), M(0, 2, 1.0), M(1, 1, 0.5)};
  EXPECT_FALSE(jcbb_.Decide(m, 2, 4, gates_, JointCompatibility::kDefaultNodeBudget, &out_));
  ASSERT_EQ(out_.size(), 2u);
  EXPECT_EQ(out_[0].kind, Decision::kAssociated);
  EXPECT_EQ(out_[0].key, 2u);
  EXPECT_EQ(out_[0].log_likelihood, -1.0);
  EXPECT_EQ(out_[1].kind, Decision::kAssociated);
  EXPECT_EQ(out_[1].key, 1u);
}

// Each pair passes its individual gate (3.9 < 4) but the two together fail chi2(4) (7.8 > 7.0):
// one is kept, the one of the smaller distance; the other is ignored, a third detection whose
// only landmark lies in the augment band is ignored and one with none is new.
TEST_F(JointCompatibilityTest, JointGateDropsThePairOfLargerDistance) {
  ASSERT_LT(gates_[1], 7.8);
  std::vector<Match> m = {M(0, 5, 3.9), M(1, 6, 3.8), M(2, 7, 10)};
  EXPECT_FALSE(jcbb_.Decide(m, 4, 4, gates_, JointCompatibility::kDefaultNodeBudget, &out_));
  EXPECT_EQ(out_[0].kind, Decision::kIgnored);
  EXPECT_EQ(out_[1].kind, Decision::kAssociated);
  EXPECT_EQ(out_[1].key, 6u);
  EXPECT_EQ(out_[2].kind, Decision::kIgnored);
  EXPECT_EQ(out_[3].kind, Decision::kNew);
}

// With a budget of 3 nodes the search stops after its first, greedy descent (detection 0 takes
// its nearest landmark, detection 1 is left without one) and reports it; with the default
// budget it finds both pairs.
TEST_F(JointCompatibilityTest, BudgetKeepsTheBestFoundSoFar) {
  std::vector<Match> m = {M(0, 1, 0.1), M(0, 2, 1.0), M(1, 1, 0.5)};
  EXPECT_TRUE(jcbb_.Decide(m, 2, 4, gates_, 3, &out_));
  EXPECT_EQ(out_[0].kind, Decision::kAssociated);
  EXPECT_EQ(out_[0].key, 1u);
  EXPECT_EQ(out_[1].kind, Decision::kIgnored);
  EXPECT_FALSE(jcbb_.Decide(m, 2, 4, gates_, 5, &out_));
  EXPECT_EQ(out_[0].key, 2u);
  EXPECT_EQ(out_[1].kind, Decision::kAssociated);
}

// Eight detections, each inside the reject gate of the same three landmarks: at most three
// pairs, and proving no hypothesis beats the first takes more than a small budget.
TEST_F(JointCompatibilityTest, CrowdedScanHitsTheBudgetAndStillPairs) {
  std::vector<Match> m;
  for (uint32_t j = 0; j < 8; ++j) {
    for (uint64_t k = 0; k < 3; ++k) m.push_back(M(j, 10 + k, 0.5 + 0.1 * j + 0.01 * k));
  }
  EXPECT_TRUE(jcbb_.Decide(m, 8, 4, gates_, 20, &out_));
  EXPECT_EQ(jcbb_.nodes(), 20);
  int pairs = 0;
  for (const Decision& d : out_) pairs += d.kind == Decision::kAssociated;
  EXPECT_EQ(pairs, 3);
  EXPECT_FALSE(jcbb_.Decide(m, 8, 4, gates_, JointCompatibility::kDefaultNodeBudget, &out_));
  EXPECT_LT(jcbb_.nodes(), JointCompatibility::kDefaultNodeBudget);
  // The complete search pairs the three nearest detections, 0, 1 and 2, one landmark each.
  for (uint32_t j = 0; j < 8; ++j) {
    EXPECT_EQ(out_[j].kind, j < 3 ? Decision::kAssociated : Decision::kIgnored) << j;
  }
}

// Through the facade: a standing vehicle maps two landmarks 1 m apart on one ray, then sees
// them from a pose 0.6 m behind the one it believes (a shifted pose). Both detections lie
// nearer landmark B than they should: nearest neighbour gives B to both (A's detection
// wrongly), mutual exclusion gives B to A's detection and leaves B's ignored, and joint
// compatibility pairs each with its own (2.88 + 2.88 below chi2(4)).
TEST(JointCompatibilityFacade, PairsRightWhereNearestNeighbourPairsWrongly) {
  struct Expected {
    FastSlamAssociation association;
    int64_t associated, wrong;
  };
  for (FastSlamFilter filter : {FastSlamFilter::kFastSlam1, FastSlamFilter::kFastSlam2}) {
    for (const Expected& e : {Expected{FastSlamAssociation::kMaximumLikelihood, 2, 1},
                              Expected{FastSlamAssociation::kExclusive, 1, 1},
                              Expected{FastSlamAssociation::kJointCompatibility, 2, 0}}) {
      FastSlamConfig c;
      c.filter = filter;
      c.particles = 1;
      c.threads = 1;
      c.association = e.association;
      c.sigma_speed_mps = c.sigma_steer_rad = 0;
      c.sigma_range_m = 0.25;  // S = 2R: d2 = dr^2 / 0.125 along the ray
      auto slam = FastSlam::Create(c);
      ASSERT_TRUE(slam.ok()) << slam.status().message();
      ASSERT_TRUE((*slam)->Control(0, 0, 0).ok());
      const LandmarkObservation a{10, 0, 7}, b{11, 0, 8};
      ASSERT_TRUE((*slam)->Scan(0.2, std::vector{a, b}).ok());
      const LandmarkObservation a2{10.6, 0, 7}, b2{11.6, 0, 8};
      ASSERT_TRUE((*slam)->Scan(0.4, std::vector{a2, b2}).ok());
      const AssociationCounts s = (*slam)->Summary().association;
      SCOPED_TRACE(FastSlamFilterName(filter));
      SCOPED_TRACE(static_cast<int>(e.association));
      EXPECT_EQ(s.created, 2);
      EXPECT_EQ(s.associated, e.associated);
      EXPECT_EQ(s.wrong, e.wrong);
      EXPECT_EQ(s.truncated, 0);
    }
  }
}

}  // namespace
}  // namespace grove::fastslam
