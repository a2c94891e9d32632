#include "python/python_controllers.hpp"

#include <map>
#include <memory>

#include <pybind11/stl.h>
#include <spdlog/spdlog.h>

#include "agents/controller_group.hpp"
#include "python/controller_api.hpp"
#include "python/python_answers.hpp"
#include "python/python_runtime.hpp"
#include "python/swarm_columns.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

// A Python object that C++ owns: released with the GIL held, whichever thread lets it go;
// left alone once the interpreter is gone (a program's exit).
class PyRef {
 public:
  PyRef() = default;
  explicit PyRef(py::object o) : object_(new py::object(std::move(o)), release) {}
  const py::object& operator*() const { return *object_; }
  const py::object* operator->() const { return object_.get(); }

 private:
  static void release(py::object* o) {
    if (!Py_IsInitialized()) {
      o->release();  // the interpreter is gone: nothing to give back
      delete o;
      return;
    }
    PythonLock lock;
    delete o;
  }
  std::shared_ptr<py::object> object_;
};

// The class a scenario named, with what rilbed learned about it when it was loaded.
struct PythonClass {
  std::string file;        // absolute path
  std::string class_name;  // as in the file
  PyRef cls;
  bool vectorised = false;    // step_all, not step
  bool wants_team = false;    // the class's wants_team
  bool forms_convoy = false;  // the class's forms_convoy
  bool has_done = false;      // it overrides done()
  bool has_finish = false;    // it overrides finish()

  std::string stem() const { return std::filesystem::path(file).filename().string(); }
  // "convoy.py: Convoy", for messages.
  std::string who() const { return stem() + ": " + class_name; }
};

std::string robot_list_text(const std::vector<int>& ids) {
  if (ids.size() == 1) return "robot " + std::to_string(ids[0]);
  std::string out = "robots ";
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i == 8) return out + ", ... (" + std::to_string(ids.size()) + " robots)";
    out += (i ? ", " : "") + std::to_string(ids[i]);
  }
  return out;
}

py::dict params_dict(const agents::ControllerParams& params) {
  py::dict d;
  for (const auto& [name, value] : params.given_values()) d[py::str(name)] = value;
  return d;
}

// Makes an instance of the class with the robot's params; a refusal is the scenario's problem.
py::object make_instance(const PythonClass& c, const agents::ControllerParams& params, const std::string& robots) {
  try {
    return (*c.cls)(params_dict(params));
  } catch (py::error_already_set& e) {
    throw std::invalid_argument(c.who() + " refused its params for " + robots + ":\n" + traceback_text(e));
  }
}

// One robot's Python controller (a class with step).
class PythonController final : public agents::Controller {
 public:
  PythonController(std::shared_ptr<const PythonClass> c, int robot_id, py::object instance)
      : class_(std::move(c)),
        who_("robot " + std::to_string(robot_id) + "'s controller " + class_->who()),
        instance_(instance),
        step_(instance.attr("step")) {}

  agents::ControlOutput step(const agents::ControlInput& input) override {
    PythonLock lock;
    try {
      py::object result = (*step_)(py::cast(StepInput::copy_of(input)));
      agents::ControlOutput out = output_from_python(result, who_);
      if (class_->has_done) done_ = py::bool_((*instance_).attr("done")()).cast<bool>();
      return out;
    } catch (py::error_already_set& e) {
      throw agents::ControllerError(who_ + " raised an error:\n" + traceback_text(e));
    }
  }
  void finish() override {
    if (!class_->has_finish) return;
    PythonLock lock;
    try {
      (*instance_).attr("finish")();
    } catch (py::error_already_set& e) {
      spdlog::error("{}: finish() raised an error:\n{}", who_, traceback_text(e));
    }
  }
  bool wants_team() const override { return class_->wants_team; }
  bool done() const override { return done_; }
  bool concurrent() const override { return false; }  // the GIL: one Python step at a time

 private:
  std::shared_ptr<const PythonClass> class_;
  std::string who_;
  PyRef instance_;
  PyRef step_;  // the bound method, looked up once
  bool done_ = false;
};

// The robots one instance of a vectorised class (step_all) controls.
class PythonSwarm final : public agents::ControllerGroup {
 public:
  PythonSwarm(std::shared_ptr<const PythonClass> c, py::object instance)
      : class_(std::move(c)), instance_(instance), step_all_(instance.attr("step_all")) {}

  void add_member(int robot_id) override { members_.push_back(robot_id); }
  void gather(const agents::ControlInput& input) override { gathered_.add(input); }
  std::vector<agents::GroupAnswer> step_gathered() override {
    if (gathered_.rows() == 0) return {};
    auto columns = std::make_shared<const SwarmColumns>(std::move(gathered_));
    gathered_ = {};
    gathered_.reserve(columns->rows());  // the next step's rows, as many as this one's
    std::vector<int> ids(columns->robot_id.begin(), columns->robot_id.end());
    PythonLock lock;
    try {
      py::object result = (*step_all_)(py::cast(SwarmInput{columns}));
      std::vector<agents::GroupAnswer> answers = swarm_answers(result, ids, describe());
      if (class_->has_done) {
        const bool done = py::bool_((*instance_).attr("done")()).cast<bool>();
        for (agents::GroupAnswer& a : answers) a.done = done;
      }
      return answers;
    } catch (py::error_already_set& e) {
      throw agents::ControllerError(describe() + " raised an error:\n" + traceback_text(e));
    }
  }
  void finish() override {
    if (finished_ || !class_->has_finish) return;
    finished_ = true;
    PythonLock lock;
    try {
      (*instance_).attr("finish")();
    } catch (py::error_already_set& e) {
      spdlog::error("{}: finish() raised an error:\n{}", describe(), traceback_text(e));
    }
  }
  bool wants_team() const override { return class_->wants_team; }
  std::string describe() const override {
    return "the controller " + class_->who() + " of " + robot_list_text(members_);
  }

 private:
  std::shared_ptr<const PythonClass> class_;
  PyRef instance_;
  PyRef step_all_;
  std::vector<int> members_;
  SwarmColumns gathered_;
  bool finished_ = false;
};

// The entry's factory: an instance per robot, or one per group of robots with equal params.
agents::ControllerFactory factory_for(std::shared_ptr<const PythonClass> c) {
  return [c](const agents::ControllerContext& context) -> std::unique_ptr<agents::Controller> {
    const std::string robot = "robot " + std::to_string(context.robot_id);
    if (!c->vectorised) {
      PythonLock lock;
      py::object instance = make_instance(*c, context.params, robot);
      return std::make_unique<PythonController>(c, context.robot_id, instance);
    }
    std::string key = c->file + "\n" + c->class_name;
    for (const auto& [name, value] : context.params.given_values()) key += "\n" + name + "=" + std::to_string(value);
    return agents::join_group(context.groups, key, context.robot_id, [&]() -> std::unique_ptr<agents::ControllerGroup> {
      PythonLock lock;
      py::object instance = make_instance(*c, context.params, robot + " (and the robots with its params)");
      return std::make_unique<PythonSwarm>(c, instance);
    });
  };
}

// The module a file was imported as, per absolute path: a file is imported once per
// process, whichever of its classes the scenarios name.
py::object import_file(const std::string& file) {
  static std::map<std::string, PyRef> modules;
  if (const auto it = modules.find(file); it != modules.end()) return *it->second;
  py::module_ sys = py::module_::import("sys");
  const std::string folder = std::filesystem::path(file).parent_path().string();
  if (!py::cast<bool>(sys.attr("path").attr("__contains__")(folder))) sys.attr("path").attr("insert")(1, folder);
  py::module_ util = py::module_::import("importlib.util");
  const std::string name =
      "rilbed_controllers_" + std::to_string(modules.size()) + "_" + std::filesystem::path(file).stem().string();
  py::object spec = util.attr("spec_from_file_location")(name, file);
  if (spec.is_none()) throw std::runtime_error("Python cannot import it");
  py::object module = util.attr("module_from_spec")(spec);
  sys.attr("modules")[py::str(name)] = module;
  try {
    spec.attr("loader").attr("exec_module")(module);
  } catch (...) {
    sys.attr("modules").attr("pop")(name, py::none());
    throw;
  }
  modules.emplace(file, PyRef(module));
  return module;
}

bool overrides(py::handle cls, py::handle base, const char* method) {
  if (!py::hasattr(cls, method)) return false;
  return !py::hasattr(base, method) || !cls.attr(method).is(base.attr(method));
}

core::Result<std::shared_ptr<PythonClass>> read_class(const std::string& file, const std::string& class_name) {
  auto c = std::make_shared<PythonClass>();
  c->file = file;
  c->class_name = class_name;
  const std::string where = "Python controller " + file + ": ";
  py::object module;
  try {
    module = import_file(file);
  } catch (py::error_already_set& e) {
    return core::Failure{where + "it does not import:\n" + traceback_text(e)};
  } catch (const std::exception& e) {
    return core::Failure{where + e.what()};
  }
  if (!py::hasattr(module, class_name.c_str())) {
    std::string classes;
    py::object base = py::module_::import("rilbed").attr("Controller");
    for (auto item : module.attr("__dict__").cast<py::dict>()) {
      if (PyType_Check(item.second.ptr()) && !item.second.is(base) &&
          PyObject_IsSubclass(item.second.ptr(), base.ptr()) == 1) {
        classes += (classes.empty() ? "" : ", ") + item.first.cast<std::string>();
      }
    }
    return core::Failure{where + "it has no class '" + class_name + "' (its rilbed.Controller classes: " +
                         (classes.empty() ? std::string("none") : classes) + ")"};
  }
  py::object cls = module.attr(class_name.c_str());
  py::object base = py::module_::import("rilbed").attr("Controller");
  if (!PyType_Check(cls.ptr()) || PyObject_IsSubclass(cls.ptr(), base.ptr()) != 1) {
    if (PyErr_Occurred()) PyErr_Clear();
    return core::Failure{where + "'" + class_name + "' is not a class that subclasses rilbed.Controller"};
  }
  const bool step = overrides(cls, base, "step"), step_all = overrides(cls, base, "step_all");
  if (step == step_all) {
    return core::Failure{where + class_name +
                         (step ? " defines both step and step_all: give step (one robot per call) or step_all (every "
                                 "robot at once)"
                               : " defines neither step(self, inp) nor step_all(self, inp)")};
  }
  c->cls = PyRef(cls);
  c->vectorised = step_all;
  c->wants_team = py::bool_(cls.attr("wants_team")).cast<bool>();
  c->forms_convoy = py::bool_(cls.attr("forms_convoy")).cast<bool>();
  c->has_done = overrides(cls, base, "done");
  c->has_finish = overrides(cls, base, "finish");
  return c;
}

std::string summary_of(py::handle cls, const std::string& fallback) {
  py::object doc = cls.attr("__doc__");
  if (doc.is_none()) return fallback;
  std::string text = doc.cast<std::string>();
  const auto start = text.find_first_not_of(" \n\t");
  if (start == std::string::npos) return fallback;
  text = text.substr(start);
  return text.substr(0, text.find('\n'));
}

// The names of the rilbed.Controller classes `module` defines itself, in its order.
std::vector<std::string> controller_classes(py::handle module) {
  py::object base = py::module_::import("rilbed").attr("Controller");
  const py::object name = module.attr("__name__");
  std::vector<std::string> out;
  for (auto item : module.attr("__dict__").cast<py::dict>()) {
    py::handle value = item.second;
    if (!PyType_Check(value.ptr()) || value.is(base) || PyObject_IsSubclass(value.ptr(), base.ptr()) != 1) continue;
    if (!py::object(value.attr("__module__")).equal(name)) continue;
    out.push_back(item.first.cast<std::string>());
  }
  if (PyErr_Occurred()) PyErr_Clear();
  return out;
}

}  // namespace

core::Result<std::vector<agents::ControllerEntry>> load_python_controllers(const std::filesystem::path& file) {
  std::error_code ec;
  const std::filesystem::path path = std::filesystem::absolute(file, ec).lexically_normal();
  if (!std::filesystem::is_regular_file(path, ec))
    return core::Failure{"Python controller " + path.string() + ": no such file"};
  try {
    ensure_interpreter();
  } catch (const std::exception& e) {
    return core::Failure{"Python controller " + path.string() + ": " + e.what()};
  }
  std::vector<std::string> names;
  {
    PythonLock lock;
    try {
      names = controller_classes(import_file(path.string()));
    } catch (py::error_already_set& e) {
      return core::Failure{"Python controller " + path.string() + ": it does not import:\n" + traceback_text(e)};
    }
  }
  if (names.empty())
    return core::Failure{"Python controller " + path.string() + ": it defines no rilbed.Controller class"};
  std::vector<agents::ControllerEntry> entries;
  for (const std::string& name : names) {
    core::Result<agents::ControllerEntry> e = load_python_controller(path, name);
    if (!e) return core::Failure{e.error()};
    entries.push_back(std::move(*e));
  }
  return entries;
}

core::Result<agents::ControllerEntry> load_python_controller(const std::filesystem::path& file,
                                                             const std::string& class_name) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    return core::Failure{"Python controller " + file.string() + ": no such file"};
  }
  try {
    ensure_interpreter();
  } catch (const std::exception& e) {
    return core::Failure{"Python controller " + file.string() + ": " + e.what()};
  }
  PythonLock lock;
  try {
    core::Result<std::shared_ptr<PythonClass>> c = read_class(file.string(), class_name);
    if (!c) return core::Failure{c.error()};
    agents::ControllerEntry e;
    e.name = file.stem().string() + "." + class_name;
    e.summary = summary_of(*(*c)->cls, "Python class " + class_name + (((*c)->vectorised) ? " (step_all)" : ""));
    e.wants_team = (*c)->wants_team;
    e.forms_convoy = (*c)->forms_convoy;
    e.concurrent = false;
    e.origin = file.string();
    e.library = file.string();
    e.open_params = true;
    e.make = factory_for(*c);
    return e;
  } catch (py::error_already_set& e) {
    return core::Failure{"Python controller " + file.string() + ": " + class_name + ":\n" + traceback_text(e)};
  }
}

}  // namespace rilbed::python
