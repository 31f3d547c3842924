// Data association sampling on hand-built detections whose answer is known: the draw's
// frequencies against the likelihoods, the importance correction, and the draw's keys.
#include "engine/fastslam/association_sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace grove::fastslam {
namespace {

constexpr double kLogP0 = -20;

// Two landmarks (keys 7 and 9) for detection 0, at log-likelihoods p0 + log 3 and p0 + log 1:
// with the new landmark the draw's probabilities are 3/5, 1/5 and 1/5.
std::vector<Match> TwoCandidates() {
  return {Match{0, 9, kLogP0, 4.0}, Match{0, 7, kLogP0 + std::log(3.0), 1.0}};
}

TEST(SampleDecisions, DrawsInProportionToTheLikelihoodsNewLandmarkIncluded) {
  constexpr int kDraws = 40000;
  int seven = 0, nine = 0, fresh = 0;
  std::vector<Decision> out;
  for (uint32_t p = 0; p < kDraws; ++p) {
    std::vector<Match> m = TwoCandidates();
    RandomStream rs(5, 1, p, StreamPurpose::kAssociation);
    double correction = 0;
    SampleDecisions(m, 1, kLogP0, &rs, &out, &correction);
    ASSERT_EQ(out.size(), 1u);
    // The weight is the same whatever the draw: log T - log L_drawn + log L_drawn = log T.
    const double drawn = out[0].kind == Decision::kNew ? kLogP0 : out[0].log_likelihood;
    EXPECT_NEAR(correction + drawn, kLogP0 + std::log(5.0), 1e-12);
    if (out[0].kind == Decision::kNew) {
      ++fresh;
    } else if (out[0].key == 7) {
      ++seven;
      EXPECT_DOUBLE_EQ(out[0].log_likelihood, kLogP0 + std::log(3.0));
    } else {
      ++nine;
      EXPECT_EQ(out[0].key, 9u);
    }
  }
  // Binomial standard deviations: sqrt(n p (1 - p)) = 98 and 80; 5 of them allowed.
  EXPECT_NEAR(seven, 0.6 * kDraws, 5 * 98);
  EXPECT_NEAR(nine, 0.2 * kDraws, 5 * 80);
  EXPECT_NEAR(fresh, 0.2 * kDraws, 5 * 80);
}

TEST(SampleDecisions, DetectionWithoutCandidatesStartsALandmarkAtNoCorrection) {
  std::vector<Match> m = TwoCandidates();  // detection 0 only; detection 1 has none
  RandomStream rs(1, 1, 0, StreamPurpose::kAssociation);
  std::vector<Decision> out;
  double correction = 0;
  SampleDecisions(m, 2, kLogP0, &rs, &out, &correction);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].kind, Decision::kNew);
  // Detection 1 adds log p0 - log p0 = 0: the whole correction is detection 0's.
  const double drawn = out[0].kind == Decision::kNew ? kLogP0 : out[0].log_likelihood;
  EXPECT_NEAR(correction, kLogP0 + std::log(5.0) - drawn, 1e-12);
}

TEST(SampleDecisions, OverwhelmingLikelihoodIsAlwaysDrawn) {
  std::vector<Decision> out;
  for (uint32_t p = 0; p < 2000; ++p) {
    // exp(-60) against 1: the other hypotheses' share is below one uniform's resolution here.
    std::vector<Match> m = {Match{0, 3, kLogP0 - 60, 9.0}, Match{0, 4, kLogP0 + 60, 0.1}};
    RandomStream rs(2, 7, p, StreamPurpose::kAssociation);
    double correction = 0;
    SampleDecisions(m, 1, kLogP0, &rs, &out, &correction);
    ASSERT_EQ(out[0].kind, Decision::kAssociated);
    ASSERT_EQ(out[0].key, 4u);
    EXPECT_NEAR(correction, 0, 1e-20);
  }
}

// The draw depends on the stream and the matches, not on the order the query found them in.
TEST(SampleDecisions, SameStreamSameDrawWhateverTheMatchOrder) {
  std::vector<Match> base;
  for (uint32_t j = 0; j < 6; ++j) {
    for (uint64_t k = 0; k < 4; ++k) base.push_back(Match{j, 10 * k + j, kLogP0 + k - 1.0, 1});
  }
  for (uint32_t p = 0; p < 200; ++p) {
    std::vector<Match> a = base, b = base;
    std::reverse(b.begin(), b.end());
    std::rotate(b.begin(), b.begin() + p % b.size(), b.end());
    RandomStream ra(3, 4, p, StreamPurpose::kAssociation), rb(3, 4, p, StreamPurpose::kAssociation);
    std::vector<Decision> da, db;
    double ca = 0, cb = 0;
    SampleDecisions(a, 6, kLogP0, &ra, &da, &ca);
    SampleDecisions(b, 6, kLogP0, &rb, &db, &cb);
    ASSERT_EQ(da.size(), db.size());
    for (size_t j = 0; j < da.size(); ++j) {
      EXPECT_EQ(da[j].kind, db[j].kind) << p << " " << j;
      EXPECT_EQ(da[j].key, db[j].key) << p << " " << j;
    }
    EXPECT_EQ(ca, cb);
  }
}

}  // namespace
}  // namespace grove::fastslam
