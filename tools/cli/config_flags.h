// Command-line flags for every field of a configuration table: --name with '-' for '_'
// (particles -> --particles, grid_size -> --grid-size), with the field's help, type, range,
// choices and default on the help page. Flags override the values of a --config file; their
// errors name the flag.
#ifndef GROVE_TOOLS_CLI_CONFIG_FLAGS_H_
#define GROVE_TOOLS_CLI_CONFIG_FLAGS_H_

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"
#include "tools/cli/typed_flags.h"

namespace grove::tools {

template <typename Config>
class ConfigFlags {
 public:
  // `defaults`: the values the help page gives as each flag's default. The fields named in
  // `except` get no flag (the command has its own for them).
  ConfigFlags(CLI::App* app, const std::vector<ConfigField<Config>>& fields,
              const Config& defaults = Config(), const std::vector<std::string>& except = {})
      : flags_(app) {
    for (const ConfigField<Config>& f : fields) {
      if (std::find(except.begin(), except.end(), f.info.name) != except.end()) continue;
      std::string flag = std::string("--") + f.info.name;
      std::replace(flag.begin(), flag.end(), '_', '-');
      flags_.Add(flag, f.info, f.info.help, FormatFieldValue(f.info, f.get(defaults)),
                 [this, &f](const FieldValue& v) { f.set(target_, v); });
    }
  }

  // Sets every field whose flag was given; InvalidArgument naming the flag, e.g.
  // `--particles = "abc": must be an integer`, and `config` unchanged.
  Status Apply(Config* config) const {
    Config result = *config;
    target_ = &result;
    const Status s = flags_.Apply();
    target_ = nullptr;
    if (s.ok()) *config = result;
    return s;
  }

 private:
  TypedFlags flags_;
  mutable Config* target_ = nullptr;  // the configuration Apply() sets, during the call
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_CONFIG_FLAGS_H_
