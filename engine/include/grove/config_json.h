// Configurations as JSON, for every model: an object whose keys are the names of the model's
// field table (grove/config_fields.h). Unknown keys (with the nearest known key suggested),
// duplicate keys, wrong types, values out of range and syntax errors are errors naming the
// file, line and column. Text from the file is quoted and cut in every message
// (QuoteForMessage); documents nested deeper than kMaxConfigDepth or larger than
// kMaxConfigBytes are refused before they are parsed.
//
//   grove::FootSlamConfig config;
//   GROVE_RETURN_IF_ERROR(grove::ApplyConfigJson(grove::FootSlamConfigFields(), "inline",
//                                                R"({"particles": 2000, "seed": 7})", &config));
//   std::string text = grove::ConfigToJson(grove::FootSlamConfigFields(), config, 2);
#ifndef GROVE_CONFIG_JSON_H_
#define GROVE_CONFIG_JSON_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/export.h"
#include "grove/status.h"

namespace grove {

inline constexpr size_t kMaxConfigBytes = size_t{1} << 20;
inline constexpr int kMaxConfigDepth = 32;

// A field's value read from a configuration: fields[field] is to hold `value`.
struct FieldSetting {
  size_t field = 0;
  FieldValue value;
};

// A key of a configuration object that is none of the fields but one of the caller's own keys
// (ParseConfigJson's other_keys), with where it stands in the text.
struct ConfigJsonKey {
  std::string key;
  std::string value_json;  // its value as compact JSON text
  int64_t line = 1;
  int64_t column = 1;
};

// Parses `text`, a JSON object, against `fields`; `name` (the file) starts every message. Each
// key naming a field has its value type- and range-checked and appended to *settings, in the
// order of the text. A key in `other_keys` is handed to `on_other_key` (when given) as it is
// met; a non-OK status from it stops the parse and is returned. Any other key is InvalidArgument
// "name:line:column: unknown key "k" (did you mean "l"?)", the suggestion the nearest of
// `other_keys` and the fields. The whole text is checked for syntax, duplicate keys, size and
// depth before any key is handed out.
GROVE_EXPORT Status ParseConfigJson(
    const std::string& name, const std::string& text, std::span<const FieldInfo* const> fields,
    std::vector<FieldSetting>* settings, const std::vector<std::string>& other_keys = {},
    const std::function<Status(const ConfigJsonKey&)>& on_other_key = nullptr);

// A JSON object holding fields[i] = values[i], keys in sorted order; `indent` as
// nlohmann::json::dump's (-1: one line; n: n spaces per level). REQUIRES: as many values as fields.
GROVE_EXPORT std::string FieldsToJson(std::span<const FieldInfo* const> fields,
                                      std::span<const FieldValue> values, int indent = -1);

// The whole file, refused when it is not a regular file (a directory, /dev/zero) or larger
// than kMaxConfigBytes; NotFound when it does not exist.
GROVE_EXPORT StatusOr<std::string> ReadConfigFile(const std::string& path);

// The known key closest to `key` by edit distance, or "" when none is close.
GROVE_EXPORT std::string NearestKey(const std::string& key, const std::vector<std::string>& known);

// The FieldInfo of every field of a table, in table order.
template <typename Config>
std::vector<const FieldInfo*> FieldInfos(const std::vector<ConfigField<Config>>& fields) {
  std::vector<const FieldInfo*> infos;
  infos.reserve(fields.size());
  for (const ConfigField<Config>& f : fields) infos.push_back(&f.info);
  return infos;
}

namespace internal {

template <typename Config>
std::string ConfigFieldsToJson(const std::vector<ConfigField<Config>>& fields, const Config& config,
                               int indent, bool results_only) {
  std::vector<const FieldInfo*> infos;
  std::vector<FieldValue> values;
  for (const ConfigField<Config>& f : fields) {
    if (results_only && f.info.effect != kChangesResults) continue;
    infos.push_back(&f.info);
    values.push_back(f.get(config));
  }
  return FieldsToJson(infos, values, indent);
}

}  // namespace internal

// The configuration as JSON text (the effective configuration of a run; --print-config).
template <typename Config>
std::string ConfigToJson(const std::vector<ConfigField<Config>>& fields, const Config& config,
                         int indent = -1) {
  return internal::ConfigFieldsToJson(fields, config, indent, false);
}

// The fields that change results (kChangesResults) as one line of JSON: what a digest of a run's
// outputs covers (threads and batch sizes do not change them).
template <typename Config>
std::string ResultConfigToJson(const std::vector<ConfigField<Config>>& fields,
                               const Config& config) {
  return internal::ConfigFieldsToJson(fields, config, -1, true);
}

// Applies the keys of `text` (a JSON object) to `config`; `name` is the file name for messages.
// Fields not in the text keep their values; on error `config` is unchanged. Checks each value's
// type and range, not the rules between fields (Validate()).
template <typename Config>
Status ApplyConfigJson(const std::vector<ConfigField<Config>>& fields, const std::string& name,
                       const std::string& text, Config* config) {
  std::vector<FieldSetting> settings;
  GROVE_RETURN_IF_ERROR(ParseConfigJson(name, text, FieldInfos(fields), &settings));
  for (const FieldSetting& s : settings) fields[s.field].set(config, s.value);
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

#endif  // GROVE_CONFIG_JSON_H_
