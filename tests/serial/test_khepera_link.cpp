// The link against the in-process emulator on a real pty: round trips, speeds reaching the
// robot and moving it, stops, recovery from garbage, delays and dropped replies, a robot
// that never answers, and unplug/replug. Waits are "until true, or fail after a generous
// deadline", never timed assertions.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "serial/khepera_emulator.hpp"
#include "serial/khepera_link.hpp"
#include "support/link_test_support.hpp"

using namespace rilbed::serial;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

using rilbed::testing::eventually;
using rilbed::testing::LogSink;

LinkConfig config_for(const KheperaEmulator& emulator, LogSink& log, int reply_timeout_ms = 150, int retries = 3) {
  LinkConfig config;
  config.port = emulator.device_path();
  config.reply_timeout_ms = reply_timeout_ms;
  config.retries = retries;
  config.reopen_interval_ms = 50;
  config.log = log.callback();
  return config;
}

constexpr auto kQueryTimeout = 5000ms;

}  // namespace

TEST(KheperaLink, InfoRoundTrip) {
  EmulatorConfig emulated;
  emulated.proximity = {10, 20, 30, 40, 50, 60, 70, 80};
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log));
  EXPECT_EQ(link.state(), LinkState::kStopped);
  ASSERT_EQ(link.start(), std::nullopt);
  // The handshake reads the versions by itself.
  ASSERT_TRUE(eventually([&] { return link.versions().has_value(); })) << log.text();
  EXPECT_EQ(link.versions()->bios, "5");
  EXPECT_EQ(link.versions()->protocol, "4");
  EXPECT_EQ(link.state(), LinkState::kOk);

  const Result<Reply> proximity = link.query(Command::read_proximity(), kQueryTimeout);
  ASSERT_TRUE(proximity.ok()) << proximity.error();
  EXPECT_EQ(proximity->sensors, emulated.proximity);
  ASSERT_TRUE(link.query(Command::set_counters(1000, -1000), kQueryTimeout).ok());
  const Result<Reply> counters = link.query(Command::read_counters(), kQueryTimeout);
  ASSERT_TRUE(counters.ok()) << counters.error();
  EXPECT_EQ(counters->wheels, (WheelPair{1000, -1000}));
  const Result<Reply> ambient = link.query(Command::read_ambient(), kQueryTimeout);
  ASSERT_TRUE(ambient.ok()) << ambient.error();
  EXPECT_EQ(ambient->sensors[0], 500);
  EXPECT_TRUE(link.query(Command::set_led(0, LedAction::kOn), kQueryTimeout).ok());
  // A command the model cannot express fails before it reaches the line.
  const Result<Reply> bad_led = link.query(Command::set_led(5, LedAction::kOn), kQueryTimeout);
  ASSERT_FALSE(bad_led.ok());
  EXPECT_NE(bad_led.error().find(emulator.device_path()), std::string::npos) << bad_led.error();

  const LinkStatus status = link.status();
  EXPECT_EQ(status.counters.timeouts, 0u);
  EXPECT_EQ(status.counters.bad_replies, 0u);
  EXPECT_GE(status.counters.replies_ok, 6u);
  EXPECT_TRUE(link.stop());
  EXPECT_EQ(link.state(), LinkState::kStopped);
  EXPECT_TRUE(link.stop());  // again: the first result
}

TEST(KheperaLink, SpeedsReachTheRobotAndMoveIt) {
  KheperaEmulator emulator;
  LogSink log;
  LinkConfig config = config_for(emulator, log);
  config.counters_period_ms = 50;
  KheperaLink link(config);
  ASSERT_EQ(link.start(), std::nullopt);
  link.set_speeds(25, 25);
  ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{25, 25}; })) << log.text();
  ASSERT_TRUE(eventually([&] { return link.acknowledged_speeds() == WheelSpeeds{25, 25}; })) << log.text();
  // The polled counters follow the wheels.
  ASSERT_TRUE(eventually([&] {
    const auto c = link.latest_counters();
    return c && c->value.left_pulses > 1000;  // 2500 pulses/s: about 0.4 s
  })) << log.text();
  EXPECT_TRUE(link.stop());
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
  const rilbed::Pose2 pose = emulator.true_pose();
  const auto counters = emulator.counters();
  EXPECT_GT(pose.position_m.x, 0.08);  // > 1000 pulses of 0.08 mm
  EXPECT_NEAR(pose.position_m.x, counters.left_pulses * 0.08e-3, 0.1e-3);
  EXPECT_NEAR(pose.position_m.y, 0.0, 1e-9);
  EXPECT_NEAR(pose.heading_rad, 0.0, 1e-9);
}

TEST(KheperaLink, TurnsCounterClockwiseWhenTheRightWheelIsFaster) {
  KheperaEmulator emulator;
  LogSink log;
  KheperaLink link(config_for(emulator, log));
  ASSERT_EQ(link.start(), std::nullopt);
  link.set_speeds(-10, 10);
  // Caught before it could wrap round past pi.
  ASSERT_TRUE(eventually([&] { return std::abs(emulator.true_pose().heading_rad) > 0.3; })) << log.text();
  EXPECT_TRUE(link.stop());
  EXPECT_GT(emulator.true_pose().heading_rad, 0.3);
  EXPECT_LT(emulator.true_pose().heading_rad, 2.0);
  EXPECT_NEAR(emulator.true_pose().position_m.x, 0.0, 1e-9);
}

TEST(KheperaLink, TheLatestSpeedsWinAndTooFastIsClamped) {
  EmulatorConfig emulated;
  emulated.faults.reply_delay_ms = 30;  // keeps the line busy while the wishes pile up
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log));
  ASSERT_EQ(link.start(), std::nullopt);
  for (int i = 1; i <= 50; ++i) link.set_speeds(i, -i);
  link.set_speeds(500, -500);
  ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{127, -127}; })) << log.text();
  EXPECT_LT(emulator.commands_received(CommandKind::kSetSpeeds), 51u);  // stale wishes were never sent
  ASSERT_TRUE(eventually([&] { return link.acknowledged_speeds() == WheelSpeeds{127, -127}; }));
  EXPECT_GE(link.status().counters.clamped_speeds, 1u);
  EXPECT_TRUE(link.stop());
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
}

TEST(KheperaLink, PollsProximityAndSeesChanges) {
  KheperaEmulator emulator;
  LogSink log;
  LinkConfig config = config_for(emulator, log);
  config.proximity_period_ms = 20;
  KheperaLink link(config);
  ASSERT_EQ(link.start(), std::nullopt);
  ASSERT_TRUE(eventually([&] { return link.latest_proximity().has_value(); })) << log.text();
  const rilbed::environment::ProximityValues near = {0, 0, 900, 950, 0, 0, 0, 0};
  emulator.set_proximity(near);
  ASSERT_TRUE(eventually([&] { return link.latest_proximity()->value == near; })) << log.text();
  // On request too.
  const auto before = link.latest_proximity()->received;
  link.request_proximity();
  EXPECT_TRUE(eventually([&] { return link.latest_proximity()->received > before; }));
}

TEST(KheperaLink, RecoversFromGarbageAndCorruptReplies) {
  EmulatorConfig emulated;
  emulated.faults.garbage_probability = 0.3;
  emulated.faults.corrupt_probability = 0.2;
  emulated.seed = 42;
  emulated.proximity = {1, 2, 3, 4, 5, 6, 7, 8};
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log, /*reply_timeout_ms=*/80, /*retries=*/10));
  ASSERT_EQ(link.start(), std::nullopt);
  for (int i = 0; i < 25; ++i) {
    const Result<Reply> r = link.query(Command::read_proximity(), kQueryTimeout);
    ASSERT_TRUE(r.ok()) << r.error() << "\n" << log.text();
    EXPECT_EQ(r->sensors, emulated.proximity);
  }
  const LinkCounters c = link.status().counters;
  EXPECT_GT(c.bad_replies + c.stray_lines, 0u);
  EXPECT_GT(c.retries, 0u);
  EXPECT_GT(c.noise_bytes, 0u);
  EXPECT_EQ(c.failed_commands, 0u);
  EXPECT_NE(log.text().find(emulator.device_path()), std::string::npos);  // messages name the port
}

TEST(KheperaLink, RecoversFromRepliesSlowerThanItsTimeout) {
  EmulatorConfig emulated;
  emulated.faults.reply_delay_ms = 120;
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log, /*reply_timeout_ms=*/80, /*retries=*/3));
  ASSERT_EQ(link.start(), std::nullopt);
  for (int i = 0; i < 3; ++i) {
    const Result<Reply> r = link.query(Command::read_counters(), kQueryTimeout);
    ASSERT_TRUE(r.ok()) << r.error() << "\n" << log.text();
  }
  EXPECT_GT(link.status().counters.timeouts, 0u);
  EXPECT_GT(link.status().counters.retries, 0u);
}

TEST(KheperaLink, DroppedRepliesTimeOutAndAreRetried) {
  EmulatorConfig emulated;
  emulated.faults.drop_probability = 0.4;
  emulated.seed = 3;
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log, /*reply_timeout_ms=*/60, /*retries=*/12));
  ASSERT_EQ(link.start(), std::nullopt);
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(link.query(Command::read_speeds(), kQueryTimeout).ok()) << log.text();
  }
  const LinkCounters c = link.status().counters;
  EXPECT_GT(c.timeouts, 0u);
  EXPECT_EQ(c.retries, c.timeouts);  // every timeout led to a new attempt
  EXPECT_EQ(c.failed_commands, 0u);
}

TEST(KheperaLink, ARobotThatNeverAnswersFailsWithAReasonAndIsStopped) {
  KheperaEmulator emulator;
  LogSink log;
  KheperaLink link(config_for(emulator, log, /*reply_timeout_ms=*/60, /*retries=*/2));
  ASSERT_EQ(link.start(), std::nullopt);
  link.set_speeds(30, 30);
  ASSERT_TRUE(eventually([&] { return link.acknowledged_speeds() == WheelSpeeds{30, 30}; })) << log.text();
  EmulatorFaults silent;
  silent.drop_probability = 1.0;
  emulator.set_faults(silent);
  const Result<Reply> r = link.query(Command::read_proximity(), kQueryTimeout);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("khepera " + emulator.device_path()), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("N (read proximity) failed after 3 attempts: no reply within 60 ms"), std::string::npos)
      << r.error();
  EXPECT_EQ(link.state(), LinkState::kUnresponsive);
  // The link stops a robot it cannot talk to: the stop reaches it even though its replies do not.
  EXPECT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{0, 0}; })) << log.text();
  EXPECT_FALSE(link.stop(300));
}

TEST(KheperaLink, TheWrongModelIsRejectedByTheRobot) {
  EmulatorConfig emulated;
  emulated.model = epuck_model();
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log, 100, 1));  // speaks Khepera II: `B` means body LED to an e-puck
  ASSERT_EQ(link.start(), std::nullopt);
  const Result<Reply> r = link.query(Command::read_versions(), kQueryTimeout);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("protocol error"), std::string::npos) << r.error();
}

TEST(KheperaLink, SpeaksToAnEpuck) {
  EmulatorConfig emulated;
  emulated.model = epuck_model();
  KheperaEmulator emulator(emulated);
  LogSink log;
  LinkConfig config = config_for(emulator, log);
  config.model = epuck_model();
  KheperaLink link(config);
  EXPECT_EQ(link.config().baud, 115200u);
  ASSERT_EQ(link.start(), std::nullopt);
  const Result<Reply> versions = link.query(Command::read_versions(), kQueryTimeout);
  ASSERT_TRUE(versions.ok()) << versions.error();
  EXPECT_EQ(versions->versions.text, "rilbed emulated e-puck");
  link.set_speeds(800, 800);
  ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{800, 800}; })) << log.text();
  ASSERT_TRUE(eventually([&] {
    const Result<Reply> q = link.query(Command::read_counters(), kQueryTimeout);
    return q.ok() && q->wheels.left > 100;
  })) << log.text();
  EXPECT_TRUE(link.stop());
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
}

TEST(KheperaLink, UnplugMarksTheRobotLostAndReplugResumes) {
  const fs::path stable = fs::temp_directory_path() / ("rilbed_test_link_" + std::to_string(::getpid()));
  EmulatorConfig emulated;
  emulated.stable_path = stable.string();
  KheperaEmulator emulator(emulated);
  LogSink log;
  KheperaLink link(config_for(emulator, log));
  ASSERT_EQ(link.start(), std::nullopt);
  link.set_speeds(10, 10);
  ASSERT_TRUE(eventually([&] { return link.acknowledged_speeds() == WheelSpeeds{10, 10}; })) << log.text();

  emulator.unplug();
  ASSERT_TRUE(eventually([&] { return link.state() == LinkState::kLost; })) << log.text();
  EXPECT_EQ(link.status().counters.port_losses, 1u);
  EXPECT_NE(link.status().last_error.find("port lost"), std::string::npos) << link.status().last_error;
  // While lost: queries fail at once, wishes are kept.
  const Result<Reply> r = link.query(Command::read_proximity(), kQueryTimeout);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find(stable.string()), std::string::npos) << r.error();
  link.set_speeds(15, -15);
  const auto failed_before = link.status().counters.reopen_failures;
  ASSERT_TRUE(eventually([&] { return link.status().counters.reopen_failures >= failed_before + 2; }))
      << log.text();                          // a few reopen attempts fail...
  EXPECT_EQ(link.state(), LinkState::kLost);  // ...and the link stays lost, its wish kept
  EXPECT_EQ(link.wished_speeds(), (WheelSpeeds{15, -15}));

  emulator.replug();
  ASSERT_TRUE(eventually([&] { return link.state() == LinkState::kOk; })) << log.text();
  EXPECT_GE(link.status().counters.reopens, 1u);
  // The wish made while lost reaches the robot once it is back.
  ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{15, -15}; })) << log.text();
  const Result<Reply> again = link.query(Command::read_versions(), kQueryTimeout);
  EXPECT_TRUE(again.ok()) << again.error();

  // An unchanged wish is sent again after a replug too: the robot may have missed it.
  const auto speeds_sent = emulator.commands_received(CommandKind::kSetSpeeds);
  emulator.unplug();
  ASSERT_TRUE(eventually([&] { return link.state() == LinkState::kLost; })) << log.text();
  emulator.replug();
  ASSERT_TRUE(eventually([&] { return emulator.commands_received(CommandKind::kSetSpeeds) > speeds_sent; }))
      << log.text();
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{15, -15}));
  EXPECT_EQ(link.status().counters.port_losses, 2u);
  EXPECT_TRUE(link.stop());
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
}

TEST(KheperaLink, ATimedDisconnectAndReplugAreSurvived) {
  const fs::path stable = fs::temp_directory_path() / ("rilbed_test_link_timed_" + std::to_string(::getpid()));
  EmulatorConfig emulated;
  emulated.stable_path = stable.string();
  emulated.faults.disconnect_after_s = 0.3;
  emulated.faults.replug_after_s = 0.3;
  KheperaEmulator emulator(emulated);
  LogSink log;
  LinkConfig config = config_for(emulator, log);
  config.proximity_period_ms = 30;
  KheperaLink link(config);
  ASSERT_EQ(link.start(), std::nullopt);
  ASSERT_TRUE(eventually([&] { return link.state() == LinkState::kLost; })) << log.text();
  ASSERT_TRUE(eventually([&] { return link.state() == LinkState::kOk; })) << log.text();
  const auto resumed = std::chrono::steady_clock::now();
  EXPECT_TRUE(eventually([&] {
    const auto p = link.latest_proximity();
    return p && p->received > resumed;
  })) << log.text();
}

TEST(KheperaLink, DestroyingTheLinkStopsTheRobot) {
  KheperaEmulator emulator;
  LogSink log;
  {
    KheperaLink link(config_for(emulator, log));
    ASSERT_EQ(link.start(), std::nullopt);
    link.set_speeds(40, 40);
    ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{40, 40}; })) << log.text();
  }
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
}

TEST(KheperaLink, ARobotDrivenByOneProgramIsNotOpenedByAnother) {
  // Two runs on one robot would fight over its wheels and read each other's replies. The
  // second finds the port locked, says so, and gets it once the first lets go.
  KheperaEmulator emulator;
  LogSink first_log;
  LogSink second_log;
  auto first = std::make_unique<KheperaLink>(config_for(emulator, first_log));
  ASSERT_EQ(first->start(), std::nullopt);
  ASSERT_TRUE(eventually([&] { return first->state() == LinkState::kOk; })) << first_log.text();
  KheperaLink second(config_for(emulator, second_log));
  const std::optional<std::string> failure = second.start();
  ASSERT_TRUE(failure.has_value());
  EXPECT_NE(failure->find("another program is using it"), std::string::npos) << *failure;
  EXPECT_EQ(second.state(), LinkState::kLost);
  first->set_speeds(30, 30);
  ASSERT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{30, 30}; })) << first_log.text();
  first.reset();  // stops the robot and closes the port
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
  ASSERT_TRUE(eventually([&] { return second.state() == LinkState::kOk; })) << second_log.text();
  second.set_speeds(20, 20);
  EXPECT_TRUE(eventually([&] { return emulator.last_speeds() == WheelSpeeds{20, 20}; })) << second_log.text();
}

TEST(KheperaLink, AMissingPortFailsAtOnceNamingIt) {
  LogSink log;
  LinkConfig config;
  config.port = "/nonexistent/ttyKhepera";
  config.reopen_interval_ms = 50;
  config.log = log.callback();
  KheperaLink link(config);
  const auto started = std::chrono::steady_clock::now();
  const std::optional<std::string> failure = link.start();
  ASSERT_TRUE(failure.has_value());
  EXPECT_NE(failure->find("khepera /nonexistent/ttyKhepera: cannot open"), std::string::npos) << *failure;
  EXPECT_EQ(link.state(), LinkState::kLost);
  EXPECT_FALSE(link.query(Command::read_versions(), kQueryTimeout).ok());
  EXPECT_FALSE(link.stop());
  EXPECT_LT(std::chrono::steady_clock::now() - started, 3s);  // generous: nothing waits on a missing port
}

TEST(KheperaLink, NotAPortIsReported) {
  LogSink log;
  LinkConfig config;
  config.port = "/dev/null";
  config.log = log.callback();
  KheperaLink link(config);
  const std::optional<std::string> failure = link.start();
  ASSERT_TRUE(failure.has_value());
  EXPECT_NE(failure->find("khepera /dev/null: cannot"), std::string::npos) << *failure;
}

TEST(KheperaLink, RejectsABadConfig) {
  LinkConfig config;
  EXPECT_THROW(KheperaLink{config}, std::invalid_argument);  // no port
  config.port = "/dev/ttyUSB9";
  config.baud = 12345;
  try {
    KheperaLink link(config);
    FAIL() << "baud 12345 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("khepera /dev/ttyUSB9: baud rate 12345"), std::string::npos) << e.what();
  }
  config.baud = 9600;
  config.reply_timeout_ms = 0;
  EXPECT_THROW(KheperaLink{config}, std::invalid_argument);
  config.reply_timeout_ms = 100;
  KheperaLink never_started(config);
  EXPECT_FALSE(never_started.stop());
  EXPECT_EQ(never_started.state(), LinkState::kStopped);
}

// The link against peers whose replies differ from K-Team's firmware in one way each, and
// in all of them at once: versions that are not integers, extra fields, trailing spaces,
// LF or CR line ends, upper-case letters, spaces after commas, an echo of every command.
// Each must work as K-Team's does: the handshake, every reading, speeds acknowledged, and
// not one reply counted bad.
struct PeerCase {
  const char* name;
  ReplyStyle style;
  FirmwareVersions versions;
};

class KheperaLinkWithOtherFirmware : public ::testing::TestWithParam<PeerCase> {};

TEST_P(KheperaLinkWithOtherFirmware, WorksAsWithKTeamFirmware) {
  const PeerCase& peer = GetParam();
  EmulatorConfig emulated;
  emulated.style = peer.style;
  emulated.versions = peer.versions;
  emulated.proximity = {1, 2, 3, 4, 5, 6, 7, 1023};
  KheperaEmulator emulator(emulated);
  LogSink log;
  LinkConfig config = config_for(emulator, log);
  config.counters_period_ms = 40;
  KheperaLink link(config);
  ASSERT_EQ(link.start(), std::nullopt);
  ASSERT_TRUE(eventually([&] { return link.versions().has_value(); })) << log.text();
  EXPECT_EQ(link.versions()->bios, peer.versions.bios);
  EXPECT_EQ(link.versions()->protocol, peer.versions.protocol);
  const Result<Reply> proximity = link.query(Command::read_proximity(), kQueryTimeout);
  ASSERT_TRUE(proximity.ok()) << proximity.error() << "\n" << log.text();
  EXPECT_EQ(proximity->sensors, emulated.proximity);
  ASSERT_TRUE(link.query(Command::set_counters(-300, 400), kQueryTimeout).ok()) << log.text();
  const Result<Reply> counters = link.query(Command::read_counters(), kQueryTimeout);
  ASSERT_TRUE(counters.ok()) << counters.error();
  EXPECT_EQ(counters->wheels, (WheelPair{-300, 400}));
  link.set_speeds(12, -7);
  ASSERT_TRUE(eventually([&] { return link.acknowledged_speeds() == WheelSpeeds{12, -7}; })) << log.text();
  const Result<Reply> speeds = link.query(Command::read_speeds(), kQueryTimeout);
  ASSERT_TRUE(speeds.ok()) << speeds.error();
  EXPECT_EQ(speeds->wheels, (WheelPair{12, -7}));
  EXPECT_TRUE(link.stop()) << log.text();
  EXPECT_EQ(emulator.last_speeds(), (WheelSpeeds{0, 0}));
  const LinkCounters c = link.status().counters;
  EXPECT_EQ(c.bad_replies, 0u) << log.text();
  EXPECT_EQ(c.timeouts, 0u) << log.text();
  EXPECT_EQ(c.failed_commands, 0u);
  if (peer.style.echo) {
    EXPECT_GE(c.echoed_lines, 6u);  // the handshake, four queries, the speeds and the stop
  } else {
    EXPECT_EQ(c.echoed_lines, 0u);
  }
}

namespace {

ReplyStyle style_with(void (*change)(ReplyStyle&)) {
  ReplyStyle style;
  change(style);
  return style;
}

const FirmwareVersions kKTeam{"5", "4", ""};
const FirmwareVersions kDotted{"5.02", "5.01", ""};

}  // namespace

INSTANTIATE_TEST_SUITE_P(
    Peers, KheperaLinkWithOtherFirmware,
    ::testing::Values(
        PeerCase{"KTeam", {}, kKTeam}, PeerCase{"DottedVersions", {}, kDotted},
        PeerCase{"TextVersions", {}, {"K2 BIOS", "rev C", ""}},
        PeerCase{"ExtraFields", style_with([](ReplyStyle& s) { s.extra_fields = ",0,ok"; }), kKTeam},
        PeerCase{"TrailingSpaces", style_with([](ReplyStyle& s) { s.trailing_spaces = 3; }), kKTeam},
        PeerCase{"LfOnly", style_with([](ReplyStyle& s) { s.line_end = "\n"; }), kKTeam},
        PeerCase{"CrOnly", style_with([](ReplyStyle& s) { s.line_end = "\r"; }), kKTeam},
        PeerCase{"UpperCase", style_with([](ReplyStyle& s) { s.upper_case_letter = true; }), kKTeam},
        PeerCase{"SpacesAfterCommas", style_with([](ReplyStyle& s) { s.spaces_after_commas = true; }), kKTeam},
        PeerCase{"Echo", style_with([](ReplyStyle& s) { s.echo = true; }), kKTeam},
        PeerCase{"AllAtOnce", style_with([](ReplyStyle& s) { s = {true, "\n", ",9,x", 2, true, true}; }), kDotted}),
    [](const ::testing::TestParamInfo<PeerCase>& info) { return std::string(info.param.name); });
