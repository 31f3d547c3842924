#include "tools/cli/parse_errors.h"

#include <fmt/format.h>

#include <string>
#include <vector>

#include "grove/status.h"
#include "tools/cli/did_you_mean.h"
#include "tools/run/run_loop.h"

namespace grove::tools {
namespace {

// The subcommands the command line named, from `app` down to the last.
std::vector<CLI::App*> ParsedChain(CLI::App& app) {
  std::vector<CLI::App*> chain = {&app};
  while (!chain.back()->get_subcommands().empty()) {
    chain.push_back(chain.back()->get_subcommands().front());
  }
  return chain;
}

// "footslam run: " for `grove footslam run`; "" for the command itself.
std::string CommandPrefix(const std::vector<CLI::App*>& chain) {
  std::string path;
  for (size_t i = 1; i < chain.size(); ++i) path += (i > 1 ? " " : "") + chain[i]->get_name();
  return path.empty() ? path : path + ": ";
}

std::vector<std::string> OptionNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* opt : app.get_options()) {
    for (const std::string& n : opt->get_lnames()) names.push_back("--" + n);
    for (const std::string& n : opt->get_snames()) names.push_back("-" + n);
  }
  return names;
}

std::vector<std::string> CommandNames(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub :
       app.get_subcommands([](CLI::App* a) { return !a->get_name().empty(); })) {
    names.push_back(sub->get_name());
  }
  return names;
}

// "a, b or c".
std::string OneOf(const std::vector<std::string>& names) {
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return out;
}

std::string Suggestion(const std::string& nearest) {
  return nearest.empty() ? "" : fmt::format(" (did you mean {}?)", nearest);
}

// The first word `app` could not take: an unknown option, command or argument.
std::string UnexpectedWord(CLI::App& app, const std::string& prefix, std::string word) {
  if (word.size() > 1 && word[0] == '-') {
    word = word.substr(0, word.find('='));
    return fmt::format("{}unknown option {}{}", prefix, QuoteForMessage(word),
                       Suggestion(DidYouMean(word, OptionNames(app))));
  }
  const std::vector<std::string> commands = CommandNames(app);
  if (!commands.empty()) {
    const std::string nearest = DidYouMean(word, commands);
    if (!nearest.empty()) {
      return fmt::format("{}unknown command {}{}", prefix, QuoteForMessage(word),
                         Suggestion(nearest));
    }
    return fmt::format("{}unknown command {}: must be {}", prefix, QuoteForMessage(word),
                       OneOf(commands));
  }
  return fmt::format("{}unexpected argument {}{}", prefix, QuoteForMessage(word),
                     Suggestion(DidYouMean("--" + word, OptionNames(app))));
}

// CLI11's own message, one line and bounded.
std::string Cli11Message(const CLI::ParseError& e) {
  const std::string what = e.what();
  std::string out;
  for (char c : what.substr(0, 200)) out += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
  return what.size() > 200 ? out + "..." : out;
}

}  // namespace

int ReportParseError(CLI::App& app, const CLI::ParseError& e) {
  if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) {
    app.exit(e);  // --help or --version: printed on stdout
    return kExitOk;
  }
  const std::vector<CLI::App*> chain = ParsedChain(app);
  const std::string prefix = CommandPrefix(chain);
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const std::vector<std::string> left = (*it)->remaining();
    if (!left.empty()) return Fail(kExitUsage, UnexpectedWord(**it, prefix, left.front()));
  }
  CLI::App& last = *chain.back();
  const std::string name = e.get_name();
  if (name == "RequiredError" && last.get_require_subcommand_min() > 0) {
    return Fail(kExitUsage,
                fmt::format("{}a command is required: {}", prefix, OneOf(CommandNames(last))));
  }
  // CLI11's "--x: 1 required TEXT missing", "--x: At Most 1 required but received 2" and
  // "Could not convert: --flag = text" (a flag given a value).
  const std::string what = e.what();
  const size_t colon = what.find(": ");
  if (name == "ArgumentMismatch" && colon != std::string::npos) {
    const std::string option = what.substr(0, colon);
    if (what.find("missing") != std::string::npos) {
      return Fail(kExitUsage, fmt::format("{}{} needs a value", prefix, option));
    }
    if (what.find("At Most 1") != std::string::npos) {
      return Fail(kExitUsage, fmt::format("{}{} is given more than once", prefix, option));
    }
  }
  const std::string unconverted = "Could not convert: ";
  if (name == "ConversionError" && what.rfind(unconverted, 0) == 0) {
    const std::string rest = what.substr(unconverted.size());
    const size_t equals = rest.find(" = ");
    if (equals != std::string::npos) {
      return Fail(kExitUsage,
                  fmt::format("{}{} = {}: a flag takes no value", prefix, rest.substr(0, equals),
                              QuoteForMessage(rest.substr(equals + 3))));
    }
  }
  return Fail(kExitUsage, fmt::format("{}{}", prefix, Cli11Message(e)));
}

}  // namespace grove::tools
