// Controllers from plug-in libraries (rilbed/rilbed_controller.h, rilbed/controller.hpp)
// as registry entries: a library's C controllers (rilbed_controllers()) and its controller
// classes (rilbed_controller_classes(), what rilbed/controller.hpp exports for C++). What
// a library answers is checked like any input before rilbed uses it; the controllers its
// entries make keep the library loaded.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "agents/controller_registry.hpp"
#include "agents/plugin_library.hpp"
#include "core/result.hpp"
#include "rilbed/rilbed_controller.h"

namespace rilbed::agents {

/// Every controller the library at `path` holds, as registry entries (origin and
/// `library`: its absolute path), C controllers first, each in the library's order. A
/// failure names the library and the cause: it will not load (PluginLibrary::open), it
/// exports neither list, a list is NULL, or an entry is unusable (no name, no step, a
/// parameter that contradicts itself, an unknown sensor, a name given twice).
core::Result<std::vector<ControllerEntry>> load_library_controllers(const std::filesystem::path& path);

/// The entry of a C controller of `library` (its factory makes a CControllerAdapter that
/// keeps the library loaded), named `entry_name` (the controller's own name, or an alias
/// such as `c:braitenberg`).
core::Result<ControllerEntry> c_controller_entry(const rilbed_c_controller& controller,
                                                 std::shared_ptr<const PluginLibrary> library,
                                                 const std::string& entry_name);

/// The entry of a controller class, checked: its ABI version, name, summary, parameters
/// (names, units, ranges, defaults: finite where they must be, at most 64 of them, strings
/// at most 4096 bytes), sensors (known_sensor_names()), and its create, step and destroy
/// functions. `library` is kept alive by every controller the entry makes; null in tests
/// of a class that lives as long as the program. `origin` names it in messages.
core::Result<ControllerEntry> class_entry(const rilbed_controller_class& controller_class,
                                          std::shared_ptr<const PluginLibrary> library, const std::string& origin);

/// A class's step output as rilbed's: wheels clamped to ±kMaxWheelUnits, the behaviour
/// interned (intern_behaviour; NULL: "idle"; read up to 64 bytes).
ControlOutput output_from_class(const rilbed_control_output& output);

}  // namespace rilbed::agents
