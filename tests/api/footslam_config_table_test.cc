// FootSlamConfigFields(): the one table behind Validate(), JSON, flags and checkpoints.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"

namespace grove {
namespace {

// A valid configuration that differs from `base` in `field` only, or false if none is found.
bool OtherValue(const ConfigField<FootSlamConfig>& field, const FootSlamConfig& base,
                FootSlamConfig* out) {
  std::vector<FieldValue> candidates;
  FieldValue v = field.get(base);
  if (const int64_t* i = std::get_if<int64_t>(&v)) {
    for (int64_t c : {*i + 1, *i - 1, *i * 2, *i / 2, *i * 4, *i / 4}) candidates.push_back(c);
  } else if (const uint64_t* u = std::get_if<uint64_t>(&v)) {
    candidates.push_back(*u + 1);
  } else {
    const double d = std::get<double>(v);
    for (double c : {d + 0.1, d * 0.5, d * 0.5 + 0.01, d - 0.1}) candidates.push_back(c);
  }
  for (const FieldValue& c : candidates) {
    if (!CheckFieldValue(field.info, c).ok()) continue;
    FootSlamConfig changed = base;
    field.set(&changed, c);
    if (changed.Validate().ok()) {
      *out = changed;
      return true;
    }
  }
  return false;
}

FootSlamConfig Small() {
  FootSlamConfig c;
  c.particles = 50;
  c.threads = 1;
  c.grid_size = 256;
  return c;
}

// A tripwire: a member added to FootSlamConfig without a row in the table changes the size.
TEST(FootSlamConfigTableTest, EveryMemberHasARow) {
  EXPECT_EQ(FootSlamConfigFields().size(), 29u)
      << "add the new FootSlamConfig field to FootSlamConfigFields() and update this count";
  EXPECT_EQ(sizeof(FootSlamConfig), 216u)
      << "FootSlamConfig changed: give the new field a row in FootSlamConfigFields()";
  std::set<std::string> names;
  for (const auto& f : FootSlamConfigFields()) {
    EXPECT_TRUE(names.insert(f.info.name).second) << f.info.name << " twice";
    EXPECT_NE(std::string(f.info.help), "") << f.info.name;
    // The default configuration is in range for every field.
    EXPECT_TRUE(CheckFieldValue(f.info, f.get(FootSlamConfig{})).ok()) << f.info.name;
  }
}

// The checkpoint's field block holds exactly the result-changing fields: a checkpoint resumes
// under a configuration that differs in a speed-only field, and is refused, naming the field,
// under one that differs in any other.
TEST(FootSlamConfigTableTest, CheckpointBlockIsEveryResultChangingField) {
  FootSlamConfig base = Small();
  base.particles = 2 * 4096 + 1;  // room for two islands
  auto slam = FootSlam::Create(base);
  ASSERT_TRUE(slam.ok());
  for (int k = 1; k <= 5; ++k) ASSERT_TRUE((*slam)->Step(k, 0.7, 0.1).ok());
  StatusOr<std::string> checkpoint = (*slam)->Checkpoint();
  ASSERT_TRUE(checkpoint.ok());
  int result_fields = 0;
  for (const auto& f : FootSlamConfigFields()) {
    SCOPED_TRACE(f.info.name);
    FootSlamConfig other;
    ASSERT_TRUE(OtherValue(f, base, &other)) << "no other valid value to try";
    auto resumed = FootSlam::Resume(other, *checkpoint, "c.ckpt", nullptr);
    if (f.info.effect == kChangesResults) {
      ++result_fields;
      ASSERT_EQ(resumed.status().code(), StatusCode::kFailedPrecondition)
          << resumed.status().ToString();
      EXPECT_NE(resumed.status().message().find(std::string(f.info.name) + " = "),
                std::string::npos)
          << resumed.status().message();
    } else {
      EXPECT_TRUE(resumed.ok()) << resumed.status().ToString();
    }
  }
  EXPECT_EQ(result_fields, 27);
}

// Fields marked speed-only really change nothing but speed.
TEST(FootSlamConfigTableTest, SpeedOnlyFieldsDoNotChangeResults) {
  auto run = [](const FootSlamConfig& c) {
    auto slam = FootSlam::Create(c);
    EXPECT_TRUE(slam.ok());
    for (int k = 1; k <= 60; ++k) {
      EXPECT_TRUE((*slam)->Step(k, 0.7 * std::cos(0.3 * k), 0.7 * std::sin(0.3 * k)).ok());
    }
    return std::pair(ValueOf((*slam)->HeaviestTrajectory()), (*slam)->MeanTrajectory());
  };
  FootSlamConfig base = Small();
  base.particles = 3000;
  const auto expected = run(base);
  for (const auto& f : FootSlamConfigFields()) {
    if (f.info.effect != kChangesSpeedOnly) continue;
    SCOPED_TRACE(f.info.name);
    FootSlamConfig other;
    ASSERT_TRUE(OtherValue(f, base, &other));
    const auto got = run(other);
    ASSERT_EQ(got.first.size(), expected.first.size());
    for (size_t k = 0; k < got.first.size(); ++k) {
      ASSERT_EQ(got.first[k].pose.x_m, expected.first[k].pose.x_m) << k;
      ASSERT_EQ(got.second[k].pose.y_m, expected.second[k].pose.y_m) << k;
    }
  }
}

}  // namespace
}  // namespace grove
