// `rilbed controllers [--json]`: the controllers a scenario can name, with their
// parameters, from the one registry the parser and the run use.
#include <cstdio>
#include <iostream>
#include <memory>

#include "agents/builtin_controllers.hpp"
#include "app/commands.hpp"

namespace rilbed::app {

void add_controllers_command(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "controllers", "List the controllers a scenario can name, with their parameters (units, defaults, ranges)");
  cmd->add_flag("--json", *json,
                "Print JSON instead of tables: a list of {name, summary, sensors, required_sensors, wants_team, "
                "concurrent, origin, params: [{name, unit, default, min, max, summary, required, integer}]}");
  cmd->callback([json] {
    const auto registry = agents::default_controllers();
    if (*json) {
      std::cout << agents::controllers_json(*registry).dump(2) << '\n';
    } else {
      std::cout << agents::controllers_table(*registry);
    }
    exit_code() = 0;
  });
}

}  // namespace rilbed::app
