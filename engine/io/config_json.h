// Configurations as JSON, for every model: an object whose keys are the names of the model's
// field table (grove/config_fields.h). Unknown keys (with the nearest known key suggested),
// duplicate keys, wrong types, values out of range and syntax errors are errors naming the
// file, line and column. Text from the file is quoted and cut in every message
// (QuoteForMessage); documents nested deeper than kMaxConfigDepth or larger than
// kMaxConfigBytes are refused before they are parsed.
#ifndef GROVE_ENGINE_IO_CONFIG_JSON_H_
#define GROVE_ENGINE_IO_CONFIG_JSON_H_

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove {

inline constexpr size_t kMaxConfigBytes = size_t{1} << 20;
inline constexpr int kMaxConfigDepth = 32;

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
// The whole file, refused when it is not a regular file (a directory, /dev/zero) or larger
// than kMaxConfigBytes; NotFound when it does not exist.
StatusOr<std::string> ReadConfigFile(const std::string& path);

// The known key closest to `key` by edit distance, or "" when none is close.
std::string NearestKey(const std::string& key, const std::vector<std::string>& known);

// The configuration as JSON (the effective configuration of a run; --print-config).
template <typename Config>
nlohmann::json ConfigToJson(const std::vector<ConfigField<Config>>& fields, const Config& config) {
  nlohmann::json out = nlohmann::json::object();
  for (const ConfigField<Config>& f : fields)
    out[f.info.name] = FieldValueToJson(f.info, f.get(config));
  return out;
}

// Applies the keys of `text` (a JSON object) to `config`; `name` is the file name for messages.
// Fields not in the text keep their values; on error `config` is unchanged. Checks each value's
// type and range, not the rules between fields (Validate()).
template <typename Config>
Status ApplyConfigJson(const std::vector<ConfigField<Config>>& fields, const std::string& name,
                       const std::string& text, Config* config) {
  StatusOr<std::vector<ConfigEntry>> entries = ParseConfigObject(name, text);
  if (!entries.ok()) return entries.status();
  Config result = *config;
  for (const ConfigEntry& e : *entries) {
    const ConfigField<Config>* f = FindField(fields, e.key);
    if (f == nullptr) {
      std::vector<std::string> known;
      for (const ConfigField<Config>& k : fields) known.push_back(k.info.name);
      return UnknownKeyError(name, e, known);
    }
    StatusOr<FieldValue> v = FieldValueFromJson(name, f->info, e);
    if (!v.ok()) return v.status();
    f->set(&result, *v);
  }
  *config = result;
  return Status::Ok();
}

// Reads `path` (ReadConfigFile) and applies it as above.
template <typename Config>
Status LoadConfigFile(const std::vector<ConfigField<Config>>& fields, const std::string& path,
                      Config* config) {
  StatusOr<std::string> text = ReadConfigFile(path);
  if (!text.ok()) return text.status();
  return ApplyConfigJson(fields, path, *text, config);
}

}  // namespace grove

#endif  // GROVE_ENGINE_IO_CONFIG_JSON_H_
