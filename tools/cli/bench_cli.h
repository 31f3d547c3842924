// `grove bench paper|scaling|fastslam-accuracy|fastslam-speed|victoria-park`: their options and
// what runs them.
#ifndef GROVE_TOOLS_CLI_BENCH_CLI_H_
#define GROVE_TOOLS_CLI_BENCH_CLI_H_

#include <CLI/CLI.hpp>
#include <vector>

#include "tools/cli/command.h"

namespace grove::tools {

// Adds `bench` and its subcommands to `grove`.
std::vector<Command> AddBenchCommands(CLI::App* grove);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_BENCH_CLI_H_
