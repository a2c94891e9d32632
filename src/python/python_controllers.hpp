// Controllers written in Python: a class in a .py file that subclasses rilbed.Controller,
// as a registry entry. A class with step(self, inp) decides for one robot per call
// (one instance per robot); a class with step_all(self, inp) decides for every robot it
// controls in one call, with NumPy arrays (one instance per group of robots with the same
// params). A scenario names one with `controller: {python: FILE, class: NAME}`.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "agents/controller_registry.hpp"
#include "core/result.hpp"

namespace rilbed::python {

/// The registry entry of class `class_name` of the Python file `file` (an absolute path),
/// named `<file's stem>.<class>`, its `library` the file's path. Imports the file (once
/// per process and file; its folder goes on sys.path so that it can import its neighbours)
/// and checks the class: it exists, subclasses rilbed.Controller, and defines step or
/// step_all (not both). A failure names the file and the class, with Python's traceback
/// for a file that does not import. The entry takes any numeric `params` (open_params);
/// the class's `__init__` refuses what it cannot use by raising, which the entry's factory
/// turns into std::invalid_argument (a scenario error naming the robot).
core::Result<agents::ControllerEntry> load_python_controller(const std::filesystem::path& file,
                                                             const std::string& class_name);

/// Every class of the Python file `file` that subclasses rilbed.Controller and is defined
/// there (not imported into it), as load_python_controller() makes each, in the file's
/// order: what `rilbed controllers --python FILE` lists. A failure names the file (and the
/// class) as load_python_controller()'s do; none at all is a failure too.
core::Result<std::vector<agents::ControllerEntry>> load_python_controllers(const std::filesystem::path& file);

}  // namespace rilbed::python
