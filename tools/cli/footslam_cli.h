// `grove footslam run|batch|simulate|evaluate|render`: their options and what runs them.
#ifndef GROVE_TOOLS_CLI_FOOTSLAM_CLI_H_
#define GROVE_TOOLS_CLI_FOOTSLAM_CLI_H_

#include <CLI/CLI.hpp>
#include <vector>

#include "tools/cli/command.h"

namespace grove::tools {

// Adds `footslam` and its subcommands to `grove`.
std::vector<Command> AddFootSlamCommands(CLI::App* grove);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_FOOTSLAM_CLI_H_
