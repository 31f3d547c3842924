#include "tools/report/cairo_output.h"

#include <fmt/format.h>

#include <new>
#include <string>

namespace grove::tools {

cairo_status_t AppendToString(void* closure, const unsigned char* data, unsigned int length) {
  try {
    static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  } catch (const std::bad_alloc&) {
    return CAIRO_STATUS_NO_MEMORY;
  }
  return CAIRO_STATUS_SUCCESS;
}

Status CairoError(cairo_status_t status, std::string_view what) {
  std::string message = fmt::format("{}: cairo: {}", what, cairo_status_to_string(status));
  if (status == CAIRO_STATUS_NO_MEMORY || status == CAIRO_STATUS_INVALID_SIZE) {
    return ResourceExhaustedError(std::move(message));
  }
  return InternalError(std::move(message));
}

}  // namespace grove::tools
