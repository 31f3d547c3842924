#include "tools/cli/typed_flags.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <variant>

namespace grove::tools {
namespace {

std::string TypeName(FieldType type) {
  switch (type) {
    case FieldType::kInteger:
    case FieldType::kUnsigned:
      return "INT";
    case FieldType::kReal:
      return "FLOAT";
    case FieldType::kChoice:
      return "CHOICE";
  }
  return "TEXT";
}

// The range as the help page writes it: "1..1000", ">= 0", "[0, 10]", "(0, 1]" (the rule of the
// field's messages without its "in "); choices are listed apart.
std::string RangeHelp(const FieldInfo& info) {
  if (info.type == FieldType::kChoice) return "";
  const std::string rule = FieldRangeText(info);
  if (rule == "finite") return "any finite number";
  return rule.starts_with("in ") ? rule.substr(3) : rule;
}

// Parses `text` for the option `info` names: a real must be finite before its range is
// checked, so "inf" is refused as not finite rather than as out of range.
StatusOr<FieldValue> ParseOptionValue(const FieldInfo& info, const std::string& text) {
  if (info.type != FieldType::kReal) return ParseFieldValue(info, text);
  FieldInfo finite = info;
  finite.interval = Interval{};
  StatusOr<FieldValue> value = ParseFieldValue(finite, text);
  if (!value.ok()) return value.status();
  GROVE_RETURN_IF_ERROR(CheckFieldValue(info, *value));
  return value;
}

}  // namespace

CLI::Option* Document(CLI::Option* option, const OptionDoc& doc) {
  std::string description = option->get_description();
  auto sentence = [&description](const std::string& text) {
    if (text.empty()) return;
    if (!description.empty()) description += description.back() == '.' ? " " : ". ";
    description += text;
  };
  if (!doc.range.empty()) sentence("Range: " + doc.range);
  if (!doc.choices.empty()) {
    std::string list;
    for (const std::string& c : doc.choices) {
      list += (list.empty() ? "" : ", ") + (c.find(' ') == std::string::npos ? c : '"' + c + '"');
    }
    sentence((doc.type == "LIST" ? "Each one of: " : "One of: ") + list);
  }
  option->description(description);
  option->type_name(doc.type);
  option->default_str(doc.default_text);
  return option;
}

OptionDoc FieldDoc(const FieldInfo& info, std::string default_text) {
  return {TypeName(info.type), RangeHelp(info), info.choices, std::move(default_text)};
}

CLI::Option* AddPath(CLI::App* app, const std::string& flag, std::string* path,
                     const std::string& help, const std::string& default_text) {
  return Document(app->add_option(flag, *path, help), {"PATH", "", {}, default_text});
}

TypedFlags::Entry& TypedFlags::NewEntry(const std::string& flag, FieldInfo info, Setter set) {
  Entry& e = entries_.emplace_back();
  e.flag = flag;
  e.info = std::move(info);
  e.info.name = e.flag.c_str();  // messages name the flag
  e.set = std::move(set);
  return e;
}

CLI::Option* TypedFlags::Add(const std::string& flag, FieldInfo info, const std::string& help,
                             const std::string& default_text,
                             std::function<void(const FieldValue&)> set) {
  Entry& e = NewEntry(flag, std::move(info),
                      [set = std::move(set)](const std::vector<FieldValue>& v) { set(v[0]); });
  e.option = app_->add_option(flag, e.text, help);
  return Document(e.option, FieldDoc(e.info, default_text));
}

CLI::Option* TypedFlags::Unsigned(const std::string& flag, uint64_t* target,
                                  const std::string& help) {
  return Add(flag, FieldInfo{"", "", FieldType::kUnsigned, kChangesResults, 0, 0, {}, {}}, help,
             std::to_string(*target),
             [target](const FieldValue& v) { *target = std::get<uint64_t>(v); });
}

CLI::Option* TypedFlags::Real(const std::string& flag, double* target, Interval interval,
                              const std::string& help) {
  FieldInfo info{"", "", FieldType::kReal, kChangesResults, 0, 0, interval, {}};
  const std::string default_text = FormatFieldValue(info, *target);
  return Add(flag, std::move(info), help, default_text,
             [target](const FieldValue& v) { *target = std::get<double>(v); });
}

CLI::Option* TypedFlags::Choice(const std::string& flag, std::string* target,
                                std::vector<std::string> choices, const std::string& help) {
  const auto last = static_cast<int64_t>(choices.size()) - 1;
  FieldInfo info{"", "", FieldType::kChoice, kChangesResults, 0, last, {}, std::move(choices)};
  auto set = [target, names = info.choices](const FieldValue& v) {
    *target = names[static_cast<size_t>(std::get<int64_t>(v))];
  };
  return Add(flag, std::move(info), help, *target, std::move(set));
}

CLI::Option* TypedFlags::IntegerList(const std::string& flag, std::vector<int64_t>* target,
                                     int64_t min, int64_t max, const std::string& help) {
  Entry& e =
      NewEntry(flag, FieldInfo{"", "", FieldType::kInteger, kChangesResults, min, max, {}, {}},
               [target](const std::vector<FieldValue>& values) {
                 target->clear();
                 for (const FieldValue& v : values) target->push_back(std::get<int64_t>(v));
               });
  e.list = true;
  e.option = app_->add_option(flag, e.texts, help);
  std::string defaults;
  for (int64_t n : *target) defaults += (defaults.empty() ? "" : " ") + std::to_string(n);
  OptionDoc doc = FieldDoc(e.info, defaults);
  doc.type = "LIST";
  doc.range = "each " + doc.range;
  return Document(e.option, doc);
}

CLI::Option* TypedFlags::ChoiceList(const std::string& flag, std::vector<std::string>* target,
                                    std::vector<std::string> choices, const std::string& help) {
  const auto last = static_cast<int64_t>(choices.size()) - 1;
  Entry& e = NewEntry(
      flag, FieldInfo{"", "", FieldType::kChoice, kChangesResults, 0, last, {}, std::move(choices)},
      nullptr);
  e.set = [target, names = e.info.choices](const std::vector<FieldValue>& values) {
    target->clear();
    for (const FieldValue& v : values) {
      target->push_back(names[static_cast<size_t>(std::get<int64_t>(v))]);
    }
  };
  e.list = true;
  e.option = app_->add_option(flag, e.texts, help);
  std::string defaults;
  for (const std::string& n : *target) defaults += (defaults.empty() ? "" : " ") + n;
  OptionDoc doc = FieldDoc(e.info, defaults);
  doc.type = "LIST";
  return Document(e.option, doc);
}

namespace {

// A list's items: each word given, split at commas (`--threads 1,2,4` or `--threads 1 2 4`).
// InvalidArgument for an empty item (`1,,2`, a trailing comma).
StatusOr<std::vector<std::string>> ListItems(const FieldInfo& info,
                                             const std::vector<std::string>& words) {
  std::vector<std::string> items;
  for (const std::string& word : words) {
    size_t begin = 0;
    for (;;) {
      const size_t end = std::min(word.find(',', begin), word.size());
      if (end == begin) {
        return InvalidArgumentError(fmt::format(
            "{} = {}: an empty item; must be a list of values, each {}", info.name,
            QuoteForMessage(word),
            info.type == FieldType::kChoice ? "one of the choices" : FieldRangeText(info)));
      }
      items.push_back(word.substr(begin, end - begin));
      if (end == word.size()) break;
      begin = end + 1;
    }
  }
  return items;
}

}  // namespace

Status TypedFlags::Apply() const {
  for (const Entry& e : entries_) {
    if (e.option->count() == 0) continue;
    StatusOr<std::vector<std::string>> texts =
        e.list ? ListItems(e.info, e.texts) : std::vector<std::string>{e.text};
    if (!texts.ok()) return texts.status();
    std::vector<FieldValue> values;
    for (const std::string& text : *texts) {
      StatusOr<FieldValue> v = ParseOptionValue(e.info, text);
      if (!v.ok()) return v.status();
      values.push_back(*v);
    }
    e.set(values);  // a list given replaces the default one
  }
  return Status::Ok();
}

}  // namespace grove::tools
