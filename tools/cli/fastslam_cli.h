// `grove fastslam run|victoria-park|evaluate|simulate|montecarlo`: their options and what runs
// them.
#ifndef GROVE_TOOLS_CLI_FASTSLAM_CLI_H_
#define GROVE_TOOLS_CLI_FASTSLAM_CLI_H_

#include <CLI/CLI.hpp>
#include <vector>

#include "tools/cli/command.h"

namespace grove::tools {

// Adds `fastslam` and its subcommands to `grove`.
std::vector<Command> AddFastSlamCommands(CLI::App* grove);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_FASTSLAM_CLI_H_
