// A subcommand of the grove command and what runs it once the command line is parsed, and the
// command families that add theirs: footslam (footslam_cli.cc), fastslam (fastslam_cli.cc),
// tracking (tracking_cli.cc) and bench (bench_cli.cc).
#ifndef GROVE_TOOLS_CLI_COMMAND_H_
#define GROVE_TOOLS_CLI_COMMAND_H_

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <vector>

namespace grove::tools {

struct Command {
  CLI::App* app;             // parsed when the command line named it
  std::function<int()> run;  // returns the exit code; holds the options CLI11 writes into
};

// Adds the subcommand `name` to `parent`: a T made with it adds the options and holds their
// values; T::Run() runs it.
template <typename T>
Command AddCommand(CLI::App* parent, const char* name, const char* description) {
  CLI::App* app = parent->add_subcommand(name, description);
  auto state = std::make_shared<T>(app);
  return {app, [state] { return state->Run(); }};
}

// Adds the command family `name` to `grove`: a subcommand that needs one of its own.
inline CLI::App* AddFamily(CLI::App* grove, const char* name, const char* description) {
  CLI::App* family = grove->add_subcommand(name, description);
  family->require_subcommand(1);
  return family;
}

// Each adds its family and the family's subcommands to `grove`.
std::vector<Command> AddFootSlamCommands(CLI::App* grove);
std::vector<Command> AddFastSlamCommands(CLI::App* grove);
std::vector<Command> AddTrackingCommands(CLI::App* grove);
std::vector<Command> AddBenchCommands(CLI::App* grove);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_COMMAND_H_
