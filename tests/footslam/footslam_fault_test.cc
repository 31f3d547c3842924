// Allocation failure inside a FootSLAM step, injected at the k-th node allocation: the step
// returns ResourceExhausted, the engine is latched failed, every shared node is still counted
// right, and destroying it frees everything (LeakSanitizer checks that in the sanitizer build).
#include <gtest/gtest.h>

#include <cmath>

#include "alloc/node_pool.h"
#include "grove/footslam.h"

namespace grove {
namespace {

struct FaultCase {
  const char* name;
  FootSlamConfig config;
};

std::vector<FaultCase> Cases() {
  FootSlamConfig htree;
  htree.particles = 300;
  htree.threads = 2;
  htree.batch = 64;
  FootSlamConfig plain = htree;
  plain.alphabet = 0;
  plain.degree = 4;
  plain.resample_threshold = 1.0;
  return {{"alphabet", htree}, {"degree 4, resample every step", plain}};
}

TEST(FootSlamFaultTest, AnAllocationFailureStopsTheEngineCleanly) {
  for (const FaultCase& c : Cases()) {
    int failures = 0;
    for (int64_t k = 0; k < 6000; k = k * 3 / 2 + 7) {
      SCOPED_TRACE(testing::Message() << c.name << ", fail after " << k);
      auto slam = FootSlam::Create(c.config);
      ASSERT_TRUE(slam.ok());
      FailAllocationsAfter(k);
      Status s;
      int step = 0;
      while (s.ok() && step < 200) {
        ++step;
        s = (*slam)->Step(step, 0.7 * std::cos(0.2 * step), 0.7 * std::sin(0.2 * step));
      }
      FailAllocationsAfter(-1);
      if (s.ok()) continue;  // the walk needed fewer than k nodes
      ++failures;
      EXPECT_EQ(s.code(), StatusCode::kResourceExhausted) << s.ToString();
      EXPECT_NE(s.message().find("step " + std::to_string(step)), std::string::npos) << s.message();
      EXPECT_EQ((*slam)->Step(step + 1, 0.7, 0).code(), StatusCode::kFailedPrecondition);
      EXPECT_EQ((*slam)->Checkpoint().status().code(), StatusCode::kFailedPrecondition);
      Status counts = (*slam)->CheckInvariants();
      EXPECT_TRUE(counts.ok()) << counts.ToString();
    }
    EXPECT_GT(failures, 5) << c.name;
  }
}

TEST(FootSlamFaultTest, CreateWithoutMemoryFailsCleanly) {
  FailAllocationsAfter(0);
  auto slam = FootSlam::Create(Cases()[0].config);
  FailAllocationsAfter(-1);
  EXPECT_EQ(slam.status().code(), StatusCode::kResourceExhausted) << slam.status().ToString();
}

}  // namespace
}  // namespace grove
