// The web control panel of a run or of a run on the bus (`rilbed run --gui`, `rilbed gui`):
// its options, checked, and the GuiService started from them.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agents/controller_registry.hpp"
#include "gui_web/gui_service.hpp"

namespace rilbed::session {

/// Where and how the panel serves.
struct PanelOptions {
  int port = 8080;                           ///< TCP port (0: any free port)
  std::string bind = "127.0.0.1";            ///< anything else opens the run to the network
  std::string web_root;                      ///< the page's files; empty or missing: no page, only /ws
  std::vector<std::string> allowed_origins;  ///< web clients served elsewhere (their Origin)
};

/// Why the options cannot be used (a usage error: "--gui-port 70000 is not a port"), or nullopt.
std::optional<std::string> check_panel_options(const PanelOptions& options);

/// Starts the panel's service with `token` (empty: a fresh one) and `sink`, serving the
/// controllers of `controllers` to the page's editor (/controllers.json), or logs why it
/// cannot (an address it cannot listen on) and returns null. Warns when it serves beyond
/// this machine. The options must have passed check_panel_options().
std::unique_ptr<gui_web::GuiService> start_panel(const PanelOptions& options, std::string token,
                                                 gui_web::ConsoleSink sink,
                                                 const agents::ControllerRegistry& controllers);

/// The page's documents for `controllers`: /controllers.json, `rilbed controllers --json`.
std::map<std::string, gui_web::ServedDocument> panel_documents(const agents::ControllerRegistry& controllers);

}  // namespace rilbed::session
