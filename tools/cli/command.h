// A subcommand of the grove command and what runs it once the command line is parsed.
#ifndef GROVE_TOOLS_CLI_COMMAND_H_
#define GROVE_TOOLS_CLI_COMMAND_H_

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>

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

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_COMMAND_H_
