// RealBody against a real World and an in-process emulated Khepera on a pty: commands
// reach the robot while the camera sees it, a robot the camera lost or one leaving
// through the geofence is stopped, the robot's own proximity readings combine with the
// world's virtual ones, destroying the body stops the robot, and the link's health shows.
// Waits are "until true, or fail after a bounded deadline", never timed assertions.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "environment/world.hpp"
#include "run/real_body.hpp"
#include "serial/khepera_emulator.hpp"
#include "serial/khepera_link.hpp"
#include "support/link_test_support.hpp"

using namespace rilbed;
using namespace rilbed::serial;
using namespace rilbed::run;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

using rilbed::testing::eventually;
using rilbed::testing::LogSink;

constexpr int kRealId = 7;
constexpr int kLostTimeoutMs = 500;
constexpr double kMargin_m = 0.05;

environment::World make_world() {
  environment::StaticMapConfig map;
  map.field.width_m = 1.5;
  map.field.height_m = 1.2;
  map.field.boundary_walls = true;
  return environment::World(map);
}

// A world with one real robot, its emulated Khepera, a started link on the emulator's
// device, and (once make_body() is called) the RealBody over it.
class RealBodyTest : public ::testing::Test {
 protected:
  explicit RealBodyTest(serial::EmulatorConfig emulated = {}) : emulated_(std::move(emulated)) {}

  void SetUp() override {
    environment::RobotConfig rc;
    rc.id = kRealId;
    rc.kind = environment::RobotKind::kReal;
    rc.pose = {{0.75, 0.6}, 0.0};
    world_.add_robot(rc);
    // Observations are made at the world's current time; start it off zero so that a
    // sighting is not mistaken for "never seen" (RealBody treats pose_t_us == 0 so).
    world_.step(10'000);
    emulator_ = std::make_unique<serial::KheperaEmulator>(emulated_);
  }

  serial::LinkConfig link_config() {
    serial::LinkConfig config;
    config.port = emulator_->device_path();
    config.reply_timeout_ms = 150;
    config.retries = 3;
    config.reopen_interval_ms = 50;
    config.log = log_.callback();
    return config;
  }

  void make_body(std::optional<serial::LinkConfig> config = std::nullopt) {
    auto link = std::make_unique<serial::KheperaLink>(config ? *config : link_config());
    ASSERT_EQ(link->start(), std::nullopt);
    ASSERT_TRUE(eventually([&] { return link->state() == serial::LinkState::kOk; })) << log_.text();
    RealBodyConfig body;
    body.lost_timeout_ms = kLostTimeoutMs;
    body.geofence_margin_m = kMargin_m;
    body_ = std::make_unique<RealBody>(kRealId, world_, std::move(link), body);
  }

  // The camera sees the robot now.
  void observe(double x, double y, double heading_rad) {
    world_.set_observed_pose(kRealId, {{x, y}, heading_rad}, world_.time_us());
  }

  // Drives and waits until the emulated robot has the expected speeds.
  ::testing::AssertionResult drive_expecting(int left, int right, serial::WheelSpeeds expected) {
    body_->drive({left, right});
    if (eventually([&] { return emulator_->last_speeds() == expected; })) return ::testing::AssertionSuccess();
    const serial::WheelSpeeds got = emulator_->last_speeds();
    return ::testing::AssertionFailure() << "drive(" << left << "," << right << "): the robot has " << got.left_units
                                         << "," << got.right_units << ", expected " << expected.left_units << ","
                                         << expected.right_units << "; held_by='" << body_->held_by() << "'\n"
                                         << log_.text();
  }
  ::testing::AssertionResult drive_obeyed(int left, int right) { return drive_expecting(left, right, {left, right}); }
  ::testing::AssertionResult drive_stopped(int left, int right) { return drive_expecting(left, right, {0, 0}); }

  serial::EmulatorConfig emulated_;
  environment::World world_ = make_world();
  LogSink log_;
  std::unique_ptr<serial::KheperaEmulator> emulator_;
  std::unique_ptr<RealBody> body_;
};

}  // namespace

TEST_F(RealBodyTest, DrivesTheRobotWhileSeenAndReportsTheCamerasPose) {
  make_body();
  EXPECT_EQ(body_->id(), kRealId);
  observe(0.4, 0.3, 1.0);
  const std::optional<Pose2> pose = body_->pose();
  ASSERT_TRUE(pose.has_value());
  EXPECT_DOUBLE_EQ(pose->position_m.x, 0.4);
  EXPECT_DOUBLE_EQ(pose->position_m.y, 0.3);
  EXPECT_DOUBLE_EQ(pose->heading_rad, 1.0);

  ASSERT_TRUE(drive_obeyed(25, -12));
  EXPECT_EQ(body_->health(), "ok");
  EXPECT_EQ(body_->held_by(), "");
  ASSERT_TRUE(drive_obeyed(40, 40));
  // The body's stop() stops the robot.
  body_->stop();
  EXPECT_TRUE(eventually([&] { return emulator_->last_speeds() == serial::WheelSpeeds{0, 0}; })) << log_.text();

  // A new sighting moves the pose.
  observe(1.1, 0.9, -2.0);
  ASSERT_TRUE(body_->pose().has_value());
  EXPECT_DOUBLE_EQ(body_->pose()->position_m.x, 1.1);
  EXPECT_DOUBLE_EQ(body_->pose()->heading_rad, -2.0);
}

TEST_F(RealBodyTest, ARobotTheCameraNeverSawIsNotDriven) {
  make_body();
  EXPECT_FALSE(body_->pose().has_value());
  body_->drive({30, 30});
  EXPECT_EQ(body_->held_by(), "lost");
  EXPECT_EQ(body_->health(), "unseen");
  // The link is told to stop rather than to drive.
  ASSERT_TRUE(eventually([&] {
    return body_->link().acknowledged_speeds() == serial::WheelSpeeds{0, 0};
  })) << log_.text();
  EXPECT_EQ(emulator_->last_speeds(), (serial::WheelSpeeds{0, 0}));
}

TEST_F(RealBodyTest, ARobotLostByTheCameraIsStoppedAndResumesWhenSeenAgain) {
  make_body();
  observe(0.75, 0.6, 0.0);
  ASSERT_TRUE(drive_obeyed(30, 30));

  // Exactly the timeout since the sighting: still seen.
  world_.step(static_cast<TimeUs>(kLostTimeoutMs) * 1000);
  ASSERT_TRUE(body_->pose().has_value());
  ASSERT_TRUE(drive_obeyed(35, 35));
  EXPECT_EQ(body_->health(), "ok");

  // Beyond it: lost.
  world_.step(1'000);
  EXPECT_FALSE(body_->pose().has_value());
  ASSERT_TRUE(drive_stopped(20, 20));
  EXPECT_EQ(body_->held_by(), "lost");
  EXPECT_EQ(body_->health(), "unseen");
  // Still lost after more time: every drive is a stop.
  world_.step(200'000);
  body_->drive({-20, 20});
  EXPECT_EQ(body_->health(), "unseen");
  // The drive became a stop at once: that is what the link was asked to send.
  EXPECT_EQ(body_->link().wished_speeds(), (serial::WheelSpeeds{0, 0}));
  ASSERT_TRUE(eventually([&] { return body_->link().acknowledged_speeds() == serial::WheelSpeeds{0, 0}; }));
  EXPECT_EQ(emulator_->last_speeds(), (serial::WheelSpeeds{0, 0}));

  // Seen again: driving resumes.
  observe(0.8, 0.6, 0.0);
  ASSERT_TRUE(body_->pose().has_value());
  EXPECT_DOUBLE_EQ(body_->pose()->position_m.x, 0.8);
  ASSERT_TRUE(drive_obeyed(20, 20));
  EXPECT_EQ(body_->health(), "ok");
  EXPECT_EQ(body_->held_by(), "");
}

TEST_F(RealBodyTest, TheGeofenceStopsOnlyMovesOutward) {
  make_body();
  // 2 cm from the left edge (inside the 5 cm margin), facing out (-x).
  observe(0.02, 0.6, kPi);
  ASSERT_TRUE(drive_obeyed(-20, -20));  // backwards = +x, inwards
  EXPECT_EQ(body_->health(), "ok");
  ASSERT_TRUE(drive_stopped(20, 20));  // forwards = -x, outwards
  EXPECT_EQ(body_->held_by(), "geofence");
  EXPECT_EQ(body_->health(), "geofence");
  ASSERT_TRUE(drive_obeyed(-15, 15));  // turning on the spot
  EXPECT_EQ(body_->health(), "ok");
  ASSERT_TRUE(drive_stopped(10, 30));  // an arc that still goes outwards
  EXPECT_EQ(body_->health(), "geofence");

  // Facing in (+x): forwards is allowed.
  observe(0.02, 0.6, 0.0);
  ASSERT_TRUE(drive_obeyed(20, 20));
  EXPECT_EQ(body_->health(), "ok");
  ASSERT_TRUE(drive_stopped(-20, -20));  // backwards would go out
  EXPECT_EQ(body_->health(), "geofence");

  // The margin counts, not only the field's edge: 4 cm in is still inside it, 6 cm is not.
  observe(0.04, 0.6, kPi);
  ASSERT_TRUE(drive_obeyed(-25, -25));
  ASSERT_TRUE(drive_stopped(25, 25));
  observe(0.06, 0.6, kPi);
  ASSERT_TRUE(drive_obeyed(25, 25));

  // The other edges: near the top facing up, near the right facing right.
  observe(0.75, 1.18, kPi / 2);
  ASSERT_TRUE(drive_obeyed(-30, -30));
  ASSERT_TRUE(drive_stopped(30, 30));
  observe(1.47, 0.6, 0.0);
  ASSERT_TRUE(drive_obeyed(-22, -22));
  ASSERT_TRUE(drive_stopped(22, 22));
  // Nearly along the edge: a little inwards is allowed, a little outwards is not.
  observe(1.47, 0.6, kPi / 2 + 0.1);
  ASSERT_TRUE(drive_obeyed(22, 22));
  observe(1.47, 0.6, kPi / 2 - 0.1);
  ASSERT_TRUE(drive_stopped(22, 22));
  // In a corner both edges count: facing out of either is refused, into both is allowed.
  observe(0.02, 0.02, -kPi / 2);
  ASSERT_TRUE(drive_obeyed(-24, -24));  // backwards: up, inwards
  ASSERT_TRUE(drive_stopped(24, 24));   // forwards: down, out
  observe(0.02, 0.02, kPi / 4);
  ASSERT_TRUE(drive_obeyed(26, 26));  // into the field
  observe(0.02, 0.02, kPi);
  ASSERT_TRUE(drive_stopped(26, 26));  // out through the left edge, along the bottom
  // Well inside the field: anything goes.
  observe(0.75, 0.6, kPi);
  ASSERT_TRUE(drive_obeyed(50, 50));
  EXPECT_EQ(body_->health(), "ok");
}

class RealBodySenseTest : public RealBodyTest {};

TEST_F(RealBodySenseTest, CombinesTheRobotsOwnProximityWithVirtualWallsPerSensor) {
  serial::LinkConfig config = link_config();
  config.counters_period_ms = 20;  // so that sense() also reports the robot's counters
  make_body(config);
  // The robot's own readings: very near something on its left (sensor 0), a little on
  // the front-right (sensor 3), nothing elsewhere.
  const environment::ProximityValues own = {1000, 3, 4, 100, 5, 6, 7, 8};
  emulator_->set_proximity(own);
  // 1 cm from the right wall, facing it.
  const double radius = world_.robot(kRealId).radius_m;
  observe(1.5 - radius - 0.01, 0.6, 0.0);

  // Poll until the robot's reading with the new values has arrived.
  ASSERT_TRUE(eventually([&] {
    body_->sense(world_.time_us());  // asks for a fresh reading too
    const auto p = body_->link().latest_proximity();
    return p && p->value == own;
  })) << log_.text();
  ASSERT_TRUE(eventually([&] { return body_->link().latest_counters().has_value(); })) << log_.text();

  // The virtual readings the body will combine: same world, same random stream.
  const environment::SensorReadings virtual_only = world_.sense(kRealId, world_.time_us());
  ASSERT_TRUE(virtual_only.proximity.has_value());
  const environment::ProximityValues& v = *virtual_only.proximity;
  // The wall is seen by the front sensors only (sanity of the setup).
  EXPECT_GT(v[2], 300);
  EXPECT_GT(v[3], 300);
  EXPECT_LT(v[0], 50);

  const environment::SensorReadings r = body_->sense(world_.time_us());
  ASSERT_TRUE(r.proximity.has_value());
  for (int i = 0; i < environment::kProximityCount; ++i) {
    EXPECT_EQ((*r.proximity)[i], std::max(v[i], own[i])) << "sensor " << i;
  }
  EXPECT_EQ((*r.proximity)[0], 1000);  // the robot's own
  EXPECT_EQ((*r.proximity)[3], v[3]);  // the virtual wall beats the robot's 100
  EXPECT_GT((*r.proximity)[3], own[3]);
  ASSERT_TRUE(r.odometry.has_value());  // the robot's counters (a real robot's are not virtual)
  const auto counters = body_->link().latest_counters();
  ASSERT_TRUE(counters.has_value());
  EXPECT_EQ(r.odometry->left_pulses, counters->value.left_pulses);
  EXPECT_EQ(r.odometry->right_pulses, counters->value.right_pulses);
}

TEST_F(RealBodySenseTest, TheRobotsZerosLeaveTheVirtualReadings) {
  make_body();
  observe(1.5 - world_.robot(kRealId).radius_m - 0.01, 0.6, 0.0);
  ASSERT_TRUE(eventually([&] { return body_->link().latest_proximity().has_value(); })) << log_.text();
  const environment::SensorReadings virtual_only = world_.sense(kRealId, world_.time_us());
  ASSERT_TRUE(virtual_only.proximity.has_value());
  const environment::SensorReadings r = body_->sense(world_.time_us());
  ASSERT_TRUE(r.proximity.has_value());
  // The emulator reports zeros by default: the combination is the virtual readings.
  EXPECT_EQ(*r.proximity, *virtual_only.proximity);
}

TEST_F(RealBodyTest, DestroyingTheBodyStopsTheRobot) {
  make_body();
  observe(0.75, 0.6, 0.0);
  ASSERT_TRUE(drive_obeyed(30, 30));
  body_.reset();
  // The destructor waits for the robot to acknowledge the stop.
  EXPECT_EQ(emulator_->last_speeds(), (serial::WheelSpeeds{0, 0}));
}

TEST_F(RealBodyTest, RejectsARobotThatIsNotARealOneOfTheWorld) {
  environment::RobotConfig rc;
  rc.id = 3;
  rc.kind = environment::RobotKind::kVirtual;
  rc.pose = {{0.3, 0.3}, 0.0};
  world_.add_robot(rc);
  RealBodyConfig body;
  EXPECT_THROW(RealBody(3, world_, std::make_unique<serial::KheperaLink>(link_config()), body), std::invalid_argument);
  EXPECT_THROW(RealBody(99, world_, std::make_unique<serial::KheperaLink>(link_config()), body), std::invalid_argument);
  EXPECT_THROW(RealBody(kRealId, world_, nullptr, body), std::invalid_argument);
}

class RealBodyReplugTest : public RealBodyTest {
 protected:
  static serial::EmulatorConfig with_stable_path() {
    serial::EmulatorConfig emulated;
    emulated.stable_path =
        (fs::temp_directory_path() / ("rilbed_test_real_body_" + std::to_string(::getpid()))).string();
    return emulated;
  }
  RealBodyReplugTest() : RealBodyTest(with_stable_path()) {}
};

TEST_F(RealBodyReplugTest, HealthShowsTheLinkLostAndRecovered) {
  make_body();
  EXPECT_EQ(body_->link().port(), emulated_.stable_path);
  observe(0.75, 0.6, 0.0);
  ASSERT_TRUE(drive_obeyed(20, 20));
  EXPECT_EQ(body_->health(), "ok");

  emulator_->unplug();
  ASSERT_TRUE(eventually([&] { return body_->link().state() == serial::LinkState::kLost; })) << log_.text();
  EXPECT_EQ(body_->health(), "link lost");
  // The link's trouble outranks the camera's: still "link lost" when also unseen.
  world_.step(static_cast<TimeUs>(kLostTimeoutMs + 1) * 1000);
  body_->drive({10, 10});
  EXPECT_EQ(body_->held_by(), "link");
  EXPECT_EQ(body_->health(), "link lost");

  observe(0.75, 0.6, 0.0);
  body_->drive({12, 12});  // refused while unplugged: the wish is a stop
  EXPECT_EQ(body_->held_by(), "link");
  emulator_->replug();
  ASSERT_TRUE(eventually([&] { return body_->link().state() == serial::LinkState::kOk; })) << log_.text();
  EXPECT_EQ(body_->health(), "ok");
  // The first command the robot gets back on the line is a stop, not the old wish.
  EXPECT_TRUE(eventually([&] { return emulator_->last_speeds() == serial::WheelSpeeds{0, 0}; })) << log_.text();
  EXPECT_EQ(emulator_->commands_received(serial::CommandKind::kSetSpeeds) > 0, true);
  // Healthy again: the next control step drives.
  ASSERT_TRUE(drive_obeyed(18, 18));
}

// An e-puck's firmware takes speeds in its own steps per second and reads its sensors on
// 0..4095: a controller's Khepera units and the world's 0..1023 scale are converted.
class EpuckBodyTest : public RealBodyTest {
 protected:
  EpuckBodyTest()
      : RealBodyTest([] {
          serial::EmulatorConfig e;
          e.model = serial::epuck_model();
          e.proximity = {4095, 0, 2048, 0, 0, 0, 0, 0};
          return e;
        }()) {}
};

TEST_F(EpuckBodyTest, ConvertsSpeedsAndProximityToTheModelsUnits) {
  serial::LinkConfig config = link_config();
  config.model = serial::epuck_model();
  config.counters_period_ms = 20;  // so that sense() also reports the robot's counters
  make_body(config);
  observe(0.75, 0.6, 0.0);
  // 10 Khepera units are 80 mm/s: 621 e-puck steps of 0.129 mm per second.
  const double steps = 10 * 0.008 / serial::epuck_model().speed_unit_mps;
  const int expected = static_cast<int>(std::lround(steps));
  ASSERT_GT(expected, 600);
  ASSERT_TRUE(drive_expecting(10, -10, {expected, -expected}));
  ASSERT_TRUE(eventually([&] {
    const auto r = body_->sense(world_.time_us());
    return r.proximity && (*r.proximity)[0] == 1023;
  })) << log_.text();
  const auto r = body_->sense(world_.time_us());
  EXPECT_EQ((*r.proximity)[2], 512);  // 2048 of 4095, on the 0..1023 scale
  // Its wheel counters, in motor steps of 0.129 mm, reach the controller in pulses of 0.08 mm.
  ASSERT_TRUE(eventually([&] {
    const auto c = body_->link().latest_counters();
    return c && c->value.left_pulses > 20;
  })) << log_.text();
  // The left wheel goes forward: its count between the reads before and after the body's.
  const auto before = body_->link().latest_counters();
  const auto odometry = body_->sense(world_.time_us()).odometry;
  const auto after = body_->link().latest_counters();
  ASSERT_TRUE(odometry.has_value());
  const double per_step = serial::epuck_model().counter_pulse_m / environment::kKheperaPulse_m;
  EXPECT_GE(static_cast<double>(odometry->left_pulses), static_cast<double>(before->value.left_pulses) * per_step - 1);
  EXPECT_LE(static_cast<double>(odometry->left_pulses), static_cast<double>(after->value.left_pulses) * per_step + 1);
}
