#include "app/panel_options.hpp"

#include <spdlog/spdlog.h>

#include <cctype>
#include <filesystem>

#include "agents/builtin_controllers.hpp"
#include "bus/lcm_console.hpp"

namespace rilbed::app {

void add_panel_options(CLI::App& cmd, PanelOptions& o, const std::string& with) {
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

std::optional<std::string> check_panel_options(const PanelOptions& o) {
  if (o.port < 0 || o.port > 65535) return "--gui-port " + std::to_string(o.port) + " is not a port";
  return std::nullopt;
}

std::unique_ptr<gui_web::GuiService> start_panel(const PanelOptions& o, std::string token, gui_web::ConsoleSink sink) {
  gui_web::WebServerConfig config;
  config.bind_address = o.bind;
  config.port = static_cast<std::uint16_t>(o.port);
  config.token = token.empty() ? bus::make_run_token() : std::move(token);
  config.session_id = config.token.substr(0, 8);
  if (std::filesystem::is_directory(o.web_root)) config.web_root = o.web_root;
  config.allowed_origins = o.allowed_origins;
  // The editor's lists and forms of controllers: the registry scenarios are checked against.
  config.documents["/controllers.json"] = {"application/json",
                                           agents::controllers_json(*agents::default_controllers()).dump()};
  if (o.bind != "127.0.0.1") {
    spdlog::warn("gui: serving on {}: anyone who can reach it and has the URL's token can watch and steer the run",
                 o.bind);
  }
  try {
    return std::make_unique<gui_web::GuiService>(config, std::move(sink));
  } catch (const std::exception& e) {
    spdlog::error("gui: {}", e.what());
    return nullptr;
  }
}

}  // namespace rilbed::app
