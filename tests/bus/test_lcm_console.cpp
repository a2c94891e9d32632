// The console over LCM, on the in-process bus: commands parsed and checked, the token
// required, every command answered once and applied once (a retried command gets the
// first answer again), and the token file private to its user.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <variant>
#include <vector>

#include "bus/lcm_console.hpp"

namespace rilbed::bus {
namespace {

rilbed::console_command_t command(std::string name, std::vector<std::string> args = {}, std::string token = "t0k") {
  rilbed::console_command_t c;
  c.seq = 7;
  c.client = "test:1";
  c.token = std::move(token);
  c.command = std::move(name);
  c.args = std::move(args);
  c.num_args = static_cast<std::int32_t>(c.args.size());
  return c;
}

TEST(LcmConsole, ParsesEveryCommandAndRefusesTheRest) {
  using Kind = run::ControlAction::Kind;
  auto kind = [](const rilbed::console_command_t& c) {
    return std::get<run::ControlAction>(parse_console_command(c)).kind;
  };
  EXPECT_EQ(kind(command("pause")), Kind::kPause);
  EXPECT_EQ(kind(command("resume")), Kind::kResume);
  EXPECT_EQ(kind(command("exit")), Kind::kExit);
  const auto rt = parse_console_command(command("rt-factor", {"2.5"}));
  ASSERT_TRUE(std::holds_alternative<run::ControlAction>(rt));
  EXPECT_EQ(std::get<run::ControlAction>(rt).rt_factor, 2.5);
  EXPECT_EQ(std::get<run::ControlAction>(rt).who, "test:1");
  EXPECT_EQ(kind(command("reset")), Kind::kReset);
  const auto mode = std::get<run::ControlAction>(parse_console_command(command("mode", {"central"})));
  EXPECT_EQ(mode.kind, Kind::kMode);
  EXPECT_TRUE(mode.central);
  EXPECT_FALSE(std::get<run::ControlAction>(parse_console_command(command("mode", {"distributed"}))).central);
  const auto drive = std::get<run::ControlAction>(parse_console_command(command("drive", {"3", "-40", "127", "2.5"})));
  EXPECT_EQ(drive.kind, Kind::kDrive);
  EXPECT_EQ(drive.robot_id, 3);
  EXPECT_EQ(drive.left, -40);
  EXPECT_EQ(drive.right, 127);
  EXPECT_EQ(drive.duration_s, 2.5);
  for (const auto& bad :
       {command("mode"), command("mode", {"fast"}), command("mode", {"central", "x"}), command("reset", {"1"}),
        command("drive", {"3", "40", "40"}), command("drive", {"3", "128", "0", "1"}),
        command("drive", {"3", "0", "-128", "1"}), command("drive", {"x", "0", "0", "1"}),
        command("drive", {"3", "1.5", "0", "1"}), command("drive", {"3", "0", "0", "0"}),
        command("drive", {"3", "0", "0", "nan"}), command("drive", {"3", "0", "0", "601"}),
        command("drive", {"99999999999", "0", "0", "1"}), command("drive", {"-1", "0", "0", "1"})}) {
    EXPECT_TRUE(std::holds_alternative<std::string>(parse_console_command(bad)))
        << bad.command << " " << bad.args.size();
  }
  for (const auto& bad : {command("rt-factor"), command("rt-factor", {"0"}), command("rt-factor", {"x"}),
                          command("rt-factor", {"inf"}), command("pause", {"now"}), command("fly"), command("")}) {
    EXPECT_TRUE(std::holds_alternative<std::string>(parse_console_command(bad))) << bad.command;
  }
}

TEST(LcmConsole, VisionTakesNameValuePairsInRange) {
  using Kind = run::ControlAction::Kind;
  const auto v =
      std::get<run::ControlAction>(parse_console_command(command("vision", {"contrast", "1.5", "threshold", "30"})));
  EXPECT_EQ(v.kind, Kind::kVision);
  EXPECT_EQ(v.vision, (std::vector<std::pair<std::string, double>>{{"contrast", 1.5}, {"threshold", 30.0}}));
  const auto reason = [](const rilbed::console_command_t& c) {
    const auto parsed = parse_console_command(c);
    return std::holds_alternative<std::string>(parsed) ? std::get<std::string>(parsed) : std::string("accepted");
  };
  EXPECT_EQ(reason(command("vision", {"contrast", "9"})), "contrast 9 is outside 0.2..5");
  EXPECT_EQ(reason(command("vision", {"contrast", "1", "contrast", "2"})), "'contrast' is given twice");
  EXPECT_EQ(reason(command("vision", {"contrast", "x"})), "'x' is not a number");
  EXPECT_NE(reason(command("vision", {"gamma", "1"})).find("unknown vision setting 'gamma'"), std::string::npos);
  EXPECT_NE(reason(command("vision")).find("takes NAME VALUE pairs"), std::string::npos);
  EXPECT_NE(reason(command("vision", {"contrast"})).find("takes NAME VALUE pairs"), std::string::npos);
  EXPECT_EQ(reason(command("vision", {"brightness", "-20"})), "accepted");
}

TEST(LcmConsole, TheTokenFileIsPrivate) {
  const auto dir = std::filesystem::temp_directory_path() / ("rilbed_token_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  ASSERT_EQ(write_token(dir / "token", "abc"), std::nullopt);
  struct stat st {};
  ASSERT_EQ(::stat((dir / "token").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  ASSERT_EQ(::stat(dir.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  EXPECT_EQ(read_token(dir / "token"), "abc");
  EXPECT_EQ(read_token(dir / "none"), std::nullopt);
  // A folder others can enter is no place for it.
  ::chmod(dir.c_str(), 0755);
  EXPECT_NE(write_token(dir / "token", "def"), std::nullopt);
  std::filesystem::remove_all(dir);
  EXPECT_EQ(make_run_token().size(), 32u);
  EXPECT_NE(make_run_token(), make_run_token());
}

// A run stand-in: counts what it is asked to do (a mock is fine inside a unit test).
struct FakeRun {
  std::mutex mutex;
  std::vector<run::ControlAction> applied;
  bool paused = false;
  void attach(run::RunControl& control) {
    control.attach(
        [this](const run::ControlAction& a) -> std::optional<std::string> {
          std::lock_guard lock(mutex);
          if (a.kind == run::ControlAction::Kind::kPause && paused) return "the run is paused already";
          return std::nullopt;
        },
        [this](const run::ControlAction& a) {
          std::lock_guard lock(mutex);
          if (a.kind == run::ControlAction::Kind::kPause) paused = true;
          applied.push_back(a);
        });
  }
  std::size_t count() {
    std::lock_guard lock(mutex);
    return applied.size();
  }
};

struct Replies {
  std::vector<rilbed::console_reply_t> got;
  void on(const std::string&, const void* data, std::size_t size) {
    rilbed::console_reply_t r;
    if (r.decode(data, 0, static_cast<int>(size)) == static_cast<int>(size)) got.push_back(r);
  }
};

TEST(LcmConsole, AnswersEveryCommandOnceAndAppliesItOnce) {
  lcm::LCM server_bus("memq://");
  const Channels channels = Channels::with_prefix("C_");
  run::RunControl control;
  FakeRun run;
  run.attach(control);
  // One thread handles the in-process bus (memq:// is not safe with two): this one, in
  // send_console_command, which delivers the commands to the server and its replies back.
  LcmConsoleServer server(server_bus, channels, "t0k", control, {}, false);

  // The console's side on the same in-process bus.
  auto reply = send_console_command(server_bus, channels, "t0k", "pause", {}, 2000);
  ASSERT_TRUE(reply.has_value());
  EXPECT_TRUE(reply->accepted) << reply->reason;
  EXPECT_EQ(run.count(), 1u);
  reply = send_console_command(server_bus, channels, "t0k", "pause", {}, 2000);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted);
  EXPECT_EQ(reply->reason, "the run is paused already");
  // A wrong or missing token is refused, and the run records the refusal.
  reply = send_console_command(server_bus, channels, "nope", "exit", {}, 2000);
  ASSERT_TRUE(reply.has_value());
  EXPECT_FALSE(reply->accepted);
  EXPECT_NE(reply->reason.find("wrong token"), std::string::npos);
  reply = send_console_command(server_bus, channels, "", "exit", {}, 2000);
  ASSERT_TRUE(reply.has_value());
  EXPECT_NE(reply->reason.find("no token"), std::string::npos);
  ASSERT_EQ(run.count(), 3u);
  EXPECT_EQ(run.applied[1].kind, run::ControlAction::Kind::kRefused);
  EXPECT_NE(run.applied[1].what.find("'exit'"), std::string::npos);
  // The same command three times (a client retrying after a loss): three answers, one action.
  Replies replies;
  LcmSubscription subscription(
      server_bus, channels.console_reply,
      [&replies](const std::string& c, const void* data, std::size_t size) { replies.on(c, data, size); });
  const rilbed::console_command_t resume = command("resume");
  for (int i = 0; i < 3; ++i) server_bus.publish(channels.console, &resume);
  for (int i = 0; i < 200 && replies.got.size() < 3; ++i) server_bus.handleTimeout(10);
  ASSERT_EQ(replies.got.size(), 3u);
  for (const auto& r : replies.got) EXPECT_TRUE(r.accepted);
  EXPECT_EQ(run.count(), 4u);
  // No run attached: refused, saying so.
  control.detach();
  reply = send_console_command(server_bus, channels, "t0k", "exit", {}, 2000);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->reason, "no run is running");
  // Nobody on another prefix: no answer.
  EXPECT_FALSE(send_console_command(server_bus, Channels::with_prefix("NONE_"), "t0k", "pause", {}, 300).has_value());
}

}  // namespace
}  // namespace rilbed::bus
