#include "app/panel_options.hpp"

#include <cctype>

namespace rilbed::app {

void add_panel_options(CLI::App& cmd, session::PanelOptions& o, const std::string& with) {
  if (o.web_root.empty()) o.web_root = RILBED_WEB_ROOT;
  // "With --gui: address to ..." or "Address to ...".
  const auto help = [&with](std::string text) {
    if (with.empty()) text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
    return with + text;
  };
  cmd.add_option("--gui-port", o.port, help("TCP port (0: any free one)"))->default_val(o.port);
  cmd.add_option("--gui-bind", o.bind, help("address to serve on (anything but 127.0.0.1 opens it to the network)"))
      ->default_val(o.bind);
  cmd.add_option("--web-root", o.web_root, help("the page's files"))->default_val(o.web_root);
  cmd.add_option("--gui-allow-origin", o.allowed_origins,
                 help("also let in browsers' WebSockets from this Origin (a web client served elsewhere, "
                      "e.g. https://app.foxglove.dev); repeatable"));
}

}  // namespace rilbed::app
