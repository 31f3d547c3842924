// The beacon tracker's C entry points (grove/c_api.h) over the generic layer (c_handle.h): its
// configuration's C members, its input (updates) and read-out (the mean state).
#include <vector>

#include "engine/bindings/c/c_handle.h"
#include "grove/c_api.h"
#include "grove/tracking.h"

namespace grove::capi {
namespace {

const ConfigBinding<TrackerConfig, grove_tracker_config>& Binding() {
  using C = grove_tracker_config;
  return BindOnce<TrackerConfig, C>(TrackerConfigFields(), [] {
    return std::vector<std::vector<CMember<C>>>{
        FilterMembers<C>(),
        {GROVE_C_MEMBER(C, start_x_m), GROVE_C_MEMBER(C, start_y_m),
         GROVE_C_MEMBER(C, start_vx_mps), GROVE_C_MEMBER(C, start_vy_mps),
         GROVE_C_MEMBER(C, initial_position_sigma_m), GROVE_C_MEMBER(C, initial_velocity_sigma_mps),
         GROVE_C_MEMBER(C, acceleration_sigma_mps2), GROVE_C_MEMBER(C, range_sigma_m)}};
  });
}

grove_tracker_summary SummaryToC(const TrackerSummary& s) {
  return grove_tracker_summary{FilterSummaryToC(s), s.measurements};
}

}  // namespace
}  // namespace grove::capi

struct grove_tracker : grove::capi::Handle<grove::Tracker> {};

namespace capi = grove::capi;

GROVE_C_MODEL_ENTRY_POINTS(grove_tracker, capi::Binding(), capi::SummaryToC)

grove_status grove_tracker_update(grove_tracker* tracker, double t_s,
                                  const grove_range_measurement* z, size_t n) {
  if (tracker != nullptr && z == nullptr && n != 0) return tracker->NullOut(__func__, "z");
  return capi::Stepping(tracker, [&](grove::Tracker& e) {
    std::vector<grove::RangeMeasurement> ranges(n);
    for (size_t k = 0; k < n; ++k) ranges[k] = {z[k].beacon_x_m, z[k].beacon_y_m, z[k].range_m};
    return e.Update(t_s, ranges);
  });
}

grove_status grove_tracker_set_start_time(grove_tracker* tracker, double t_s) {
  return capi::Stepping(tracker, [&](grove::Tracker& e) { return e.SetStartTime(t_s); });
}

grove_status grove_tracker_mean_state(grove_tracker* tracker, grove_target_state* state) {
  return capi::Get(tracker, __func__, state, "state", [](grove::Tracker& e) {
    const grove::TargetState s = e.MeanState();
    return grove_target_state{e.MeanTrajectory().back().t_s, s.x_m, s.y_m, s.vx_mps, s.vy_mps};
  });
}
