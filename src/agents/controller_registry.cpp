#include "agents/controller_registry.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rilbed::agents {

namespace {

// A number as a person writes it: 0.1, 1.016, 4, 1000000.
std::string number_text(double v) {
  std::ostringstream out;
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    out << static_cast<long long>(v);
  } else {
    out << v;
  }
  return out.str();
}

using Json = nlohmann::ordered_json;

Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
Json optional_or_null(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }

std::string range_text(const ParamSpec& p) {
  const bool low = std::isfinite(p.min), high = std::isfinite(p.max);
  if (low && high) return number_text(p.min) + " to " + number_text(p.max);
  if (low) return "at least " + number_text(p.min);
  if (high) return "at most " + number_text(p.max);
  return "any";
}

std::string with_unit(const ParamSpec& p) { return p.unit.empty() ? "" : " (" + p.unit + ")"; }

std::string joined(const std::vector<std::string>& words, const char* separator = ", ") {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : separator) + w;
  return out;
}

void check_entry(const ControllerEntry& e) {
  const std::string who = "controller '" + e.name + "' (" + e.origin + ")";
  if (e.name.empty()) throw std::invalid_argument("a controller without a name (" + e.origin + ")");
  if (!e.make) throw std::invalid_argument(who + " has no factory");
  std::set<std::string> names;
  for (const ParamSpec& p : e.params) {
    if (p.name.empty()) throw std::invalid_argument(who + " has a parameter without a name");
    if (!names.insert(p.name).second) throw std::invalid_argument(who + " names parameter '" + p.name + "' twice");
    if (!(p.min <= p.max)) throw std::invalid_argument(who + ": parameter '" + p.name + "' has min above max");
    if (p.required && p.default_value) {
      throw std::invalid_argument(who + ": parameter '" + p.name + "' is required and has a default");
    }
    if (p.default_value && !(*p.default_value >= p.min && *p.default_value <= p.max)) {
      throw std::invalid_argument(who + ": parameter '" + p.name + "' has its default outside its range");
    }
  }
  const auto& known = known_sensor_names();
  for (const auto* list : {&e.sensors, &e.required_sensors}) {
    for (const std::string& s : *list) {
      if (std::find(known.begin(), known.end(), s) == known.end()) {
        throw std::invalid_argument(who + " reads sensor '" + s + "', which is not one of " + joined(known));
      }
    }
  }
  for (const std::string& s : e.required_sensors) {
    if (std::find(e.sensors.begin(), e.sensors.end(), s) == e.sensors.end()) {
      throw std::invalid_argument(who + " requires sensor '" + s + "' but does not list it among those it reads");
    }
  }
}

}  // namespace

const std::vector<std::string>& known_sensor_names() {
  static const std::vector<std::string> names = {"proximity", "range_finders", "beacon_finder",
                                                 "track",     "odometer",      "pose"};
  return names;
}

bool robot_has_sensor(const environment::SensorSuiteConfig& sensors, std::string_view name) {
  if (name == "proximity") return sensors.proximity.has_value();
  if (name == "range_finders") return !sensors.range_finders.empty();
  if (name == "beacon_finder") return sensors.beacon_finder.has_value();
  if (name == "track") {
    return !sensors.track_sensors.empty() ||
           std::any_of(sensors.models.begin(), sensors.models.end(),
                       [](const environment::SensorModelMount& m) { return m.model && m.model->provides_track(); });
  }
  if (name == "odometer") return sensors.odometer;
  return name == "pose";
}

ControllerParams::ControllerParams(const std::vector<ParamSpec>& specs, std::map<std::string, double> given)
    : specs_(&specs), given_(given.begin(), given.end()) {}

bool ControllerParams::given(std::string_view name) const { return given_.find(name) != given_.end(); }

double ControllerParams::get(std::string_view name) const {
  if (const auto it = given_.find(name); it != given_.end()) return it->second;
  for (const ParamSpec& p : *specs_) {
    if (p.name == name && p.default_value) return *p.default_value;
  }
  throw std::out_of_range("parameter '" + std::string(name) + "' was not given and has no default");
}

const ParamSpec* ControllerEntry::param(std::string_view wanted) const {
  const auto it = std::find_if(params.begin(), params.end(), [&](const ParamSpec& p) { return p.name == wanted; });
  return it == params.end() ? nullptr : &*it;
}

std::optional<ParamProblem> check_params(const ControllerEntry& entry, const std::map<std::string, double>& given) {
  for (const auto& [key, value] : given) {
    const ParamSpec* p = entry.param(key);
    if (!p && entry.open_params) {
      if (!std::isfinite(value)) return ParamProblem{key, "must be a finite number"};
      continue;
    }
    if (!p) {
      std::vector<std::string> names;
      for (const ParamSpec& q : entry.params) names.push_back(q.name);
      return ParamProblem{key, "controller " + entry.name + " has no parameter '" + key + "' (it takes " +
                                   (names.empty() ? std::string("none") : joined(names)) + ")"};
    }
    if (!std::isfinite(value)) return ParamProblem{key, "must be a finite number"};
    if (p->integer && value != std::floor(value)) return ParamProblem{key, "must be a whole number"};
    if (value < p->min || value > p->max) {
      return ParamProblem{key, "must be " + range_text(*p) + with_unit(*p) + ", not " + number_text(value)};
    }
  }
  for (const ParamSpec& p : entry.params) {
    if (p.required && !given.contains(p.name)) {
      return ParamProblem{"", "controller " + entry.name + " needs parameter '" + p.name + "' (" + p.summary + ")"};
    }
  }
  return std::nullopt;
}

std::optional<std::string> missing_sensor(const ControllerEntry& entry, const environment::SensorSuiteConfig& sensors) {
  for (const std::string& s : entry.required_sensors) {
    if (!robot_has_sensor(sensors, s)) return s;
  }
  return std::nullopt;
}

void ControllerRegistry::add(ControllerEntry entry) {
  check_entry(entry);
  if (const ControllerEntry* taken = find(entry.name)) {
    throw std::invalid_argument("controller '" + entry.name + "' (" + entry.origin + ") is already registered (" +
                                taken->origin + ")");
  }
  entries_.push_back(std::move(entry));
}

const ControllerEntry* ControllerRegistry::find(std::string_view name) const {
  const auto it =
      std::find_if(entries_.begin(), entries_.end(), [&](const ControllerEntry& e) { return e.name == name; });
  return it == entries_.end() ? nullptr : &*it;
}

std::string ControllerRegistry::names_text() const {
  std::vector<std::string> names;
  for (const ControllerEntry& e : entries_) names.push_back(e.name);
  return joined(names);
}

nlohmann::ordered_json controllers_json(const ControllerRegistry& registry) {
  Json list = Json::array();
  for (const ControllerEntry& e : registry.entries()) {
    Json params = Json::array();
    for (const ParamSpec& p : e.params) {
      params.push_back({{"name", p.name},
                        {"unit", p.unit},
                        {"default", optional_or_null(p.default_value)},
                        {"min", finite_or_null(p.min)},
                        {"max", finite_or_null(p.max)},
                        {"summary", p.summary},
                        {"required", p.required},
                        {"integer", p.integer}});
    }
    list.push_back({{"name", e.name},
                    {"summary", e.summary},
                    {"sensors", e.sensors},
                    {"required_sensors", e.required_sensors},
                    {"wants_team", e.wants_team},
                    {"concurrent", e.concurrent},
                    {"origin", e.origin},
                    {"library", e.library.empty() ? Json(nullptr) : Json(e.library)},
                    {"params", params}});
  }
  return list;
}

std::string controllers_table(const ControllerRegistry& registry) {
  std::ostringstream out;
  out << "| controller | what it does | reads | team broadcast | concurrent |\n";
  out << "| --- | --- | --- | --- | --- |\n";
  for (const ControllerEntry& e : registry.entries()) {
    std::vector<std::string> reads;
    for (const std::string& s : e.sensors) {
      const bool needed =
          std::find(e.required_sensors.begin(), e.required_sensors.end(), s) != e.required_sensors.end();
      reads.push_back("`" + s + "`" + (needed ? " (required)" : ""));
    }
    out << "| `" << e.name << "` | " << e.summary << " | " << (reads.empty() ? "-" : joined(reads)) << " | "
        << (e.wants_team ? "yes" : "no") << " | " << (e.concurrent ? "yes" : "no") << " |\n";
  }
  out << "\n| controller | parameter | unit | default | allowed | meaning |\n";
  out << "| --- | --- | --- | --- | --- | --- |\n";
  for (const ControllerEntry& e : registry.entries()) {
    for (const ParamSpec& p : e.params) {
      const std::string fallback = p.required ? "required" : p.default_value ? number_text(*p.default_value) : "-";
      out << "| `" << e.name << "` | `" << p.name << "` | " << (p.unit.empty() ? "-" : p.unit) << " | " << fallback
          << " | " << range_text(p) << (p.integer ? ", whole" : "") << " | " << p.summary << " |\n";
    }
  }
  return out.str();
}

}  // namespace rilbed::agents
