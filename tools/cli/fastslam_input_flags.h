// The input flags of every command that reads FastSLAM's CSV inputs (`grove fastslam run`,
// `grove bench fastslam`): --controls and --observations, both required.
#ifndef GROVE_TOOLS_CLI_FASTSLAM_INPUT_FLAGS_H_
#define GROVE_TOOLS_CLI_FASTSLAM_INPUT_FLAGS_H_

#include <CLI/CLI.hpp>
#include <string>

#include "tools/cli/typed_flags.h"

namespace grove::tools {

struct FastSlamInputFlags {
  FastSlamInputFlags(CLI::App* app, std::string* controls_path, std::string* observations_path)
      : controls(AddPath(app, "--controls", controls_path, "controls.csv (t,v,steer)")->required()),
        observations(AddPath(app, "--observations", observations_path,
                             "observations.csv (t,range,bearing,id; without id: unknown "
                             "association)")
                         ->required()) {}
  CLI::Option* controls;
  CLI::Option* observations;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_FASTSLAM_INPUT_FLAGS_H_
