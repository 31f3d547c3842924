// FootSlamConfig <-> JSON. Every field of grove::FootSlamConfig is a key of the same name;
// unknown keys, wrong types and syntax errors are errors with the file position.
#ifndef GROVE_TOOLS_FOOTSLAM_CONFIG_JSON_H_
#define GROVE_TOOLS_FOOTSLAM_CONFIG_JSON_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/footslam.h"
#include "grove/status.h"

namespace grove::tools {

// The configuration as JSON (the effective configuration of a run).
nlohmann::json FootSlamConfigToJson(const FootSlamConfig& config);

// Applies the keys of `text` (a JSON object) to `config`; `name` is the file name for messages.
// Fields not in the text keep their values. Does not Validate().
Status ApplyFootSlamConfigJson(const std::string& name, const std::string& text,
                               FootSlamConfig* config);
// Reads `path` and applies it as above.
Status LoadFootSlamConfigFile(const std::string& path, FootSlamConfig* config);

// The known key closest to `key` by edit distance, or "" when none is close.
std::string NearestKey(const std::string& key, const std::vector<std::string>& known);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_FOOTSLAM_CONFIG_JSON_H_
