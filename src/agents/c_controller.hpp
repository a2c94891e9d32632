// Runs a C controller written against rilbed/rilbed_controller.h (peek/poke on a register
// map) as a rilbed Controller: fills the robot's registers from its ControlInput before
// each call and reads the motor registers back after. The controllers come from plug-in
// libraries (library_controllers.hpp); rilbed lends each library the peek and poke of
// plugin_host().
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "agents/controller.hpp"
#include "agents/track_features.hpp"
#include "rilbed/rilbed_controller.h"

namespace rilbed::agents {

/// One robot's register map (RILBED_REG_COUNT 32-bit words).
class RegisterMap {
 public:
  RegisterMap();
  /// The value at `address`, 0 outside the map.
  std::int32_t peek(std::uint32_t address) const;
  /// Controller write: ignored (and counted) for read-only or unknown addresses.
  void poke(std::uint32_t address, std::int32_t value);
  /// rilbed's own write of a sensor register (any address inside the map).
  void set(std::uint32_t address, std::int32_t value);
  /// Writes the controller attempted where it may not write.
  int rejected_writes() const { return rejected_writes_; }

 private:
  std::vector<std::int32_t> words_;
  int rejected_writes_ = 0;
};

/// What rilbed lends every plug-in library (rilbed/plugin.h): peek and poke on the
/// register map of the robot whose C controller is being called on this thread (0 and
/// nothing outside such a call). Lives as long as the program.
const rilbed_host& plugin_host();

/// Adapter from a C controller to the Controller interface; one per robot. The C
/// controller's functions are called with this robot's register map current (per
/// thread), so several robots may share one C controller.
class CControllerAdapter final : public Controller {
 public:
  /// `controller` must stay valid while `library` lives (what keeps the library it comes
  /// from loaded; null for one that lives as long as the program). `track_sensors`: the
  /// robot's track sensors, for the track reading's registers (RILBED_REG_TRACK_ON, ...).
  /// Throws std::invalid_argument if it has no step function.
  explicit CControllerAdapter(const rilbed_c_controller& controller, std::shared_ptr<const void> library = {},
                              std::span<const environment::TrackSensorConfig> track_sensors = {});
  ~CControllerAdapter() override;
  ControlOutput step(const ControlInput& input) override;
  /// Calls cleanup once (also done by the destructor if the run did not).
  void finish() override;
  /// False: C static variables are shared by every robot running the same controller, so
  /// C controllers step one at a time on the run's thread, whatever `--threads` says.
  bool concurrent() const override { return false; }
  const RegisterMap& registers() const { return registers_; }

 private:
  void load_inputs(const ControlInput& input);
  std::shared_ptr<const void> library_;
  const rilbed_c_controller& controller_;
  RegisterMap registers_;
  TrackArray track_array_;
  TrackReadingConfig track_reading_;
  std::vector<int> arm_sides_;
  bool initialised_ = false;
  bool finished_ = false;
  std::optional<TimeUs> last_t_us_;
};

}  // namespace rilbed::agents
