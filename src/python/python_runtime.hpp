// The Python interpreter rilbed's Python controllers run in: Debian's CPython, embedded in
// the rilbed binary, or the one that imported the `rilbed` module (a script, a notebook).
// Every call into Python holds the GIL through a PythonLock; rilbed's own threads hold it
// only while they call.
#pragma once

#include <filesystem>
#include <string>

#include <pybind11/pybind11.h>

namespace rilbed::python {

/// Starts the embedded interpreter if none runs in this process yet (the rilbed binary),
/// once: Debian's /usr/bin/python3's standard library and site packages, no signal
/// handlers (Ctrl-C stays rilbed's), the `rilbed` package's folder (python_package_dir())
/// on sys.path, and the controller API as the built-in module `_rilbed_embedded`. Does
/// nothing inside a Python process that imported rilbed. Thread-safe; returns with the GIL
/// not held. Throws std::runtime_error when the interpreter cannot start.
void ensure_interpreter();

/// The folder that holds the `rilbed` package: RILBED_PYTHON_DIR when set, else
/// `python` beside the executable (build/python for build/rilbed).
std::filesystem::path python_package_dir();

/// Holds the GIL on the calling thread while it lives (PyGILState_Ensure/Release: any
/// thread, nested or not). ensure_interpreter() must have run.
class PythonLock {
 public:
  PythonLock() : state_(PyGILState_Ensure()) {}
  ~PythonLock() { PyGILState_Release(state_); }
  PythonLock(const PythonLock&) = delete;
  PythonLock& operator=(const PythonLock&) = delete;

 private:
  PyGILState_STATE state_;
};

/// The Python error `e` as Python prints it: the traceback (file, line, the code) and the
/// exception. Call with the GIL held.
std::string traceback_text(pybind11::error_already_set& e);

/// Adds the controller API (Controller's inputs and outputs, the constants) to `m`, as
/// both the embedded module and the extension module hold it.
void bind_controller_api(pybind11::module_& m);
/// Adds what a robot knows of a tape network on board (agents/track_features.hpp) to `m`:
/// TrackSensorConfig, TrackArray, read_track_array, BranchScan, ... Called by
/// bind_controller_api.
void bind_track_features(pybind11::module_& m);

}  // namespace rilbed::python
