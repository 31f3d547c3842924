// TrackerConfig's field table, its validation and the summary's report.
#include <fmt/format.h>

#include "grove/tracking.h"

namespace grove {

namespace {

// The table: the filter's rows around the tracker's own, all reals that change results.
std::vector<ConfigField<TrackerConfig>> MakeTrackerFields() {
  using C = TrackerConfig;
  using I = Interval;
  std::vector<ConfigField<C>> own;
  auto real = [&own](const char* name, double C::*member, Interval range, const char* help) {
    own.push_back(RealField(name, member, range, kChangesResults, help));
  };
  real("start_x_m", &C::start_x_m, I::Closed(-1e9, 1e9), "Prior mean position x, metres");
  real("start_y_m", &C::start_y_m, I::Closed(-1e9, 1e9), "Prior mean position y, metres");
  real("start_vx_mps", &C::start_vx_mps, I::Closed(-1e6, 1e6), "Prior mean velocity x, m/s");
  real("start_vy_mps", &C::start_vy_mps, I::Closed(-1e6, 1e6), "Prior mean velocity y, m/s");
  real("initial_position_sigma_m", &C::initial_position_sigma_m, I::Closed(0, 1e6),
       "Prior spread of the position per axis, metres");
  real("initial_velocity_sigma_mps", &C::initial_velocity_sigma_mps, I::Closed(0, 1e6),
       "Prior spread of the velocity per axis, m/s");
  real("acceleration_sigma_mps2", &C::acceleration_sigma_mps2, I::Closed(0, 1e4),
       "Acceleration noise of the motion per axis, m/s^2");
  real("range_sigma_m", &C::range_sigma_m, I::LeftOpen(0, 1e6), "Range noise, metres");
  const FilterFieldRows<C> filter =
      FilterFields<C>("Resample after an update when ESS/N is below this; 1: every update");
  return JoinFields<C>({filter.population, own, filter.resampling, filter.speed});
}

}  // namespace

const std::vector<ConfigField<TrackerConfig>>& TrackerConfigFields() {
  // Never destroyed: read-outs of it may run during static destruction.
  static const auto* fields = new std::vector<ConfigField<TrackerConfig>>(MakeTrackerFields());
  return *fields;
}

Status TrackerConfig::Validate() const { return CheckFieldRanges(TrackerConfigFields(), *this); }

std::string TrackerSummary::BriefReport() const {
  return BriefFilterReport("Tracker") +
         fmt::format(
             "; {} ranges; last estimate ({:.2f}, {:.2f}) m moving at ({:.2f}, {:.2f}) "
             "m/s.",
             measurements, mean_state.x_m, mean_state.y_m, mean_state.vx_mps, mean_state.vy_mps);
}

}  // namespace grove
