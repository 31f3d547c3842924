// ConfigField: one field of a configuration struct, named, typed, bounded and documented.
//
// Each model lists its configuration once, as a table of these beside its struct
// (FootSlamConfigFields()). The table drives the range checks of the struct's Validate(), the
// keys of its JSON form, --print-config, the command line's flags and the block of
// result-changing fields that a checkpoint stores, so a new field is added in two places: the
// struct and the table.
//
//   struct MyConfig {
//     int64_t particles = 1000;
//     double sigma_m = 0.1;
//   };
//   static const auto* fields = new std::vector<grove::ConfigField<MyConfig>>{
//       grove::IntegerField("particles", &MyConfig::particles, 1, 1000000,
//                           grove::kChangesResults, "Number of particles"),
//       grove::RealField("sigma_m", &MyConfig::sigma_m, grove::Interval::AtLeast(0),
//                        grove::kChangesResults, "Noise, metres"),
//   };
//   return grove::CheckFieldRanges(*fields, MyConfig{});  // OK, or the first field out of range
#ifndef GROVE_CONFIG_FIELDS_H_
#define GROVE_CONFIG_FIELDS_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "grove/export.h"
#include "grove/status.h"

namespace grove {

enum class FieldType {
  kInteger,   // a signed integer (int, int64_t)
  kUnsigned,  // an unsigned 64-bit integer (seeds)
  kReal,      // a double
  kChoice,    // an enum, named by one of its choices
};

// Whether a field changes what a run computes. Checkpoints store the fields that do and resume
// only under equal values; the others (threads, batch sizes) may differ on resume.
enum FieldEffect : bool { kChangesSpeedOnly = false, kChangesResults = true };

// An interval of reals; open or closed at each end. Every real field must also be finite.
struct Interval {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;
  static Interval Closed(double lo, double hi) { return {lo, hi, false, false}; }
  static Interval AtLeast(double lo) { return {lo, std::numeric_limits<double>::infinity()}; }
  static Interval Above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true}; }
  static Interval LeftOpen(double lo, double hi) { return {lo, hi, true, false}; }
  static Interval Open(double lo, double hi) { return {lo, hi, true, true}; }
};

// A field's value: int64_t (kInteger, and kChoice as the choice's index), uint64_t (kUnsigned)
// or double (kReal).
using FieldValue = std::variant<int64_t, uint64_t, double>;

// Everything about a field but how to reach it in the struct.
struct FieldInfo {
  const char* name;  // JSON key; the command line's flag is --name with '-' for '_'
  const char* help;  // one line: meaning and unit
  FieldType type;
  FieldEffect effect;
  int64_t min_integer = 0;  // kInteger: the closed range
  int64_t max_integer = 0;
  Interval interval;                 // kReal
  std::vector<std::string> choices;  // kChoice: names, in the order of the enum's values
};

// The value as text: decimal integers, the shortest exact form of a double ("0.5", "1e+308",
// "nan"), a choice's name.
GROVE_EXPORT std::string FormatFieldValue(const FieldInfo& info, const FieldValue& value);
// The field's rule as its messages end: "in 1..1000", ">= 0", "in (0, 1]", "finite",
// "one of \"a\", \"b\"".
GROVE_EXPORT std::string FieldRangeText(const FieldInfo& info);
// InvalidArgument "name = value: must be ..." when `value` is outside the field's range.
GROVE_EXPORT Status CheckFieldValue(const FieldInfo& info, const FieldValue& value);
// Parses the text form of a value (a command-line flag): InvalidArgument
// "name = \"text\": must be an integer" (a number, one of "a", "b"), then the range check.
GROVE_EXPORT StatusOr<FieldValue> ParseFieldValue(const FieldInfo& info, std::string_view text);

template <typename Config>
struct ConfigField {
  FieldInfo info;
  std::function<FieldValue(const Config&)> get;
  // REQUIRES: `value` holds the alternative of info.type (and a valid choice index).
  std::function<void(Config*, const FieldValue&)> set;
};

template <typename Config, typename T>
ConfigField<Config> IntegerField(const char* name, T Config::*member, int64_t min, int64_t max,
                                 FieldEffect effect, const char* help) {
  static_assert(std::is_integral_v<T> && std::is_signed_v<T>);
  return {FieldInfo{name, help, FieldType::kInteger, effect, min, max, {}, {}},
          [member](const Config& c) { return FieldValue(static_cast<int64_t>(c.*member)); },
          [member](Config* c, const FieldValue& v) {
            c->*member = static_cast<T>(std::get<int64_t>(v));
          }};
}

template <typename Config>
ConfigField<Config> UnsignedField(const char* name, uint64_t Config::*member, FieldEffect effect,
                                  const char* help) {
  return {FieldInfo{name, help, FieldType::kUnsigned, effect, 0, 0, {}, {}},
          [member](const Config& c) { return FieldValue(c.*member); },
          [member](Config* c, const FieldValue& v) { c->*member = std::get<uint64_t>(v); }};
}

template <typename Config>
ConfigField<Config> RealField(const char* name, double Config::*member, Interval interval,
                              FieldEffect effect, const char* help) {
  return {FieldInfo{name, help, FieldType::kReal, effect, 0, 0, interval, {}},
          [member](const Config& c) { return FieldValue(c.*member); },
          [member](Config* c, const FieldValue& v) { c->*member = std::get<double>(v); }};
}

// REQUIRES: the enum's values are 0 .. choices.size() - 1, in the order of `choices`.
template <typename Config, typename E>
ConfigField<Config> ChoiceField(const char* name, E Config::*member,
                                std::vector<std::string> choices, FieldEffect effect,
                                const char* help) {
  static_assert(std::is_enum_v<E>);
  const int64_t last = static_cast<int64_t>(choices.size()) - 1;
  return {FieldInfo{name, help, FieldType::kChoice, effect, 0, last, {}, std::move(choices)},
          [member](const Config& c) { return FieldValue(static_cast<int64_t>(c.*member)); },
          [member](Config* c, const FieldValue& v) {
            c->*member = static_cast<E>(std::get<int64_t>(v));
          }};
}

// The range check of every field, in table order: the first field out of range.
template <typename Config>
Status CheckFieldRanges(const std::vector<ConfigField<Config>>& fields, const Config& config) {
  for (const ConfigField<Config>& f : fields) {
    GROVE_RETURN_IF_ERROR(CheckFieldValue(f.info, f.get(config)));
  }
  return Status::Ok();
}

// The field named `name`, or nullptr.
template <typename Config>
const ConfigField<Config>* FindField(const std::vector<ConfigField<Config>>& fields,
                                     std::string_view name) {
  for (const ConfigField<Config>& f : fields) {
    if (name == f.info.name) return &f;
  }
  return nullptr;
}

}  // namespace grove

#endif  // GROVE_CONFIG_FIELDS_H_
