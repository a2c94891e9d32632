// Sensor models from plug-in libraries (rilbed/sensor_model.h): a library's models,
// checked like any input, and one mounted on a robot as an environment::SensorModel that
// the world calls through the model's C functions. The mounted model keeps its library
// loaded and destroys its instance ("clean-up") when the last robot carrying it is gone.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agents/plugin_library.hpp"
#include "core/result.hpp"
#include "core/time.hpp"
#include "environment/sensor_model.hpp"
#include "environment/static_map.hpp"
#include "rilbed/sensor_model.h"

namespace rilbed::agents {

/// One key of a model's parameter file.
struct SensorParamSpec {
  std::string key;                      ///< as the model writes it: "Cone Angle"
  std::string unit;                     ///< "mm", "deg", "%"; "" for a count
  std::string summary;                  ///< one line of what it means
  std::optional<double> default_value;  ///< nullopt: the file must give it
  bool integer = false;                 ///< whole numbers only
  double min = -HUGE_VAL;               ///< inclusive
  double max = HUGE_VAL;                ///< inclusive
};

/// A parameter file's key as the models' keys are matched: lower case, spaces and
/// hyphens as underscores, runs of them as one ("Cone Angle" and "cone_angle" alike).
std::string sensor_param_key(std::string_view key);

/// A C string a library answered, read no further than `limit` bytes: printable ASCII
/// only (it goes to terminals, JSON and messages as it is). `what` names it in the failure.
core::Result<std::string> model_text(const char* text, const std::string& what, std::size_t limit = 4096);

/// A model's name as a scenario writes it after `name:`: not empty, no space or YAML punctuation.
core::Result<std::string> model_name(const char* text, const std::string& what);

/// What every model of a library starts with, checked.
struct ModelHeader {
  std::string name;
  std::string summary;
  std::string who;  ///< "ORIGIN: sensor model 'NAME'", for the next messages
};

/// The ABI version (RILBED_ABI_VERSION), the name (model_name) and the summary (model_text)
/// of a model; `what` is "ORIGIN: sensor model" or the like.
core::Result<ModelHeader> model_header(std::uint32_t abi_version, const char* name, const char* summary,
                                       const std::string& what);

/// Every model a library exports as the NULL-terminated list `symbol()` returns (`kind`:
/// "sensor model", for messages), each read by `check(raw, library, origin)`; names unique.
template <class Entry, class Raw, class Check>
core::Result<std::vector<Entry>> load_model_list(const std::filesystem::path& path, const char* symbol,
                                                 const std::string& kind, Check check) {
  core::Result<std::shared_ptr<const PluginLibrary>> opened = PluginLibrary::open(path);
  if (!opened) return core::Failure{opened.error()};
  const std::shared_ptr<const PluginLibrary>& library = *opened;
  const std::string who = "plug-in library " + library->path().string();
  using List = const Raw* const* (*)();
  auto list = reinterpret_cast<List>(library->symbol(symbol));
  if (!list) return core::Failure{who + ": does not export " + symbol + "(), so it holds no " + kind};
  const Raw* const* models = list();
  if (!models) return core::Failure{who + ": " + symbol + "() returned NULL"};
  std::vector<Entry> entries;
  for (std::size_t i = 0; models[i]; ++i) {
    if (i >= 4096) return core::Failure{who + ": more than 4096 " + kind + "s"};
    core::Result<Entry> e = check(*models[i], library, library->path().string());
    if (!e) return core::Failure{e.error()};
    for (const Entry& before : entries) {
      if (before.name == e->name) return core::Failure{who + ": holds two " + kind + "s named '" + e->name + "'"};
    }
    entries.push_back(std::move(*e));
  }
  return entries;
}

/// A model's declared parameter keys checked (printable ASCII, ranges ordered, defaults
/// finite, in range and whole where they must be, no key twice as matched, at most 64);
/// `who` names the model in the failure. Sensor and actuator models share them.
core::Result<std::vector<SensorParamSpec>> model_param_specs(const rilbed_sensor_param* params, std::uint32_t count,
                                                             const std::string& who);

/// The static world of `map` as a model's create() gets it, with the arrays it points
/// into (valid while this lives).
struct StaticWorldView {
  explicit StaticWorldView(const environment::StaticMap& map);
  StaticWorldView(const StaticWorldView&) = delete;
  StaticWorldView& operator=(const StaticWorldView&) = delete;
  std::vector<rilbed_segment> segments;
  std::vector<rilbed_track_segment> tracks;
  rilbed_static_world raw{};
};

/// A library's sensor model, checked, ready to be mounted.
struct SensorModelEntry {
  std::string name;
  std::string summary;
  std::string origin;  ///< the library's path
  std::vector<SensorParamSpec> params;
  std::size_t value_count = 1;
  bool provides_track = false;
  bool concurrent = true;
  std::shared_ptr<const PluginLibrary> library;  ///< null in tests of a model that lives as long as the program
  const rilbed_sensor_model* model = nullptr;
  /// The spec of the parameter whose key is `key` (any spelling sensor_param_key() matches), or nullptr.
  const SensorParamSpec* param(std::string_view key) const;
};

/// Every sensor model the library at `path` holds. A failure names the library and the
/// cause (PluginLibrary::open's, no rilbed_sensor_models(), a NULL list, an entry that
/// is unusable, two models of one name).
core::Result<std::vector<SensorModelEntry>> load_library_sensor_models(const std::filesystem::path& path);

/// `model` checked: ABI version, name, summary, parameters (keys unique as matched, at
/// most 64, defaults finite and in range), 1..64 values, `provides` NULL or "track", its
/// three functions.
core::Result<SensorModelEntry> sensor_model_entry(const rilbed_sensor_model& model,
                                                  std::shared_ptr<const PluginLibrary> library,
                                                  const std::string& origin);

/// Where and how one robot carries a model.
struct SensorMount {
  std::string name;                  ///< what its readings are called (default: the model's name)
  std::vector<double> param_values;  ///< one per entry parameter, in the entry's order, defaults filled in
  double mount_x_m = 0.0;            ///< forward of the robot's centre
  double mount_y_m = 0.0;            ///< left of it
  double mount_yaw_deg = 0.0;        ///< counter-clockwise from its forward direction
  std::string parameter_file;        ///< where the values came from, for messages
};

/// The model mounted: its create() ("register") called with the mount, the static world
/// of `map` and the control period. A failure names the model, the library and the file.
core::Result<std::shared_ptr<const environment::SensorModel>> mount_sensor_model(const SensorModelEntry& entry,
                                                                                 const SensorMount& mount,
                                                                                 const environment::StaticMap& map,
                                                                                 TimeUs quantum_us);

}  // namespace rilbed::agents
