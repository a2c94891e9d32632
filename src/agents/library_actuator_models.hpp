// Actuator models from plug-in libraries (rilbed/actuator_model.h): a library's models,
// checked, and one given to robots as an environment::DriveModelFactory whose drives call
// the model's C functions, one instance per robot.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "agents/library_sensor_models.hpp"
#include "agents/plugin_library.hpp"
#include "core/result.hpp"
#include "environment/drive_model.hpp"
#include "rilbed/actuator_model.h"

namespace rilbed::agents {

/// A library's actuator model, checked.
struct ActuatorModelEntry {
  std::string name;
  std::string summary;
  std::string origin;  ///< the library's path
  std::vector<SensorParamSpec> params;
  bool concurrent = true;
  std::shared_ptr<const PluginLibrary> library;  ///< null for a model that lives as long as the program
  const rilbed_actuator_model* model = nullptr;
};

/// Every actuator model the library at `path` holds. A failure names the library and the
/// cause (PluginLibrary::open's, no rilbed_actuator_models(), a NULL list, an unusable
/// entry, two models of one name).
core::Result<std::vector<ActuatorModelEntry>> load_library_actuator_models(const std::filesystem::path& path);

/// `model` checked: ABI version, name, summary, parameters (model_param_specs), functions.
core::Result<ActuatorModelEntry> actuator_model_entry(const rilbed_actuator_model& model,
                                                      std::shared_ptr<const PluginLibrary> library,
                                                      const std::string& origin);

/// The factory that makes each robot's drive with `param_values` (one per entry
/// parameter, defaults filled in), on `map`, stepped every `step_us`. It keeps the library
/// loaded; each drive destroys its instance.
std::shared_ptr<const environment::DriveModelFactory> actuator_factory(const ActuatorModelEntry& entry,
                                                                       std::vector<double> param_values,
                                                                       const environment::StaticMap& map,
                                                                       TimeUs step_us, std::string parameter_file);

}  // namespace rilbed::agents
