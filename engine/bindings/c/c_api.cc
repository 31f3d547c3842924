// The C API (grove/c_api.h) over the public facades: the calls that belong to no model (status
// names, version) and the checks of the shared enumerations. Each model's entry points are in
// its own file (footslam_c_api.cc, fastslam_c_api.cc, tracker_c_api.cc) over the generic layer
// (c_handle.h).
#include "grove/c_api.h"

#include <string>

#include "grove/resampling.h"
#include "grove/status.h"
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

}  // namespace
}  // namespace grove

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
