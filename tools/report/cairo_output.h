// Small pieces shared by the cairo drawings of the map images.
#ifndef GROVE_TOOLS_REPORT_CAIRO_OUTPUT_H_
#define GROVE_TOOLS_REPORT_CAIRO_OUTPUT_H_

#include <cairo.h>

#include <string_view>

#include "grove/status.h"

namespace grove::tools {

// A cairo write callback that appends to the std::string passed as `closure`; no exception
// crosses the C callback (an allocation failure becomes CAIRO_STATUS_NO_MEMORY).
cairo_status_t AppendToString(void* closure, const unsigned char* data, unsigned int length);

// A cairo failure while doing `what`: ResourceExhausted for memory and size, Internal otherwise.
Status CairoError(cairo_status_t status, std::string_view what);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_CAIRO_OUTPUT_H_
