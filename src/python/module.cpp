// The extension module `rilbed._rilbed`: the controller API (as the embedded interpreter
// has it) and runs started from Python through the same RunSession as `rilbed run`.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include <atomic>
#include <csignal>

#include "python/python_runtime.hpp"
#include "session/run_session.hpp"

namespace py = pybind11;

namespace rilbed::python {

namespace {

// The options `rilbed.run` passes on (their names are those of SessionOptions).
void read_session_options(const nlohmann::json& o, session::SessionOptions& s) {
  for (const auto& [key, value] : o.items()) {
    if (key == "fast") {
      s.fast = value.get<bool>();
    } else if (key == "realtime") {
      s.realtime = value.get<bool>();
    } else if (key == "rt_factor") {
      s.rt_factor = value.get<double>();
    } else if (key == "stop_when_formed") {
      s.stop_when_formed = value.get<bool>();
    } else if (key == "stop_when_done") {
      s.stop_when_done = value.get<bool>();
    } else if (key == "threads") {
      s.threads = value.get<int>();
    } else if (key == "quiet") {
      s.quiet = value.get<bool>();
    } else if (key == "all_virtual") {
      s.all_virtual = value.get<bool>();
    } else if (key == "lcm_url") {
      s.lcm_url = value.get<std::string>();
    } else if (key == "record") {
      s.record = value.get<std::string>();
    } else if (key == "mode") {
      const std::string mode = value.get<std::string>();
      if (mode != "central" && mode != "distributed") throw py::value_error("mode is 'central' or 'distributed'");
      s.mode = mode == "central" ? run::ConvoyMode::kCentral : run::ConvoyMode::kDistributed;
    } else if (key == "on_controller_error") {
      const std::string action = value.get<std::string>();
      if (action != "end-run" && action != "stop-robot") {
        throw py::value_error("on_controller_error is 'end-run' or 'stop-robot'");
      }
      s.on_controller_error =
          action == "stop-robot" ? run::ControllerErrorAction::kStopRobot : run::ControllerErrorAction::kEndRun;
    } else {
      throw py::type_error(
          "run() got an unexpected option '" + key +
          "' (it takes fast, realtime, rt_factor, stop_when_formed, stop_when_done, threads, quiet, all_virtual, "
          "lcm_url, record, mode, on_controller_error)");
    }
  }
}

// rilbed.run's C++ half: `scenario` a file's path, or (with `scenario_text`) the name the
// text goes by; `overrides_json` a list of [path, value as JSON]. Returns the summary as
// JSON text; raises RuntimeError for a run that fails (its message names why).
std::string run_session(const std::string& scenario, const std::string& scenario_text,
                        const std::string& overrides_json, std::uint64_t seed, double duration_s,
                        const std::string& out, const std::string& options_json) {
  session::SessionOptions o;
  o.scenario = scenario;
  o.scenario_text = scenario_text;
  o.seed = seed;
  if (duration_s >= 0) o.duration_s = duration_s;
  o.out = out;
  o.quiet = true;
  try {
    for (const auto& item : nlohmann::json::parse(overrides_json)) {
      o.overrides.push_back({item.at(0).get<std::string>(), item.at(1).dump()});
    }
    read_session_options(nlohmann::json::parse(options_json), o);
  } catch (const nlohmann::json::exception& e) {
    throw py::value_error(std::string("run(): bad options: ") + e.what());
  }
  std::vector<std::string> lines;
  session::SessionOutput output;
  output.print = [&lines](const std::string& line) { lines.push_back(line); };
  output.notice = [](const std::string&) {};
  session::SessionResult result;
  {
    // Ctrl-C (a notebook's interrupt) ends the run cleanly, as `rilbed run`'s does: its
    // robots stopped and its files written; Python's own handler is back afterwards.
    static std::atomic<bool> interrupted;
    interrupted = false;
    o.interrupt = &interrupted;
    const auto previous = std::signal(SIGINT, [](int) { interrupted = true; });
    py::gil_scoped_release release;  // the run's controllers take it when they call Python
    session::RunSession s(o, output);
    result = s.run();
    std::signal(SIGINT, previous);
    if (interrupted) {
      py::gil_scoped_acquire acquire;
      PyErr_SetString(PyExc_KeyboardInterrupt, "the run was interrupted; it ended cleanly");
      throw py::error_already_set();
    }
  }
  if (result.status == session::SessionResult::Status::kUsage) throw py::value_error(result.error);
  if (result.status != session::SessionResult::Status::kOk || result.runs.empty())
    throw std::runtime_error(result.error);
  nlohmann::json summary = result.runs.front().summary();
  summary["out"] = out.empty() ? nlohmann::json(nullptr) : nlohmann::json(out);
  return summary.dump();
}

}  // namespace

}  // namespace rilbed::python

PYBIND11_MODULE(_rilbed, m) {
  m.doc() = "rilbed's controller API and runs (use the package `rilbed`)";
  rilbed::python::bind_controller_api(m);
  m.def("_run_session", &rilbed::python::run_session, py::arg("scenario"), py::arg("scenario_text"),
        py::arg("overrides_json"), py::arg("seed"), py::arg("duration_s"), py::arg("out"), py::arg("options_json"));
}
