#include "tools/montecarlo/monte_carlo_scenario.h"

#include <fmt/format.h>

#include <filesystem>
#include <utility>

#include "tools/montecarlo/fnv1a.h"
#include "tools/montecarlo/scenario_file.h"

namespace grove::tools {

using nlohmann::json;

StatusOr<MonteCarloScenarioSpec> ParseMonteCarloScenario(const std::string& name, int64_t loops) {
  if (loops != 0 && (loops < 1 || loops > kMonteCarloMaxLoops)) {
    return InvalidArgumentError(
        fmt::format("--loops = {}: must be in 1..{}", loops, kMonteCarloMaxLoops));
  }
  MonteCarloScenarioSpec spec;
  if (name == "sim1" || name == "sim2" || name == "sim3") {
    spec.name = name;
    spec.preset = name;
    StatusOr<BaileySimOptions> preset = BaileyPreset(name);
    if (!preset.ok()) return preset.status();
    spec.sim = *preset;
    spec.map_bundle = name == "sim1" ? "webmap" : name;
    spec.association =
        name == "sim2" ? FastSlamAssociation::kMaximumLikelihood : FastSlamAssociation::kKnown;
  } else {
    std::error_code ec;
    const bool json_name = name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0;
    if (name.empty() || (!json_name && !std::filesystem::exists(name, ec))) {
      return InvalidArgumentError(
          fmt::format("--scenario = {}: must be sim1, sim2, sim3 or a scenario file FILE.json",
                      QuoteForMessage(name)));
    }
    StatusOr<MonteCarloScenarioSpec> file = ParseScenarioFile(name);
    if (!file.ok()) return file.status();
    spec = std::move(*file);
  }
  if (loops != 0) spec.sim.loops = static_cast<int32_t>(loops);
  if (Status s = spec.sim.Validate(); !s.ok()) {
    return InvalidArgumentError(fmt::format("{}: {}", spec.name, s.message()));
  }
  return spec;
}

StatusOr<MonteCarloScenario> LoadMonteCarloScenario(const MonteCarloScenarioSpec& spec) {
  MonteCarloScenario scenario;
  scenario.spec = spec;
  StatusOr<BaileyMap> map = InternalError("no map");
  if (!spec.map_path.empty()) {
    scenario.map_name = spec.map_path;
    map = ReadBaileyMap(spec.map_path);
  } else if (spec.map_bundle == "sim2") {
    scenario.map_name = EmbeddedSim2MapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedSim2Map());
  } else if (spec.map_bundle == "sim3") {
    scenario.map_name = EmbeddedSim3MapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedSim3Map());
  } else {
    scenario.map_name = EmbeddedBaileyWebmapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedBaileyWebmap());
  }
  if (!map.ok()) return map.status();
  scenario.map = std::move(*map);
  BaileySimOptions o = spec.sim;
  o.seed = 0;  // per run
  std::string canonical = fmt::format("grove fastslam montecarlo scenario 1\nassociation {}\n{}\n",
                                      AssociationName(spec.association), SimOptionsJson(o).dump());
  for (const BaileyPoint& p : scenario.map.landmarks) {
    canonical += fmt::format("lm {} {}\n", p.x_m, p.y_m);
  }
  for (const BaileyPoint& p : scenario.map.waypoints) {
    canonical += fmt::format("wp {} {}\n", p.x_m, p.y_m);
  }
  scenario.digest = Hex16(Fnv1a(canonical));
  return scenario;
}

const char* AssociationName(FastSlamAssociation a) {
  return a == FastSlamAssociation::kKnown ? "known" : "ml";
}

json SimOptionsJson(const BaileySimOptions& o) {
  return {{"speed_mps", o.speed_mps},
          {"wheelbase_m", o.wheelbase_m},
          {"max_steer_rad", o.max_steer_rad},
          {"max_steer_rate_radps", o.max_steer_rate_radps},
          {"at_waypoint_m", o.at_waypoint_m},
          {"loops", o.loops},
          {"dt_control_s", o.dt_control_s},
          {"dt_observe_s", o.dt_observe_s},
          {"max_range_m", o.max_range_m},
          {"field_of_view_rad", o.field_of_view_rad},
          {"sigma_speed_mps", o.sigma_speed_mps},
          {"sigma_steer_rad", o.sigma_steer_rad},
          {"sigma_range_m", o.sigma_range_m},
          {"sigma_bearing_rad", o.sigma_bearing_rad},
          {"start_x_m", o.start_x_m},
          {"start_y_m", o.start_y_m},
          {"start_heading_rad", o.start_heading_rad},
          {"max_steps", o.max_steps}};
}

}  // namespace grove::tools
