// The web panel's flags, shared by `rilbed run --gui` and `rilbed gui`: --gui-port,
// --gui-bind, --web-root, --gui-allow-origin, onto session::PanelOptions.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "session/panel.hpp"

namespace rilbed::app {

/// Adds the four flags to `cmd`; `with` prefixes their help ("With --gui: "). The web
/// root defaults to the page's files in this source tree (RILBED_WEB_ROOT).
void add_panel_options(CLI::App& cmd, session::PanelOptions& options, const std::string& with = "");

}  // namespace rilbed::app
