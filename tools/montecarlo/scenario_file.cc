#include "tools/montecarlo/scenario_file.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <numbers>
#include <utility>
#include <variant>
#include <vector>

#include "engine/io/config_json.h"
#include "grove/config_fields.h"

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
  StatusOr<std::vector<ConfigEntry>> entries = ParseConfigObject(path, *text);
  if (!entries.ok()) return entries.status();
  std::map<std::string, FieldValue> values;
  const ConfigEntry* map_entry = nullptr;
  for (const ConfigEntry& e : *entries) {
    if (e.key == "map") {
      if (!e.value.is_string() || e.value.get<std::string>().empty()) {
        return InvalidArgumentError(fmt::format(
            "{}:{}:{}: map = {}: must be the path of a map file (a non-empty string), found {}",
            path, e.line, e.column,
            e.value.is_string() ? QuoteForMessage(e.value.get<std::string>())
                                : QuoteForMessage(e.value.dump()),
            e.value.type_name()));
      }
      map_entry = &e;
      continue;
    }
    const FieldInfo* info = nullptr;
    for (const FieldInfo& k : ScenarioKeys()) {
      if (e.key == k.name) info = &k;
    }
    if (info == nullptr) {
      std::vector<std::string> known = {"map"};
      for (const FieldInfo& k : ScenarioKeys()) known.push_back(k.name);
      return UnknownKeyError(path, e, known);
    }
    StatusOr<FieldValue> v = FieldValueFromJson(path, *info, e);
    if (!v.ok()) return v.status();
    values[e.key] = *v;
  }
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
  if (map_entry != nullptr) {
    std::filesystem::path map = map_entry->value.get<std::string>();
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
