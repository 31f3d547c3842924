// The C API of the foot IMU front end (grove/c_api_foot_imu.h) over grove::FootImu. As in
// c_api.cc, every entry point catches everything: no exception crosses into C.
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

#include "grove/c_api_foot_imu.h"
#include "grove/config_json.h"
#include "grove/foot_imu.h"
#include "grove/status.h"

static_assert(GROVE_DETECTOR_SHOE == static_cast<int>(grove::ZeroVelocityDetector::kShoe));
static_assert(GROVE_DETECTOR_ARE == static_cast<int>(grove::ZeroVelocityDetector::kAre));
static_assert(GROVE_DETECTOR_MV == static_cast<int>(grove::ZeroVelocityDetector::kMv));
static_assert(GROVE_DETECTOR_MAG == static_cast<int>(grove::ZeroVelocityDetector::kMag));
static_assert(std::is_same_v<std::underlying_type_t<grove::ZeroVelocityDetector>, int>);

struct grove_foot_imu {
  std::unique_ptr<grove::FootImu> imu;
  // Steps finished and not yet handed out (the size-query rule keeps them until a fill).
  std::vector<grove::FootStep> pending;
  std::string error;
  bool error_lost = false;  // the message could not be copied (out of memory)
};

namespace {

constexpr const char* kOutOfMemory = "out of memory";

// grove_foot_imu_config's fields, in the order of grove::FootImuConfig, as member pointer pairs:
// one list converts both ways.
template <typename F>
void ForEachReal(F&& f) {
  using C = grove::FootImuConfig;
  using G = grove_foot_imu_config;
  f(&C::detector_threshold, &G::detector_threshold);
  f(&C::detector_accel_sigma_mps2, &G::detector_accel_sigma_mps2);
  f(&C::detector_gyro_sigma_radps, &G::detector_gyro_sigma_radps);
  f(&C::min_step_m, &G::min_step_m);
  f(&C::accel_noise_mps2_per_sqrt_hz, &G::accel_noise_mps2_per_sqrt_hz);
  f(&C::gyro_noise_radps_per_sqrt_hz, &G::gyro_noise_radps_per_sqrt_hz);
  f(&C::accel_bias_walk_mps3_per_sqrt_hz, &G::accel_bias_walk_mps3_per_sqrt_hz);
  f(&C::gyro_bias_walk_radps2_per_sqrt_hz, &G::gyro_bias_walk_radps2_per_sqrt_hz);
  f(&C::zupt_sigma_mps, &G::zupt_sigma_mps);
  f(&C::zaru_sigma_radps, &G::zaru_sigma_radps);
  f(&C::alignment_s, &G::alignment_s);
  f(&C::alignment_heading_rad, &G::alignment_heading_rad);
  f(&C::alignment_tilt_sigma_rad, &G::alignment_tilt_sigma_rad);
  f(&C::alignment_heading_sigma_rad, &G::alignment_heading_sigma_rad);
  f(&C::initial_accel_bias_sigma_mps2, &G::initial_accel_bias_sigma_mps2);
  f(&C::initial_gyro_bias_sigma_radps, &G::initial_gyro_bias_sigma_radps);
  f(&C::gravity_mps2, &G::gravity_mps2);
  f(&C::latitude_deg, &G::latitude_deg);
  f(&C::height_m, &G::height_m);
  f(&C::accel_range_mps2, &G::accel_range_mps2);
  f(&C::gyro_range_radps, &G::gyro_range_radps);
  f(&C::max_sample_interval_s, &G::max_sample_interval_s);
}

grove::FootImuConfig ToCpp(const grove_foot_imu_config& c) {
  grove::FootImuConfig o;
  o.detector = static_cast<grove::ZeroVelocityDetector>(c.detector);
  o.detector_window = c.detector_window;
  o.stance_gap_samples = c.stance_gap_samples;
  o.min_stance_samples = c.min_stance_samples;
  ForEachReal([&](auto cpp, auto cc) { o.*cpp = c.*cc; });
  return o;
}

grove_foot_imu_config ToC(const grove::FootImuConfig& c) {
  grove_foot_imu_config o{};
  o.detector = static_cast<int>(c.detector);
  o.detector_window = c.detector_window;
  o.stance_gap_samples = c.stance_gap_samples;
  o.min_stance_samples = c.min_stance_samples;
  ForEachReal([&](auto cpp, auto cc) { o.*cc = c.*cpp; });
  return o;
}

grove_foot_step ToC(const grove::FootStep& s) {
  grove_foot_step o{};
  o.t_s = s.t_s;
  o.dx_m = s.dx_m;
  o.dy_m = s.dy_m;
  o.dz_m = s.dz_m;
  o.dheading_rad = s.dheading_rad;
  const grove::Pose2Covariance& c = s.covariance;
  o.covariance = grove_pose_covariance{c.xx, c.xy, c.xh, c.yy, c.yh, c.hh};
  o.stance_begin_s = s.stance_begin_s;
  o.stance_end_s = s.stance_end_s;
  o.stance_end_sample = s.stance_end_sample;
  return o;
}

void WriteError(std::string_view message, char* error, size_t error_size) noexcept {
  if (error == nullptr || error_size == 0) return;
  const size_t n = std::min(message.size(), error_size - 1);
  if (n > 0) std::memcpy(error, message.data(), n);
  error[n] = '\0';
}

grove_status Record(grove_foot_imu* h, grove_status code, std::string_view message) noexcept {
  try {
    h->error.assign(message.data(), message.size());
    h->error_lost = false;
  } catch (...) {
    h->error.clear();
    h->error_lost = true;
  }
  return code;
}

grove_status Record(grove_foot_imu* h, const grove::Status& s) noexcept {
  return Record(h, static_cast<grove_status>(s.code()), s.ok() ? "" : s.message());
}

// Runs `f` (-> grove::Status): on the handle `h` when given, recording the message there, else
// writing it into the caller's buffer.
template <typename F>
grove_status Guard(grove_foot_imu* h, char* error, size_t error_size, F&& f) noexcept {
  grove::Status s;
  try {
    s = f();
  } catch (const std::bad_alloc&) {
    s = grove::ResourceExhaustedError(kOutOfMemory);
  } catch (const std::exception& e) {
    try {
      s = grove::InternalError(std::string("unexpected exception: ") + e.what());
    } catch (...) {
      s = grove::Status(grove::StatusCode::kInternal, "");
    }
  } catch (...) {
    s = grove::Status(grove::StatusCode::kInternal, "");
  }
  if (h != nullptr) return Record(h, s);
  WriteError(s.ok() ? std::string_view() : std::string_view(s.message()), error, error_size);
  return static_cast<grove_status>(s.code());
}

template <typename F>
grove_status OnHandle(grove_foot_imu* h, F&& f) noexcept {
  if (h == nullptr) return GROVE_INVALID_ARGUMENT;  // no handle to record the error in
  return Guard(h, nullptr, 0, std::forward<F>(f));
}

grove::Status ConfigFromJson(const char* json, grove::FootImuConfig* config) {
  if (json == nullptr) return grove::InvalidArgumentError("json is NULL");
  grove::FootImuConfig result = *config;
  GROVE_RETURN_IF_ERROR(
      grove::ApplyConfigJson(grove::FootImuConfigFields(), "config", json, &result));
  GROVE_RETURN_IF_ERROR(result.Validate());
  *config = result;
  return grove::Status::Ok();
}

grove::Status Make(const grove::FootImuConfig& config, grove_foot_imu** out) {
  grove::StatusOr<std::unique_ptr<grove::FootImu>> made = grove::FootImu::Create(config);
  if (!made.ok()) return made.status();
  auto handle = std::make_unique<grove_foot_imu>();
  handle->imu = std::move(*made);
  *out = handle.release();
  return grove::Status::Ok();
}

grove::Status AddOne(grove_foot_imu* h, const grove_imu_sample& c) {
  grove::ImuSample s;
  s.t_s = c.t_s;
  for (int i = 0; i < 3; ++i) {
    s.accel_mps2[i] = c.accel_mps2[i];
    s.gyro_radps[i] = c.gyro_radps[i];
  }
  GROVE_RETURN_IF_ERROR(h->imu->AddSample(s));
  for (grove::FootStep& step : h->imu->TakeSteps()) h->pending.push_back(step);
  return grove::Status::Ok();
}

}  // namespace

void grove_foot_imu_config_default(grove_foot_imu_config* config) {
  if (config != nullptr) *config = ToC(grove::FootImuConfig());
}

grove_status grove_foot_imu_config_from_json(const char* json, grove_foot_imu_config* config,
                                             char* error, size_t error_size) {
  return Guard(nullptr, error, error_size, [&]() -> grove::Status {
    if (config == nullptr) return grove::InvalidArgumentError("config is NULL");
    grove::FootImuConfig c = ToCpp(*config);
    GROVE_RETURN_IF_ERROR(ConfigFromJson(json, &c));
    *config = ToC(c);
    return grove::Status::Ok();
  });
}

grove_status grove_foot_imu_create(const grove_foot_imu_config* config, grove_foot_imu** out,
                                   char* error, size_t error_size) {
  return Guard(nullptr, error, error_size, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    *out = nullptr;
    if (config == nullptr) return grove::InvalidArgumentError("config is NULL");
    return Make(ToCpp(*config), out);
  });
}

grove_status grove_foot_imu_create_json(const char* json, grove_foot_imu** out, char* error,
                                        size_t error_size) {
  return Guard(nullptr, error, error_size, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    *out = nullptr;
    grove::FootImuConfig c;
    GROVE_RETURN_IF_ERROR(ConfigFromJson(json, &c));
    return Make(c, out);
  });
}

void grove_foot_imu_destroy(grove_foot_imu* imu) {
  try {
    delete imu;
  } catch (...) {
    // A destructor that throws is a bug in the engine; it must not reach C.
  }
}

const char* grove_foot_imu_last_error(const grove_foot_imu* imu) {
  if (imu == nullptr) return "";
  return imu->error_lost ? kOutOfMemory : imu->error.c_str();
}

grove_status grove_foot_imu_add_sample(grove_foot_imu* imu, const grove_imu_sample* sample) {
  return OnHandle(imu, [&]() -> grove::Status {
    if (sample == nullptr) return grove::InvalidArgumentError("sample is NULL");
    return AddOne(imu, *sample);
  });
}

grove_status grove_foot_imu_add_samples(grove_foot_imu* imu, const grove_imu_sample* samples,
                                        size_t n, size_t* added) {
  if (added != nullptr) *added = 0;
  return OnHandle(imu, [&]() -> grove::Status {
    if (samples == nullptr && n > 0) {
      return grove::InvalidArgumentError("samples is NULL with n = " + std::to_string(n));
    }
    for (size_t i = 0; i < n; ++i) {
      GROVE_RETURN_IF_ERROR(AddOne(imu, samples[i]));
      if (added != nullptr) *added = i + 1;
    }
    return grove::Status::Ok();
  });
}

grove_status grove_foot_imu_finish(grove_foot_imu* imu) {
  return OnHandle(imu, [&]() -> grove::Status {
    GROVE_RETURN_IF_ERROR(imu->imu->Finish());
    for (grove::FootStep& step : imu->imu->TakeSteps()) imu->pending.push_back(step);
    return grove::Status::Ok();
  });
}

grove_status grove_foot_imu_take_steps(grove_foot_imu* imu, grove_foot_step* out, size_t capacity,
                                       size_t* count) {
  return OnHandle(imu, [&]() -> grove::Status {
    if (count == nullptr) return grove::InvalidArgumentError("count is NULL");
    if (out == nullptr && capacity != 0) {
      return grove::InvalidArgumentError("out is NULL but capacity is " + std::to_string(capacity) +
                                         " (a size query passes 0)");
    }
    *count = imu->pending.size();
    if (out == nullptr) return grove::Status::Ok();
    if (capacity < imu->pending.size()) {
      return grove::OutOfRangeError("capacity " + std::to_string(capacity) + " < " +
                                    std::to_string(imu->pending.size()) +
                                    " needed (the size is in *count)");
    }
    for (size_t i = 0; i < imu->pending.size(); ++i) out[i] = ToC(imu->pending[i]);
    imu->pending.clear();
    return grove::Status::Ok();
  });
}

grove_status grove_foot_imu_get_state(grove_foot_imu* imu, grove_foot_imu_state* out) {
  return OnHandle(imu, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    const grove::FootImuState s = imu->imu->State();
    grove_foot_imu_state o{};
    o.t_s = s.t_s;
    for (int i = 0; i < 3; ++i) {
      o.position_m[i] = s.position_m[i];
      o.velocity_mps[i] = s.velocity_mps[i];
      o.accel_bias_mps2[i] = s.accel_bias_mps2[i];
      o.gyro_bias_radps[i] = s.gyro_bias_radps[i];
    }
    o.roll_rad = s.roll_rad;
    o.pitch_rad = s.pitch_rad;
    o.heading_rad = s.heading_rad;
    o.still = s.still ? 1 : 0;
    *out = o;
    return grove::Status::Ok();
  });
}

grove_status grove_foot_imu_get_summary(grove_foot_imu* imu, grove_foot_imu_summary* out) {
  return OnHandle(imu, [&]() -> grove::Status {
    if (out == nullptr) return grove::InvalidArgumentError("out is NULL");
    const grove::FootImuSummary s = imu->imu->Summary();
    grove_foot_imu_summary o{};
    o.samples = s.samples;
    o.processed_samples = s.processed_samples;
    o.still_samples = s.still_samples;
    o.stances = s.stances;
    o.steps = s.steps;
    o.aligned = s.aligned ? 1 : 0;
    o.alignment_t_s = s.alignment_t_s;
    o.has_origin = s.has_origin ? 1 : 0;
    o.origin_t_s = s.origin_t_s;
    o.gravity_mps2 = s.gravity_mps2;
    o.distance_m = s.distance_m;
    o.seconds = s.seconds;
    *out = o;
    return grove::Status::Ok();
  });
}
