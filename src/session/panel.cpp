#include "session/panel.hpp"

#include <spdlog/spdlog.h>

#include <filesystem>

#include "bus/lcm_console.hpp"

namespace rilbed::session {

std::optional<std::string> check_panel_options(const PanelOptions& o) {
  if (o.port < 0 || o.port > 65535) return "--gui-port " + std::to_string(o.port) + " is not a port";
  return std::nullopt;
}

std::map<std::string, gui_web::ServedDocument> panel_documents(const agents::ControllerRegistry& controllers) {
  return {{"/controllers.json", {"application/json", agents::controllers_json(controllers).dump()}}};
}

std::unique_ptr<gui_web::GuiService> start_panel(const PanelOptions& o, std::string token, gui_web::ConsoleSink sink,
                                                 const agents::ControllerRegistry& controllers) {
  gui_web::WebServerConfig config;
  config.bind_address = o.bind;
  config.port = static_cast<std::uint16_t>(o.port);
  config.token = token.empty() ? bus::make_run_token() : std::move(token);
  config.session_id = config.token.substr(0, 8);
  if (!o.web_root.empty() && std::filesystem::is_directory(o.web_root)) config.web_root = o.web_root;
  config.allowed_origins = o.allowed_origins;
  // The editor's lists and forms of controllers: the registry scenarios are checked against.
  config.documents = panel_documents(controllers);
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

}  // namespace rilbed::session
