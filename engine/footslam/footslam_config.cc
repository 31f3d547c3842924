// FootSlamConfig's field table, its validation, the names of its enums and the summary's report.
#include <fmt/format.h>

#include <cmath>

#include "engine/filter/filter_options.h"
#include "engine/filter/resampler.h"
#include "engine/footslam/htree_layout.h"
#include "engine/ranks/collective.h"
#include "grove/footslam.h"

namespace grove {

const std::vector<ConfigField<FootSlamConfig>>& FootSlamConfigFields() {
  using C = FootSlamConfig;
  using I = Interval;
  // Never destroyed: read-outs of it may run during static destruction.
  static const auto* fields = new std::vector<ConfigField<C>>([] {
    const FilterFieldRows<C> filter =
        FilterFields<C>("Resample when ESS/N is below this; 1 resamples every step");
    return JoinFields<C>(
        {filter.population,
         {
             RealField("hex_radius_m", &C::hex_radius_m, I::LeftOpen(0, 1000), kChangesResults,
                       "Circumradius of the hexagons, metres"),
             RealField("prior_count", &C::prior_count, I::LeftOpen(0, 1e6), kChangesResults,
                       "Prior count added to every edge counter"),
             ChoiceField("weighting", &C::weighting, {"paper", "prior_ratio"}, kChangesResults,
                         "Weighting rule: paper or prior_ratio"),
             RealField("prior_map_confidence", &C::prior_map_confidence, I::Closed(0, 1e6),
                       kChangesResults, "Weight of a prior map's counts, added to the prior count"),
             RealField(
                 "store_distance_m", &C::store_distance_m, I::Closed(0, 1e9), kChangesResults,
                 "Store map areas this far from every particle (storage of diversity); 0: off"),
             RealField("start_x_m", &C::start_x_m, I::Closed(-1e12, 1e12), kChangesResults,
                       "Start position x in the map frame, metres"),
             RealField("start_y_m", &C::start_y_m, I::Closed(-1e12, 1e12), kChangesResults,
                       "Start position y in the map frame, metres"),
             RealField("start_heading_rad", &C::start_heading_rad, I::Closed(-1000, 1000),
                       kChangesResults, "Start heading in the map frame, radians"),
             RealField("initial_heading_sigma_rad", &C::initial_heading_sigma_rad, I::Closed(0, 10),
                       kChangesResults, "Initial spread of the heading error, radians"),
             RealField("heading_drift_sigma_rad", &C::heading_drift_sigma_rad, I::Closed(0, 10),
                       kChangesResults, "Random-walk step of the heading error per step, radians"),
             RealField("heading_sigma_rad", &C::heading_sigma_rad, I::Closed(0, 10),
                       kChangesResults, "White noise on each step's heading, radians"),
             RealField("scale_sigma", &C::scale_sigma, I::Closed(0, 10), kChangesResults,
                       "Initial spread of the step-length scale error"),
             RealField("scale_drift_sigma", &C::scale_drift_sigma, I::Closed(0, 10),
                       kChangesResults, "Random-walk step of the scale error per step"),
             RealField("step_length_sigma_m", &C::step_length_sigma_m, I::Closed(0, 100),
                       kChangesResults, "White noise on each step's length, metres"),
             RealField("position_sigma_m", &C::position_sigma_m, I::Closed(0, 100), kChangesResults,
                       "White noise on each step's end position, per axis, metres"),
         },
         filter.resampling,
         {
             ChoiceField("map", &C::map, {"htree", "naive"}, kChangesResults,
                         "Map representation: htree or naive"),
             IntegerField("degree", &C::degree, 1, 256, kChangesResults,
                          "H-tree degree: 4, 16, 64 or 256"),
             IntegerField("grid_size", &C::grid_size, 1, 65536, kChangesResults,
                          "Hexagons per grid side, a power of sqrt(degree)"),
             ChoiceField(
                 "grid", &C::grid, {"growing", "fixed"}, kChangesResults,
                 "Grid: growing (gains levels when a particle leaves it) or fixed (the paper's)"),
             IntegerField("alphabet", &C::alphabet, 0, 5, kChangesResults,
                          "Alphabet bound T; 0 switches the alphabet off"),
         },
         filter.speed});
  }());
  return *fields;
}

Status FootSlamConfig::Validate() const {
  GROVE_RETURN_IF_ERROR(CheckFieldRanges(FootSlamConfigFields(), *this));
  // The hexagon grid's coordinates are 32-bit integers.
  for (auto [name, v] : {std::pair{"start_x_m", start_x_m}, std::pair{"start_y_m", start_y_m}}) {
    if (std::fabs(v) > 1e9 * hex_radius_m) {
      return InvalidArgumentError(
          fmt::format("{} = {}: must be within 1e9 hexagon radii of the origin (hex_radius_m = "
                      "{}: |{}| <= {})",
                      name, v, hex_radius_m, name, 1e9 * hex_radius_m));
    }
  }
  GROVE_RETURN_IF_ERROR(CheckIslands(static_cast<uint64_t>(particles), islands, 1, kSumBlock));
  if (islands > 1) {
    if (resampling != ResamplingScheme::kSystematic) {
      return InvalidArgumentError(
          fmt::format("islands = {}: island mode resamples systematically (resampling = {})",
                      islands, ResamplingSchemeName(resampling)));
    }
  }
  StatusOr<footslam::HTreeLayout> layout = footslam::HTreeLayout::Create(grid_size, degree, grid);
  if (!layout.ok()) return layout.status();
  if (store_distance_m > 0 && map == FootSlamMapKind::kNaive) {
    return InvalidArgumentError(
        fmt::format("store_distance_m = {}: storage of diversity needs map = htree (map = naive)",
                    store_distance_m));
  }
  if (store_distance_m > 0 && layout->height() < 2) {
    return InvalidArgumentError(fmt::format(
        "store_distance_m = {}: storage of diversity needs grid_size >= degree (grid_size = {}, "
        "degree = {}): a stored block is a subtree below the first grid's root",
        store_distance_m, grid_size, degree));
  }
  return Status::Ok();
}

const char* FootSlamMapKindName(FootSlamMapKind kind) {
  return kind == FootSlamMapKind::kNaive ? "naive" : "htree";
}
bool ParseFootSlamMapKind(const std::string& name, FootSlamMapKind* kind) {
  if (name == "htree") {
    *kind = FootSlamMapKind::kHTree;
  } else if (name == "naive") {
    *kind = FootSlamMapKind::kNaive;
  } else {
    return false;
  }
  return true;
}
const char* FootSlamWeightingName(FootSlamWeighting w) {
  return w == FootSlamWeighting::kPaper ? "paper" : "prior_ratio";
}
bool ParseFootSlamWeighting(const std::string& name, FootSlamWeighting* w) {
  if (name == "paper") {
    *w = FootSlamWeighting::kPaper;
  } else if (name == "prior_ratio") {
    *w = FootSlamWeighting::kPriorRatio;
  } else {
    return false;
  }
  return true;
}

std::string FootSlamSummary::BriefReport() const {
  return BriefFilterReport("FootSLAM") +
         fmt::format(
             "; map {} live nodes ({:.1f} MiB, peak {:.1f} MiB), trajectory {} live nodes "
             "({:.1f} MiB).",
             map_memory.live_nodes, map_memory.live_bytes / 1048576.0,
             map_memory.peak_live_bytes / 1048576.0, trajectory_memory.live_nodes,
             trajectory_memory.live_bytes / 1048576.0);
}

}  // namespace grove
