#include "tools/cli/did_you_mean.h"

#include "grove/config_json.h"

namespace grove::tools {

std::string DidYouMean(const std::string& given, const std::vector<std::string>& known) {
  return NearestKey(given, known);
}

}  // namespace grove::tools
