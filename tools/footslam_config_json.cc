#include "tools/footslam_config_json.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>

namespace grove::tools {
namespace {

using nlohmann::json;

// One table drives reading, writing and the list of known keys.
struct Field {
  const char* name;
  std::function<json(const FootSlamConfig&)> get;
  // Returns "" on success or the expected type / allowed values.
  std::function<std::string(const json&, FootSlamConfig*)> set;
};

template <typename T>
Field Number(const char* name, T FootSlamConfig::*member) {
  return {
      name, [member](const FootSlamConfig& c) { return json(c.*member); },
      [member](const json& v, FootSlamConfig* c) -> std::string {
        if constexpr (std::is_floating_point_v<T>) {
          if (!v.is_number()) return "a number";
          c->*member = v.get<T>();
        } else {
          if (!v.is_number_integer()) return "an integer";
          if constexpr (std::is_unsigned_v<T>) {
            if (v.is_number_unsigned()) {
              c->*member = v.get<T>();
            } else {
              if (v.get<int64_t>() < 0) return "a non-negative integer";
              c->*member = static_cast<T>(v.get<int64_t>());
            }
          } else {
            if (v.is_number_unsigned() &&
                v.get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) {
              return "an integer in range";
            }
            int64_t x =
                v.is_number_unsigned() ? static_cast<int64_t>(v.get<uint64_t>()) : v.get<int64_t>();
            if (x < static_cast<int64_t>(std::numeric_limits<T>::min()) ||
                x > static_cast<int64_t>(std::numeric_limits<T>::max())) {
              return "an integer in range";
            }
            c->*member = static_cast<T>(x);
          }
        }
        return "";
      }};
}

template <typename E>
Field Enum(const char* name, E FootSlamConfig::*member, const char* (*to_name)(E),
           bool (*parse)(const std::string&, E*), const char* choices) {
  return {name, [=](const FootSlamConfig& c) { return json(to_name(c.*member)); },
          [=](const json& v, FootSlamConfig* c) -> std::string {
            if (!v.is_string() || !parse(v.get<std::string>(), &(c->*member))) {
              return std::string("one of ") + choices;
            }
            return "";
          }};
}

bool ParseScheme(const std::string& s, ResamplingScheme* out) {
  return ParseResamplingScheme(s, out);
}

const std::vector<Field>& Fields() {
  static const std::vector<Field> fields = {
      Number("particles", &FootSlamConfig::particles),
      Number("seed", &FootSlamConfig::seed),
      Number("hex_radius_m", &FootSlamConfig::hex_radius_m),
      Number("prior_count", &FootSlamConfig::prior_count),
      Enum("weighting", &FootSlamConfig::weighting, &FootSlamWeightingName, &ParseFootSlamWeighting,
           "\"paper\", \"prior_ratio\""),
      Number("start_x_m", &FootSlamConfig::start_x_m),
      Number("start_y_m", &FootSlamConfig::start_y_m),
      Number("start_heading_rad", &FootSlamConfig::start_heading_rad),
      Number("initial_heading_sigma_rad", &FootSlamConfig::initial_heading_sigma_rad),
      Number("heading_drift_sigma_rad", &FootSlamConfig::heading_drift_sigma_rad),
      Number("heading_sigma_rad", &FootSlamConfig::heading_sigma_rad),
      Number("scale_sigma", &FootSlamConfig::scale_sigma),
      Number("scale_drift_sigma", &FootSlamConfig::scale_drift_sigma),
      Number("step_length_sigma_m", &FootSlamConfig::step_length_sigma_m),
      Number("position_sigma_m", &FootSlamConfig::position_sigma_m),
      Enum("resampling", &FootSlamConfig::resampling, &ResamplingSchemeName, &ParseScheme,
           "\"systematic\", \"stratified\", \"residual\", \"multinomial\""),
      Number("resample_threshold", &FootSlamConfig::resample_threshold),
      Enum("map", &FootSlamConfig::map, &FootSlamMapKindName, &ParseFootSlamMapKind,
           "\"htree\", \"naive\""),
      Number("degree", &FootSlamConfig::degree),
      Number("grid_size", &FootSlamConfig::grid_size),
      Number("alphabet", &FootSlamConfig::alphabet),
      Number("threads", &FootSlamConfig::threads),
      Number("batch", &FootSlamConfig::batch),
  };
  return fields;
}

std::string TypeName(const json& v) { return std::string(v.type_name()); }

// 1-based line and column of byte offset `pos` in `text`.
std::pair<int64_t, int64_t> LineColumn(const std::string& text, size_t pos) {
  int64_t line = 1, column = 1;
  for (size_t i = 0; i < pos && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

// The key as JSON writes it: quoted, control characters escaped; safe in a one-line message.
std::string QuotedKey(const std::string& key) {
  return json(key).dump(-1, ' ', false, json::error_handler_t::replace);
}

// Where the key starts in the text, for messages about it (first occurrence; 1:1 when the file
// spells it with escapes that differ from JSON's own).
std::pair<int64_t, int64_t> KeyPosition(const std::string& text, const std::string& key) {
  size_t pos = text.find(QuotedKey(key));
  return pos == std::string::npos ? std::pair<int64_t, int64_t>{1, 1} : LineColumn(text, pos);
}

}  // namespace

json FootSlamConfigToJson(const FootSlamConfig& config) {
  json out = json::object();
  for (const Field& f : Fields()) out[f.name] = f.get(config);
  return out;
}

std::string NearestKey(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  size_t best_distance = std::max<size_t>(3, key.size() / 3) + 1;
  for (const std::string& k : known) {
    // Levenshtein distance.
    std::vector<size_t> prev(k.size() + 1), cur(k.size() + 1);
    for (size_t j = 0; j <= k.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= key.size(); ++i) {
      cur[0] = i;
      for (size_t j = 1; j <= k.size(); ++j) {
        cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (key[i - 1] != k[j - 1])});
      }
      prev.swap(cur);
    }
    if (prev[k.size()] < best_distance) {
      best_distance = prev[k.size()];
      best = k;
    }
  }
  return best;
}

Status ApplyFootSlamConfigJson(const std::string& name, const std::string& text,
                               FootSlamConfig* config) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    // e.byte is the 1-based offset of the byte where parsing failed; one past the end means
    // "unexpected end of input", reported at the last byte.
    size_t offset = e.byte == 0 ? 0 : e.byte - 1;
    if (!text.empty() && offset >= text.size()) offset = text.size() - 1;
    auto [line, column] = LineColumn(text, offset);
    std::string what = e.what();
    size_t cut = what.find("syntax error");
    return InvalidArgumentError(fmt::format("{}:{}:{}: invalid JSON: {}", name, line, column,
                                            cut == std::string::npos ? what : what.substr(cut)));
  } catch (const json::exception& e) {
    // Anything else the parser rejects, e.g. a number too large for a double (no position).
    return InvalidArgumentError(fmt::format("{}: invalid JSON: {}", name, e.what()));
  }
  if (!doc.is_object()) {
    return InvalidArgumentError(
        fmt::format("{}:1:1: the configuration must be a JSON object, "
                    "found {}",
                    name, TypeName(doc)));
  }
  std::vector<std::string> known;
  for (const Field& f : Fields()) known.push_back(f.name);
  FootSlamConfig result = *config;
  for (auto item = doc.begin(); item != doc.end(); ++item) {
    const std::string& key = item.key();
    const json& value = item.value();
    auto it = std::find_if(Fields().begin(), Fields().end(),
                           [&](const Field& f) { return key == f.name; });
    auto [line, column] = KeyPosition(text, key);
    if (it == Fields().end()) {
      std::string nearest = NearestKey(key, known);
      return InvalidArgumentError(
          fmt::format("{}:{}:{}: unknown key {}{}", name, line, column, QuotedKey(key),
                      nearest.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", nearest)));
    }
    std::string expected = it->set(value, &result);
    if (!expected.empty()) {
      return InvalidArgumentError(fmt::format(
          "{}:{}:{}: {} = {}: must be {}, found {}", name, line, column, key,
          value.dump(-1, ' ', false, json::error_handler_t::replace), expected, TypeName(value)));
    }
  }
  *config = result;
  return Status::Ok();
}

Status LoadFootSlamConfigFile(const std::string& path, FootSlamConfig* config) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return NotFoundError(fmt::format("{}: cannot open the configuration file", path));
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().size() > (size_t{16} << 20)) {
    return InvalidArgumentError(fmt::format("{}: configuration file larger than 16 MiB", path));
  }
  return ApplyFootSlamConfigJson(path, text.str(), config);
}

}  // namespace grove::tools
