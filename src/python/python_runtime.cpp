#include "python/python_runtime.hpp"

#include <cstdlib>
#include <mutex>
#include <stdexcept>

#include "core/beside_executable.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

// The built-in module an embedded interpreter gets (the extension module `_rilbed`
// holds the same API for a Python that imports rilbed).
PyObject* init_embedded_module() {
  static py::module_::module_def definition;
  try {
    py::module_ m =
        py::module_::create_extension_module("_rilbed_embedded", "rilbed's controller API, embedded", &definition);
    bind_controller_api(m);
    return m.release().ptr();
  } catch (py::error_already_set& e) {
    e.restore();
    return nullptr;
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_ImportError, e.what());
    return nullptr;
  }
}

// Buffered output of the controllers' print() is written when the program ends (the
// interpreter is never finalised: rilbed's threads may still hold Python objects then).
void flush_python_output() {
  if (!Py_IsInitialized()) return;
  PyGILState_STATE state = PyGILState_Ensure();
  PyRun_SimpleString(
      "import sys\nfor s in (sys.stdout, sys.stderr):\n    try: s.flush()\n    except Exception: pass\n");
  PyGILState_Release(state);
}

void start_interpreter() {
  if (PyImport_AppendInittab("_rilbed_embedded", &init_embedded_module) != 0) {
    throw std::runtime_error("python: cannot register the embedded module");
  }
  PyConfig config;
  PyConfig_InitPythonConfig(&config);
  config.install_signal_handlers = 0;
  config.parse_argv = 0;
  // Debian's python3: its prefix, its standard library, its dist-packages (NumPy). Named
  // outright, so that another python3 first on PATH is never the one found.
  PyStatus status = PyConfig_SetBytesString(&config, &config.program_name, RILBED_PYTHON_EXECUTABLE);
  if (!PyStatus_Exception(status)) status = Py_InitializeFromConfig(&config);
  PyConfig_Clear(&config);
  if (PyStatus_Exception(status)) {
    throw std::runtime_error(std::string("python: the interpreter does not start: ") +
                             (status.err_msg ? status.err_msg : "unknown error"));
  }
  {
    py::module_ sys = py::module_::import("sys");
    sys.attr("path").attr("insert")(0, python_package_dir().string());
  }
  std::atexit(flush_python_output);
  // rilbed's threads take the GIL when they call into Python (PythonLock).
  PyEval_SaveThread();
}

}  // namespace

std::filesystem::path python_package_dir() { return core::beside_executable("python", "RILBED_PYTHON_DIR"); }

void ensure_interpreter() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!Py_IsInitialized()) start_interpreter();
  });
}

std::string traceback_text(py::error_already_set& e) {
  try {
    py::module_ traceback = py::module_::import("traceback");
    // Python's import machinery's own frames (`<frozen importlib._bootstrap>`) say nothing
    // about the lab's file: left out.
    py::object report = traceback.attr("TracebackException")(e.type(), e.value(), e.trace());
    py::list kept;
    for (py::handle frame : report.attr("stack")) {
      if (frame.attr("filename").cast<std::string>().rfind("<frozen ", 0) != 0) kept.append(frame);
    }
    report.attr("stack") = traceback.attr("StackSummary").attr("from_list")(kept);
    std::string text;
    for (py::handle line : report.attr("format")()) text += line.cast<std::string>();
    while (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
  } catch (const std::exception&) {
    return e.what();
  }
}

}  // namespace rilbed::python
