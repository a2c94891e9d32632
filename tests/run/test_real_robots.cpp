// The scenario's real robots: an emulated robot is reached through a path that follows it
// across an unplug, even when its old /dev/pts/N has meanwhile gone to another program
// (as /dev/ttyUSB0 can after a real replug), and that path goes with the robots.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "run/real_robots.hpp"
#include "run/scenario.hpp"
#include "support/eventually.hpp"

namespace rilbed::run {
namespace {

using rilbed::testing::eventually;

using namespace std::chrono_literals;
namespace fs = std::filesystem;

run::Scenario one_real_robot() {
  return run::parse_scenario(
      "name: replugging\n"
      "field: {width_m: 1.5, height_m: 1.2, walls: true}\n"
      "camera: {emulate: true, fps: 30}\n"
      "robots:\n"
      "  - id: 7\n"
      "    kind: real\n"
      "    link: {emulate: true}\n"
      "    pose: [0.5, 0.5, 0]\n"
      "    controller: none\n",
      "replugging.yaml");
}

// A pty master held by "another program", with its slave's path.
struct StrangerPty {
  int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  std::string slave_path;
  StrangerPty() {
    if (master >= 0 && ::grantpt(master) == 0 && ::unlockpt(master) == 0) slave_path = ::ptsname(master);
  }
  ~StrangerPty() {
    if (master >= 0) ::close(master);
  }
};

TEST(RealRobots, AnEmulatedRobotIsFoundAgainWhenItsReplugGetsAnotherPty) {
  const run::Scenario scenario = one_real_robot();
  fs::path port;
  {
    RealRobots robots(scenario, {});
    const auto link = robots.connect(scenario.robots.front(), Pose2{{0.5, 0.5}, 0.0});
    ASSERT_EQ(link->state(), serial::LinkState::kOk);
    port = link->config().port;
    serial::KheperaEmulator& emulator = *robots.emulator(7);
    const std::string first_pty = emulator.slave_path();
    EXPECT_EQ(fs::read_symlink(port), first_pty);

    emulator.unplug();
    ASSERT_TRUE(eventually([&] { return link->state() == serial::LinkState::kLost; }));
    // While it is unplugged, another program takes the lowest free pty: the robot's old one
    // once the link has let go of it.
    StrangerPty stranger;
    ASSERT_FALSE(stranger.slave_path.empty());
    emulator.replug();
    ASSERT_TRUE(eventually([&] { return link->state() == serial::LinkState::kOk; })) << link->status().last_error;
    link->set_speeds(25, -25);
    EXPECT_TRUE(eventually([&] { return emulator.last_speeds() == serial::WheelSpeeds{25, -25}; }));
    // Nothing of it went to the stranger.
    char byte = 0;
    ::fcntl(stranger.master, F_SETFL, O_NONBLOCK);
    EXPECT_LT(::read(stranger.master, &byte, 1), 1);
  }
  // The robots' folder went with them.
  EXPECT_FALSE(fs::exists(port.parent_path()));
}

}  // namespace
}  // namespace rilbed::run
