// Fuzz target for what a Python controller answers (python/python_answers.hpp): any
// Python value the input describes (numbers with NaN, infinities and huge ints, bools,
// None, str with lone surrogates, bytes, tuples and lists of them, NumPy arrays of any
// shape and dtype, rilbed.Output, objects whose __len__ or __getitem__ raise), read as a
// step's answer or as step_all's for 0 to 5 robots, in the embedded interpreter.
//
// Invariants, whatever the value:
//   - it is accepted, refused with an agents::ControllerError whose message starts with the
//     controller's name, or a Python error propagates (the caller adds the traceback);
//   - an accepted answer's wheels are within +-127 and its behaviour non-empty; step_all's
//     has one answer per robot, in the robots' order;
//   - no Python error is left pending afterwards.
// LeakSanitizer is off for this target (tests/fuzz/fuzz_tests.cmake): the interpreter it
// starts lives until exit.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <pybind11/embed.h>
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "python/controller_api.hpp"
#include "python/python_answers.hpp"

namespace py = pybind11;

// Of the controller API, what an answer can be: rilbed.Output (bound as controller_bindings.cpp
// binds it; the rest of the API, which no answer holds, stays out of this target's build).
PYBIND11_EMBEDDED_MODULE(_rilbed_embedded, m) {
  py::class_<rilbed::python::StepOutput>(m, "Output")
      .def(py::init<int, int, std::string>(), py::arg("left"), py::arg("right"), py::arg("behaviour") = "idle");
}

namespace {

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_python_answers: invariant broken: %s\n", what);
  std::abort();
}

#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (0)

const char* const kWho = "fuzz.py: Fuzz";

py::object helpers() {
  static py::object module = [] {
    py::dict globals;
    py::exec(R"(
class RaisingLen:
    def __len__(self): raise RuntimeError("len")
    def __getitem__(self, i): return 1
class RaisingItem:
    def __len__(self): return 2
    def __getitem__(self, i): raise IndexError("item")
class Number:
    def __float__(self): raise ValueError("float")
    def __index__(self): return 3
)",
             globals);
    return py::object(globals);
  }();
  return module;
}

double any_double(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 5)) {
    case 0: return std::nan("");
    case 1: return HUGE_VAL;
    case 2: return -HUGE_VAL;
    default: return in.ConsumeFloatingPointInRange<double>(-1e6, 1e6);
  }
}

py::object any_value(FuzzedDataProvider& in, int depth);

py::object any_array(FuzzedDataProvider& in) {
  const int rows = in.ConsumeIntegralInRange<int>(0, 6), cols = in.ConsumeIntegralInRange<int>(0, 3);
  py::list values;
  for (int i = 0; i < rows * std::max(cols, 1); ++i) values.append(any_double(in));
  py::module_ np = py::module_::import("numpy");
  static const char* const kinds[] = {"float64", "int64", "float32", "object", "U8", "bool"};
  py::object a = np.attr("array")(values);
  try {
    a = a.attr("astype")(kinds[in.ConsumeIntegralInRange<int>(0, 5)]);
  } catch (py::error_already_set&) {  // NaN to int, ...: keep the floats
  }
  if (cols > 0 && rows > 0) a = a.attr("reshape")(rows, cols);
  return a;
}

py::object any_value(FuzzedDataProvider& in, int depth) {
  const int kind = in.ConsumeIntegralInRange<int>(0, depth >= 3 ? 8 : 12);
  switch (kind) {
    case 0: return py::int_(in.ConsumeIntegral<std::int32_t>());
    case 1: return py::reinterpret_steal<py::object>(PyLong_FromString(std::string(40, '9').c_str(), nullptr, 10));
    case 2: return py::float_(any_double(in));
    case 3: return py::bool_(in.ConsumeBool());
    case 4: return py::none();
    case 5: {
      const std::string bytes = in.ConsumeRandomLengthString(80);
      return py::reinterpret_steal<py::object>(
          PyUnicode_DecodeUTF8(bytes.data(), static_cast<Py_ssize_t>(bytes.size()), "surrogateescape"));
    }
    case 6: return py::bytes(in.ConsumeRandomLengthString(16));
    case 7: {
      static const char* const names[] = {"RaisingLen", "RaisingItem", "Number"};
      return helpers()[names[in.ConsumeIntegralInRange<int>(0, 2)]]();
    }
    case 8: {
      py::object output = py::module_::import("_rilbed_embedded").attr("Output");
      return output(in.ConsumeIntegral<std::int32_t>(), in.ConsumeIntegral<std::int32_t>(),
                    in.ConsumeRandomLengthString(80));
    }
    case 9: return any_array(in);
    default: {
      py::list items;
      const int n = in.ConsumeIntegralInRange<int>(0, 5);
      for (int i = 0; i < n; ++i) items.append(any_value(in, depth + 1));
      if (kind == 10) return items;
      return py::tuple(items);
    }
  }
}

void check_output(const rilbed::agents::ControlOutput& o) {
  FUZZ_CHECK(o.wheels.left >= -127 && o.wheels.left <= 127);
  FUZZ_CHECK(o.wheels.right >= -127 && o.wheels.right <= 127);
  FUZZ_CHECK(!o.behaviour.empty());
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Debian's python3, as rilbed embeds it (python_runtime.cpp): named outright, no signal
  // handlers.
  PyConfig config;
  PyConfig_InitPythonConfig(&config);
  config.install_signal_handlers = 0;
  PyConfig_SetBytesString(&config, &config.program_name, "/usr/bin/python3");
  py::initialize_interpreter(&config, 0, nullptr, false);
  py::module_::import("_rilbed_embedded");
  py::module_::import("numpy");
  helpers();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);  // (this thread holds the GIL from the start)
  const bool swarm = in.ConsumeBool();
  std::vector<int> ids(static_cast<std::size_t>(in.ConsumeIntegralInRange<int>(0, 5)));
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(i) + 1;
  try {
    py::object value = any_value(in, 0);
    if (swarm) {
      const std::vector<rilbed::agents::GroupAnswer> answers = rilbed::python::swarm_answers(value, ids, kWho);
      FUZZ_CHECK(answers.size() == ids.size());
      for (std::size_t i = 0; i < answers.size(); ++i) {
        FUZZ_CHECK(answers[i].robot_id == ids[i]);
        check_output(answers[i].output);
      }
    } else {
      check_output(rilbed::python::output_from_python(value, kWho));
    }
  } catch (const rilbed::agents::ControllerError& e) {
    FUZZ_CHECK(std::string(e.what()).rfind(kWho, 0) == 0);
  } catch (py::error_already_set&) {
    // A Python error while reading the value: the caller reports it with its traceback.
  }
  FUZZ_CHECK(!PyErr_Occurred());
  return 0;
}
