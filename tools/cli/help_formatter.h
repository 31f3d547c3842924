// The help pages of the grove command (`grove ... --help`), laid out as a manual page: each
// option with its type (and REQUIRED) on the left; its description, range, choices and default
// on the right, wrapped to kHelpWidth columns.
#ifndef GROVE_TOOLS_CLI_HELP_FORMATTER_H_
#define GROVE_TOOLS_CLI_HELP_FORMATTER_H_

#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>

namespace grove::tools {

inline constexpr size_t kHelpWidth = 100;
inline constexpr size_t kHelpColumn = 30;  // where descriptions start

class HelpFormatter : public CLI::Formatter {
 public:
  HelpFormatter() { column_width(kHelpColumn); }

  std::string make_option(const CLI::Option* opt, bool is_positional) const override;
  std::string make_option_opts(const CLI::Option* opt) const override;
  std::string make_option_desc(const CLI::Option* opt) const override;
  std::string make_subcommand(const CLI::App* sub) const override;
  std::string make_description(const CLI::App* app) const override;
};

// Sets the formatter of `app`; the subcommands added after inherit it.
void UseHelpFormatter(CLI::App* app);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_HELP_FORMATTER_H_
