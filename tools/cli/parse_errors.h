// CLI11's parse errors in grove's form: one short line "grove: error: ...", exit code 2, with
// the nearest option or command suggested for a mistyped one.
#ifndef GROVE_TOOLS_CLI_PARSE_ERRORS_H_
#define GROVE_TOOLS_CLI_PARSE_ERRORS_H_

#include <CLI/CLI.hpp>

namespace grove::tools {

// After app.parse() threw `e`: prints the help page or the version for --help and --version
// (exit code 0), otherwise one error line naming the command, e.g.
//   grove: error: footslam run: unknown option "--particels" (did you mean --particles?)
//   grove: error: footslam: unknown command "rn" (did you mean run?)
// and returns 2.
int ReportParseError(CLI::App& app, const CLI::ParseError& e);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_PARSE_ERRORS_H_
