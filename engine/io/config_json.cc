#include "engine/io/config_json.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <limits>
#include <set>
#include <system_error>

namespace grove {
namespace {

using nlohmann::json;

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

// The key as JSON writes it: quoted, control characters escaped.
std::string JsonQuoted(const std::string& key) {
  return json(key).dump(-1, ' ', false, json::error_handler_t::replace);
}

// A JSON value for a one-line message: a string quoted and escaped, anything else as its
// compact JSON text (printable ASCII: JSON escapes control characters), both cut.
std::string ValueText(const json& value) {
  if (value.is_string()) return QuoteForMessage(value.get<std::string>());
  std::string text = value.dump(-1, ' ', true, json::error_handler_t::replace);
  return text.size() > 64 ? text.substr(0, 64) + "..." : text;
}

// The byte offset of the first place nesting passes kMaxConfigDepth, or npos. Counts brackets
// outside strings, so the parser (and the recursive dump of a value for a message) never sees
// a deep document.
size_t TooDeepAt(const std::string& text) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxConfigDepth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::string::npos;
}

}  // namespace

StatusOr<std::vector<ConfigEntry>> ParseConfigObject(const std::string& name,
                                                     const std::string& text) {
  if (text.size() > kMaxConfigBytes) {
    return InvalidArgumentError(
        fmt::format("{}: larger than {} bytes: not a configuration", name, kMaxConfigBytes));
  }
  if (size_t at = TooDeepAt(text); at != std::string::npos) {
    auto [line, column] = LineColumn(text, at);
    return InvalidArgumentError(
        fmt::format("{}:{}:{}: nested deeper than {} levels", name, line, column, kMaxConfigDepth));
  }
  // The parser takes a NUL byte for the end of the input, so a document followed by a NUL and
  // anything at all would pass; JSON text has no raw NUL (not even in a string).
  if (size_t at = text.find('\0'); at != std::string::npos) {
    auto [line, column] = LineColumn(text, at);
    return InvalidArgumentError(
        fmt::format("{}:{}:{}: invalid JSON: a NUL byte (JSON text has none)", name, line, column));
  }
  json doc;
  std::vector<std::string> keys;  // the top-level keys in order, repeats included
  try {
    doc = json::parse(text, [&](int depth, json::parse_event_t event, json& parsed) {
      if (depth == 1 && event == json::parse_event_t::key)
        keys.push_back(parsed.get<std::string>());
      return true;
    });
  } catch (const json::parse_error& e) {
    // e.byte is the 1-based offset of the byte where parsing failed; one past the end means
    // "unexpected end of input", reported at the last byte.
    size_t offset = e.byte == 0 ? 0 : e.byte - 1;
    if (!text.empty() && offset >= text.size()) offset = text.size() - 1;
    auto [line, column] = LineColumn(text, offset);
    std::string what = e.what();
    size_t cut = what.find("syntax error");
    return InvalidArgumentError(
        fmt::format("{}:{}:{}: invalid JSON: {}", name, line, column,
                    QuoteForMessage(cut == std::string::npos ? what : what.substr(cut), 200)));
  } catch (const json::exception& e) {
    // Anything else the parser rejects, e.g. a number too large for a double (no position).
    return InvalidArgumentError(
        fmt::format("{}: invalid JSON: {}", name, QuoteForMessage(e.what(), 200)));
  }
  if (!doc.is_object()) {
    return InvalidArgumentError(fmt::format(
        "{}:1:1: the configuration must be a JSON object, found {}", name, doc.type_name()));
  }
  std::vector<ConfigEntry> entries;
  std::set<std::string> seen;
  size_t search_from = 0;
  for (const std::string& key : keys) {
    // Where the key stands: its next quoted spelling (1:1 when the file spells it with escapes
    // that differ from JSON's own).
    size_t pos = text.find(JsonQuoted(key), search_from);
    auto [line, column] =
        pos == std::string::npos ? std::pair<int64_t, int64_t>{1, 1} : LineColumn(text, pos);
    if (pos != std::string::npos) search_from = pos + 1;
    if (!seen.insert(key).second) {
      return InvalidArgumentError(fmt::format("{}:{}:{}: duplicate key {}: give each key once",
                                              name, line, column, QuoteForMessage(key)));
    }
    entries.push_back({key, doc.at(key), line, column});
  }
  return entries;
}

StatusOr<FieldValue> FieldValueFromJson(const std::string& name, const FieldInfo& info,
                                        const ConfigEntry& e) {
  const json& v = e.value;
  FieldValue value;
  const char* expected = nullptr;
  switch (info.type) {
    case FieldType::kInteger:
      if (!v.is_number_integer()) {
        expected = "an integer";
      } else if (v.is_number_unsigned() &&
                 v.get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) {
        expected = "an integer in range";
      } else {
        value = v.is_number_unsigned() ? static_cast<int64_t>(v.get<uint64_t>()) : v.get<int64_t>();
      }
      break;
    case FieldType::kUnsigned:
      if (v.is_number_unsigned()) {
        value = v.get<uint64_t>();
      } else if (v.is_number_integer() && v.get<int64_t>() >= 0) {
        value = static_cast<uint64_t>(v.get<int64_t>());
      } else {
        expected = "a non-negative integer";
      }
      break;
    case FieldType::kReal:
      if (!v.is_number()) {
        expected = "a number";
      } else {
        value = v.get<double>();
      }
      break;
    case FieldType::kChoice: {
      auto it = v.is_string()
                    ? std::find(info.choices.begin(), info.choices.end(), v.get<std::string>())
                    : info.choices.end();
      if (it == info.choices.end()) {
        std::string choices;
        for (const std::string& c : info.choices) {
          choices += fmt::format("{}\"{}\"", choices.empty() ? "" : ", ", c);
        }
        return InvalidArgumentError(fmt::format("{}:{}:{}: {} = {}: must be one of {}, found {}",
                                                name, e.line, e.column, e.key, ValueText(v),
                                                choices, v.type_name()));
      }
      value = static_cast<int64_t>(it - info.choices.begin());
      break;
    }
  }
  if (expected != nullptr) {
    return InvalidArgumentError(fmt::format("{}:{}:{}: {} = {}: must be {}, found {}", name, e.line,
                                            e.column, e.key, ValueText(v), expected,
                                            v.type_name()));
  }
  if (Status s = CheckFieldValue(info, value); !s.ok()) {
    return InvalidArgumentError(fmt::format("{}:{}:{}: {}", name, e.line, e.column, s.message()));
  }
  return value;
}

json FieldValueToJson(const FieldInfo& info, const FieldValue& value) {
  if (info.type == FieldType::kChoice) return json(FormatFieldValue(info, value));
  return std::visit([](auto v) { return json(v); }, value);
}

Status UnknownKeyError(const std::string& name, const ConfigEntry& e,
                       const std::vector<std::string>& known) {
  std::string nearest = NearestKey(e.key, known);
  return InvalidArgumentError(
      fmt::format("{}:{}:{}: unknown key {}{}", name, e.line, e.column, QuoteForMessage(e.key),
                  nearest.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", nearest)));
}

Status ParseConfigJson(const std::string& name, const std::string& text,
                       std::span<const FieldInfo* const> fields,
                       std::vector<FieldSetting>* settings,
                       const std::vector<std::string>& other_keys,
                       const std::function<Status(const ConfigJsonKey&)>& on_other_key) {
  StatusOr<std::vector<ConfigEntry>> entries = ParseConfigObject(name, text);
  if (!entries.ok()) return entries.status();
  for (const ConfigEntry& e : *entries) {
    auto field = std::find_if(fields.begin(), fields.end(),
                              [&](const FieldInfo* f) { return e.key == f->name; });
    if (field != fields.end()) {
      StatusOr<FieldValue> v = FieldValueFromJson(name, **field, e);
      if (!v.ok()) return v.status();
      settings->push_back({static_cast<size_t>(field - fields.begin()), *v});
    } else if (std::find(other_keys.begin(), other_keys.end(), e.key) != other_keys.end()) {
      if (on_other_key) {
        GROVE_RETURN_IF_ERROR(on_other_key(
            ConfigJsonKey{e.key, e.value.dump(-1, ' ', false, json::error_handler_t::replace),
                          e.line, e.column}));
      }
    } else {
      std::vector<std::string> known = other_keys;
      for (const FieldInfo* f : fields) known.push_back(f->name);
      return UnknownKeyError(name, e, known);
    }
  }
  return Status::Ok();
}

std::string FieldsToJson(std::span<const FieldInfo* const> fields,
                         std::span<const FieldValue> values, int indent) {
  json out = json::object();
  for (size_t i = 0; i < fields.size() && i < values.size(); ++i) {
    out[fields[i]->name] = FieldValueToJson(*fields[i], values[i]);
  }
  return out.dump(indent);
}

StatusOr<std::string> ReadConfigFile(const std::string& path) {
  if (path.empty()) return InvalidArgumentError("--config: the path is empty");
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    std::string message = fmt::format("{}: cannot open the configuration file: {}", path,
                                      std::generic_category().message(err));
    return err == ENOENT ? Status(NotFoundError(message)) : Status(IoError(message));
  }
  struct stat st = {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return IoError(fmt::format("{}: {}, not a configuration file", path,
                               S_ISDIR(st.st_mode) ? "is a directory" : "is not a regular file"));
  }
  std::string text;
  char chunk[1 << 16];
  for (;;) {
    ssize_t n = ::read(fd, chunk, sizeof(chunk));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      return IoError(
          fmt::format("{}: cannot read: {}", path, std::generic_category().message(err)));
    }
    if (n == 0) break;
    text.append(chunk, static_cast<size_t>(n));
    if (text.size() > kMaxConfigBytes) {
      ::close(fd);
      return InvalidArgumentError(
          fmt::format("{}: larger than {} bytes: not a configuration", path, kMaxConfigBytes));
    }
  }
  ::close(fd);
  return text;
}

std::string NearestKey(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  size_t best_distance = std::max<size_t>(3, key.size() / 3) + 1;
  if (key.size() > 256) return best;  // no key is that long
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

}  // namespace grove
