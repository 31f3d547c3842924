// FootSLAM's C entry points (grove/c_api.h) over the generic layer (c_handle.h): its
// configuration's C members, its inputs (steps, the prior map) and read-outs (maps, summary).
#include <string>
#include <vector>

#include "engine/bindings/c/c_handle.h"
#include "grove/c_api.h"
#include "grove/footslam.h"

namespace grove::capi {
namespace {

static_assert(GROVE_FOOTSLAM_MAP_HTREE == static_cast<int>(FootSlamMapKind::kHTree));
static_assert(GROVE_FOOTSLAM_MAP_NAIVE == static_cast<int>(FootSlamMapKind::kNaive));
static_assert(GROVE_FOOTSLAM_WEIGHTING_PAPER == static_cast<int>(FootSlamWeighting::kPaper));
static_assert(GROVE_FOOTSLAM_WEIGHTING_PRIOR_RATIO ==
              static_cast<int>(FootSlamWeighting::kPriorRatio));
static_assert(GROVE_FOOTSLAM_GRID_GROWING == static_cast<int>(FootSlamGrid::kGrowing));
static_assert(GROVE_FOOTSLAM_GRID_FIXED == static_cast<int>(FootSlamGrid::kFixed));

const ConfigBinding<FootSlamConfig, grove_footslam_config>& Binding() {
  using C = grove_footslam_config;
  return BindOnce<FootSlamConfig, C>(FootSlamConfigFields(), [] {
    return std::vector<std::vector<CMember<C>>>{FilterMembers<C>(),
                                                IslandMembers<C>(),
                                                {GROVE_C_MEMBER(C, hex_radius_m),
                                                 GROVE_C_MEMBER(C, prior_count),
                                                 GROVE_C_MEMBER(C, weighting),
                                                 GROVE_C_MEMBER(C, start_x_m),
                                                 GROVE_C_MEMBER(C, start_y_m),
                                                 GROVE_C_MEMBER(C, start_heading_rad),
                                                 GROVE_C_MEMBER(C, initial_heading_sigma_rad),
                                                 GROVE_C_MEMBER(C, heading_drift_sigma_rad),
                                                 GROVE_C_MEMBER(C, heading_sigma_rad),
                                                 GROVE_C_MEMBER(C, scale_sigma),
                                                 GROVE_C_MEMBER(C, scale_drift_sigma),
                                                 GROVE_C_MEMBER(C, step_length_sigma_m),
                                                 GROVE_C_MEMBER(C, position_sigma_m),
                                                 GROVE_C_MEMBER(C, map),
                                                 GROVE_C_MEMBER(C, degree),
                                                 GROVE_C_MEMBER(C, grid_size),
                                                 GROVE_C_MEMBER(C, grid),
                                                 GROVE_C_MEMBER(C, prior_map_confidence),
                                                 GROVE_C_MEMBER(C, alphabet),
                                                 GROVE_C_MEMBER(C, store_distance_m)}};
  });
}

// grove_hex_counts and HexCounts hold the same fields.
template <typename To, typename From>
To HexAs(const From& h) {
  To out{};
  out.q = h.q;
  out.r = h.r;
  out.x_m = h.x_m;
  out.y_m = h.y_m;
  for (int i = 0; i < 6; ++i) out.counts[i] = h.counts[i];
  return out;
}
constexpr auto HexToC = HexAs<grove_hex_counts, HexCounts>;

grove_footslam_summary SummaryToC(const FootSlamSummary& s) {
  grove_footslam_summary out{};
  out.filter = FilterSummaryToC(s);
  out.mean_scale = s.mean_scale;
  out.mean_heading_error_rad = s.mean_heading_error_rad;
  out.map_memory = MemoryToC(s.map_memory);
  out.trajectory_memory = MemoryToC(s.trajectory_memory);
  out.grid_size = s.grid_size;
  out.prior_hexagons = s.prior_hexagons;
  out.prior_hexagons_outside = s.prior_hexagons_outside;
  out.stored_blocks = s.stored_blocks;
  out.stored_blocks_exact = s.stored_blocks_exact;
  out.stored_hexagons = s.stored_hexagons;
  out.store_s = s.store_s;
  return out;
}

// The maps, hexagons converted by HexToC.
template <typename Read>
grove_status Map(grove_footslam* h, const char* call, grove_hex_counts* out, size_t capacity,
                 size_t* count, Read read) noexcept {
  return ReadOut(
      h, call, out, capacity, count, [read](FootSlam& e) { return (e.*read)(); }, HexToC);
}

}  // namespace
}  // namespace grove::capi

struct grove_footslam : grove::capi::Handle<grove::FootSlam> {};

namespace capi = grove::capi;

GROVE_C_MODEL_ENTRY_POINTS(grove_footslam, capi::Binding(), capi::SummaryToC)
using grove::FootSlam;

grove_status grove_footslam_step(grove_footslam* slam, double t_s, double dx_m, double dy_m) {
  return capi::Stepping(slam, [&](FootSlam& e) { return e.Step(t_s, dx_m, dy_m); });
}

grove_status grove_footslam_steps(grove_footslam* slam, const double* t_s, const double* dx_m,
                                  const double* dy_m, size_t n, size_t* done) {
  if (done != nullptr) *done = 0;
  if (slam != nullptr && n > 0 && (t_s == nullptr || dx_m == nullptr || dy_m == nullptr)) {
    return capi::Guard(slam, [&] {
      return slam->Fail(GROVE_INVALID_ARGUMENT,
                        std::string(__func__) + ": an array is NULL with n = " + std::to_string(n));
    });
  }
  return capi::Stepping(slam, [&](FootSlam& e) {
    for (size_t i = 0; i < n; ++i) {
      grove::Status s = e.Step(t_s[i], dx_m[i], dy_m[i]);
      if (!s.ok())
        return grove::Status(s.code(), "steps[" + std::to_string(i) + "]: " + s.message());
      if (done != nullptr) *done = i + 1;
    }
    return grove::Status::Ok();
  });
}

grove_status grove_footslam_set_prior_map(grove_footslam* slam, const grove_hex_counts* hexes,
                                          size_t n) {
  if (slam != nullptr && hexes == nullptr && n != 0) return slam->NullOut(__func__, "hexes");
  return capi::Stepping(slam, [&](FootSlam& e) {
    std::vector<grove::HexCounts> map(n);
    for (size_t k = 0; k < n; ++k) map[k] = capi::HexAs<grove::HexCounts>(hexes[k]);
    return e.SetPriorMap(map);
  });
}

grove_status grove_footslam_set_start_time(grove_footslam* slam, double t_s) {
  return capi::Stepping(slam, [&](FootSlam& e) { return e.SetStartTime(t_s); });
}

grove_status grove_footslam_heaviest_trajectory(grove_footslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  return capi::Trajectory(slam, __func__, out, capacity, count, &FootSlam::HeaviestTrajectory);
}

grove_status grove_footslam_smoothed_trajectory(grove_footslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  return capi::Trajectory(slam, __func__, out, capacity, count, &FootSlam::SmoothedTrajectory);
}

grove_status grove_footslam_cumulative_map(grove_footslam* slam, grove_hex_counts* out,
                                           size_t capacity, size_t* count) {
  return capi::Map(slam, __func__, out, capacity, count, &FootSlam::CumulativeMap);
}

grove_status grove_footslam_heaviest_map(grove_footslam* slam, grove_hex_counts* out,
                                         size_t capacity, size_t* count) {
  return capi::Map(slam, __func__, out, capacity, count, &FootSlam::HeaviestMap);
}

grove_status grove_footslam_stored_map(grove_footslam* slam, grove_hex_counts* out, size_t capacity,
                                       size_t* count) {
  return capi::Map(slam, __func__, out, capacity, count, &FootSlam::StoredMap);
}
