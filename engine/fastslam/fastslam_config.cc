// FastSlamConfig's field table, its validation, the names of its enums and the summary's report.
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <utility>

#include "grove/fastslam.h"

namespace grove {

const std::vector<ConfigField<FastSlamConfig>>& FastSlamConfigFields() {
  using C = FastSlamConfig;
  using I = Interval;
  constexpr double kPi = std::numbers::pi;
  // Never destroyed: read-outs of it may run during static destruction.
  static const auto* fields = new std::vector<ConfigField<C>>([] {
    const FilterFieldRows<C> filter =
        FilterFields<C>("Resample after a scan when ESS/N is below this; 1 resamples every scan");
    return JoinFields<C>(
        {filter.population,
         {
             ChoiceField("filter", &C::filter,
                         {"fastslam1", "fastslam2", "ufastslam", "srcd", "srcd_aided", "srcd_pf",
                          "de_srcd"},
                         kChangesResults,
                         "The filter: fastslam1, fastslam2, ufastslam (U-FastSLAM), srcd "
                         "(SRCD-FastSLAM), srcd_aided, srcd_pf (the seed's other SRCD variants), "
                         "de_srcd (DE-SRCD-FastSLAM)"),
             ChoiceField("vehicle", &C::vehicle, {"bailey", "guivant_nebot"}, kChangesResults,
                         "The vehicle model: bailey or guivant_nebot"),
             RealField("wheelbase_m", &C::wheelbase_m, I::LeftOpen(0, 100), kChangesResults,
                       "Distance between the axles, metres"),
             RealField("encoder_offset_m", &C::encoder_offset_m, I::Closed(-100, 100),
                       kChangesResults,
                       "guivant_nebot: rear axle centre to the encoder wheel, metres"),
             RealField("laser_forward_m", &C::laser_forward_m, I::Closed(-100, 100),
                       kChangesResults, "guivant_nebot: laser ahead of the rear axle, metres"),
             RealField("laser_left_m", &C::laser_left_m, I::Closed(-100, 100), kChangesResults,
                       "guivant_nebot: laser to the side of the axle centre, metres"),
             RealField("sigma_speed_mps", &C::sigma_speed_mps, I::Closed(0, 100), kChangesResults,
                       "Speed noise (standard deviation), m/s"),
             RealField("sigma_steer_rad", &C::sigma_steer_rad, I::Closed(0, kPi), kChangesResults,
                       "Steering angle noise (standard deviation), radians"),
             RealField("sigma_range_m", &C::sigma_range_m, I::Closed(0, 1e4), kChangesResults,
                       "Range noise (standard deviation), metres"),
             RealField("sigma_bearing_rad", &C::sigma_bearing_rad, I::Closed(0, kPi),
                       kChangesResults, "Bearing noise (standard deviation), radians"),
             RealField("start_x_m", &C::start_x_m, I::Closed(-1e9, 1e9), kChangesResults,
                       "Start position x, metres"),
             RealField("start_y_m", &C::start_y_m, I::Closed(-1e9, 1e9), kChangesResults,
                       "Start position y, metres"),
             RealField("start_heading_rad", &C::start_heading_rad, I::Closed(-1000, 1000),
                       kChangesResults, "Start heading, radians"),
         },
         filter.resampling,
         {
             RealField("ut_alpha", &C::ut_alpha, I::LeftOpen(0, 10), kChangesResults,
                       "ufastslam: the unscented transform's alpha"),
             RealField("ut_beta", &C::ut_beta, I::Closed(0, 100), kChangesResults,
                       "ufastslam: the unscented transform's beta"),
             RealField("ut_kappa", &C::ut_kappa, I::LeftOpen(-4, 100), kChangesResults,
                       "ufastslam: the unscented transform's kappa"),
             RealField("cd_step", &C::cd_step, I::Closed(1, 10), kChangesResults,
                       "srcd filters: the central-difference half-step h (sqrt(3) for Gaussians)"),
             RealField("de_scale", &C::de_scale, I::Closed(0, 2), kChangesResults,
                       "de_srcd: differential evolution's scale factor F"),
             RealField("de_crossover", &C::de_crossover, I::Closed(0, 1), kChangesResults,
                       "de_srcd: differential evolution's crossover probability Cr"),
             IntegerField("de_generations", &C::de_generations, 0, 255, kChangesResults,
                          "de_srcd: differential evolution's generations per scan"),
             ChoiceField("association", &C::association,
                         {"known", "ml", "ml_exclusive", "sampled", "jcbb"}, kChangesResults,
                         "Data association: known (observation ids), ml (maximum likelihood with "
                         "gates), ml_exclusive (ml, one landmark per detection in a scan), sampled "
                         "(each particle draws its associations, a new landmark included), jcbb "
                         "(joint compatibility branch and bound per scan)"),
             RealField("reject_gate", &C::reject_gate, I::LeftOpen(0, 1e6), kChangesResults,
                       "ml, jcbb: associate inside this gate (gate_unit)"),
             RealField("augment_gate", &C::augment_gate, I::LeftOpen(0, 1e6), kChangesResults,
                       "ml: a new landmark beyond this gate of every landmark (gate_unit)"),
             ChoiceField("gate_unit", &C::gate_unit, {"distance2", "probability"}, kChangesResults,
                         "ml: gates as squared Mahalanobis distances or chi-square probabilities"),
             ChoiceField("evidence", &C::evidence, {"off", "on"}, kChangesResults,
                         "ml: remove landmarks in view and not seen (existence evidence)"),
             IntegerField("evidence_threshold", &C::evidence_threshold, -1000000, 1000000,
                          kChangesResults,
                          "ml: remove a landmark when its evidence falls below this"),
             RealField("sensor_range_m", &C::sensor_range_m, I::LeftOpen(0, 1e6), kChangesResults,
                       "ml evidence: a landmark is in view within this range, metres"),
             RealField("sensor_fov_rad", &C::sensor_fov_rad, I::LeftOpen(0, 2 * kPi),
                       kChangesResults, "ml evidence: ... and within this field of view, radians"),
             RealField("index_cell_m", &C::index_cell_m, I::Closed(0.05, 1e4), kChangesResults,
                       "ml: cell side of the landmark index, metres (8 landmarks a cell)"),
         },
         filter.speed});
  }());
  return *fields;
}

Status FastSlamConfig::Validate() const {
  GROVE_RETURN_IF_ERROR(CheckFieldRanges(FastSlamConfigFields(), *this));
  if (vehicle == FastSlamVehicle::kGuivantNebot && !(encoder_offset_m < wheelbase_m)) {
    // 1 - tan(G) H / L > 0 must hold for small steering angles of either sign.
    return InvalidArgumentError(fmt::format(
        "encoder_offset_m = {}: must be below wheelbase_m = {} for the guivant_nebot vehicle",
        encoder_offset_m, wheelbase_m));
  }
  if (gate_unit == FastSlamGateUnit::kProbability) {
    for (auto [name, v] : {std::pair{"reject_gate", reject_gate}, {"augment_gate", augment_gate}}) {
      if (!(v < 1)) {
        return InvalidArgumentError(
            fmt::format("{} = {}: must be below 1 for gate_unit = probability", name, v));
      }
    }
  }
  if (!(augment_gate >= reject_gate)) {
    return InvalidArgumentError(fmt::format("augment_gate = {}: must be at least reject_gate = {}",
                                            augment_gate, reject_gate));
  }
  return Status::Ok();
}

double FastSlamGateDistance2(double gate, FastSlamGateUnit unit) {
  return unit == FastSlamGateUnit::kDistance2 ? gate : -2 * std::log1p(-gate);
}

const char* FastSlamFilterName(FastSlamFilter filter) {
  switch (filter) {
    case FastSlamFilter::kFastSlam1:
      return "fastslam1";
    case FastSlamFilter::kFastSlam2:
      return "fastslam2";
    case FastSlamFilter::kUnscented:
      return "ufastslam";
    case FastSlamFilter::kSrcd:
      return "srcd";
    case FastSlamFilter::kSrcdAided:
      return "srcd_aided";
    case FastSlamFilter::kSrcdParticle:
      return "srcd_pf";
    case FastSlamFilter::kDeSrcd:
      return "de_srcd";
  }
  return "unknown";
}
bool FastSlamFilterFromName(std::string_view name, FastSlamFilter* filter) {
  for (int k = 0; k <= static_cast<int>(FastSlamFilter::kDeSrcd); ++k) {
    if (name == FastSlamFilterName(static_cast<FastSlamFilter>(k))) {
      *filter = static_cast<FastSlamFilter>(k);
      return true;
    }
  }
  return false;
}

const char* FastSlamVehicleName(FastSlamVehicle vehicle) {
  return vehicle == FastSlamVehicle::kBailey ? "bailey" : "guivant_nebot";
}

std::string FastSlamSummary::BriefReport() const {
  return BriefFilterReport("FastSLAM") +
         fmt::format(
             "; {} controls, {} scans, {} observations, {} landmarks in the heaviest map; map {} "
             "live nodes ({:.1f} MiB, peak {:.1f} MiB), paths {} live nodes ({:.1f} MiB).",
             controls, scans, observations, landmarks, map_memory.live_nodes,
             map_memory.live_bytes / 1048576.0, map_memory.peak_live_bytes / 1048576.0,
             trajectory_memory.live_nodes, trajectory_memory.live_bytes / 1048576.0) +
         (association.associated + association.created + association.ignored == 0
              ? std::string()
              : fmt::format(" Association (heaviest particle): {} associated, {} new, {} "
                            "ignored, {} removed, {} dropped; {} of {} tagged associations wrong.",
                            association.associated, association.created, association.ignored,
                            association.removed, association.dropped, association.wrong,
                            association.tagged)) +
         (association.truncated == 0
              ? std::string()
              : fmt::format(" {} scans stopped at the joint compatibility search's node budget.",
                            association.truncated)) +
         (evolution.trials == 0 ? std::string()
                                : fmt::format(" Differential evolution: {} of {} trial poses "
                                              "accepted.",
                                              evolution.accepted, evolution.trials));
}

}  // namespace grove
