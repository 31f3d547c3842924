// Status and StatusOr: how grove reports errors across its public API.
//
// No exception crosses the public API: every call that can fail on user input returns a Status
// (or a StatusOr<T>), and after a failed call the object it was made on is unchanged.
#ifndef GROVE_STATUS_H_
#define GROVE_STATUS_H_

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "grove/export.h"

namespace grove {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,     // a configuration value or an input record breaks a rule
  kNotFound,            // a file or a key that must exist does not
  kOutOfRange,          // a position left the map grid, an index is past the end
  kFailedPrecondition,  // the call is not valid in the object's current state
  kResourceExhausted,   // memory budget, disk full
  kDataLoss,            // a corrupt or truncated file
  kIoError,             // the operating system refused a read or a write
  kInternal,            // a broken invariant that was caught without aborting
};

class [[nodiscard]] GROVE_EXPORT Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "ok", or "<code name>: <message>".
  std::string ToString() const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status InvalidArgumentError(std::string m) {
  return Status(StatusCode::kInvalidArgument, std::move(m));
}
inline Status NotFoundError(std::string m) { return Status(StatusCode::kNotFound, std::move(m)); }
inline Status OutOfRangeError(std::string m) {
  return Status(StatusCode::kOutOfRange, std::move(m));
}
inline Status FailedPreconditionError(std::string m) {
  return Status(StatusCode::kFailedPrecondition, std::move(m));
}
inline Status ResourceExhaustedError(std::string m) {
  return Status(StatusCode::kResourceExhausted, std::move(m));
}
inline Status DataLossError(std::string m) { return Status(StatusCode::kDataLoss, std::move(m)); }
inline Status IoError(std::string m) { return Status(StatusCode::kIoError, std::move(m)); }
inline Status InternalError(std::string m) { return Status(StatusCode::kInternal, std::move(m)); }

GROVE_EXPORT const char* StatusCodeName(StatusCode code);

// `text` for a one-line message: in double quotes, every byte outside printable ASCII (and the
// quote and backslash) as \xNN, cut after `max_bytes` bytes with "..." so that one bad field or
// key cannot flood a terminal. Every message that shows text from a file or a user uses it.
GROVE_EXPORT std::string QuoteForMessage(std::string_view text, size_t max_bytes = 64);

// A value or the Status saying why there is none. REQUIRES for value(): ok().
// Built from an ok Status (a bug in the caller: there is no value) it holds an Internal error.
template <typename T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(Status status)  // NOLINT: implicit by design
      : status_(status.ok() ? Status(StatusCode::kInternal, "StatusOr made from an ok Status")
                            : std::move(status)) {}
  StatusOr(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design

  bool ok() const { return status_.ok(); }
  const Status& status() const { return status_; }
  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() & { return *value_; }
  const T& operator*() const& { return *value_; }

 private:
  Status status_;
  std::optional<T> value_;
};

}  // namespace grove

// Returns early from the enclosing function when `expr` yields a non-ok Status.
#define GROVE_RETURN_IF_ERROR(expr)                \
  do {                                             \
    ::grove::Status grove_status_ = (expr);        \
    if (!grove_status_.ok()) return grove_status_; \
  } while (0)

#endif  // GROVE_STATUS_H_
