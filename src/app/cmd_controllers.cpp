// `rilbed controllers [--json] [--library PATH]... [--python FILE]...`: the controllers a scenario can name,
// with their parameters, from the one registry the parser and the run use; or what
// plug-in libraries and Python files hold.
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "agents/builtin_controllers.hpp"
#include "agents/library_controllers.hpp"
#include "app/commands.hpp"
#include "python/python_controllers.hpp"

namespace rilbed::app {

namespace {

struct ControllersArgs {
  bool json = false;
  std::vector<std::string> libraries;
  std::vector<std::string> python_files;
};

// Adds `entries` to `registry`; false (and why, on stderr) when one will not go in.
bool add_entries(agents::ControllerRegistry& registry, core::Result<std::vector<agents::ControllerEntry>> entries) {
  if (!entries) {
    std::fprintf(stderr, "controllers: %s\n", entries.error().c_str());
    return false;
  }
  for (agents::ControllerEntry& e : *entries) {
    try {
      registry.add(std::move(e));
    } catch (const std::invalid_argument& error) {
      std::fprintf(stderr, "controllers: %s\n", error.what());
      return false;
    }
  }
  return true;
}

// The registry to print: rilbed's own, or the controllers of the libraries and Python
// files given alone.
std::optional<agents::ControllerRegistry> registry_to_print(const ControllersArgs& args) {
  if (args.libraries.empty() && args.python_files.empty()) return *agents::default_controllers();
  agents::ControllerRegistry registry;
  for (const std::string& path : args.libraries) {
    if (!add_entries(registry, agents::load_library_controllers(path))) return std::nullopt;
  }
  for (const std::string& path : args.python_files) {
    if (!add_entries(registry, python::load_python_controllers(path))) return std::nullopt;
  }
  return registry;
}

}  // namespace

void add_controllers_command(CLI::App& app) {
  auto args = std::make_shared<ControllersArgs>();
  CLI::App* cmd = app.add_subcommand(
      "controllers", "List the controllers a scenario can name, with their parameters (units, defaults, ranges)");
  cmd->add_flag("--json", args->json,
                "Print JSON instead of tables: a list of {name, summary, sensors, required_sensors, wants_team, "
                "concurrent, origin, library, params: [{name, unit, default, min, max, summary, required, integer}]}");
  cmd->add_option("--library", args->libraries,
                  "List what this plug-in library holds instead (repeatable); a scenario names one of its "
                  "controllers as {library: PATH, name: NAME}");
  cmd->add_option("--python", args->python_files,
                  "List the rilbed.Controller classes this Python file defines instead (repeatable); a scenario names "
                  "one as {python: FILE, class: NAME}");
  cmd->callback([args] {
    const std::optional<agents::ControllerRegistry> registry = registry_to_print(*args);
    if (!registry) {
      exit_code() = 1;
      return;
    }
    if (args->json) {
      std::cout << agents::controllers_json(*registry).dump(2) << '\n';
    } else {
      std::cout << agents::controllers_table(*registry);
    }
    exit_code() = 0;
  });
}

}  // namespace rilbed::app
