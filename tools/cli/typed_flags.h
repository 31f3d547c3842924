// Command-line options described for the help page and parsed by grove rather than by CLI11.
//
// CLI11 gets every value as text; Apply() parses it with ParseFieldValue, so every bad value is
// refused alike, naming the flag, the value and the rule (`--until = "abc": must be a number`,
// `--runs = 0: must be in 1..100000`), and non-finite numbers are refused for every real
// option. The help page (HelpFormatter) shows each option's type (INT, FLOAT, CHOICE, PATH,
// SIZE, LIST, TEXT), range, choices and default, taken from the same FieldInfo that checks the
// value, so the two cannot drift.
#ifndef GROVE_TOOLS_CLI_TYPED_FLAGS_H_
#define GROVE_TOOLS_CLI_TYPED_FLAGS_H_

#include <CLI/CLI.hpp>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove::tools {

// What the help page says of an option besides its description.
struct OptionDoc {
  std::string type;                  // INT, FLOAT, CHOICE, PATH, SIZE, LIST, TEXT, ...
  std::string range;                 // e.g. "1..1000", "[0, 10]", "> 0"; empty: none
  std::vector<std::string> choices;  // the allowed values (of each item, for a LIST)
  std::string default_text;          // empty: none shown
};

// Gives `option` the type, range, choices and default of `doc` for the help page.
CLI::Option* Document(CLI::Option* option, const OptionDoc& doc);

// The help page's type, range and choices of a field; the default is the caller's.
OptionDoc FieldDoc(const FieldInfo& info, std::string default_text);

// A path option (type PATH); `default_text` as the help page shows it ("" for none).
CLI::Option* AddPath(CLI::App* app, const std::string& flag, std::string* path,
                     const std::string& help, const std::string& default_text = "");

// Options of one subcommand whose values Apply() parses and range-checks.
class TypedFlags {
 public:
  explicit TypedFlags(CLI::App* app) : app_(app) {}
  TypedFlags(const TypedFlags&) = delete;
  TypedFlags& operator=(const TypedFlags&) = delete;

  // An option of `info`'s type and range (info.name is ignored: the flag names it); Apply()
  // passes its value to `set` when it was given. The help shows `default_text` as the default.
  CLI::Option* Add(const std::string& flag, FieldInfo info, const std::string& help,
                   const std::string& default_text, std::function<void(const FieldValue&)> set);

  // An integer in [min, max] into *target; the help's default is *target now.
  template <typename T>
  CLI::Option* Integer(const std::string& flag, T* target, int64_t min, int64_t max,
                       const std::string& help) {
    static_assert(std::is_integral_v<T> && std::is_signed_v<T>);
    return Add(flag, FieldInfo{"", "", FieldType::kInteger, kChangesResults, min, max, {}, {}},
               help, std::to_string(*target),
               [target](const FieldValue& v) { *target = static_cast<T>(std::get<int64_t>(v)); });
  }
  // A non-negative 64-bit integer into *target.
  CLI::Option* Unsigned(const std::string& flag, uint64_t* target, const std::string& help);
  // A finite number in `interval` into *target.
  CLI::Option* Real(const std::string& flag, double* target, Interval interval,
                    const std::string& help);
  // One of `choices` into *target.
  CLI::Option* Choice(const std::string& flag, std::string* target,
                      std::vector<std::string> choices, const std::string& help);
  // One or more integers in [min, max] (`--flag 10 100 1000` or `--flag 10,100,1000`) into
  // *target.
  CLI::Option* IntegerList(const std::string& flag, std::vector<int64_t>* target, int64_t min,
                           int64_t max, const std::string& help);
  // One or more of `choices` (`--flag a b` or `--flag a,b`) into *target.
  CLI::Option* ChoiceList(const std::string& flag, std::vector<std::string>* target,
                          std::vector<std::string> choices, const std::string& help);

  // Sets the target of every option given, in the order they were added. InvalidArgument for
  // the first bad value: "--flag = value: must be ...".
  Status Apply() const;

 private:
  // Receives the values given (one unless a list).
  using Setter = std::function<void(const std::vector<FieldValue>&)>;
  struct Entry {
    std::string flag;
    FieldInfo info;
    std::string text;                // a single value
    std::vector<std::string> texts;  // a list's values
    bool list = false;
    CLI::Option* option = nullptr;
    Setter set;
  };
  Entry& NewEntry(const std::string& flag, FieldInfo info, Setter set);

  CLI::App* app_;
  std::deque<Entry> entries_;  // stable addresses: CLI11 writes into `text` and `texts`
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_TYPED_FLAGS_H_
