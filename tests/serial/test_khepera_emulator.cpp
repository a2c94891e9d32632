// The emulated Khepera, talked to with plain POSIX calls on its pty (no link), so that its
// behaviour is checked independently of the link that the other tests run against it.
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "serial/khepera_emulator.hpp"
#include "support/eventually.hpp"
#include "support/manual_clock.hpp"

using namespace rilbed::serial;
using namespace std::chrono_literals;
using rilbed::Pose2;
namespace fs = std::filesystem;

namespace {

using rilbed::testing::eventually;
using rilbed::testing::ManualClock;

// A client end of the emulator's pty, in raw mode, closed on destruction.
class RawClient {
 public:
  explicit RawClient(const std::string& path) : fd_(::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC)) {
    if (fd_ >= 0) {
      termios tio{};
      ::tcgetattr(fd_, &tio);
      ::cfmakeraw(&tio);
      ::tcsetattr(fd_, TCSANOW, &tio);
    }
  }
  ~RawClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  bool ok() const { return fd_ >= 0; }

  void send(const std::string& bytes) {
    ASSERT_EQ(::write(fd_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

  // Bytes up to and including the next LF, or nullopt if none within `timeout`.
  std::optional<std::string> line(std::chrono::milliseconds timeout = 2000ms) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      const std::size_t lf = pending_.find('\n');
      if (lf != std::string::npos) {
        std::string line = pending_.substr(0, lf + 1);
        pending_.erase(0, lf + 1);
        return line;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char buffer[256];
      const ssize_t n = ::read(fd_, buffer, sizeof buffer);
      if (n <= 0) {
        read_failed_ = true;
        return std::nullopt;
      }
      pending_.append(buffer, static_cast<std::size_t>(n));
    }
  }
  // Sends a command and returns the reply line.
  std::optional<std::string> ask(const std::string& command) {
    send(command);
    return line();
  }
  bool read_failed() const { return read_failed_; }

 private:
  int fd_;
  std::string pending_;
  bool read_failed_ = false;
};

}  // namespace

TEST(KheperaEmulator, AnswersAsTheFirmwareDoes) {
  EmulatorConfig config;
  config.proximity = {1, 2, 3, 4, 5, 6, 7, 1023};
  KheperaEmulator emulator(config);
  ASSERT_TRUE(fs::exists(emulator.device_path())) << emulator.device_path();
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  EXPECT_EQ(robot.ask("B\r"), "b,5,4\r\n");
  EXPECT_EQ(robot.ask("N\r"), "n,1,2,3,4,5,6,7,1023\r\n");
  EXPECT_EQ(robot.ask("O\r"), "o,500,500,500,500,500,500,500,500\r\n");
  EXPECT_EQ(robot.ask("L,1,1\r"), "l\r\n");
  EXPECT_EQ(robot.ask("G,100,-100\r"), "g\r\n");
  EXPECT_EQ(robot.ask("H\n"), "h,100,-100\r\n");  // LF accepted as a line end
  EXPECT_EQ(robot.ask("E\r"), "e,0,0\r\n");
  emulator.set_proximity({0, 0, 0, 0, 0, 0, 0, 9});
  EXPECT_EQ(robot.ask("N\r"), "n,0,0,0,0,0,0,0,9\r\n");
  // What the firmware does not understand.
  EXPECT_EQ(robot.ask("X\r"), "z,Protocol error\r\n");
  EXPECT_EQ(robot.ask("D,500,0\r"), "z,Protocol error\r\n");
  EXPECT_EQ(emulator.bad_commands(), 2u);
  EXPECT_EQ(emulator.commands_received(CommandKind::kReadProximity), 2u);
}

TEST(KheperaEmulator, DrivesExactArcsAndCountsPulses) {
  // On a clock of the test's own: 200 ms of driving is 200 ms, whatever the machine does.
  ManualClock clock;
  EmulatorConfig config;
  config.initial_pose = Pose2{{0.5, 0.25}, 0.0};
  config.clock = clock.function();
  KheperaEmulator emulator(config);
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  EXPECT_EQ(robot.ask("D,20,20\r"), "d\r\n");
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{20, 20}));
  clock.advance(200ms);
  EXPECT_EQ(robot.ask("D,0,0\r"), "d\r\n");
  const Pose2 straight = emulator.true_pose();
  const auto counters = emulator.counters();
  // Straight ahead along +x: 20 units of 8 mm/s for 0.2 s, as far as the counters say
  // (1 pulse = 0.08 mm).
  EXPECT_EQ(counters.left_pulses, counters.right_pulses);
  EXPECT_NEAR(straight.position_m.x - 0.5, 20 * 0.008 * 0.2, 1e-9);
  EXPECT_NEAR(straight.position_m.x - 0.5, counters.left_pulses * 0.08e-3, 0.1e-3);
  EXPECT_NEAR(straight.position_m.y, 0.25, 1e-9);
  EXPECT_NEAR(straight.heading_rad, 0.0, 1e-9);
  // Stopped means stopped.
  clock.advance(50ms);
  EXPECT_NEAR(emulator.true_pose().position_m.x, straight.position_m.x, 1e-12);

  // Spinning in place: the heading turns by (right - left travel) / wheel base; the
  // centre stays put.
  EXPECT_EQ(robot.ask("G,0,0\r"), "g\r\n");
  EXPECT_EQ(robot.ask("D,-10,10\r"), "d\r\n");
  clock.advance(150ms);
  EXPECT_EQ(robot.ask("D,0,0\r"), "d\r\n");
  const Pose2 spun = emulator.true_pose();
  const auto turned = emulator.counters();
  EXPECT_EQ(turned.left_pulses, -turned.right_pulses);
  EXPECT_GT(turned.right_pulses, 0);
  const double expected_turn = (turned.right_pulses - turned.left_pulses) * 0.08e-3 / 0.053;
  EXPECT_NEAR(spun.heading_rad, expected_turn, 2 * 0.08e-3 / 0.053);  // counters are rounded to pulses
  EXPECT_NEAR(spun.heading_rad, 2 * 10 * 0.008 * 0.15 / 0.053, 1e-9);
  EXPECT_NEAR(spun.position_m.x, straight.position_m.x, 1e-9);
  EXPECT_NEAR(spun.position_m.y, straight.position_m.y, 1e-9);
  EXPECT_EQ(robot.ask("E\r"), "e,0,0\r\n");
}

TEST(KheperaEmulator, SpeaksTheEpuckDialect) {
  EmulatorConfig config;
  config.model = epuck_model();
  KheperaEmulator emulator(config);
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  EXPECT_EQ(robot.ask("V\r"), "v,rilbed emulated e-puck\r\n");
  EXPECT_EQ(robot.ask("P,5,6\r"), "p\r\n");
  EXPECT_EQ(robot.ask("Q\r"), "q,5,6\r\n");
  EXPECT_EQ(robot.ask("D,1000,-1000\r"), "d\r\n");
  EXPECT_EQ(robot.ask("B\r"), "z,Protocol error\r\n");
}

TEST(KheperaEmulator, DelaysAndDropsReplies) {
  EmulatorConfig config;
  config.faults.reply_delay_ms = 150;
  KheperaEmulator emulator(config);
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  const auto sent = std::chrono::steady_clock::now();
  EXPECT_EQ(robot.ask("B\r"), "b,5,4\r\n");
  EXPECT_GE(std::chrono::steady_clock::now() - sent, 140ms);

  EmulatorFaults silent;
  silent.drop_probability = 1.0;
  emulator.set_faults(silent);
  robot.send("D,5,5\r");
  EXPECT_EQ(robot.line(300ms), std::nullopt);
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{5, 5}));  // the command took effect all the same
}

TEST(KheperaEmulator, InjectsGarbageAndCorruptsReplies) {
  EmulatorConfig config;
  config.faults.garbage_probability = 1.0;
  config.seed = 7;
  KheperaEmulator emulator(config);
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  robot.send("H\r");
  // Garbage first (perhaps as a line of its own), the reply's bytes at the end.
  std::string received;
  while (received.find("h,0,0\r\n") == std::string::npos) {
    const auto line = robot.line(1000ms);
    ASSERT_TRUE(line.has_value()) << printable(received);
    received += *line;
  }
  EXPECT_GT(received.size(), std::string("h,0,0\r\n").size());

  EmulatorFaults corrupt;
  corrupt.corrupt_probability = 1.0;
  emulator.set_faults(corrupt);
  for (int i = 0; i < 10; ++i) {
    const auto line = robot.ask("N\r");
    ASSERT_TRUE(line.has_value());
    EXPECT_FALSE(decode_reply(khepera2_model(), CommandKind::kReadProximity, *line).ok()) << printable(*line);
  }
}

TEST(KheperaEmulator, UnplugMakesTheDeviceVanishAndReplugKeepsTheStablePath) {
  const fs::path stable = fs::temp_directory_path() / ("rilbed_test_emu_" + std::to_string(::getpid()));
  EmulatorConfig config;
  config.stable_path = stable.string();
  KheperaEmulator emulator(config);
  EXPECT_EQ(emulator.device_path(), stable.string());
  ASSERT_TRUE(fs::is_symlink(stable));
  const std::string first_slave = emulator.slave_path();
  EXPECT_EQ(fs::read_symlink(stable).string(), first_slave);
  {
    RawClient robot(emulator.device_path());
    ASSERT_TRUE(robot.ok());
    EXPECT_EQ(robot.ask("B\r"), "b,5,4\r\n");
    emulator.unplug();
    EXPECT_FALSE(emulator.plugged());
    EXPECT_EQ(emulator.slave_path(), "");
    EXPECT_FALSE(fs::exists(fs::symlink_status(stable)));
    // The client sees the port go: its read fails (EIO or end of file).
    EXPECT_EQ(robot.line(1000ms), std::nullopt);
    EXPECT_TRUE(robot.read_failed());
  }
  emulator.replug();
  EXPECT_TRUE(emulator.plugged());
  ASSERT_TRUE(fs::is_symlink(stable));
  EXPECT_EQ(fs::read_symlink(stable).string(), emulator.slave_path());
  RawClient again(stable.string());
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again.ask("B\r"), "b,5,4\r\n");
}

TEST(KheperaEmulator, DisconnectsAndReplugsOnATimer) {
  EmulatorConfig config;
  config.faults.disconnect_after_s = 0.2;
  config.faults.replug_after_s = 0.3;
  KheperaEmulator emulator(config);
  EXPECT_TRUE(emulator.plugged());
  EXPECT_TRUE(eventually([&] { return !emulator.plugged(); }));
  EXPECT_TRUE(eventually([&] { return emulator.plugged(); }));
  RawClient robot(emulator.device_path());
  ASSERT_TRUE(robot.ok());
  EXPECT_EQ(robot.ask("B\r"), "b,5,4\r\n");
}

TEST(KheperaEmulator, SaysWhenItCannotMakeItsStablePath) {
  EmulatorConfig config;
  config.stable_path = "/nonexistent/dir/khepera";
  try {
    KheperaEmulator emulator(config);
    FAIL() << "no error";
  } catch (const std::system_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/khepera"), std::string::npos) << e.what();
  }
}

TEST(KheperaEmulator, RejectsBadFaults) {
  EmulatorConfig config;
  config.faults.drop_probability = 1.5;
  EXPECT_THROW(KheperaEmulator{config}, std::invalid_argument);
  KheperaEmulator emulator;
  EmulatorFaults bad;
  bad.reply_delay_ms = -1;
  EXPECT_THROW(emulator.set_faults(bad), std::invalid_argument);
}
