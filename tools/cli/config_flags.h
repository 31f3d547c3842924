// Command-line flags for every field of a configuration table: --name with '-' for '_'
// (particles -> --particles, grid_size -> --grid-size), with the field's help. Flags override
// the values of a --config file; their errors name the flag.
#ifndef GROVE_TOOLS_CLI_CONFIG_FLAGS_H_
#define GROVE_TOOLS_CLI_CONFIG_FLAGS_H_

#include <CLI/CLI.hpp>
#include <algorithm>
#include <deque>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove::tools {

template <typename Config>
class ConfigFlags {
 public:
  ConfigFlags(CLI::App* app, const std::vector<ConfigField<Config>>& fields) {
    for (const ConfigField<Config>& f : fields) {
      std::string flag = std::string("--") + f.info.name;
      std::replace(flag.begin(), flag.end(), '_', '-');
      Flag& entry = flags_.emplace_back();
      entry.field = &f;
      entry.name = flag;
      entry.option = app->add_option(flag, entry.text, f.info.help);
    }
  }

  // Sets every field whose flag was given; InvalidArgument naming the flag, e.g.
  // `--particles = "abc": must be an integer`, and `config` unchanged.
  Status Apply(Config* config) const {
    Config result = *config;
    for (const Flag& f : flags_) {
      if (f.option->count() == 0) continue;
      FieldInfo info = f.field->info;
      info.name = f.name.c_str();
      StatusOr<FieldValue> v = ParseFieldValue(info, f.text);
      if (!v.ok()) return v.status();
      f.field->set(&result, *v);
    }
    *config = result;
    return Status::Ok();
  }

 private:
  struct Flag {
    const ConfigField<Config>* field = nullptr;
    std::string name;
    std::string text;
    CLI::Option* option = nullptr;
  };
  std::deque<Flag> flags_;  // stable addresses: CLI11 writes into `text`
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_CLI_CONFIG_FLAGS_H_
