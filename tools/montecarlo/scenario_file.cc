#include "tools/montecarlo/scenario_file.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <utility>
#include <variant>
#include <vector>

#include "grove/config_fields.h"
#include "grove/config_json.h"

namespace grove::tools {
namespace {

// The scenario file's keys besides "map", typed and bounded as FastSlamConfig's fields are.
const std::vector<FieldInfo>& ScenarioKeys() {
  auto real = [](const char* name, Interval interval) {
    return FieldInfo{name, "", FieldType::kReal, kChangesResults, 0, 0, interval, {}};
  };
  auto choice = [](const char* name, std::vector<std::string> names) {
    const auto last = static_cast<int64_t>(names.size()) - 1;
    return FieldInfo{name, "", FieldType::kChoice, kChangesResults, 0, last, {}, std::move(names)};
  };
  static const auto* keys = new std::vector<FieldInfo>{
      choice("preset", {"webmap", "sim1", "sim2", "sim3"}),
      choice("association", {"known", "ml"}),
      {"loops", "", FieldType::kInteger, kChangesResults, 1, kMonteCarloMaxLoops, {}, {}},
      real("sigma_speed_mps", Interval::Closed(0, 100)),
      real("sigma_steer_rad", Interval::Closed(0, std::numbers::pi)),
      real("sigma_range_m", Interval::Closed(0, 1e4)),
      real("sigma_bearing_rad", Interval::Closed(0, std::numbers::pi)),
      real("max_range_m", Interval::LeftOpen(0, 1e6)),
  };
  return *keys;
}

}  // namespace

StatusOr<MonteCarloScenarioSpec> ParseScenarioFile(const std::string& path) {
  StatusOr<std::string> text = ReadConfigFile(path);
  if (!text.ok()) return text.status();
  std::vector<const FieldInfo*> keys;
  for (const FieldInfo& k : ScenarioKeys()) keys.push_back(&k);
  std::vector<FieldSetting> settings;
  std::optional<std::string> map_path;
  auto read_map = [&](const ConfigJsonKey& k) -> Status {
    const nlohmann::json v = nlohmann::json::parse(k.value_json);
    if (!v.is_string() || v.get<std::string>().empty()) {
      return InvalidArgumentError(fmt::format(
          "{}:{}:{}: map = {}: must be the path of a map file (a non-empty string), found {}", path,
          k.line, k.column,
          v.is_string() ? QuoteForMessage(v.get<std::string>()) : QuoteForMessage(v.dump()),
          v.type_name()));
    }
    map_path = v.get<std::string>();
    return Status::Ok();
  };
  GROVE_RETURN_IF_ERROR(ParseConfigJson(path, *text, keys, &settings, {"map"}, read_map));
  std::map<std::string, FieldValue> values;
  for (const FieldSetting& s : settings) values[keys[s.field]->name] = s.value;
  for (const char* required : {"preset", "association"}) {
    if (values.count(required) == 0) {
      return InvalidArgumentError(
          fmt::format("{}:1:1: missing key \"{}\" (a scenario needs \"preset\": webmap, sim1, "
                      "sim2 or sim3, and \"association\": known or ml)",
                      path, required));
    }
  }
  MonteCarloScenarioSpec spec;
  spec.name = path;
  spec.preset = ScenarioKeys()[0].choices[std::get<int64_t>(values["preset"])];
  StatusOr<BaileySimOptions> preset = BaileyPreset(spec.preset);
  if (!preset.ok()) return preset.status();
  spec.sim = *preset;
  spec.association = std::get<int64_t>(values["association"]) == 0
                         ? FastSlamAssociation::kKnown
                         : FastSlamAssociation::kMaximumLikelihood;
  if (map_path) {
    std::filesystem::path map = *map_path;
    if (map.is_relative()) map = std::filesystem::path(path).parent_path() / map;
    spec.map_path = map.string();
  } else {
    spec.map_bundle = "webmap";
  }
  auto real = [&](const char* key, double* field) {
    if (auto it = values.find(key); it != values.end()) *field = std::get<double>(it->second);
  };
  real("sigma_speed_mps", &spec.sim.sigma_speed_mps);
  real("sigma_steer_rad", &spec.sim.sigma_steer_rad);
  real("sigma_range_m", &spec.sim.sigma_range_m);
  real("sigma_bearing_rad", &spec.sim.sigma_bearing_rad);
  real("max_range_m", &spec.sim.max_range_m);
  if (auto it = values.find("loops"); it != values.end()) {
    spec.sim.loops = static_cast<int32_t>(std::get<int64_t>(it->second));
  }
  return spec;
}

}  // namespace grove::tools
