// The C API's generic layer (grove/c_api.h): a handle around any model's facade and, as
// templates, the C entry points every model has (create, resume, destroy, last_error, the
// stepping calls' bookkeeping, step_count, get_config, poses, trajectories, computed read-outs
// under the size-query rule, summary, checkpoint). A model's entry points are one line each
// over these, given its ConfigBinding (c_config.h) and its own converters.
//
// Every function here catches everything: no exception crosses into C, and bad arguments
// become statuses. Thread safety: one thread at a time per handle (grove/c_api.h).
#ifndef GROVE_ENGINE_BINDINGS_C_C_HANDLE_H_
#define GROVE_ENGINE_BINDINGS_C_C_HANDLE_H_

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "engine/bindings/c/c_config.h"
#include "grove/c_api.h"
#include "grove/config_json.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove::capi {

inline constexpr const char* kOutOfMemoryMessage = "out of memory";
// A null handle cannot record its error; every call reports it by status only.
inline constexpr grove_status kNullHandle = GROVE_INVALID_ARGUMENT;

inline grove_status ToC(StatusCode code) { return static_cast<grove_status>(code); }

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

// The kept read-outs of a handle, one per C function (named by its __func__).
class KeptReadOuts {
 public:
  template <typename T>
  Kept<T>* Of(const char* call) {
    for (const Entry& e : entries_) {
      if (std::strcmp(e.call, call) == 0) return static_cast<Kept<T>*>(e.kept.get());
    }
    entries_.push_back({call, std::make_shared<Kept<T>>()});
    return static_cast<Kept<T>*>(entries_.back().kept.get());
  }

 private:
  struct Entry {
    const char* call;
    std::shared_ptr<void> kept;  // a Kept<T>, deleted as one
  };
  std::vector<Entry> entries_;
};

// What a model's C handle holds: struct grove_footslam : Handle<FootSlam> {}.
template <typename Engine>
struct Handle {
  using EngineType = Engine;

  std::unique_ptr<Engine> engine;
  ErrorSlot error;
  uint64_t version = 0;  // stepping calls so far
  KeptReadOuts kept;

  grove_status Ok() noexcept {
    error.Clear();
    return GROVE_OK;
  }
  grove_status Fail(const Status& s) noexcept {
    error.Set(s.message());
    return ToC(s.code());
  }
  grove_status Fail(grove_status code, std::string_view message) noexcept {
    error.Set(message);
    return code;
  }
  grove_status NullOut(const char* call, const char* what) noexcept {
    try {
      return Fail(GROVE_INVALID_ARGUMENT, std::string(call) + ": " + what + " is NULL");
    } catch (...) {
      return Fail(GROVE_INVALID_ARGUMENT, "an output pointer is NULL");
    }
  }
};

// Runs f() -> grove_status on handle `h`, turning any exception into a status recorded in the
// handle.
template <typename H, typename F>
grove_status Guard(H* h, F&& f) noexcept {
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
inline void WriteError(std::string_view message, char* error, size_t error_size) noexcept {
  if (error == nullptr || error_size == 0) return;
  const size_t n = std::min(message.size(), error_size - 1);
  if (n > 0) std::memcpy(error, message.data(), n);
  error[n] = '\0';
}

// Runs f() -> Status for a call that makes a handle, writing its message (or "") into the
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

// The shared value types.
inline grove_pose PoseToC(const StampedPose& p) {
  return grove_pose{p.t_s, p.pose.x_m, p.pose.y_m, p.pose.heading_rad};
}
inline grove_memory_use MemoryToC(const MemoryUse& m) {
  return grove_memory_use{m.live_nodes, m.live_bytes, m.peak_live_nodes, m.peak_live_bytes,
                          m.reserved_bytes};
}
inline grove_filter_summary FilterSummaryToC(const FilterSummary& s) {
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

// Configurations and handles: config_default, config_from_json, create, create_json,
// resume, destroy, last_error

template <typename Binding>
void ConfigDefault(const Binding& b, typename Binding::CStruct* config) {
  if (config != nullptr) *config = b.ToC(typename Binding::CppConfig());
}

// The keys of `json` applied over `*config`, then validated; `*config` unchanged on error.
template <typename Config>
Status ApplyJson(const std::vector<ConfigField<Config>>& fields, const char* json, Config* config) {
  if (json == nullptr) return InvalidArgumentError("json is NULL");
  Config result = *config;
  GROVE_RETURN_IF_ERROR(ApplyConfigJson(fields, "config", std::string(json), &result));
  GROVE_RETURN_IF_ERROR(result.Validate());
  *config = result;
  return Status::Ok();
}

template <typename Binding>
grove_status ConfigFromJson(const Binding& b, const char* json, typename Binding::CStruct* config,
                            char* error, size_t error_size) {
  return GuardCreate(error, error_size, [&]() -> Status {
    GROVE_RETURN_IF_ERROR(b.status());
    if (config == nullptr) return InvalidArgumentError("config is NULL");
    auto c = b.ToCpp(*config);
    GROVE_RETURN_IF_ERROR(ApplyJson(b.fields(), json, &c));
    *config = b.ToC(c);
    return Status::Ok();
  });
}

// Makes a handle of type H around the engine `made` (a StatusOr<unique_ptr<Engine>>).
template <typename H, typename Made>
Status Adopt(Made made, H** out) {
  if (!made.ok()) return made.status();
  auto handle = std::make_unique<H>();
  handle->engine = std::move(*made);
  *out = handle.release();
  return Status::Ok();
}

template <typename H, typename Binding>
grove_status Create(const Binding& b, const typename Binding::CStruct* config, H** out, char* error,
                    size_t error_size) {
  return GuardCreate(error, error_size, [&]() -> Status {
    if (out == nullptr) return InvalidArgumentError("out is NULL");
    *out = nullptr;
    GROVE_RETURN_IF_ERROR(b.status());
    if (config == nullptr) return InvalidArgumentError("config is NULL");
    return Adopt(H::EngineType::Create(b.ToCpp(*config)), out);
  });
}

template <typename H, typename Binding>
grove_status CreateJson(const Binding& b, const char* json, H** out, char* error,
                        size_t error_size) {
  return GuardCreate(error, error_size, [&]() -> Status {
    if (out == nullptr) return InvalidArgumentError("out is NULL");
    *out = nullptr;
    typename Binding::CppConfig c;
    GROVE_RETURN_IF_ERROR(ApplyJson(b.fields(), json, &c));
    return Adopt(H::EngineType::Create(c), out);
  });
}

template <typename H, typename Binding>
grove_status Resume(const Binding& b, const typename Binding::CStruct* config, const void* data,
                    size_t size, H** out, char* error, size_t error_size) {
  return GuardCreate(error, error_size, [&]() -> Status {
    if (out == nullptr) return InvalidArgumentError("out is NULL");
    *out = nullptr;
    GROVE_RETURN_IF_ERROR(b.status());
    if (config == nullptr) return InvalidArgumentError("config is NULL");
    if (data == nullptr && size != 0) {
      return InvalidArgumentError("data is NULL with size " + std::to_string(size));
    }
    const std::string_view bytes(data == nullptr ? "" : static_cast<const char*>(data), size);
    return Adopt(H::EngineType::Resume(b.ToCpp(*config), bytes, "checkpoint", nullptr), out);
  });
}

template <typename H>
void Destroy(H* h) noexcept {
  try {
    delete h;
  } catch (...) {
    // A destructor that throws is a bug in the engine; it must not reach C.
  }
}

template <typename H>
const char* LastError(const H* h) noexcept {
  return h == nullptr ? "" : h->error.c_str();
}

// Calls on a handle

// A stepping call: f(Engine&) -> Status after counting the call (which drops the kept
// read-outs).
template <typename H, typename F>
grove_status Stepping(H* h, F&& f) noexcept {
  if (h == nullptr) return kNullHandle;
  return Guard(h, [&] {
    ++h->version;
    Status s = f(*h->engine);
    return s.ok() ? h->Ok() : h->Fail(s);
  });
}

// A value read-out: *out = f(Engine&), refused when `out` is NULL.
template <typename H, typename Out, typename F>
grove_status Get(H* h, const char* call, Out* out, const char* what, F&& f) noexcept {
  if (h == nullptr) return kNullHandle;
  if (out == nullptr) return h->NullOut(call, what);
  return Guard(h, [&] {
    *out = f(*h->engine);
    return h->Ok();
  });
}

template <typename H>
grove_status StepCount(H* h, const char* call, int64_t* steps) noexcept {
  return Get(h, call, steps, "steps", [](auto& e) { return e.steps(); });
}

template <typename H, typename Binding>
grove_status GetConfig(const Binding& b, H* h, const char* call,
                       typename Binding::CStruct* config) noexcept {
  return Get(h, call, config, "config", [&](auto& e) { return b.ToC(e.config()); });
}

// The last pose of the mean trajectory with the pose f(Engine&) (its time; 0 with no trajectory
// yet).
template <typename H, typename F>
grove_status PoseAt(H* h, const char* call, grove_pose* pose, F&& f) noexcept {
  return Get(h, call, pose, "pose", [&](auto& e) {
    const std::vector<StampedPose>& trajectory = e.MeanTrajectory();
    const double t = trajectory.empty() ? 0.0 : trajectory.back().t_s;
    const Pose2 p = f(e);
    return grove_pose{t, p.x_m, p.y_m, p.heading_rad};
  });
}
template <typename H>
grove_status MeanPose(H* h, const char* call, grove_pose* pose) noexcept {
  return PoseAt(h, call, pose, [](auto& e) { return e.MeanPose(); });
}
template <typename H>
grove_status HeaviestPose(H* h, const char* call, grove_pose* pose) noexcept {
  return PoseAt(h, call, pose, [](auto& e) { return e.HeaviestPose(); });
}

template <typename H, typename CSummary, typename Convert>
grove_status Summary(H* h, const char* call, CSummary* summary, Convert&& convert) noexcept {
  return Get(h, call, summary, "summary", [&](auto& e) { return convert(e.Summary()); });
}

// Arrays under the size-query rule (grove/c_api.h)

// Checks (out, capacity, count) before anything is computed.
template <typename H, typename Out>
bool CheckArrayArgs(H* h, const char* call, const Out* out, size_t capacity, const size_t* count,
                    grove_status* result) {
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

// Copies `items` (a vector, or the bytes of a string) into `out` converted by `convert`, under
// the size-query rule; *filled tells whether the fill was done (the kept copy may then be
// released). `needed` ends the message of a capacity too small.
template <typename H, typename Items, typename Out, typename Convert>
grove_status CopyOut(H* h, const char* call, const Items& items, Out* out, size_t capacity,
                     size_t* count, Convert&& convert, bool* filled,
                     const char* needed = " needed (the size is in *count)") {
  *filled = false;
  *count = items.size();
  if (out == nullptr) return h->Ok();
  if (capacity < items.size()) {
    return h->Fail(GROVE_OUT_OF_RANGE, std::string(call) + ": capacity " +
                                           std::to_string(capacity) + " < " +
                                           std::to_string(items.size()) + needed);
  }
  for (size_t i = 0; i < items.size(); ++i) out[i] = convert(items[i]);
  *filled = true;
  return h->Ok();
}

// The read-out kept for `call`: still valid, or computed by compute(Engine&) -> StatusOr<T>.
template <typename T, typename H, typename Compute>
StatusOr<Kept<T>*> Refresh(H* h, const char* call, Compute&& compute) {
  Kept<T>* kept = h->kept.template Of<T>(call);
  if (kept->valid && kept->version == h->version) return kept;
  kept->Release();
  StatusOr<T> value = compute(*h->engine);
  if (!value.ok()) return value.status();
  kept->value = std::move(*value);
  kept->valid = true;
  kept->version = h->version;
  return kept;
}

// The mean trajectory, which the engine holds: nothing to keep.
template <typename H>
grove_status MeanTrajectory(H* h, const char* call, grove_pose* out, size_t capacity,
                            size_t* count) noexcept {
  if (h == nullptr) return kNullHandle;
  return Guard(h, [&] {
    grove_status result = GROVE_OK;
    if (!CheckArrayArgs(h, call, out, capacity, count, &result)) return result;
    bool filled = false;
    return CopyOut(h, call, h->engine->MeanTrajectory(), out, capacity, count, PoseToC, &filled);
  });
}

// A read-out computed by compute(Engine&) -> StatusOr<std::vector<T>> (or a string of bytes),
// items converted by convert(const T&) -> Out, kept between a size query and its fill.
template <typename H, typename Out, typename Compute, typename Convert>
grove_status ReadOut(H* h, const char* call, Out* out, size_t capacity, size_t* count,
                     Compute&& compute, Convert&& convert,
                     const char* needed = " needed (the size is in *count)") noexcept {
  if (h == nullptr) return kNullHandle;
  return Guard(h, [&] {
    grove_status result = GROVE_OK;
    if (!CheckArrayArgs(h, call, out, capacity, count, &result)) return result;
    using Items = std::decay_t<decltype(compute(*h->engine).value())>;
    StatusOr<Kept<Items>*> kept = Refresh<Items>(h, call, compute);
    if (!kept.ok()) return h->Fail(kept.status());
    bool filled = false;
    result = CopyOut(h, call, (*kept)->value, out, capacity, count, convert, &filled, needed);
    if (filled) (*kept)->Release();
    return result;
  });
}

template <typename H>
grove_status Trajectory(H* h, const char* call, grove_pose* out, size_t capacity, size_t* count,
                        StatusOr<std::vector<StampedPose>> (H::EngineType::*read)()
                            const) noexcept {
  return ReadOut(
      h, call, out, capacity, count, [read](auto& e) { return (e.*read)(); }, PoseToC);
}

// The checkpoint bytes (no user data), under the size-query rule counting bytes.
template <typename H>
grove_status Checkpoint(H* h, const char* call, void* buffer, size_t capacity,
                        size_t* size) noexcept {
  return ReadOut(
      h, call, static_cast<char*>(buffer), capacity, size, [](auto& e) { return e.Checkpoint(); },
      [](char c) { return c; }, " bytes needed (the size is in *size)");
}

}  // namespace grove::capi

// Defines the C entry points every model has, for the model whose handle is `prefix` (a struct
// deriving from Handle<Engine>) and whose configuration is prefix##_config: config_default,
// config_from_json, create, create_json, destroy, last_error, step_count, get_config,
// mean_pose, heaviest_pose, mean_trajectory, get_summary (summary_to_c converts the facade's
// summary to prefix##_summary), checkpoint and resume. `binding` is the model's ConfigBinding.
#define GROVE_C_MODEL_ENTRY_POINTS(prefix, binding, summary_to_c)                                \
  void prefix##_config_default(prefix##_config* config) {                                        \
    ::grove::capi::ConfigDefault(binding, config);                                               \
  }                                                                                              \
  grove_status prefix##_config_from_json(const char* json, prefix##_config* config, char* error, \
                                         size_t error_size) {                                    \
    return ::grove::capi::ConfigFromJson(binding, json, config, error, error_size);              \
  }                                                                                              \
  grove_status prefix##_create(const prefix##_config* config, prefix** out, char* error,         \
                               size_t error_size) {                                              \
    return ::grove::capi::Create(binding, config, out, error, error_size);                       \
  }                                                                                              \
  grove_status prefix##_create_json(const char* json, prefix** out, char* error,                 \
                                    size_t error_size) {                                         \
    return ::grove::capi::CreateJson(binding, json, out, error, error_size);                     \
  }                                                                                              \
  void prefix##_destroy(prefix* h) { ::grove::capi::Destroy(h); }                                \
  const char* prefix##_last_error(const prefix* h) { return ::grove::capi::LastError(h); }       \
  grove_status prefix##_step_count(prefix* h, int64_t* steps) {                                  \
    return ::grove::capi::StepCount(h, __func__, steps);                                         \
  }                                                                                              \
  grove_status prefix##_get_config(prefix* h, prefix##_config* config) {                         \
    return ::grove::capi::GetConfig(binding, h, __func__, config);                               \
  }                                                                                              \
  grove_status prefix##_mean_pose(prefix* h, grove_pose* pose) {                                 \
    return ::grove::capi::MeanPose(h, __func__, pose);                                           \
  }                                                                                              \
  grove_status prefix##_heaviest_pose(prefix* h, grove_pose* pose) {                             \
    return ::grove::capi::HeaviestPose(h, __func__, pose);                                       \
  }                                                                                              \
  grove_status prefix##_mean_trajectory(prefix* h, grove_pose* out, size_t capacity,             \
                                        size_t* count) {                                         \
    return ::grove::capi::MeanTrajectory(h, __func__, out, capacity, count);                     \
  }                                                                                              \
  grove_status prefix##_get_summary(prefix* h, prefix##_summary* summary) {                      \
    return ::grove::capi::Summary(h, __func__, summary, summary_to_c);                           \
  }                                                                                              \
  grove_status prefix##_checkpoint(prefix* h, void* buffer, size_t capacity, size_t* size) {     \
    return ::grove::capi::Checkpoint(h, __func__, buffer, capacity, size);                       \
  }                                                                                              \
  grove_status prefix##_resume(const prefix##_config* config, const void* data, size_t size,     \
                               prefix** out, char* error, size_t error_size) {                   \
    return ::grove::capi::Resume(binding, config, data, size, out, error, error_size);           \
  }

#endif  // GROVE_ENGINE_BINDINGS_C_C_HANDLE_H_
