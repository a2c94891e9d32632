#include "python/python_answers.hpp"

#include <algorithm>
#include <cmath>

#include <pybind11/numpy.h>

#include "agents/behaviour_names.hpp"
#include "python/controller_api.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

// A finite wheel speed, rounded half away from zero and clamped to ±127.
int clamped_units(double v) {
  return static_cast<int>(std::clamp(std::round(v), double(-agents::kMaxWheelUnits), double(agents::kMaxWheelUnits)));
}

int wheel_units(double v, const std::string& what) {
  if (!std::isfinite(v)) throw agents::ControllerError(what + " is not a finite number");
  return clamped_units(v);
}

std::string repr_text(py::handle h) {
  std::string text = py::repr(h).cast<std::string>();
  if (text.size() > 200) text = text.substr(0, 200) + "...";
  return text;
}

const char* const kReturnHint =
    "; return (left, right) wheel speeds in Khepera units (8 mm/s, ±127) or rilbed.Output(left, right, "
    "behaviour=...)";

agents::ControlOutput output_from_python_unchecked(py::handle result, const std::string& who) {
  if (py::isinstance<StepOutput>(result)) {
    const StepOutput& o = result.cast<const StepOutput&>();
    return {{wheel_units(o.left, who + "'s left wheel"), wheel_units(o.right, who + "'s right wheel")},
            agents::intern_behaviour(o.behaviour)};
  }
  if (!py::isinstance<py::str>(result) && !py::isinstance<py::bytes>(result) && PySequence_Check(result.ptr()) &&
      PySequence_Size(result.ptr()) == 2) {
    py::sequence s = py::reinterpret_borrow<py::sequence>(result);
    double wheel[2];
    for (int k = 0; k < 2; ++k) {
      py::object item = s[k];
      if (py::isinstance<py::bool_>(item) || !PyNumber_Check(item.ptr())) {
        throw agents::ControllerError(who + " returned " + repr_text(result) + kReturnHint);
      }
      wheel[k] = py::float_(item).cast<double>();
    }
    return {{wheel_units(wheel[0], who + "'s left wheel"), wheel_units(wheel[1], who + "'s right wheel")}, "python"};
  }
  if (PyErr_Occurred()) PyErr_Clear();
  throw agents::ControllerError(who + " returned " + repr_text(result) + kReturnHint);
}

bool is_text_list(py::handle h) {
  if (!py::isinstance<py::list>(h) && !py::isinstance<py::tuple>(h)) return false;
  py::sequence s = py::reinterpret_borrow<py::sequence>(h);
  return py::len(s) > 0 && py::isinstance<py::str>(s[0]);
}
// A NumPy array of str (dtype 'U', what np.where(mask, "a", "b") gives).
bool is_text_array(py::handle h) {
  return py::isinstance<py::array>(h) && py::reinterpret_borrow<py::array>(h).dtype().kind() == 'U';
}

// The behaviours of a 1-D 'U' array: its fixed-width UCS4 rows compared as bytes, each
// distinct one converted and interned once.
void read_behaviour_array(py::handle h, std::vector<std::string_view>& out, const std::string& who) {
  py::array a = py::reinterpret_borrow<py::array>(h);
  if (a.ndim() != 1 || a.shape(0) != static_cast<py::ssize_t>(out.size())) {
    throw agents::ControllerError(who + ": step_all returned behaviours of shape " +
                                  py::str(a.attr("shape")).cast<std::string>() + " for " + std::to_string(out.size()) +
                                  " robots");
  }
  const py::ssize_t width = a.itemsize();
  std::vector<std::pair<std::string, std::string_view>> seen;  // raw row bytes -> interned name
  for (std::size_t i = 0; i < out.size(); ++i) {
    const char* row = static_cast<const char*>(a.data(static_cast<py::ssize_t>(i)));
    const std::string_view raw(row, static_cast<std::size_t>(width));
    auto known = std::find_if(seen.begin(), seen.end(), [&](const auto& entry) { return entry.first == raw; });
    if (known == seen.end()) {
      py::object item = a.attr("__getitem__")(i);
      seen.emplace_back(std::string(raw), agents::intern_behaviour(py::str(item).cast<std::string>()));
      known = seen.end() - 1;
    }
    out[i] = known->second;
  }
}

void read_behaviours(py::handle h, std::vector<std::string_view>& out, const std::string& who) {
  if (is_text_array(h)) {
    read_behaviour_array(h, out, who);
    return;
  }
  if (py::isinstance<py::str>(h)) {
    std::fill(out.begin(), out.end(), agents::intern_behaviour(h.cast<std::string>()));
    return;
  }
  py::sequence s = py::reinterpret_borrow<py::sequence>(h);
  if (py::len(s) != out.size()) {
    throw agents::ControllerError(who + ": step_all returned " + std::to_string(py::len(s)) + " behaviours for " +
                                  std::to_string(out.size()) + " robots");
  }
  // A swarm has a few behaviours for many robots: each distinct name is read and interned
  // once per call, not once per robot.
  std::vector<std::pair<py::object, std::string_view>> seen;
  for (std::size_t i = 0; i < out.size(); ++i) {
    py::object item = s[i];
    if (!py::isinstance<py::str>(item)) {
      throw agents::ControllerError(who + ": step_all's behaviour " + std::to_string(i) + " is " + repr_text(item) +
                                    ", not a str");
    }
    auto known = std::find_if(seen.begin(), seen.end(), [&](const auto& entry) {
      return entry.first.is(item) || PyUnicode_Compare(entry.first.ptr(), item.ptr()) == 0;
    });
    if (known == seen.end()) {
      seen.emplace_back(item, agents::intern_behaviour(item.cast<std::string>()));
      known = seen.end() - 1;
    }
    out[i] = known->second;
  }
}
std::string shape_text(py::handle h) {
  if (py::hasattr(h, "shape")) return "an array of shape " + py::str(h.attr("shape")).cast<std::string>();
  return repr_text(h);
}

std::vector<agents::GroupAnswer> swarm_answers_unchecked(py::handle result, std::span<const int> robot_ids,
                                                         const std::string& who) {
  const std::size_t n = robot_ids.size();
  py::object wheels = py::reinterpret_borrow<py::object>(result);
  std::vector<std::string_view> behaviours(n, "python");
  if (py::isinstance<py::tuple>(result) && py::len(result) == 2) {
    py::tuple t = py::reinterpret_borrow<py::tuple>(result);
    if (py::isinstance<py::str>(t[1]) || is_text_list(t[1]) || is_text_array(t[1])) {
      wheels = t[0];
      read_behaviours(t[1], behaviours, who);
    }
  }
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(wheels);
  } catch (py::error_already_set&) {}
  if (!a || a.ndim() != 2 || a.shape(0) != py::ssize_t(n) || a.shape(1) != 2) {
    if (PyErr_Occurred()) PyErr_Clear();
    throw agents::ControllerError(who + ": step_all returned " + shape_text(wheels) + "; return an array of shape (" +
                                  std::to_string(n) +
                                  ", 2), a (left, right) row per robot in inp.robot_id's order, or (that array, "
                                  "behaviour)");
  }
  auto w = a.unchecked<2>();
  std::vector<agents::GroupAnswer> answers(n);
  for (std::size_t i = 0; i < n; ++i) {
    const int id = robot_ids[i];
    const double left = w(i, 0), right = w(i, 1);
    if (!std::isfinite(left) || !std::isfinite(right)) {
      throw agents::ControllerError(who + ": step_all's row " + std::to_string(i) + " (robot " + std::to_string(id) +
                                    ") is not two finite numbers");
    }
    answers[i] = {id, {{clamped_units(left), clamped_units(right)}, behaviours[i]}, false};
  }
  return answers;
}

// A value pybind11 cannot convert (a str that is not UTF-8) is the controller's error too.
template <typename Read>
auto checked(const std::string& who, Read read) {
  try {
    return read();
  } catch (const py::cast_error& e) {
    throw agents::ControllerError(who + " returned a value rilbed cannot read: " + e.what());
  }
}

}  // namespace

agents::ControlOutput output_from_python(py::handle result, const std::string& who) {
  return checked(who, [&] { return output_from_python_unchecked(result, who); });
}

std::vector<agents::GroupAnswer> swarm_answers(py::handle result, std::span<const int> robot_ids,
                                               const std::string& who) {
  return checked(who, [&] { return swarm_answers_unchecked(result, robot_ids, who); });
}

}  // namespace rilbed::python
