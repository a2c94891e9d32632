// The web panel's options, shared by `rilbed run --gui` and `rilbed gui`: the same flags
// (--gui-port, --gui-bind, --web-root, --gui-allow-origin), checked and turned into a
// running GuiService the same way.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gui_web/gui_service.hpp"

namespace rilbed::app {

/// What the flags say.
struct PanelOptions {
  int port = 8080;                           ///< --gui-port (0: any free port)
  std::string bind = "127.0.0.1";            ///< --gui-bind
  std::string web_root = RILBED_WEB_ROOT;    ///< --web-root: the page's files
  std::vector<std::string> allowed_origins;  ///< --gui-allow-origin: web clients served elsewhere
};

/// Adds the four flags to `cmd`; `with` prefixes their help ("With --gui: ").
void add_panel_options(CLI::App& cmd, PanelOptions& options, const std::string& with = "");

/// Why the options cannot be used (a usage error: "--gui-port 70000 is not a port"), or nullopt.
std::optional<std::string> check_panel_options(const PanelOptions& options);

/// Starts the panel's service with `token` (empty: a fresh one) and `sink`, or logs why it
/// cannot (an address it cannot listen on) and returns null. Warns when it serves beyond
/// this machine. The options must have passed check_panel_options().
std::unique_ptr<gui_web::GuiService> start_panel(const PanelOptions& options, std::string token,
                                                 gui_web::ConsoleSink sink);

}  // namespace rilbed::app
