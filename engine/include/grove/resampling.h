// Resampling schemes a filter can use.
#ifndef GROVE_RESAMPLING_H_
#define GROVE_RESAMPLING_H_

#include <string_view>

#include "grove/export.h"

namespace grove {

enum class ResamplingScheme { kSystematic, kStratified, kResidual, kMultinomial };

// "systematic", "stratified", "residual" or "multinomial".
GROVE_EXPORT const char* ResamplingSchemeName(ResamplingScheme scheme);
// Parses one of the names above; returns false for anything else.
GROVE_EXPORT bool ParseResamplingScheme(std::string_view name, ResamplingScheme* scheme);

}  // namespace grove

#endif  // GROVE_RESAMPLING_H_
