#include "grove/config_fields.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

namespace grove {
namespace {

std::string IntervalText(const Interval& in) {
  const bool no_max = std::isinf(in.max) && in.max > 0;
  const bool no_min = std::isinf(in.min) && in.min < 0;
  if (no_min && no_max) return "finite";
  if (no_max) return fmt::format("{} {}", in.min_open ? ">" : ">=", in.min);
  if (no_min) return fmt::format("{} {}", in.max_open ? "<" : "<=", in.max);
  return fmt::format("in {}{}, {}{}", in.min_open ? '(' : '[', in.min, in.max,
                     in.max_open ? ')' : ']');
}

}  // namespace

std::string FieldRangeText(const FieldInfo& info) {
  switch (info.type) {
    case FieldType::kInteger:
      if (info.max_integer == std::numeric_limits<int64_t>::max()) {
        return fmt::format(">= {}", info.min_integer);
      }
      return fmt::format("in {}..{}", info.min_integer, info.max_integer);
    case FieldType::kUnsigned:
      return "in 0..18446744073709551615";
    case FieldType::kReal:
      return IntervalText(info.interval);
    case FieldType::kChoice: {
      std::string out = "one of ";
      for (size_t i = 0; i < info.choices.size(); ++i) {
        out += fmt::format("{}\"{}\"", i == 0 ? "" : ", ", info.choices[i]);
      }
      return out;
    }
  }
  return "";
}

namespace {

std::string_view Trimmed(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

template <typename T>
bool ParseWhole(std::string_view text, T* value) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return ec == std::errc() && end == text.data() + text.size();
}

}  // namespace

std::string FormatFieldValue(const FieldInfo& info, const FieldValue& value) {
  if (info.type == FieldType::kChoice) {
    const int64_t i = std::get<int64_t>(value);
    if (i >= 0 && i < static_cast<int64_t>(info.choices.size())) return info.choices[i];
    return std::to_string(i);
  }
  return std::visit([](auto v) { return fmt::format("{}", v); }, value);
}

Status CheckFieldValue(const FieldInfo& info, const FieldValue& value) {
  bool ok = true;
  switch (info.type) {
    case FieldType::kInteger:
    case FieldType::kChoice: {
      const int64_t v = std::get<int64_t>(value);
      ok = v >= info.min_integer && v <= info.max_integer;
      break;
    }
    case FieldType::kUnsigned:
      break;
    case FieldType::kReal: {
      const double v = std::get<double>(value);
      const Interval& in = info.interval;
      ok = std::isfinite(v) && (in.min_open ? v > in.min : v >= in.min) &&
           (in.max_open ? v < in.max : v <= in.max);
      break;
    }
  }
  if (ok) return Status::Ok();
  return InvalidArgumentError(fmt::format("{} = {}: must be {}", info.name,
                                          FormatFieldValue(info, value), FieldRangeText(info)));
}

StatusOr<FieldValue> ParseFieldValue(const FieldInfo& info, std::string_view text) {
  const std::string_view t = Trimmed(text);
  FieldValue value;
  bool parsed = false;
  const char* expected = "";
  switch (info.type) {
    case FieldType::kInteger: {
      int64_t v = 0;
      parsed = ParseWhole(t, &v);
      value = v;
      expected = "an integer";
      break;
    }
    case FieldType::kUnsigned: {
      uint64_t v = 0;
      parsed = !t.starts_with('-') && ParseWhole(t, &v);
      value = v;
      expected = "a non-negative integer";
      break;
    }
    case FieldType::kReal: {
      double v = 0;
      parsed = ParseWhole(t, &v);
      value = v;
      expected = "a number";
      break;
    }
    case FieldType::kChoice:
      for (size_t i = 0; i < info.choices.size(); ++i) {
        if (t == info.choices[i]) {
          value = static_cast<int64_t>(i);
          parsed = true;
        }
      }
      if (!parsed) {
        return InvalidArgumentError(fmt::format("{} = {}: must be {}", info.name,
                                                QuoteForMessage(text), FieldRangeText(info)));
      }
      break;
  }
  if (!parsed) {
    return InvalidArgumentError(
        fmt::format("{} = {}: must be {}", info.name, QuoteForMessage(text), expected));
  }
  GROVE_RETURN_IF_ERROR(CheckFieldValue(info, value));
  return value;
}

}  // namespace grove
