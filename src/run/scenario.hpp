// Scenario files (YAML) for `rilbed run`: the field, its walls, obstacles, tracks,
// beacons and moving obstacles, the robots with their poses, sensors and controllers,
// and the convoy's mode. scenarios/README.md documents every key. Parsing is strict:
// an unknown key, a wrong type or a bad value is an error naming the file, line and key.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "agents/controller_registry.hpp"
#include "agents/convoy.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/kinematics.hpp"
#include "environment/moving_obstacle.hpp"
#include "environment/robot_state.hpp"
#include "environment/sensor_suite.hpp"
#include "environment/static_map.hpp"
#include "run/robot_description.hpp"
#include "serial/khepera_emulator.hpp"
#include "vision/vision_settings.hpp"

namespace rilbed::run {

/// A scenario that cannot be used; what() is "FILE:LINE: KEY: problem".
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Who decides for the convoy (paper 001 §5).
enum class ConvoyMode { kDistributed, kCentral };

/// How a real robot gets to a run's start pose (before each run of a batch, and before a
/// single run): a real robot is driven there slowly under the camera; an emulated one is
/// put there, as a hand would, unless it is to try the driving.
enum class Placement { kTeleport, kDrive };

/// How a real robot is reached (used by runs with real robots).
struct LinkSpec {
  std::string port;                         ///< serial device, e.g. /dev/ttyUSB0; empty when emulated
  int baud = 0;                             ///< 0: the model's own (Khepera 38400, e-puck 115200)
  std::string model = "khepera2";           ///< protocol variant: khepera2 | epuck
  bool emulate = false;                     ///< start an emulated Khepera on a pseudo-terminal instead
  Placement placement = Placement::kDrive;  ///< `placement:` (emulated robots: teleport by default)
  int reply_timeout_ms = 250;               ///< how long one command waits for its reply
  int retries = 3;                          ///< further attempts before a command fails
  int counters_period_ms = 200;             ///< read the wheel counters (`H`) this often (0: never)
  /// Faults the emulated robot injects (emulate only: `faults:`): reply delay, dropped,
  /// garbled and corrupted replies, an unplug and a replug.
  serial::EmulatorFaults faults;
  /// The firmware's speed units where the robot's model file gives them (other gearing or
  /// wheels than the protocol's robot); none: the protocol's own.
  std::optional<double> speed_unit_mps;
  std::optional<double> counter_pulse_m;
};

/// The overhead camera of a run with real robots.
struct CameraSpec {
  bool emulate = false;             ///< render the emulated real robots (their true poses) instead of a real camera
  std::optional<int> device;        ///< a live camera's index
  std::string file;                 ///< recorded footage (a video, an image directory or sequence)
  std::string calibration;          ///< field calibration file (OpenCV YAML); not used when emulated
  double fps = 30.0;                ///< frames per second (emulated, or the rate a file is replayed at)
  double marker_diameter_m = 0.05;  ///< outer diameter of the printed markers
  std::string family = "6ucp";      ///< marker family
  /// The vision settings the run starts with (`vision: {brightness: 0, contrast: 1, ...}`,
  /// what the web panel shows for the settings a person tuned).
  vision::VisionSettings vision;
  int line = 0;
};

/// A robot's controller and its knobs.
struct ControllerSpec {
  /// An entry of the scenario's controller registry (`rilbed controllers` lists them):
  /// "convoy", "wander", ..., "none" (stands still).
  std::string name = "convoy";
  /// The plug-in library it comes from, an absolute path (`controller: {library: PATH,
  /// name: NAME}`, PATH relative to the scenario file), or the Python file of a Python class
  /// (`controller: {python: FILE, class: NAME}`; `name` is then `<file's stem>.<class>`);
  /// empty for a name of the registry.
  std::string library;
  std::map<std::string, double> params;  ///< the entry's parameters, checked against it
};

/// One robot of a scenario.
struct RobotSpec {
  int id = 0;
  environment::RobotKind kind = environment::RobotKind::kVirtual;
  std::optional<Pose2> pose;  ///< nullopt: a random free pose drawn from the run's seed
  ControllerSpec controller;
  environment::WheelNoiseConfig noise;
  /// Virtual robots: its wheels' model from a plug-in library (`actuator:`); null: the
  /// built-in differential drive with `noise`.
  std::shared_ptr<const environment::DriveModelFactory> drive;
  environment::SensorSuiteConfig sensors;
  /// Its body and wheels: a robot model file's (`model:`) with the entry's `body:` and
  /// `wheels:` over it; by default a Khepera II.
  RobotBody body;
  std::optional<LinkSpec> link;  ///< real robots only
  int line = 0;                  ///< where it was defined, for messages
};

/// A whole scenario.
/// Where the robots' controllers run (the `agents:` block). Without it, every
/// controller runs in the run's own process.
struct AgentsSpec {
  /// `rilbed agent` processes that `rilbed run` starts on this machine, the remote robots
  /// split among them in ID order. 0: they are started by hand (`rilbed agent --ids ...`,
  /// on any machine of the LAN), and the run waits for them.
  int processes = 0;
  /// The robots whose controllers run elsewhere; empty: every robot with a controller.
  std::vector<int> ids;
  /// How long the run waits for every remote robot's process to announce itself.
  double announce_timeout_s = 10.0;
  /// A quantum not answered within this is sent again (milliseconds).
  int resend_ms = 20;
  /// A process that answers nothing for this long is lost: its robots stop (milliseconds).
  int dead_after_ms = 750;
  /// Real-time runs: how long a control step waits for its answers (milliseconds).
  int deadline_ms = 20;
  /// Machines to start the `processes` on, in turn (process i on hosts[i % size]), each with
  /// `launch`; empty: on this machine. Each entry is what `launch` puts for `{host}`
  /// (for ssh: `host`, `user@host`).
  std::vector<std::string> hosts;
  /// The command that starts one agent process on a host, one list item per argument:
  /// `{host}` in an item becomes the host, `{command}` the agent's command line as one
  /// shell-quoted text (what ssh hands to the remote shell). The scenario itself goes to
  /// the command's standard input, which the agent keeps open as its lifeline: when the run
  /// goes, the connection closes and the remote agent ends.
  std::vector<std::string> launch = {"ssh",    "-T",       "-o", "BatchMode=yes", "-o", "ConnectTimeout=10",
                                     "{host}", "{command}"};
  /// The rilbed binary on the hosts; empty: this binary's own absolute path (machines set
  /// up alike, or a shared file system).
  std::string remote_rilbed;
};

struct Scenario {
  std::string name;              ///< the file's `name`, else its stem
  std::filesystem::path source;  ///< the file it came from
  ConvoyMode mode = ConvoyMode::kDistributed;
  environment::StaticMapConfig map;
  std::vector<environment::MovingObstacleConfig> moving_obstacles;
  TimeUs physics_step_us = 20'000;       ///< world integration step
  TimeUs control_period_us = 100'000;    ///< controllers run this often
  TimeUs broadcast_period_us = 100'000;  ///< team broadcast (distributed mode)
  double duration_s = 120.0;             ///< default run length
  agents::ConvoyConfig convoy;           ///< the convoy's knobs (the `convoy:` block)
  std::optional<CameraSpec> camera;      ///< how real robots are seen (required when there are real robots)
  /// Safety for real robots: stop one the camera has not seen for this long, milliseconds.
  int lost_timeout_ms = 500;
  /// Safety: stop a real robot whose centre comes nearer than this to the field's edge, metres.
  double geofence_margin_m = 0.0;
  std::vector<RobotSpec> robots;     ///< sorted by ID
  std::optional<AgentsSpec> agents;  ///< controllers in other processes (the `agents:` block)
  /// The controllers its robots were checked against when it was read; the run makes
  /// them from it. Never null for a scenario read by load_scenario() or parse_scenario().
  std::shared_ptr<const agents::ControllerRegistry> controllers;
};

/// The IDs of the scenario's real robots, in ID order.
std::vector<int> real_robot_ids(const Scenario& scenario);

/// Reads and checks a scenario file, its robots' controllers and their `params` against
/// `controllers` (null: rilbed's own, default_controllers()). Throws ScenarioError.
Scenario load_scenario(const std::filesystem::path& path,
                       std::shared_ptr<const agents::ControllerRegistry> controllers = {});
/// Parses scenario text (`source_name` is used in messages), as load_scenario() does.
/// Throws ScenarioError.
Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name,
                        std::shared_ptr<const agents::ControllerRegistry> controllers = {});

/// The benchmarks' scenario (sim-bench, bench_gui): `robots` wandering Kheperas with their
/// eight IR sensors and 2 % wheel slip in a field of `density_per_m2` (the lab's convoy is 8
/// robots on 1.5 x 1.2 m), 5:4, control period 100 ms, random starts.
Scenario wandering_scenario(int robots, double seconds, double physics_step_ms = 100.0,
                            double density_per_m2 = 8.0 / (1.5 * 1.2));

/// Poses for the robots without one: uniformly random in the field, at least
/// `clearance_m` from walls, obstacles and every other robot, random heading; fixed poses
/// are kept. Deterministic for a given seed. Throws ScenarioError if the field is too
/// crowded to place them.
std::vector<Pose2> draw_initial_poses(const Scenario& scenario, std::mt19937_64& rng, double clearance_m = 0.02);

}  // namespace rilbed::run
