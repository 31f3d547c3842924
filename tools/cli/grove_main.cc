// grove: the command-line front end. Subcommands:
//   grove footslam run|batch|simulate|evaluate|render ...
//   grove fastslam run|victoria-park|evaluate|simulate|montecarlo ...
//   grove tracking run|simulate ...
//   grove bench paper|scaling|fastslam-accuracy|fastslam-speed|victoria-park|footslam|fastslam
#include <CLI/CLI.hpp>
#include <cstdio>
#include <new>
#include <vector>

#include "grove/version.h"
#include "tools/cli/command.h"
#include "tools/cli/help_formatter.h"
#include "tools/cli/parse_errors.h"
#include "tools/run/run_loop.h"

namespace {

namespace gt = grove::tools;

int Main(int argc, char** argv) {
  CLI::App app{"grove: particle-filter SLAM with shared persistent maps", "grove"};
  gt::UseHelpFormatter(&app);
  app.set_version_flag(
      "--version", [] { return grove::VersionString(); },
      "The version, commit, compiler and SIMD targets of this build");
  app.require_subcommand(1);
  std::vector<gt::Command> commands;
  for (auto add : {gt::AddFootSlamCommands, gt::AddFastSlamCommands, gt::AddTrackingCommands,
                   gt::AddBenchCommands}) {
    for (gt::Command& c : add(&app)) commands.push_back(std::move(c));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return gt::ReportParseError(app, e);
  }
  for (const gt::Command& c : commands) {
    if (c.app->parsed()) return c.run();
  }
  return gt::kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "grove: error: out of memory\n");
    return grove::tools::kExitMemory;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "grove: internal error: %s\n", e.what());
    return grove::tools::kExitInternal;
  }
}
