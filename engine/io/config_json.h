// The nlohmann-level pieces behind grove/config_json.h: a configuration object's entries with
// where they stand in the text, and one field's value from and to JSON.
#ifndef GROVE_ENGINE_IO_CONFIG_JSON_H_
#define GROVE_ENGINE_IO_CONFIG_JSON_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/config_json.h"
#include "grove/status.h"

namespace grove {

// One key of a configuration object, with where it stands in the text.
struct ConfigEntry {
  std::string key;
  nlohmann::json value;
  int64_t line = 1;
  int64_t column = 1;
};

// Parses `text` as a JSON object of configuration keys; `name` (the file) starts each message.
StatusOr<std::vector<ConfigEntry>> ParseConfigObject(const std::string& name,
                                                     const std::string& text);
// The value of `entry` for the field `info`, type- and range-checked; InvalidArgument
// "name:line:column: key = value: must be ...".
StatusOr<FieldValue> FieldValueFromJson(const std::string& name, const FieldInfo& info,
                                        const ConfigEntry& entry);
nlohmann::json FieldValueToJson(const FieldInfo& info, const FieldValue& value);
// "name:line:column: unknown key "k" (did you mean "l"?)".
Status UnknownKeyError(const std::string& name, const ConfigEntry& entry,
                       const std::vector<std::string>& known);

}  // namespace grove

#endif  // GROVE_ENGINE_IO_CONFIG_JSON_H_
