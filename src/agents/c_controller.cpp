#include "agents/c_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rilbed::agents {

namespace {

// The register map of the robot whose C controller is running on this thread. Set only
// for the duration of one init/step/cleanup call.
thread_local RegisterMap* current_registers = nullptr;

class CurrentRegisters {
 public:
  explicit CurrentRegisters(RegisterMap& map) : previous_(current_registers) { current_registers = &map; }
  ~CurrentRegisters() { current_registers = previous_; }
  CurrentRegisters(const CurrentRegisters&) = delete;
  CurrentRegisters& operator=(const CurrentRegisters&) = delete;

 private:
  RegisterMap* previous_;
};

bool controller_writable(std::uint32_t address) {
  return address == RILBED_REG_MOTOR_LEFT || address == RILBED_REG_MOTOR_RIGHT || address == RILBED_REG_BEHAVIOUR ||
         (address >= RILBED_REG_USER_0 && address < RILBED_REG_USER_0 + 256);
}

constexpr std::string_view kBehaviourNames[] = {"c0", "c1", "c2", "c3", "c4", "c5", "c6", "c7"};

std::int32_t saturate(double v) {
  return static_cast<std::int32_t>(std::clamp(std::lround(v), -2147483647L, 2147483647L));
}

}  // namespace

RegisterMap::RegisterMap() : words_(RILBED_REG_COUNT, 0) {}

std::int32_t RegisterMap::peek(std::uint32_t address) const { return address < words_.size() ? words_[address] : 0; }

void RegisterMap::poke(std::uint32_t address, std::int32_t value) {
  if (address >= words_.size() || !controller_writable(address)) {
    ++rejected_writes_;
    return;
  }
  words_[address] = value;
}

void RegisterMap::set(std::uint32_t address, std::int32_t value) {
  if (address >= words_.size()) throw std::out_of_range("register address outside the map");
  words_[address] = value;
}

const rilbed_host& plugin_host() {
  static const rilbed_host host = {
      RILBED_ABI_VERSION,
      [](std::uint32_t address) { return current_registers ? current_registers->peek(address) : 0; },
      [](std::uint32_t address, std::int32_t value) {
        if (current_registers) current_registers->poke(address, value);
      }};
  return host;
}

CControllerAdapter::CControllerAdapter(const rilbed_c_controller& controller, std::shared_ptr<const void> library,
                                       std::span<const environment::TrackSensorConfig> track_sensors)
    : library_(std::move(library)), controller_(controller), track_array_(TrackArray::of(track_sensors)) {
  if (!controller.step) throw std::invalid_argument("C controller has no step function");
  if (!track_sensors.empty()) track_reading_.max_value = track_sensors.front().max_value;
  arm_sides_ = arm_sides(track_array_, track_reading_);
}

CControllerAdapter::~CControllerAdapter() { finish(); }

void CControllerAdapter::load_inputs(const ControlInput& input) {
  RegisterMap& r = registers_;
  r.set(RILBED_REG_ID, input.robot_id);
  r.set(RILBED_REG_TIME_MS, static_cast<std::int32_t>((input.t_us / 1000) & 0x7FFFFFFF));
  if (last_t_us_) r.set(RILBED_REG_PERIOD_MS, static_cast<std::int32_t>((input.t_us - *last_t_us_) / 1000));
  const auto& s = input.sensors;
  for (int i = 0; i < environment::kProximityCount; ++i) {
    r.set(RILBED_REG_PROX_0 + i, s.proximity ? (*s.proximity)[i] : -1);
  }
  if (s.odometry) {
    r.set(RILBED_REG_ODO_LEFT, static_cast<std::int32_t>(static_cast<std::uint32_t>(s.odometry->left_pulses)));
    r.set(RILBED_REG_ODO_RIGHT, static_cast<std::int32_t>(static_cast<std::uint32_t>(s.odometry->right_pulses)));
  }
  const int ranges = static_cast<int>(std::min<std::size_t>(s.ranges.size(), 8));
  r.set(RILBED_REG_RANGE_COUNT, ranges);
  for (int i = 0; i < ranges; ++i)
    r.set(RILBED_REG_RANGE_0 + i, s.ranges[i].hit ? saturate(s.ranges[i].distance_m * 1000) : -1);
  const int tracks = static_cast<int>(std::min<std::size_t>(s.track.size(), 16));
  r.set(RILBED_REG_TRACK_COUNT, tracks);
  for (int i = 0; i < tracks; ++i) r.set(RILBED_REG_TRACK_0 + i, s.track[i]);
  // The reading track_explore steers by, for controllers in C (track_features.hpp).
  const TrackArrayReading track = read_track_array(track_array_, s.track, track_reading_, arm_sides_);
  r.set(RILBED_REG_TRACK_ON, track.on_track ? 1 : 0);
  r.set(RILBED_REG_TRACK_OFFSET_UM, saturate(track.offset_m * 1e6));
  r.set(RILBED_REG_TRACK_ARMS, (track.arm_left ? 1 : 0) | (track.arm_right ? 2 : 0));
  const int beacons = static_cast<int>(std::min<std::size_t>(s.beacons.size(), 8));
  r.set(RILBED_REG_BEACON_COUNT, beacons);
  for (int i = 0; i < beacons; ++i) {
    r.set(RILBED_REG_BEACON_0 + 2 * i, s.beacons[i].id);
    r.set(RILBED_REG_BEACON_0 + 2 * i + 1, saturate(rad_to_deg(s.beacons[i].bearing_rad) * 1000));
  }
  std::uint32_t values = 0;
  for (const environment::ModelReading& m : s.models) {
    for (const double v : m.values) {
      if (values == 256) break;
      r.set(RILBED_REG_MODEL_0 + values++, saturate(v * 1000));
    }
  }
  r.set(RILBED_REG_MODEL_COUNT, static_cast<std::int32_t>(values));
  r.set(RILBED_REG_POSE_VALID, input.pose ? 1 : 0);
  if (input.pose) {
    r.set(RILBED_REG_POSE_X_MM, saturate(input.pose->position_m.x * 1000));
    r.set(RILBED_REG_POSE_Y_MM, saturate(input.pose->position_m.y * 1000));
    r.set(RILBED_REG_POSE_HEADING_MDEG, saturate(wrap_deg_360(rad_to_deg(input.pose->heading_rad)) * 1000) % 360000);
  }
  last_t_us_ = input.t_us;
}

ControlOutput CControllerAdapter::step(const ControlInput& input) {
  load_inputs(input);
  CurrentRegisters scope(registers_);
  if (!initialised_) {
    initialised_ = true;
    if (controller_.init) controller_.init();
  }
  controller_.step();
  ControlOutput out;
  out.wheels = {std::clamp(registers_.peek(RILBED_REG_MOTOR_LEFT), -kMaxWheelUnits, kMaxWheelUnits),
                std::clamp(registers_.peek(RILBED_REG_MOTOR_RIGHT), -kMaxWheelUnits, kMaxWheelUnits)};
  const std::int32_t code = registers_.peek(RILBED_REG_BEHAVIOUR);
  out.behaviour = code >= 0 && code < 8 ? kBehaviourNames[code] : "c?";
  return out;
}

void CControllerAdapter::finish() {
  if (finished_ || !initialised_) return;
  finished_ = true;
  CurrentRegisters scope(registers_);
  if (controller_.cleanup) controller_.cleanup();
}

}  // namespace rilbed::agents
