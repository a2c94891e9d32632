#include "agents/library_controllers.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string_view>

#include "agents/behaviour_names.hpp"
#include "agents/c_controller.hpp"

namespace rilbed::agents {

namespace {

constexpr std::size_t kMaxText = 4096;
constexpr std::uint32_t kMaxParams = 64;
constexpr std::size_t kMaxSensors = 16;
constexpr std::size_t kMaxControllers = 4096;

// Whether `text` is UTF-8 (no overlong forms, no surrogates) without control characters:
// what the registry's JSON, the terminal and the web page can show.
bool printable_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      if (c < 0x20 || c == 0x7f) return false;
      ++i;
      continue;
    }
    const std::size_t length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 ? 2 : 0;
    if (length == 0 || c > 0xf4 || i + length > text.size()) return false;
    std::uint32_t code = c & (0x7f >> length);
    for (std::size_t k = 1; k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xc0) != 0x80) return false;
      code = (code << 6) | (next & 0x3f);
    }
    const std::uint32_t least = length == 2 ? 0x80 : length == 3 ? 0x800 : 0x10000;
    if (code < least || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff)) return false;
    i += length;
  }
  return true;
}

// A C string from a library, read no further than `limit` bytes.
core::Result<std::string> library_text(const char* text, const std::string& what, std::size_t limit = kMaxText) {
  if (!text) return core::Failure{what + " is NULL"};
  const std::size_t n = strnlen(text, limit + 1);
  if (n > limit) return core::Failure{what + " is longer than " + std::to_string(limit) + " bytes"};
  std::string out(text, n);
  if (!printable_utf8(out)) return core::Failure{what + " is not UTF-8 text without control characters"};
  return out;
}

// A name a scenario can write after `name:` and a parameter after `params:`: letters,
// digits and _ . : -.
core::Result<std::string> library_name(const char* text, const std::string& what) {
  core::Result<std::string> name = library_text(text, what, 128);
  if (!name) return name;
  if (name->empty()) return core::Failure{what + " is empty"};
  for (const char c : *name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '.' || c == ':' || c == '-';
    if (!ok) return core::Failure{what + " '" + *name + "' holds a character other than letters, digits, _ . : -"};
  }
  return name;
}

core::Result<std::vector<std::string>> library_sensors(const char* const* list, const std::string& what) {
  std::vector<std::string> out;
  if (!list) return out;
  for (std::size_t i = 0; list[i]; ++i) {
    if (i >= kMaxSensors) return core::Failure{what + " lists more than " + std::to_string(kMaxSensors) + " sensors"};
    core::Result<std::string> s = library_name(list[i], what + " sensor " + std::to_string(i));
    if (!s) return core::Failure{s.error()};
    out.push_back(*s);
  }
  return out;
}

core::Result<ParamSpec> library_param(const rilbed_param& p, const std::string& what) {
  core::Result<std::string> name = library_name(p.name, what + " name");
  if (!name) return core::Failure{name.error()};
  const std::string who = what + " '" + *name + "'";
  core::Result<std::string> unit = library_text(p.unit, who + " unit", 32);
  core::Result<std::string> summary = library_text(p.summary, who + " summary");
  if (!unit) return core::Failure{unit.error()};
  if (!summary) return core::Failure{summary.error()};
  if (std::isnan(p.min) || std::isnan(p.max)) return core::Failure{who + " has a range that is not a number"};
  if (p.has_default && !std::isfinite(p.default_value)) return core::Failure{who + " has a default that is not finite"};
  ParamSpec spec;
  spec.name = *name;
  spec.unit = *unit;
  spec.summary = *summary;
  if (p.has_default) spec.default_value = p.default_value;
  spec.required = p.required != 0;
  spec.integer = p.integer != 0;
  spec.min = p.min;
  spec.max = p.max;
  return spec;
}

// A class's controller for one robot: the instance the library made, stepped through the
// class's functions with the input as rilbed_control_input.
class ClassController final : public Controller {
 public:
  ClassController(std::shared_ptr<const PluginLibrary> library, const rilbed_controller_class& c, void* instance,
                  std::string who)
      : library_(std::move(library)),
        class_(c),
        instance_(instance),
        who_(std::move(who)),
        wants_team_(c.wants_team != 0),
        concurrent_(c.concurrent != 0) {}
  ~ClassController() override {
    finish();
    class_.destroy(instance_);
  }
  ClassController(const ClassController&) = delete;
  ClassController& operator=(const ClassController&) = delete;

  ControlOutput step(const ControlInput& input) override {
    fill(input);
    rilbed_control_output out{0, 0, nullptr};
    char error[512] = {0};
    if (class_.step(instance_, &raw_, &out, error, sizeof error) != 0) {
      error[sizeof error - 1] = '\0';
      throw ControllerError(who_ + ": its step at t = " + std::to_string(input.t_us / 1000) +
                            " ms failed: " + (error[0] ? error : "(no message)"));
    }
    return output_from_class(out);
  }
  void finish() override {
    if (finished_) return;
    finished_ = true;
    if (class_.finish) class_.finish(instance_);
  }
  bool wants_team() const override { return wants_team_; }
  bool done() const override { return class_.done && class_.done(instance_) != 0; }
  bool concurrent() const override { return concurrent_; }

 private:
  void fill(const ControlInput& in) {
    raw_ = {};
    raw_.t_us = in.t_us;
    raw_.robot_id = in.robot_id;
    if (in.pose) {
      raw_.has_pose = 1;
      raw_.x_m = in.pose->position_m.x;
      raw_.y_m = in.pose->position_m.y;
      raw_.heading_rad = in.pose->heading_rad;
    }
    const environment::SensorReadings& s = in.sensors;
    if (s.proximity) {
      raw_.has_proximity = 1;
      std::copy(s.proximity->begin(), s.proximity->end(), raw_.proximity);
    }
    if (s.odometry) {
      raw_.has_odometry = 1;
      raw_.odometry_left_pulses = s.odometry->left_pulses;
      raw_.odometry_right_pulses = s.odometry->right_pulses;
    }
    ranges_.clear();
    for (const environment::RangeReading& r : s.ranges) ranges_.push_back({r.hit ? 1 : 0, r.distance_m});
    track_.assign(s.track.begin(), s.track.end());
    beacons_.clear();
    for (const environment::BeaconSighting& b : s.beacons) beacons_.push_back({b.id, b.bearing_rad});
    team_.clear();
    for (const TeamMessage& m : in.team) {
      team_.push_back({m.id, m.pose.position_m.x, m.pose.position_m.y, m.pose.heading_rad,
                       intern_behaviour(m.behaviour).data(), m.t_us});
    }
    raw_.ranges = ranges_.data();
    raw_.range_count = static_cast<std::uint32_t>(ranges_.size());
    raw_.track = track_.data();
    raw_.track_count = static_cast<std::uint32_t>(track_.size());
    raw_.beacons = beacons_.data();
    raw_.beacon_count = static_cast<std::uint32_t>(beacons_.size());
    raw_.team = team_.data();
    raw_.team_count = static_cast<std::uint32_t>(team_.size());
    models_.clear();
    for (const environment::ModelReading& m : s.models) {
      // The names are the mounts' (NUL-terminated std::strings of the run's sensor models).
      models_.push_back({m.name.data(), m.values.data(), static_cast<std::uint32_t>(m.values.size())});
    }
    raw_.models = models_.data();
    raw_.model_count = static_cast<std::uint32_t>(models_.size());
  }

  std::shared_ptr<const PluginLibrary> library_;
  const rilbed_controller_class& class_;
  void* instance_;
  std::string who_;
  bool wants_team_;
  bool concurrent_;
  bool finished_ = false;
  rilbed_control_input raw_{};
  // The arrays raw_ points into, kept between steps so that a step allocates nothing.
  std::vector<rilbed_range> ranges_;
  std::vector<std::int32_t> track_;
  std::vector<rilbed_beacon> beacons_;
  std::vector<rilbed_team_member> team_;
  std::vector<rilbed_model_reading> models_;
};

// One robot's controller of class `c`: its parameters as the class's create() takes them.
struct ClassIdentity {
  std::string name;
  std::string origin;
  std::vector<ParamSpec> params;
};

std::unique_ptr<Controller> make_class_controller(const std::shared_ptr<const PluginLibrary>& library,
                                                  const rilbed_controller_class& c, const ClassIdentity& entry,
                                                  const ControllerContext& context) {
  std::vector<const char*> names;
  std::vector<double> values;
  std::vector<std::int32_t> given;
  for (const ParamSpec& p : entry.params) {
    const bool was_given = context.params.given(p.name);
    if (!was_given && !p.default_value) continue;
    names.push_back(p.name.c_str());
    values.push_back(context.params.get(p.name));
    given.push_back(was_given ? 1 : 0);
  }
  const rilbed_controller_args args{context.robot_id, static_cast<std::uint32_t>(names.size()), names.data(),
                                    values.data(), given.data()};
  char error[512] = {0};
  void* instance = c.create(c.context, &args, error, sizeof error);
  error[sizeof error - 1] = '\0';
  if (!instance) {
    throw std::invalid_argument("(" + entry.origin + ") cannot be made: " + (error[0] ? error : "(no message)"));
  }
  return std::make_unique<ClassController>(
      library, c, instance,
      "controller " + entry.name + " of robot " + std::to_string(context.robot_id) + " (" + entry.origin + ")");
}

// Whether `entry` would be accepted by a registry: ControllerRegistry::add's checks.
core::Result<ControllerEntry> checked(ControllerEntry entry) {
  try {
    ControllerRegistry probe;
    probe.add(entry);
  } catch (const std::invalid_argument& e) {
    return core::Failure{e.what()};
  }
  return entry;
}

template <typename T>
core::Result<std::vector<const T*>> library_list(const T* const* list, const std::string& what) {
  if (!list) return core::Failure{what + " returned NULL"};
  std::vector<const T*> out;
  for (std::size_t i = 0; list[i]; ++i) {
    if (i >= kMaxControllers) return core::Failure{what + " holds more than 4096 entries (no NULL at its end?)"};
    out.push_back(list[i]);
  }
  return out;
}

}  // namespace

core::Result<ControllerEntry> c_controller_entry(const rilbed_c_controller& controller,
                                                 std::shared_ptr<const PluginLibrary> library,
                                                 const std::string& entry_name) {
  const std::string origin = library ? library->path().string() : std::string("built in");
  const std::string who = origin + ": C controller";
  core::Result<std::string> name = library_name(controller.name, who + " name");
  if (!name) return core::Failure{name.error()};
  if (!controller.step) return core::Failure{who + " '" + *name + "' has no step function"};
  ControllerEntry e;
  e.name = entry_name.empty() ? *name : entry_name;
  e.summary = "the C controller '" + *name + "' of " + (library ? library->path().filename().string() : origin) +
              ", reading and driving its robot through rilbed_controller.h's register map";
  e.sensors = {"proximity", "odometer", "range_finders", "track", "beacon_finder", "pose"};
  e.concurrent = false;
  e.origin = origin;
  if (library) e.library = library->path().string();
  e.make = [library, &controller](const ControllerContext& c) {
    return std::make_unique<CControllerAdapter>(controller, library, c.sensors.track_sensors);
  };
  return checked(std::move(e));
}

core::Result<ControllerEntry> class_entry(const rilbed_controller_class& c,
                                          std::shared_ptr<const PluginLibrary> library, const std::string& origin) {
  const std::string what = origin + ": controller class";
  if (c.abi_version != RILBED_ABI_VERSION) {
    return core::Failure{what + " was built against rilbed's SDK ABI version " + std::to_string(c.abi_version) +
                         ", this rilbed loads version " + std::to_string(RILBED_ABI_VERSION)};
  }
  core::Result<std::string> name = library_name(c.name, what + " name");
  if (!name) return core::Failure{name.error()};
  const std::string who = what + " '" + *name + "'";
  core::Result<std::string> summary = library_text(c.summary, who + " summary");
  if (!summary) return core::Failure{summary.error()};
  if (!c.create || !c.step || !c.destroy) return core::Failure{who + " lacks its create, step or destroy function"};
  if (c.param_count > kMaxParams) return core::Failure{who + " has more than 64 parameters"};
  if (c.param_count > 0 && !c.params) return core::Failure{who + " has parameters but their list is NULL"};
  ControllerEntry e;
  e.name = *name;
  e.summary = *summary;
  for (std::uint32_t i = 0; i < c.param_count; ++i) {
    core::Result<ParamSpec> p = library_param(c.params[i], who + " parameter " + std::to_string(i));
    if (!p) return core::Failure{p.error()};
    e.params.push_back(*p);
  }
  core::Result<std::vector<std::string>> sensors = library_sensors(c.sensors, who);
  if (!sensors) return core::Failure{sensors.error()};
  core::Result<std::vector<std::string>> required = library_sensors(c.required_sensors, who + " required");
  if (!required) return core::Failure{required.error()};
  e.sensors = *sensors;
  e.required_sensors = *required;
  e.wants_team = c.wants_team != 0;
  e.concurrent = c.concurrent != 0;
  e.origin = origin;
  if (library) e.library = library->path().string();
  // The factory keeps its own copy of what it needs: entries are copied with registries.
  auto identity = std::make_shared<const ClassIdentity>(ClassIdentity{e.name, origin, e.params});
  e.make = [library, &c, identity](const ControllerContext& context) {
    return make_class_controller(library, c, *identity, context);
  };
  return checked(std::move(e));
}

ControlOutput output_from_class(const rilbed_control_output& out) {
  ControlOutput o;
  o.wheels = {std::clamp<int>(out.left, -kMaxWheelUnits, kMaxWheelUnits),
              std::clamp<int>(out.right, -kMaxWheelUnits, kMaxWheelUnits)};
  if (out.behaviour) {
    o.behaviour = intern_behaviour(std::string_view(out.behaviour, strnlen(out.behaviour, 65)));
  }
  return o;
}

core::Result<std::vector<ControllerEntry>> load_library_controllers(const std::filesystem::path& path) {
  core::Result<std::shared_ptr<const PluginLibrary>> opened = PluginLibrary::open(path);
  if (!opened) return core::Failure{opened.error()};
  const std::shared_ptr<const PluginLibrary>& library = *opened;
  const std::string origin = library->path().string();
  using CList = const rilbed_c_controller* const* (*)();
  using ClassList = const rilbed_controller_class* const* (*)();
  auto c_list = reinterpret_cast<CList>(library->symbol("rilbed_controllers"));
  auto class_list = reinterpret_cast<ClassList>(library->symbol("rilbed_controller_classes"));
  if (!c_list && !class_list) {
    return core::Failure{"plug-in library " + origin +
                         ": exports neither rilbed_controllers() nor rilbed_controller_classes(), so it holds no "
                         "controller"};
  }
  std::vector<ControllerEntry> entries;
  if (c_list) {
    core::Result<std::vector<const rilbed_c_controller*>> list =
        library_list(c_list(), "plug-in library " + origin + ": rilbed_controllers()");
    if (!list) return core::Failure{list.error()};
    for (const rilbed_c_controller* c : *list) {
      core::Result<ControllerEntry> e = c_controller_entry(*c, library, "");
      if (!e) return core::Failure{e.error()};
      entries.push_back(std::move(*e));
    }
  }
  if (class_list) {
    core::Result<std::vector<const rilbed_controller_class*>> list =
        library_list(class_list(), "plug-in library " + origin + ": rilbed_controller_classes()");
    if (!list) return core::Failure{list.error()};
    for (const rilbed_controller_class* c : *list) {
      core::Result<ControllerEntry> e = class_entry(*c, library, origin);
      if (!e) return core::Failure{e.error()};
      entries.push_back(std::move(*e));
    }
  }
  for (std::size_t i = 0; i < entries.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (entries[i].name == entries[j].name) {
        return core::Failure{"plug-in library " + origin + ": holds two controllers named '" + entries[i].name + "'"};
      }
    }
  }
  return entries;
}

}  // namespace rilbed::agents
