// The C API (grove/c_api.h) over the public facades FootSlam and FastSlam. Every entry point
// catches everything: no exception crosses into C, and bad arguments become statuses.
#include "grove/c_api.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "grove/config_json.h"
#include "grove/fastslam.h"
#include "grove/footslam.h"
#include "grove/resampling.h"
#include "grove/status.h"
#include "grove/types.h"
#include "grove/version.h"

namespace grove {
namespace {

static_assert(GROVE_OK == static_cast<int>(StatusCode::kOk));
static_assert(GROVE_INVALID_ARGUMENT == static_cast<int>(StatusCode::kInvalidArgument));
static_assert(GROVE_NOT_FOUND == static_cast<int>(StatusCode::kNotFound));
static_assert(GROVE_OUT_OF_RANGE == static_cast<int>(StatusCode::kOutOfRange));
static_assert(GROVE_FAILED_PRECONDITION == static_cast<int>(StatusCode::kFailedPrecondition));
static_assert(GROVE_RESOURCE_EXHAUSTED == static_cast<int>(StatusCode::kResourceExhausted));
static_assert(GROVE_DATA_LOSS == static_cast<int>(StatusCode::kDataLoss));
static_assert(GROVE_IO_ERROR == static_cast<int>(StatusCode::kIoError));
static_assert(GROVE_INTERNAL == static_cast<int>(StatusCode::kInternal));

static_assert(GROVE_RESAMPLING_SYSTEMATIC == static_cast<int>(ResamplingScheme::kSystematic));
static_assert(GROVE_RESAMPLING_STRATIFIED == static_cast<int>(ResamplingScheme::kStratified));
static_assert(GROVE_RESAMPLING_RESIDUAL == static_cast<int>(ResamplingScheme::kResidual));
static_assert(GROVE_RESAMPLING_MULTINOMIAL == static_cast<int>(ResamplingScheme::kMultinomial));
static_assert(GROVE_FOOTSLAM_MAP_HTREE == static_cast<int>(FootSlamMapKind::kHTree));
static_assert(GROVE_FOOTSLAM_MAP_NAIVE == static_cast<int>(FootSlamMapKind::kNaive));
static_assert(GROVE_FOOTSLAM_WEIGHTING_PAPER == static_cast<int>(FootSlamWeighting::kPaper));
static_assert(GROVE_FOOTSLAM_WEIGHTING_PRIOR_RATIO ==
              static_cast<int>(FootSlamWeighting::kPriorRatio));
static_assert(GROVE_FASTSLAM_FILTER_FASTSLAM1 == static_cast<int>(FastSlamFilter::kFastSlam1));
static_assert(GROVE_FASTSLAM_FILTER_FASTSLAM2 == static_cast<int>(FastSlamFilter::kFastSlam2));
static_assert(GROVE_FASTSLAM_FILTER_UNSCENTED == static_cast<int>(FastSlamFilter::kUnscented));
static_assert(GROVE_FASTSLAM_FILTER_SRCD == static_cast<int>(FastSlamFilter::kSrcd));
static_assert(GROVE_FASTSLAM_FILTER_SRCD_AIDED == static_cast<int>(FastSlamFilter::kSrcdAided));
static_assert(GROVE_FASTSLAM_FILTER_SRCD_PARTICLE ==
              static_cast<int>(FastSlamFilter::kSrcdParticle));
static_assert(GROVE_FASTSLAM_FILTER_DE_SRCD == static_cast<int>(FastSlamFilter::kDeSrcd));
static_assert(GROVE_FASTSLAM_VEHICLE_BAILEY == static_cast<int>(FastSlamVehicle::kBailey));
static_assert(GROVE_FASTSLAM_VEHICLE_GUIVANT_NEBOT ==
              static_cast<int>(FastSlamVehicle::kGuivantNebot));
static_assert(GROVE_FASTSLAM_ASSOCIATION_KNOWN == static_cast<int>(FastSlamAssociation::kKnown));
static_assert(GROVE_FASTSLAM_ASSOCIATION_MAXIMUM_LIKELIHOOD ==
              static_cast<int>(FastSlamAssociation::kMaximumLikelihood));
static_assert(GROVE_FASTSLAM_ASSOCIATION_EXCLUSIVE ==
              static_cast<int>(FastSlamAssociation::kExclusive));
static_assert(GROVE_FASTSLAM_ASSOCIATION_SAMPLED ==
              static_cast<int>(FastSlamAssociation::kSampled));
static_assert(GROVE_FASTSLAM_GATE_DISTANCE2 == static_cast<int>(FastSlamGateUnit::kDistance2));
static_assert(GROVE_FASTSLAM_GATE_PROBABILITY == static_cast<int>(FastSlamGateUnit::kProbability));
static_assert(GROVE_FASTSLAM_EVIDENCE_OFF == static_cast<int>(FastSlamEvidence::kOff));
static_assert(GROVE_FASTSLAM_EVIDENCE_ON == static_cast<int>(FastSlamEvidence::kOn));
// The enumerations' underlying types are int (fixed), so every int the C struct holds is a
// value of the enum; Validate() refuses the ones outside the named choices.
static_assert(std::is_same_v<std::underlying_type_t<FootSlamWeighting>, int>);
static_assert(std::is_same_v<std::underlying_type_t<FastSlamFilter>, int>);

constexpr const char* kOutOfMemoryMessage = "out of memory";

// The message of a handle's last failed call. Recording never throws: when the message cannot
// be copied, a static one stands in.
class ErrorSlot {
 public:
  void Clear() noexcept {
    message_.clear();
    fallback_ = nullptr;
  }
  void Set(std::string_view message) noexcept {
    try {
      message_.assign(message.data(), message.size());
      fallback_ = nullptr;
    } catch (...) {
      message_.clear();
      fallback_ = kOutOfMemoryMessage;
    }
  }
  const char* c_str() const noexcept { return fallback_ != nullptr ? fallback_ : message_.c_str(); }

 private:
  std::string message_;
  const char* fallback_ = nullptr;
};

// A read-out computed by a call, kept from a size query to its fill while no stepping call
// came in between (`version` is the handle's count of stepping calls when it was computed).
template <typename T>
struct Kept {
  bool valid = false;
  uint64_t version = 0;
  T value;
  void Release() noexcept {
    valid = false;
    T().swap(value);
  }
};

// What both handles share: the error slot and the count of stepping calls.
struct HandleBase {
  ErrorSlot error;
  uint64_t version = 0;

  grove_status Ok() noexcept {
    error.Clear();
    return GROVE_OK;
  }
  grove_status Fail(const Status& s) noexcept {
    error.Set(s.message());
    return static_cast<grove_status>(s.code());
  }
  grove_status Fail(grove_status code, std::string_view message) noexcept {
    error.Set(message);
    return code;
  }
};

grove_status ToC(StatusCode code) { return static_cast<grove_status>(code); }

// Runs `f` (-> grove_status) on handle `h`, turning any exception into a status recorded in
// the handle.
template <typename Handle, typename F>
grove_status Guard(Handle* h, F&& f) noexcept {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    return h->Fail(GROVE_RESOURCE_EXHAUSTED, kOutOfMemoryMessage);
  } catch (const std::exception& e) {
    try {
      return h->Fail(GROVE_INTERNAL, std::string("unexpected exception: ") + e.what());
    } catch (...) {
      return h->Fail(GROVE_INTERNAL, "unexpected exception");
    }
  } catch (...) {
    return h->Fail(GROVE_INTERNAL, "unexpected exception");
  }
}

// Copies `message` into the caller's buffer, cut to fit and NUL-terminated.
void WriteError(std::string_view message, char* error, size_t error_size) noexcept {
  if (error == nullptr || error_size == 0) return;
  const size_t n = std::min(message.size(), error_size - 1);
  if (n > 0) std::memcpy(error, message.data(), n);
  error[n] = '\0';
}

// Runs `f` (-> Status) for a call that makes a handle, writing its message (or "") into the
// caller's buffer; no exception escapes.
template <typename F>
grove_status GuardCreate(char* error, size_t error_size, F&& f) noexcept {
  Status s;
  try {
    s = f();
  } catch (const std::bad_alloc&) {
    WriteError(kOutOfMemoryMessage, error, error_size);
    return GROVE_RESOURCE_EXHAUSTED;
  } catch (const std::exception& e) {
    WriteError(e.what(), error, error_size);
    return GROVE_INTERNAL;
  } catch (...) {
    WriteError("unexpected exception", error, error_size);
    return GROVE_INTERNAL;
  }
  WriteError(s.ok() ? std::string_view() : std::string_view(s.message()), error, error_size);
  return ToC(s.code());
}

grove_pose ToC(const StampedPose& p) {
  return grove_pose{p.t_s, p.pose.x_m, p.pose.y_m, p.pose.heading_rad};
}

grove_hex_counts ToC(const HexCounts& h) {
  grove_hex_counts out{};
  out.q = h.q;
  out.r = h.r;
  out.x_m = h.x_m;
  out.y_m = h.y_m;
  for (int i = 0; i < 6; ++i) out.counts[i] = h.counts[i];
  return out;
}

HexCounts ToCpp(const grove_hex_counts& h) {
  HexCounts out;
  out.q = h.q;
  out.r = h.r;
  out.x_m = h.x_m;
  out.y_m = h.y_m;
  for (int i = 0; i < 6; ++i) out.counts[i] = h.counts[i];
  return out;
}

grove_landmark_estimate ToC(const LandmarkEstimate& e) {
  return grove_landmark_estimate{e.id, e.x_m, e.y_m, e.sxx, e.sxy, e.syy, e.source_id};
}

grove_memory_use ToC(const MemoryUse& m) {
  return grove_memory_use{m.live_nodes, m.live_bytes, m.peak_live_nodes, m.peak_live_bytes,
                          m.reserved_bytes};
}

grove_filter_summary ToC(const FilterSummary& s) {
  grove_filter_summary out{};
  out.particles = s.particles;
  out.threads_requested = s.threads_requested;
  out.threads_used = s.threads_used;
  out.steps = s.steps;
  out.resamplings = s.resamplings;
  out.mean_ess = s.mean_ess;
  out.advance_s = s.advance_s;
  out.normalize_s = s.normalize_s;
  out.resample_s = s.resample_s;
  out.release_s = s.release_s;
  out.bookkeeping_s = s.bookkeeping_s;
  out.filter_s = s.filter_s();
  return out;
}

// ---- Configurations ----

FootSlamConfig ToCpp(const grove_footslam_config& c) {
  FootSlamConfig o;
  o.particles = c.particles;
  o.seed = c.seed;
  o.hex_radius_m = c.hex_radius_m;
  o.prior_count = c.prior_count;
  o.weighting = static_cast<FootSlamWeighting>(c.weighting);
  o.start_x_m = c.start_x_m;
  o.start_y_m = c.start_y_m;
  o.start_heading_rad = c.start_heading_rad;
  o.initial_heading_sigma_rad = c.initial_heading_sigma_rad;
  o.heading_drift_sigma_rad = c.heading_drift_sigma_rad;
  o.heading_sigma_rad = c.heading_sigma_rad;
  o.scale_sigma = c.scale_sigma;
  o.scale_drift_sigma = c.scale_drift_sigma;
  o.step_length_sigma_m = c.step_length_sigma_m;
  o.position_sigma_m = c.position_sigma_m;
  o.resampling = static_cast<ResamplingScheme>(c.resampling);
  o.resample_threshold = c.resample_threshold;
  o.map = static_cast<FootSlamMapKind>(c.map);
  o.degree = c.degree;
  o.grid_size = c.grid_size;
  o.grid = static_cast<FootSlamGrid>(c.grid);
  o.prior_map_confidence = c.prior_map_confidence;
  o.alphabet = c.alphabet;
  o.store_distance_m = c.store_distance_m;
  o.islands = c.islands;
  o.island_exchange_steps = c.island_exchange_steps;
  o.island_exchange_fraction = c.island_exchange_fraction;
  o.threads = c.threads;
  o.batch = c.batch;
  return o;
}

grove_footslam_config ToC(const FootSlamConfig& c) {
  grove_footslam_config o{};
  o.particles = c.particles;
  o.seed = c.seed;
  o.hex_radius_m = c.hex_radius_m;
  o.prior_count = c.prior_count;
  o.weighting = static_cast<int>(c.weighting);
  o.start_x_m = c.start_x_m;
  o.start_y_m = c.start_y_m;
  o.start_heading_rad = c.start_heading_rad;
  o.initial_heading_sigma_rad = c.initial_heading_sigma_rad;
  o.heading_drift_sigma_rad = c.heading_drift_sigma_rad;
  o.heading_sigma_rad = c.heading_sigma_rad;
  o.scale_sigma = c.scale_sigma;
  o.scale_drift_sigma = c.scale_drift_sigma;
  o.step_length_sigma_m = c.step_length_sigma_m;
  o.position_sigma_m = c.position_sigma_m;
  o.resampling = static_cast<int>(c.resampling);
  o.resample_threshold = c.resample_threshold;
  o.map = static_cast<int>(c.map);
  o.degree = c.degree;
  o.grid_size = c.grid_size;
  o.grid = static_cast<int>(c.grid);
  o.prior_map_confidence = c.prior_map_confidence;
  o.alphabet = c.alphabet;
  o.store_distance_m = c.store_distance_m;
  o.islands = c.islands;
  o.island_exchange_steps = c.island_exchange_steps;
  o.island_exchange_fraction = c.island_exchange_fraction;
  o.threads = c.threads;
  o.batch = c.batch;
  return o;
}

FastSlamConfig ToCpp(const grove_fastslam_config& c) {
  FastSlamConfig o;
  o.particles = c.particles;
  o.seed = c.seed;
  o.filter = static_cast<FastSlamFilter>(c.filter);
  o.vehicle = static_cast<FastSlamVehicle>(c.vehicle);
  o.wheelbase_m = c.wheelbase_m;
  o.encoder_offset_m = c.encoder_offset_m;
  o.laser_forward_m = c.laser_forward_m;
  o.laser_left_m = c.laser_left_m;
  o.sigma_speed_mps = c.sigma_speed_mps;
  o.sigma_steer_rad = c.sigma_steer_rad;
  o.sigma_range_m = c.sigma_range_m;
  o.sigma_bearing_rad = c.sigma_bearing_rad;
  o.start_x_m = c.start_x_m;
  o.start_y_m = c.start_y_m;
  o.start_heading_rad = c.start_heading_rad;
  o.resampling = static_cast<ResamplingScheme>(c.resampling);
  o.resample_threshold = c.resample_threshold;
  o.ut_alpha = c.ut_alpha;
  o.ut_beta = c.ut_beta;
  o.ut_kappa = c.ut_kappa;
  o.cd_step = c.cd_step;
  o.de_scale = c.de_scale;
  o.de_crossover = c.de_crossover;
  o.de_generations = c.de_generations;
  o.association = static_cast<FastSlamAssociation>(c.association);
  o.reject_gate = c.reject_gate;
  o.augment_gate = c.augment_gate;
  o.gate_unit = static_cast<FastSlamGateUnit>(c.gate_unit);
  o.evidence = static_cast<FastSlamEvidence>(c.evidence);
  o.evidence_threshold = c.evidence_threshold;
  o.sensor_range_m = c.sensor_range_m;
  o.sensor_fov_rad = c.sensor_fov_rad;
  o.index_cell_m = c.index_cell_m;
  o.threads = c.threads;
  o.batch = c.batch;
  return o;
}

grove_fastslam_config ToC(const FastSlamConfig& c) {
  grove_fastslam_config o{};
  o.particles = c.particles;
  o.seed = c.seed;
  o.filter = static_cast<int>(c.filter);
  o.vehicle = static_cast<int>(c.vehicle);
  o.wheelbase_m = c.wheelbase_m;
  o.encoder_offset_m = c.encoder_offset_m;
  o.laser_forward_m = c.laser_forward_m;
  o.laser_left_m = c.laser_left_m;
  o.sigma_speed_mps = c.sigma_speed_mps;
  o.sigma_steer_rad = c.sigma_steer_rad;
  o.sigma_range_m = c.sigma_range_m;
  o.sigma_bearing_rad = c.sigma_bearing_rad;
  o.start_x_m = c.start_x_m;
  o.start_y_m = c.start_y_m;
  o.start_heading_rad = c.start_heading_rad;
  o.resampling = static_cast<int>(c.resampling);
  o.resample_threshold = c.resample_threshold;
  o.ut_alpha = c.ut_alpha;
  o.ut_beta = c.ut_beta;
  o.ut_kappa = c.ut_kappa;
  o.cd_step = c.cd_step;
  o.de_scale = c.de_scale;
  o.de_crossover = c.de_crossover;
  o.de_generations = c.de_generations;
  o.association = static_cast<int>(c.association);
  o.reject_gate = c.reject_gate;
  o.augment_gate = c.augment_gate;
  o.gate_unit = static_cast<int>(c.gate_unit);
  o.evidence = static_cast<int>(c.evidence);
  o.evidence_threshold = c.evidence_threshold;
  o.sensor_range_m = c.sensor_range_m;
  o.sensor_fov_rad = c.sensor_fov_rad;
  o.index_cell_m = c.index_cell_m;
  o.threads = c.threads;
  o.batch = c.batch;
  return o;
}

// The keys of `json` applied over `*config`, then validated; `*config` unchanged on error.
template <typename Config>
Status ConfigFromJson(const std::vector<ConfigField<Config>>& fields, const char* json,
                      Config* config) {
  if (json == nullptr) return InvalidArgumentError("json is NULL");
  Config result = *config;
  GROVE_RETURN_IF_ERROR(ApplyConfigJson(fields, "config", std::string(json), &result));
  GROVE_RETURN_IF_ERROR(result.Validate());
  *config = result;
  return Status::Ok();
}

// ---- Array read-outs under the size-query rule (grove/c_api.h) ----

// Checks (out, capacity, count) before anything is computed.
template <typename Handle, typename Out>
bool CheckArrayArgs(Handle* h, const char* call, const Out* out, size_t capacity,
                    const size_t* count, grove_status* result) {
  if (count == nullptr) {
    *result = h->Fail(GROVE_INVALID_ARGUMENT, std::string(call) + ": count is NULL");
    return false;
  }
  if (out == nullptr && capacity != 0) {
    *result =
        h->Fail(GROVE_INVALID_ARGUMENT, std::string(call) + ": out is NULL but capacity is " +
                                            std::to_string(capacity) + " (a size query passes 0)");
    return false;
  }
  return true;
}

// Copies `items` into `out` converted by ToC, under the size-query rule; true when the fill
// was done (the kept copy may then be released).
template <typename Handle, typename In, typename Out>
grove_status CopyOut(Handle* h, const char* call, const std::vector<In>& items, Out* out,
                     size_t capacity, size_t* count, bool* filled) {
  *filled = false;
  *count = items.size();
  if (out == nullptr) return h->Ok();
  if (capacity < items.size()) {
    return h->Fail(GROVE_OUT_OF_RANGE,
                   std::string(call) + ": capacity " + std::to_string(capacity) + " < " +
                       std::to_string(items.size()) + " needed (the size is in *count)");
  }
  for (size_t i = 0; i < items.size(); ++i) out[i] = ToC(items[i]);
  *filled = true;
  return h->Ok();
}

// A computed read-out: from `kept` when still valid, else by `compute` (-> StatusOr<T>).
template <typename Handle, typename T, typename Compute>
Status Refresh(Handle* h, Kept<T>* kept, Compute&& compute) {
  if (kept->valid && kept->version == h->version) return Status::Ok();
  kept->Release();
  auto value = compute();
  if (!value.ok()) return value.status();
  kept->value = std::move(*value);
  kept->valid = true;
  kept->version = h->version;
  return Status::Ok();
}

template <typename Handle, typename In, typename Out, typename Compute>
grove_status ComputedArray(Handle* h, const char* call, Kept<std::vector<In>>* kept,
                           Compute&& compute, Out* out, size_t capacity, size_t* count) {
  grove_status result = GROVE_OK;
  if (!CheckArrayArgs(h, call, out, capacity, count, &result)) return result;
  Status s = Refresh(h, kept, compute);
  if (!s.ok()) return h->Fail(s);
  bool filled = false;
  result = CopyOut(h, call, kept->value, out, capacity, count, &filled);
  if (filled) kept->Release();
  return result;
}

template <typename Handle, typename Compute>
grove_status ComputedBytes(Handle* h, const char* call, Kept<std::string>* kept, Compute&& compute,
                           void* buffer, size_t capacity, size_t* size) {
  grove_status result = GROVE_OK;
  if (!CheckArrayArgs(h, call, buffer, capacity, size, &result)) return result;
  Status s = Refresh(h, kept, compute);
  if (!s.ok()) return h->Fail(s);
  const std::string& bytes = kept->value;
  *size = bytes.size();
  if (buffer == nullptr) return h->Ok();
  if (capacity < bytes.size()) {
    return h->Fail(GROVE_OUT_OF_RANGE,
                   std::string(call) + ": capacity " + std::to_string(capacity) + " < " +
                       std::to_string(bytes.size()) + " bytes needed (the size is in *size)");
  }
  if (!bytes.empty()) std::memcpy(buffer, bytes.data(), bytes.size());
  kept->Release();
  return h->Ok();
}

// The last pose of a mean trajectory with `pose` (its time, or 0 with no trajectory yet).
grove_pose PoseAt(const std::vector<StampedPose>& trajectory, const Pose2& pose) {
  const double t = trajectory.empty() ? 0.0 : trajectory.back().t_s;
  return grove_pose{t, pose.x_m, pose.y_m, pose.heading_rad};
}

}  // namespace
}  // namespace grove

struct grove_footslam : grove::HandleBase {
  std::unique_ptr<grove::FootSlam> slam;
  grove::Kept<std::vector<grove::StampedPose>> heaviest_trajectory;
  grove::Kept<std::vector<grove::StampedPose>> smoothed_trajectory;
  grove::Kept<std::vector<grove::HexCounts>> cumulative_map;
  grove::Kept<std::vector<grove::HexCounts>> heaviest_map;
  grove::Kept<std::vector<grove::HexCounts>> stored_map;
  grove::Kept<std::string> checkpoint;
};

struct grove_fastslam : grove::HandleBase {
  std::unique_ptr<grove::FastSlam> slam;
  grove::Kept<std::vector<grove::StampedPose>> heaviest_trajectory;
  grove::Kept<std::vector<grove::LandmarkEstimate>> landmarks;
  grove::Kept<std::string> checkpoint;
};

namespace {

// A null handle cannot record its error; every call reports it by status only.
constexpr grove_status kNullHandle = GROVE_INVALID_ARGUMENT;

template <typename Handle>
grove_status NullOut(Handle* h, const char* call, const char* what) noexcept {
  return h->Fail(GROVE_INVALID_ARGUMENT, std::string(call) + ": " + what + " is NULL");
}

// Makes a handle of type Handle around the engine `made` (a StatusOr<unique_ptr<Engine>>).
template <typename Handle, typename Engine>
grove::Status Adopt(grove::StatusOr<std::unique_ptr<Engine>> made, Handle** out) {
  if (!made.ok()) return made.status();
  auto handle = std::make_unique<Handle>();
  handle->slam = std::move(*made);
  *out = handle.release();
  return grove::Status::Ok();
}

// The configuration tables, by configuration type.
const auto& FieldsOf(const grove::FootSlamConfig&) { return grove::FootSlamConfigFields(); }
const auto& FieldsOf(const grove::FastSlamConfig&) { return grove::FastSlamConfigFields(); }

// What both models' config_from_json, create, create_json, resume and mean_trajectory do;
// Engine is grove::FootSlam or grove::FastSlam, CConfig and Handle its C types.
template <typename CConfig>
grove_status ConfigFromJsonC(const char* json, CConfig* config, char* error, size_t error_size) {
  return grove::GuardCreate(error, error_size, [&]() -> grove::Status {
    if (config == nullptr) return grove::InvalidArgumentError("config is NULL");
    auto c = grove::ToCpp(*config);
    GROVE_RETURN_IF_ERROR(grove::ConfigFromJson(FieldsOf(c), json, &c));
    *config = grove::ToC(c);
    return grove::Status::Ok();
  });
}

template <typename Engine, typename CConfig, typename Handle>
grove_status CreateC(const CConfig* config, Handle** out, char* error, size_t error_size) {
  return grove::GuardCreate(error, error_size, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    *out = nullptr;
    if (config == nullptr) return grove::InvalidArgumentError("config is NULL");
    return Adopt(Engine::Create(grove::ToCpp(*config)), out);
  });
}

template <typename Engine, typename Handle>
grove_status CreateJsonC(const char* json, Handle** out, char* error, size_t error_size) {
  return grove::GuardCreate(error, error_size, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    *out = nullptr;
    std::decay_t<decltype(std::declval<const Engine&>().config())> c;
    GROVE_RETURN_IF_ERROR(grove::ConfigFromJson(FieldsOf(c), json, &c));
    return Adopt(Engine::Create(c), out);
  });
}

template <typename Engine, typename CConfig, typename Handle>
grove_status ResumeC(const CConfig* config, const void* data, size_t size, Handle** out,
                     char* error, size_t error_size) {
  return grove::GuardCreate(error, error_size, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    *out = nullptr;
    if (config == nullptr) return grove::InvalidArgumentError("config is NULL");
    if (data == nullptr && size != 0) {
      return grove::InvalidArgumentError("data is NULL with size " + std::to_string(size));
    }
    const std::string_view bytes(data == nullptr ? "" : static_cast<const char*>(data), size);
    return Adopt(Engine::Resume(grove::ToCpp(*config), bytes, "checkpoint", nullptr), out);
  });
}

template <typename Handle>
grove_status MeanTrajectoryC(Handle* slam, const char* call, grove_pose* out, size_t capacity,
                             size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    grove_status result = GROVE_OK;
    if (!grove::CheckArrayArgs(slam, call, out, capacity, count, &result)) return result;
    bool filled = false;
    return grove::CopyOut(slam, call, slam->slam->MeanTrajectory(), out, capacity, count, &filled);
  });
}

}  // namespace

// ---- Status and version ----

const char* grove_status_name(grove_status status) {
  const int code = static_cast<int>(status);
  if (code < GROVE_OK || code > GROVE_INTERNAL) return "unknown";
  return grove::StatusCodeName(static_cast<grove::StatusCode>(status));
}

const char* grove_version(void) {
  try {
    static const std::string* const version = new std::string(grove::VersionString());
    return version->c_str();
  } catch (...) {
    return "grove (version unavailable: out of memory)";
  }
}

void grove_version_numbers(int* major, int* minor, int* patch) {
  if (major != nullptr) *major = GROVE_VERSION_MAJOR;
  if (minor != nullptr) *minor = GROVE_VERSION_MINOR;
  if (patch != nullptr) *patch = GROVE_VERSION_PATCH;
}

// ---- FootSLAM ----

void grove_footslam_config_default(grove_footslam_config* config) {
  if (config != nullptr) *config = grove::ToC(grove::FootSlamConfig());
}

grove_status grove_footslam_config_from_json(const char* json, grove_footslam_config* config,
                                             char* error, size_t error_size) {
  return ConfigFromJsonC(json, config, error, error_size);
}

grove_status grove_footslam_create(const grove_footslam_config* config, grove_footslam** out,
                                   char* error, size_t error_size) {
  return CreateC<grove::FootSlam>(config, out, error, error_size);
}

grove_status grove_footslam_create_json(const char* json, grove_footslam** out, char* error,
                                        size_t error_size) {
  return CreateJsonC<grove::FootSlam>(json, out, error, error_size);
}

void grove_footslam_destroy(grove_footslam* slam) {
  try {
    delete slam;
  } catch (...) {
    // A destructor that throws is a bug in the engine; it must not reach C.
  }
}

const char* grove_footslam_last_error(const grove_footslam* slam) {
  return slam == nullptr ? "" : slam->error.c_str();
}

grove_status grove_footslam_step(grove_footslam* slam, double t_s, double dx_m, double dy_m) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    ++slam->version;
    grove::Status s = slam->slam->Step(t_s, dx_m, dy_m);
    return s.ok() ? slam->Ok() : slam->Fail(s);
  });
}

grove_status grove_footslam_steps(grove_footslam* slam, const double* t_s, const double* dx_m,
                                  const double* dy_m, size_t n, size_t* done) {
  if (done != nullptr) *done = 0;
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    if (n > 0 && (t_s == nullptr || dx_m == nullptr || dy_m == nullptr)) {
      return slam->Fail(GROVE_INVALID_ARGUMENT,
                        "grove_footslam_steps: an array is NULL with n = " + std::to_string(n));
    }
    ++slam->version;
    for (size_t i = 0; i < n; ++i) {
      grove::Status s = slam->slam->Step(t_s[i], dx_m[i], dy_m[i]);
      if (!s.ok()) {
        return slam->Fail(grove::ToC(s.code()), "steps[" + std::to_string(i) + "]: " + s.message());
      }
      if (done != nullptr) *done = i + 1;
    }
    return slam->Ok();
  });
}

grove_status grove_footslam_set_prior_map(grove_footslam* slam, const grove_hex_counts* hexes,
                                          size_t n) {
  if (slam == nullptr) return kNullHandle;
  if (hexes == nullptr && n != 0) return NullOut(slam, "grove_footslam_set_prior_map", "hexes");
  return grove::Guard(slam, [&] {
    std::vector<grove::HexCounts> map(n);
    for (size_t k = 0; k < n; ++k) map[k] = grove::ToCpp(hexes[k]);
    ++slam->version;
    grove::Status s = slam->slam->SetPriorMap(map);
    return s.ok() ? slam->Ok() : slam->Fail(s);
  });
}

grove_status grove_footslam_set_start_time(grove_footslam* slam, double t_s) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    ++slam->version;
    grove::Status s = slam->slam->SetStartTime(t_s);
    return s.ok() ? slam->Ok() : slam->Fail(s);
  });
}

grove_status grove_footslam_step_count(grove_footslam* slam, int64_t* steps) {
  if (slam == nullptr) return kNullHandle;
  if (steps == nullptr) return NullOut(slam, "grove_footslam_step_count", "steps");
  *steps = slam->slam->steps();
  return slam->Ok();
}

grove_status grove_footslam_get_config(grove_footslam* slam, grove_footslam_config* config) {
  if (slam == nullptr) return kNullHandle;
  if (config == nullptr) return NullOut(slam, "grove_footslam_get_config", "config");
  *config = grove::ToC(slam->slam->config());
  return slam->Ok();
}

grove_status grove_footslam_mean_pose(grove_footslam* slam, grove_pose* pose) {
  if (slam == nullptr) return kNullHandle;
  if (pose == nullptr) return NullOut(slam, "grove_footslam_mean_pose", "pose");
  return grove::Guard(slam, [&] {
    *pose = grove::PoseAt(slam->slam->MeanTrajectory(), slam->slam->MeanPose());
    return slam->Ok();
  });
}

grove_status grove_footslam_heaviest_pose(grove_footslam* slam, grove_pose* pose) {
  if (slam == nullptr) return kNullHandle;
  if (pose == nullptr) return NullOut(slam, "grove_footslam_heaviest_pose", "pose");
  return grove::Guard(slam, [&] {
    *pose = grove::PoseAt(slam->slam->MeanTrajectory(), slam->slam->HeaviestPose());
    return slam->Ok();
  });
}

grove_status grove_footslam_mean_trajectory(grove_footslam* slam, grove_pose* out, size_t capacity,
                                            size_t* count) {
  return MeanTrajectoryC(slam, "grove_footslam_mean_trajectory", out, capacity, count);
}

grove_status grove_footslam_heaviest_trajectory(grove_footslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_footslam_heaviest_trajectory", &slam->heaviest_trajectory,
        [&] { return slam->slam->HeaviestTrajectory(); }, out, capacity, count);
  });
}

grove_status grove_footslam_smoothed_trajectory(grove_footslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_footslam_smoothed_trajectory", &slam->smoothed_trajectory,
        [&] { return slam->slam->SmoothedTrajectory(); }, out, capacity, count);
  });
}

grove_status grove_footslam_cumulative_map(grove_footslam* slam, grove_hex_counts* out,
                                           size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_footslam_cumulative_map", &slam->cumulative_map,
        [&] { return slam->slam->CumulativeMap(); }, out, capacity, count);
  });
}

grove_status grove_footslam_heaviest_map(grove_footslam* slam, grove_hex_counts* out,
                                         size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_footslam_heaviest_map", &slam->heaviest_map,
        [&] { return slam->slam->HeaviestMap(); }, out, capacity, count);
  });
}

grove_status grove_footslam_stored_map(grove_footslam* slam, grove_hex_counts* out, size_t capacity,
                                       size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_footslam_stored_map", &slam->stored_map,
        [&] { return slam->slam->StoredMap(); }, out, capacity, count);
  });
}

grove_status grove_footslam_get_summary(grove_footslam* slam, grove_footslam_summary* summary) {
  if (slam == nullptr) return kNullHandle;
  if (summary == nullptr) return NullOut(slam, "grove_footslam_get_summary", "summary");
  return grove::Guard(slam, [&] {
    const grove::FootSlamSummary s = slam->slam->Summary();
    grove_footslam_summary out{};
    out.filter = grove::ToC(static_cast<const grove::FilterSummary&>(s));
    out.mean_scale = s.mean_scale;
    out.mean_heading_error_rad = s.mean_heading_error_rad;
    out.map_memory = grove::ToC(s.map_memory);
    out.trajectory_memory = grove::ToC(s.trajectory_memory);
    out.grid_size = s.grid_size;
    out.prior_hexagons = s.prior_hexagons;
    out.prior_hexagons_outside = s.prior_hexagons_outside;
    out.stored_blocks = s.stored_blocks;
    out.stored_blocks_exact = s.stored_blocks_exact;
    out.stored_hexagons = s.stored_hexagons;
    out.store_s = s.store_s;
    *summary = out;
    return slam->Ok();
  });
}

grove_status grove_footslam_checkpoint(grove_footslam* slam, void* buffer, size_t capacity,
                                       size_t* size) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedBytes(
        slam, "grove_footslam_checkpoint", &slam->checkpoint,
        [&] { return slam->slam->Checkpoint(); }, buffer, capacity, size);
  });
}

grove_status grove_footslam_resume(const grove_footslam_config* config, const void* data,
                                   size_t size, grove_footslam** out, char* error,
                                   size_t error_size) {
  return ResumeC<grove::FootSlam>(config, data, size, out, error, error_size);
}

// ---- Landmark FastSLAM ----

void grove_fastslam_config_default(grove_fastslam_config* config) {
  if (config != nullptr) *config = grove::ToC(grove::FastSlamConfig());
}

grove_status grove_fastslam_config_from_json(const char* json, grove_fastslam_config* config,
                                             char* error, size_t error_size) {
  return ConfigFromJsonC(json, config, error, error_size);
}

grove_status grove_fastslam_create(const grove_fastslam_config* config, grove_fastslam** out,
                                   char* error, size_t error_size) {
  return CreateC<grove::FastSlam>(config, out, error, error_size);
}

grove_status grove_fastslam_create_json(const char* json, grove_fastslam** out, char* error,
                                        size_t error_size) {
  return CreateJsonC<grove::FastSlam>(json, out, error, error_size);
}

void grove_fastslam_destroy(grove_fastslam* slam) {
  try {
    delete slam;
  } catch (...) {
    // As grove_footslam_destroy.
  }
}

const char* grove_fastslam_last_error(const grove_fastslam* slam) {
  return slam == nullptr ? "" : slam->error.c_str();
}

grove_status grove_fastslam_control(grove_fastslam* slam, double t_s, double speed_mps,
                                    double steer_rad) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    ++slam->version;
    grove::Status s = slam->slam->Control(t_s, speed_mps, steer_rad);
    return s.ok() ? slam->Ok() : slam->Fail(s);
  });
}

grove_status grove_fastslam_scan(grove_fastslam* slam, double t_s,
                                 const grove_landmark_observation* obs, size_t n) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    if (obs == nullptr && n != 0) {
      return slam->Fail(GROVE_INVALID_ARGUMENT,
                        "grove_fastslam_scan: obs is NULL with n = " + std::to_string(n));
    }
    std::vector<grove::LandmarkObservation> z(n);
    for (size_t i = 0; i < n; ++i) {
      z[i].range_m = obs[i].range_m;
      z[i].bearing_rad = obs[i].bearing_rad;
      z[i].id = obs[i].id;
    }
    ++slam->version;
    grove::Status s = slam->slam->Scan(t_s, z);
    return s.ok() ? slam->Ok() : slam->Fail(s);
  });
}

grove_status grove_fastslam_step_count(grove_fastslam* slam, int64_t* steps) {
  if (slam == nullptr) return kNullHandle;
  if (steps == nullptr) return NullOut(slam, "grove_fastslam_step_count", "steps");
  *steps = slam->slam->steps();
  return slam->Ok();
}

grove_status grove_fastslam_get_config(grove_fastslam* slam, grove_fastslam_config* config) {
  if (slam == nullptr) return kNullHandle;
  if (config == nullptr) return NullOut(slam, "grove_fastslam_get_config", "config");
  *config = grove::ToC(slam->slam->config());
  return slam->Ok();
}

grove_status grove_fastslam_mean_pose(grove_fastslam* slam, grove_pose* pose) {
  if (slam == nullptr) return kNullHandle;
  if (pose == nullptr) return NullOut(slam, "grove_fastslam_mean_pose", "pose");
  return grove::Guard(slam, [&] {
    *pose = grove::PoseAt(slam->slam->MeanTrajectory(), slam->slam->MeanPose());
    return slam->Ok();
  });
}

grove_status grove_fastslam_heaviest_pose(grove_fastslam* slam, grove_pose* pose) {
  if (slam == nullptr) return kNullHandle;
  if (pose == nullptr) return NullOut(slam, "grove_fastslam_heaviest_pose", "pose");
  return grove::Guard(slam, [&] {
    *pose = grove::PoseAt(slam->slam->MeanTrajectory(), slam->slam->HeaviestPose());
    return slam->Ok();
  });
}

grove_status grove_fastslam_pose_covariance(grove_fastslam* slam,
                                            grove_pose_covariance* covariance) {
  if (slam == nullptr) return kNullHandle;
  if (covariance == nullptr) {
    return NullOut(slam, "grove_fastslam_pose_covariance", "covariance");
  }
  return grove::Guard(slam, [&] {
    const grove::Pose2Covariance c = slam->slam->PoseCovariance();
    *covariance = grove_pose_covariance{c.xx, c.xy, c.xh, c.yy, c.yh, c.hh};
    return slam->Ok();
  });
}

grove_status grove_fastslam_mean_trajectory(grove_fastslam* slam, grove_pose* out, size_t capacity,
                                            size_t* count) {
  return MeanTrajectoryC(slam, "grove_fastslam_mean_trajectory", out, capacity, count);
}

grove_status grove_fastslam_heaviest_trajectory(grove_fastslam* slam, grove_pose* out,
                                                size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_fastslam_heaviest_trajectory", &slam->heaviest_trajectory,
        [&] { return slam->slam->HeaviestTrajectory(); }, out, capacity, count);
  });
}

grove_status grove_fastslam_landmarks(grove_fastslam* slam, grove_landmark_estimate* out,
                                      size_t capacity, size_t* count) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedArray(
        slam, "grove_fastslam_landmarks", &slam->landmarks,
        [&] { return slam->slam->HeaviestLandmarks(); }, out, capacity, count);
  });
}

grove_status grove_fastslam_get_summary(grove_fastslam* slam, grove_fastslam_summary* summary) {
  if (slam == nullptr) return kNullHandle;
  if (summary == nullptr) return NullOut(slam, "grove_fastslam_get_summary", "summary");
  return grove::Guard(slam, [&] {
    const grove::FastSlamSummary s = slam->slam->Summary();
    grove_fastslam_summary out{};
    out.filter = grove::ToC(static_cast<const grove::FilterSummary&>(s));
    out.controls = s.controls;
    out.scans = s.scans;
    out.observations = s.observations;
    out.predict_steps = s.predict_steps;
    out.landmarks = s.landmarks;
    out.associated = s.association.associated;
    out.created = s.association.created;
    out.ignored = s.association.ignored;
    out.removed = s.association.removed;
    out.dropped = s.association.dropped;
    out.tagged = s.association.tagged;
    out.wrong = s.association.wrong;
    out.evolution_trials = s.evolution.trials;
    out.evolution_accepted = s.evolution.accepted;
    out.map_memory = grove::ToC(s.map_memory);
    out.trajectory_memory = grove::ToC(s.trajectory_memory);
    *summary = out;
    return slam->Ok();
  });
}

grove_status grove_fastslam_checkpoint(grove_fastslam* slam, void* buffer, size_t capacity,
                                       size_t* size) {
  if (slam == nullptr) return kNullHandle;
  return grove::Guard(slam, [&] {
    return grove::ComputedBytes(
        slam, "grove_fastslam_checkpoint", &slam->checkpoint,
        [&] { return slam->slam->Checkpoint(); }, buffer, capacity, size);
  });
}

grove_status grove_fastslam_resume(const grove_fastslam_config* config, const void* data,
                                   size_t size, grove_fastslam** out, char* error,
                                   size_t error_size) {
  return ResumeC<grove::FastSlam>(config, data, size, out, error, error_size);
}
