// grove/config_json.h: configurations as JSON, seen from an embedder.
#include "grove/config_json.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "grove/footslam.h"
#include "grove/status.h"

namespace grove {
namespace {

const std::vector<ConfigField<FootSlamConfig>>& Fields() { return FootSlamConfigFields(); }

TEST(ConfigJsonTest, ApplySetsTheKeysGivenAndNoOthers) {
  FootSlamConfig config;
  config.threads = 3;
  ASSERT_TRUE(ApplyConfigJson(Fields(), "c.json",
                              R"({"particles": 1234, "map": "naive", "hex_radius_m": 0.75})",
                              &config)
                  .ok());
  EXPECT_EQ(config.particles, 1234);
  EXPECT_EQ(config.map, FootSlamMapKind::kNaive);
  EXPECT_EQ(config.hex_radius_m, 0.75);
  EXPECT_EQ(config.threads, 3);
  EXPECT_EQ(config.seed, FootSlamConfig{}.seed);
}

TEST(ConfigJsonTest, AFailedApplyLeavesTheConfigUnchangedAndNamesThePlace) {
  FootSlamConfig config;
  const Status s =
      ApplyConfigJson(Fields(), "c.json", "{\"particles\": 10,\n \"seed\": -1}", &config);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(), "c.json:2:2: seed = -1: must be a non-negative integer, found number");
  EXPECT_EQ(config.particles, FootSlamConfig{}.particles);
}

TEST(ConfigJsonTest, UnknownKeySuggestsTheNearestField) {
  FootSlamConfig config;
  const Status s = ApplyConfigJson(Fields(), "c.json", R"({"particels": 10})", &config);
  EXPECT_EQ(s.message(), R"(c.json:1:2: unknown key "particels" (did you mean "particles"?))");
}

TEST(ConfigJsonTest, ConfigToJsonReadsBackAsTheSameConfig) {
  FootSlamConfig config;
  config.particles = 777;
  config.seed = 18446744073709551615u;
  config.heading_sigma_rad = 0.1 + 0.2;
  config.weighting = FootSlamWeighting::kPriorRatio;
  FootSlamConfig back;
  ASSERT_TRUE(ApplyConfigJson(Fields(), "c.json", ConfigToJson(Fields(), config, 2), &back).ok());
  EXPECT_EQ(ConfigToJson(Fields(), back), ConfigToJson(Fields(), config));
  EXPECT_EQ(back.seed, config.seed);
  EXPECT_EQ(back.heading_sigma_rad, config.heading_sigma_rad);
}

TEST(ConfigJsonTest, ResultConfigToJsonLeavesOutFieldsThatChangeOnlySpeed) {
  FootSlamConfig config;
  const std::string all = ConfigToJson(Fields(), config);
  const std::string results = ResultConfigToJson(Fields(), config);
  EXPECT_NE(all.find("\"threads\":0"), std::string::npos) << all;
  EXPECT_NE(results.find("\"particles\":30000"), std::string::npos) << results;
  EXPECT_EQ(results.find("\"threads\""), std::string::npos) << results;
  EXPECT_EQ(results.find("\"batch\""), std::string::npos) << results;
}

// A scenario-like file: two fields of the caller's own and a key that is not a field.
std::vector<FieldInfo> ScenarioFields() {
  return {{"loops", "", FieldType::kInteger, kChangesResults, 1, 100, {}, {}},
          {"sigma_m", "", FieldType::kReal, kChangesResults, 0, 0, Interval::AtLeast(0), {}}};
}

TEST(ConfigJsonTest, ParseHandsTheCallersOwnKeysOverWithTheirPlace) {
  const std::vector<FieldInfo> fields = ScenarioFields();
  const std::vector<const FieldInfo*> infos = {&fields[0], &fields[1]};
  std::vector<FieldSetting> settings;
  std::vector<ConfigJsonKey> others;
  const Status s = ParseConfigJson(
      "s.json", "{\n  \"sigma_m\": 0.5,\n  \"map\": \"maps/a.txt\",\n  \"loops\": 3\n}", infos,
      &settings, {"map"}, [&](const ConfigJsonKey& k) {
        others.push_back(k);
        return Status::Ok();
      });
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(settings.size(), 2u);
  EXPECT_EQ(settings[0].field, 1u);
  EXPECT_EQ(std::get<double>(settings[0].value), 0.5);
  EXPECT_EQ(settings[1].field, 0u);
  EXPECT_EQ(std::get<int64_t>(settings[1].value), 3);
  ASSERT_EQ(others.size(), 1u);
  EXPECT_EQ(others[0].key, "map");
  EXPECT_EQ(others[0].value_json, "\"maps/a.txt\"");
  EXPECT_EQ(others[0].line, 3);
  EXPECT_EQ(others[0].column, 3);
}

TEST(ConfigJsonTest, ParseStopsAtTheFirstErrorInTextOrder) {
  const std::vector<FieldInfo> fields = ScenarioFields();
  const std::vector<const FieldInfo*> infos = {&fields[0], &fields[1]};
  std::vector<FieldSetting> settings;
  auto refuse = [](const ConfigJsonKey& k) {
    return InvalidArgumentError("s.json:" + std::to_string(k.line) + ": map refused");
  };
  // The caller's error on line 2 comes before the range error on line 3.
  EXPECT_EQ(
      ParseConfigJson("s.json", "{\n\"map\": 1,\n\"loops\": 0}", infos, &settings, {"map"}, refuse)
          .message(),
      "s.json:2: map refused");
  EXPECT_EQ(
      ParseConfigJson("s.json", "{\n\"loops\": 0,\n\"map\": 1}", infos, &settings, {"map"}, refuse)
          .message(),
      "s.json:2:1: loops = 0: must be in 1..100");
}

TEST(ConfigJsonTest, UnknownKeyMaySuggestOneOfTheCallersKeys) {
  const std::vector<FieldInfo> fields = ScenarioFields();
  const std::vector<const FieldInfo*> infos = {&fields[0], &fields[1]};
  std::vector<FieldSetting> settings;
  EXPECT_EQ(ParseConfigJson("s.json", R"({"mapp": "a"})", infos, &settings, {"map"}).message(),
            R"(s.json:1:2: unknown key "mapp" (did you mean "map"?))");
}

TEST(ConfigJsonTest, NearestKeySuggestsOnlyCloseKeys) {
  const std::vector<std::string> known = {"grid_size", "particles", "seed"};
  EXPECT_EQ(NearestKey("grid-size", known), "grid_size");
  EXPECT_EQ(NearestKey("sed", known), "seed");
  EXPECT_EQ(NearestKey("hexagon_radius", known), "");
}

TEST(ConfigJsonTest, ReadConfigFileTellsAMissingFileFromADirectory) {
  EXPECT_EQ(ReadConfigFile("/nonexistent/grove.json").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(ReadConfigFile("/").status().code(), StatusCode::kIoError);
}

}  // namespace
}  // namespace grove
