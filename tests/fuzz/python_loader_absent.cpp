// The scenario parser's fuzz target without an interpreter: a Python controller named by
// a scenario (`controller: {python: FILE, class: NAME}`) is refused here, as a missing
// file would be, so that the parser's own handling of the keys is what gets fuzzed. The
// interpreter stays out of this target (starting it leaves allocations that live until
// exit, which LeakSanitizer would report on the first input that names a real file).
#include "python/python_controllers.hpp"

namespace rilbed::python {

core::Result<agents::ControllerEntry> load_python_controller(const std::filesystem::path& file,
                                                             const std::string& class_name) {
  return core::Failure{"Python controller " + file.string() + ": " + class_name +
                       ": Python is not loaded in the scenario parser's fuzz target"};
}

}  // namespace rilbed::python
