// rilbed's controller API for C++ plug-in libraries: a Controller subclass per kind of
// controller, described by a ControllerInfo (its name, its parameters with units and
// ranges, the sensors it reads), exported with RILBED_CONTROLLERS(...). rilbed checks a
// scenario's `params` against the description before it makes a controller, prints it in
// `rilbed controllers --library`, and the web editor offers it.
//
// Header-only: what crosses into rilbed is the C ABI of rilbed_controller.h
// (rilbed_controller_class), which this header fills in from the C++ classes, so a
// library may be built with another compiler or standard library than rilbed's. No C++
// exception crosses into rilbed: one thrown by a constructor or a step becomes the error
// rilbed reports, naming the library and the robot, and the run ends (its real robots
// stopped).
//
//   #include <rilbed/controller.hpp>
//   class Cruise : public rilbed::sdk::Controller {
//    public:
//     explicit Cruise(double speed_mps) : speed_mps_(speed_mps) {}
//     rilbed::sdk::Output step(const rilbed::sdk::Input&) override {
//       return rilbed::sdk::wheels_from_twist(speed_mps_, 0.0, "cruise");
//     }
//    private:
//     double speed_mps_;
//   };
//   rilbed::sdk::ControllerInfo cruise() {
//     rilbed::sdk::ControllerInfo info{"cruise", "drives straight ahead"};
//     info.params = {rilbed::sdk::Param::number("speed_mps", "m/s", 0.1, 0.0, 1.016, "its speed")};
//     info.make = [](const rilbed::sdk::Context& c) { return std::make_unique<Cruise>(c.params.get("speed_mps")); };
//     return info;
//   }
//   RILBED_DEFINE_PLUGIN();
//   RILBED_CONTROLLERS(cruise());
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "rilbed/rilbed_controller.h"

namespace rilbed::sdk {

/// Khepera wheel speed units: pulses per 10 ms; 1 unit = 8 mm/s.
inline constexpr double kMetresPerSecondPerUnit = 0.008;
/// Largest wheel speed in those units (rilbed clamps to it).
inline constexpr int kMaxWheelUnits = 127;
/// Distance between a Khepera's wheels, metres.
inline constexpr double kWheelBase_m = 0.053;

/// A pose in the field frame: metres, heading in radians counter-clockwise from +x.
struct Pose {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;
};

/// Wheel counters: pulses of 0.08 mm.
struct Odometry {
  std::int64_t left_pulses = 0;
  std::int64_t right_pulses = 0;
};

/// A member of the team broadcast.
struct TeamMember {
  int id = 0;
  Pose pose;
  std::string_view behaviour;
  std::int64_t t_us = 0;
};

/// One control step's input: a view of rilbed's rilbed_control_input, valid during the
/// step() call it is passed to.
class Input {
 public:
  explicit Input(const rilbed_control_input& raw) : raw_(&raw) {}
  /// Simulated time of this step, microseconds.
  std::int64_t t_us() const { return raw_->t_us; }
  /// The robot being controlled.
  int robot_id() const { return raw_->robot_id; }
  /// Its pose from localisation (the world, or the camera for a real robot); nullopt while unknown.
  std::optional<Pose> pose() const {
    if (!raw_->has_pose) return std::nullopt;
    return Pose{raw_->x_m, raw_->y_m, raw_->heading_rad};
  }
  /// The eight IR proximity sensors, 0..1023 (higher is nearer), 0 = left, 2 and 3 = front,
  /// 5 = right, 6 and 7 = back; nullopt for a robot without them.
  std::optional<std::array<int, 8>> proximity() const {
    if (!raw_->has_proximity) return std::nullopt;
    std::array<int, 8> p{};
    std::copy(raw_->proximity, raw_->proximity + 8, p.begin());
    return p;
  }
  /// The wheel counters; nullopt without an odometer.
  std::optional<Odometry> odometry() const {
    if (!raw_->has_odometry) return std::nullopt;
    return Odometry{raw_->odometry_left_pulses, raw_->odometry_right_pulses};
  }
  /// The range finders, in configured order.
  std::span<const rilbed_range> ranges() const { return {raw_->ranges, raw_->range_count}; }
  /// The track sensors, 0..their max value, in configured order.
  std::span<const std::int32_t> track() const { return {raw_->track, raw_->track_count}; }
  /// The beacons in view.
  std::span<const rilbed_beacon> beacons() const { return {raw_->beacons, raw_->beacon_count}; }
  /// Number of members in the team broadcast (0 unless the controller wants_team).
  std::size_t team_size() const { return raw_->team_count; }
  /// Member `i` of the team broadcast, i < team_size().
  TeamMember team(std::size_t i) const {
    const rilbed_team_member& m = raw_->team[i];
    return {m.id, {m.x_m, m.y_m, m.heading_rad}, m.behaviour ? m.behaviour : "", m.t_us};
  }
  /// The readings of the sensor model mounted as `name`; empty if the robot carries none.
  std::span<const double> model(std::string_view name) const {
    for (std::uint32_t i = 0; i < raw_->model_count; ++i) {
      if (raw_->models[i].model && name == raw_->models[i].model)
        return {raw_->models[i].values, raw_->models[i].count};
    }
    return {};
  }
  /// The C struct itself.
  const rilbed_control_input& raw() const { return *raw_; }

 private:
  const rilbed_control_input* raw_;
};

/// One control step's decision.
struct Output {
  int left = 0;   ///< wheel speed, Khepera units (8 mm/s each), clamped to ±127 by rilbed
  int right = 0;  ///< wheel speed, Khepera units
  /// The active behaviour, shown in the run's records; rilbed copies it. Keep the set of
  /// names small (a few per controller): each distinct name is kept for the whole run.
  std::string behaviour = "idle";
};

/// Forward speed (m/s) and turn rate (rad/s, counter-clockwise) to wheel units, rounded
/// and clamped to ±127 keeping the curvature: rilbed's own agents::wheels_from_twist.
inline Output wheels_from_twist(double speed_mps, double turn_rate_radps, std::string behaviour = "idle") {
  double left = (speed_mps - 0.5 * turn_rate_radps * kWheelBase_m) / kMetresPerSecondPerUnit;
  double right = (speed_mps + 0.5 * turn_rate_radps * kWheelBase_m) / kMetresPerSecondPerUnit;
  const double biggest = std::max(std::abs(left), std::abs(right));
  if (biggest > kMaxWheelUnits) {
    left *= kMaxWheelUnits / biggest;
    right *= kMaxWheelUnits / biggest;
  }
  return {static_cast<int>(std::lround(left)), static_cast<int>(std::lround(right)), std::move(behaviour)};
}

/// One robot's controller; one instance per robot, made by its ControllerInfo::make.
class Controller {
 public:
  virtual ~Controller() = default;
  /// One control step. An exception ends the run with its message.
  virtual Output step(const Input& input) = 0;
  /// Called once when the run ends, after the last step.
  virtual void finish() {}
  /// Whether it has reached its goal (a run with `--stop-when-done` ends once all are).
  virtual bool done() const { return false; }
};

/// One number a controller takes from `params`.
struct Param {
  std::string name;                                       ///< the key, with its unit in it: "speed_mps"
  std::string unit;                                       ///< "m/s", "m", "deg", ...; "" for counts, IDs, levels
  std::optional<double> default_value;                    ///< nullopt: required, or the controller decides
  bool required = false;                                  ///< the scenario must give it
  double min = -std::numeric_limits<double>::infinity();  ///< inclusive
  double max = std::numeric_limits<double>::infinity();   ///< inclusive
  bool integer = false;                                   ///< whole numbers only
  std::string summary;                                    ///< one line of what it means

  /// A number with a default and a range.
  static Param number(std::string name, std::string unit, double default_value, double min, double max,
                      std::string summary) {
    return {std::move(name), std::move(unit), default_value, false, min, max, false, std::move(summary)};
  }
  /// A number the scenario must give.
  static Param required_number(std::string name, std::string unit, double min, double max, std::string summary) {
    return {std::move(name), std::move(unit), std::nullopt, true, min, max, false, std::move(summary)};
  }
};

/// The parameters one robot's controller was given, with the defaults behind them.
class Params {
 public:
  explicit Params(const rilbed_controller_args& args) : args_(&args) {}
  /// Whether `name` has a value (given, or a default).
  bool has(std::string_view name) const { return find(name) >= 0; }
  /// Whether the scenario gave `name` (not a default).
  bool given(std::string_view name) const {
    const int i = find(name);
    return i >= 0 && args_->param_given[i] != 0;
  }
  /// The value of `name`, given or default; `fallback` when it has none.
  double get(std::string_view name, double fallback = 0.0) const {
    const int i = find(name);
    return i >= 0 ? args_->param_values[i] : fallback;
  }

 private:
  int find(std::string_view name) const {
    for (std::uint32_t i = 0; i < args_->param_count; ++i) {
      if (name == args_->param_names[i]) return static_cast<int>(i);
    }
    return -1;
  }
  const rilbed_controller_args* args_;
};

/// What ControllerInfo::make gets for one robot. Valid during the call only.
struct Context {
  int robot_id = 0;
  const Params& params;
};

/// A kind of controller: what the registry shows, and how to make one.
struct ControllerInfo {
  ControllerInfo() = default;
  /// A controller called `name` that does what `summary` says; fill in the rest.
  ControllerInfo(std::string name, std::string summary) : name(std::move(name)), summary(std::move(summary)) {}

  std::string name;                           ///< the name a scenario gives
  std::string summary;                        ///< one line of what it does
  std::vector<Param> params;                  ///< what it takes from `params`
  std::vector<std::string> sensors;           ///< what it reads: proximity, range_finders, beacon_finder,
                                              ///< track, odometer, pose
  std::vector<std::string> required_sensors;  ///< of those, what a robot must carry
  bool wants_team = false;                    ///< it reads the team broadcast
  bool concurrent = true;  ///< its robots may step at once on `--threads N`; false if they share mutable state
  /// Makes one robot's controller; may throw (the message is reported).
  std::function<std::unique_ptr<Controller>(const Context&)> make;
};

namespace detail {

inline void write_error(char* error, std::uint32_t size, const char* text) {
  if (!error || size == 0) return;
  std::strncpy(error, text, size - 1);
  error[size - 1] = '\0';
}

inline void write_current_error(char* error, std::uint32_t size) {
  try {
    throw;
  } catch (const std::exception& e) {
    write_error(error, size, e.what());
  } catch (...) {
    write_error(error, size, "an exception that is not a std::exception");
  }
}

// One ControllerInfo as a rilbed_controller_class, with the C strings and arrays it
// points to kept alive beside it.
class ExportedClass {
 public:
  explicit ExportedClass(ControllerInfo info) : info_(std::move(info)) {
    for (const Param& p : info_.params) {
      params_.push_back({p.name.c_str(), p.unit.c_str(), p.summary.c_str(), p.default_value.value_or(0.0),
                         p.default_value ? 1 : 0, p.required ? 1 : 0, p.integer ? 1 : 0, p.min, p.max});
    }
    for (const std::string& s : info_.sensors) sensors_.push_back(s.c_str());
    sensors_.push_back(nullptr);
    for (const std::string& s : info_.required_sensors) required_.push_back(s.c_str());
    required_.push_back(nullptr);
    raw_ = {RILBED_ABI_VERSION,
            info_.name.c_str(),
            info_.summary.c_str(),
            params_.data(),
            static_cast<std::uint32_t>(params_.size()),
            sensors_.data(),
            required_.data(),
            info_.wants_team ? 1 : 0,
            info_.concurrent ? 1 : 0,
            this,
            &create,
            &step,
            &finish,
            &done,
            &destroy};
  }
  ExportedClass(const ExportedClass&) = delete;
  ExportedClass& operator=(const ExportedClass&) = delete;
  const rilbed_controller_class* raw() const { return &raw_; }

 private:
  struct Instance {
    std::unique_ptr<Controller> controller;
    std::string behaviour;  // what output.behaviour points into until the next step
  };

  static void* create(const void* context, const rilbed_controller_args* args, char* error, std::uint32_t size) {
    try {
      const auto* self = static_cast<const ExportedClass*>(context);
      if (!self->info_.make) throw std::logic_error("ControllerInfo '" + self->info_.name + "' has no make function");
      const Params params(*args);
      auto instance = std::make_unique<Instance>();
      instance->controller = self->info_.make(Context{args->robot_id, params});
      if (!instance->controller) throw std::logic_error("make returned no controller");
      return instance.release();
    } catch (...) {
      write_current_error(error, size);
      return nullptr;
    }
  }
  static std::int32_t step(void* raw, const rilbed_control_input* input, rilbed_control_output* output, char* error,
                           std::uint32_t size) {
    try {
      auto* instance = static_cast<Instance*>(raw);
      Output out = instance->controller->step(Input(*input));
      instance->behaviour = std::move(out.behaviour);
      output->left = out.left;
      output->right = out.right;
      output->behaviour = instance->behaviour.c_str();
      return 0;
    } catch (...) {
      write_current_error(error, size);
      return 1;
    }
  }
  static void finish(void* raw) {
    try {
      static_cast<Instance*>(raw)->controller->finish();
    } catch (...) {
      // Nothing to report to at the end of a run; the robot is being stopped anyway.
    }
  }
  static std::int32_t done(const void* raw) {
    try {
      return static_cast<const Instance*>(raw)->controller->done() ? 1 : 0;
    } catch (...) {
      return 0;
    }
  }
  static void destroy(void* raw) { delete static_cast<Instance*>(raw); }

  ControllerInfo info_;
  std::vector<rilbed_param> params_;
  std::vector<const char*> sensors_;
  std::vector<const char*> required_;
  rilbed_controller_class raw_{};
};

// The library's classes, made once (on the first call) and kept until it is unloaded.
class ExportedClasses {
 public:
  explicit ExportedClasses(std::vector<ControllerInfo> infos) {
    for (ControllerInfo& info : infos) classes_.push_back(std::make_unique<ExportedClass>(std::move(info)));
    for (const auto& c : classes_) list_.push_back(c->raw());
    list_.push_back(nullptr);
  }
  const rilbed_controller_class* const* list() const { return list_.data(); }

 private:
  std::vector<std::unique_ptr<ExportedClass>> classes_;
  std::vector<const rilbed_controller_class*> list_;
};

}  // namespace detail

}  // namespace rilbed::sdk

/// Exports the library's controller classes: RILBED_CONTROLLERS(first_info(), second_info());
/// each argument a ControllerInfo. Write it once per library, at file scope, beside
/// RILBED_DEFINE_PLUGIN(). An exception while making the list makes rilbed report that the
/// library gave no list.
#define RILBED_CONTROLLERS(...)                                                                    \
  extern "C" RILBED_EXPORT const rilbed_controller_class* const* rilbed_controller_classes(void) { \
    try {                                                                                          \
      static const ::rilbed::sdk::detail::ExportedClasses classes(                                 \
          std::vector<::rilbed::sdk::ControllerInfo>{__VA_ARGS__});                                \
      return classes.list();                                                                       \
    } catch (...) {                                                                                \
      return nullptr;                                                                              \
    }                                                                                              \
  }                                                                                                \
  static_assert(true, "RILBED_CONTROLLERS is used as a statement")
