#include "tools/cli/help_formatter.h"

#include <cctype>
#include <memory>
#include <sstream>
#include <vector>

namespace grove::tools {
namespace {

// The words of `text`, except that a word ending in ':' ("Default:") keeps the next one, and an
// interval ("[0, 10]", "(0, 1]") stays whole: the units a line may break between.
std::vector<std::string> Units(const std::string& text) {
  std::vector<std::string> units;
  std::istringstream words(text);
  std::string word;
  bool join = false;
  int depth = 0;  // inside an interval
  while (words >> word) {
    if (join) {
      units.back() += " " + word;
    } else {
      units.push_back(word);
    }
    for (size_t i = 0; i < word.size(); ++i) {
      const bool opens = (word[i] == '[' || word[i] == '(') && i + 1 < word.size() &&
                         (std::isdigit(static_cast<unsigned char>(word[i + 1])) ||
                          word[i + 1] == '-' || word[i + 1] == '.');
      if (opens) ++depth;
      if (depth > 0 && (word[i] == ']' || word[i] == ')')) --depth;
    }
    join = depth > 0 || word.back() == ':';
  }
  return units;
}

// `text` broken into lines of at most `width` characters (a longer unit stands alone).
std::vector<std::string> Wrap(const std::string& text, size_t width) {
  std::vector<std::string> lines;
  std::string line;
  for (const std::string& unit : Units(text)) {
    if (!line.empty() && line.size() + 1 + unit.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + unit;
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

// `left` in the first column and `text` wrapped beside it, on the next line when `left` is too
// wide.
std::string TwoColumns(const std::string& left, const std::string& text) {
  const std::string indent(kHelpColumn, ' ');
  std::string out = "  " + left;
  const std::vector<std::string> lines = Wrap(text, kHelpWidth - kHelpColumn);
  if (lines.empty()) return out + "\n";
  if (out.size() + 1 > kHelpColumn) {
    out += "\n" + indent;
  } else {
    out.append(kHelpColumn - out.size(), ' ');
  }
  for (size_t i = 0; i < lines.size(); ++i) out += (i > 0 ? "\n" + indent : "") + lines[i];
  return out + "\n";
}

}  // namespace

std::string HelpFormatter::make_option(const CLI::Option* opt, bool is_positional) const {
  return TwoColumns(make_option_name(opt, is_positional) + make_option_opts(opt),
                    make_option_desc(opt));
}

std::string HelpFormatter::make_option_opts(const CLI::Option* opt) const {
  if (opt->get_type_size() == 0) return "";  // a flag
  std::string out = " " + opt->get_type_name();
  if (opt->get_required()) out += " REQUIRED";
  return out;
}

std::string HelpFormatter::make_option_desc(const CLI::Option* opt) const {
  std::string text = opt->get_description();
  const std::string& default_text = opt->get_default_str();
  if (!default_text.empty()) {
    if (!text.empty()) text += text.back() == '.' ? " " : ". ";
    text += "Default: " + default_text;
  }
  return text;
}

std::string HelpFormatter::make_subcommand(const CLI::App* sub) const {
  return TwoColumns(sub->get_display_name(true), sub->get_description());
}

std::string HelpFormatter::make_description(const CLI::App* app) const {
  std::string out;
  for (const std::string& line : Wrap(app->get_description(), kHelpWidth)) out += line + "\n";
  return out;
}

void UseHelpFormatter(CLI::App* app) { app->formatter(std::make_shared<HelpFormatter>()); }

}  // namespace grove::tools
