// The panel's service with real WebSocket clients and a recording console sink: console
// commands relayed and answered, and manual driving's dead man's switch (keys stop coming,
// release, a socket that closes, a take-over), bad drive messages answered with a status.
// Waits are "until it happens, or fail after a generous deadline".
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "gui_web/gui_service.hpp"
#include "support/eventually.hpp"
#include "support/manual_clock.hpp"
#include "ws_test_client.hpp"

namespace rilbed::gui_web {
namespace {

using rilbed::testing::eventually;
using rilbed::testing::ManualClock;
using namespace std::chrono_literals;

using namespace rilbed::gui_web::testing;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

// Records what reaches the run, and when (by `clock`: the wall's, or a test's own), and
// answers as the run would.
struct RecordingSink {
  struct Call {
    ConsoleRequest request;
    Clock::time_point at;
  };
  explicit RecordingSink(std::function<Clock::time_point()> clock = [] { return Clock::now(); })
      : clock(std::move(clock)) {}
  std::function<Clock::time_point()> clock;
  std::mutex mutex;
  std::vector<Call> calls;
  ConsoleSink sink() {
    return [this](const ConsoleRequest& r) {
      std::lock_guard lock(mutex);
      calls.push_back({r, clock()});
      if (r.command == "pause") return ConsoleAnswer{true, "pause"};
      if (r.command == "drive" && r.args.at(0) == "99") return ConsoleAnswer{false, "this run has no robot 99"};
      if (r.command == "drive") return ConsoleAnswer{true, "drive"};
      if (r.command == "vision" && r.args.size() >= 2 && r.args[1] == "9")
        return ConsoleAnswer{false, "contrast 9 is outside 0.2..5"};
      if (r.command == "vision") return ConsoleAnswer{true, "vision"};
      return ConsoleAnswer{false, "unknown command '" + r.command + "'"};
    };
  }
  std::vector<Call> snapshot() {
    std::lock_guard lock(mutex);
    return calls;
  }
  // The drives of robot `id` so far, as "L R".
  std::vector<std::string> drives(int id) {
    std::vector<std::string> out;
    for (const Call& c : snapshot()) {
      if (c.request.command == "drive" && c.request.args.at(0) == std::to_string(id)) {
        out.push_back(c.request.args.at(1) + " " + c.request.args.at(2));
      }
    }
    return out;
  }
};

// A client that has read the greeting and advertised its two topics (1: console, 2: drive).
struct PanelClient : Client {
  explicit PanelClient(std::uint16_t port) {
    EXPECT_EQ(connect(port, "/ws?token=" + kToken), 101);
    next_json();  // serverInfo
    advertised = next_json();
    send_text({{"op", "advertise"},
               {"channels",
                {{{"id", 1}, {"topic", "/rilbed/console"}, {"encoding", "json"}, {"schemaName", ""}},
                 {{"id", 2}, {"topic", "/rilbed/drive"}, {"encoding", "json"}, {"schemaName", ""}}}}});
  }
  void publish(std::uint32_t channel, const json& message) {
    std::string frame(5, '\0');
    frame[0] = 1;
    for (int i = 0; i < 4; ++i) frame[1 + i] = static_cast<char>((channel >> (8 * i)) & 0xff);
    send_binary(frame + message.dump());
  }
  void drive(int id, int left, int right) { publish(2, {{"id", id}, {"left", left}, {"right", right}}); }
  // Subscribes to the run's answers (subscription 7).
  void hear_replies() {
    for (const auto& c : advertised["channels"]) {
      if (c["topic"] == "/rilbed/console_reply") {
        send_text({{"op", "subscribe"}, {"subscriptions", {{{"id", 7}, {"channelId", c["id"]}}}}});
      }
    }
  }
  // The next answer's JSON (skipping anything else).
  json next_reply() {
    for (;;) {
      const auto m = next();
      if (std::holds_alternative<std::string>(m) && std::get<std::string>(m).size() > 13 &&
          std::get<std::string>(m)[1] == 7) {
        return json::parse(std::get<std::string>(m).substr(13));
      }
    }
  }
  json advertised;
};

std::uint32_t channel_id(const json& advertise, const std::string& topic) {
  for (const auto& c : advertise["channels"]) {
    if (c["topic"] == topic) return c["id"].get<std::uint32_t>();
  }
  return 0;
}

TEST(GuiService, ConsoleCommandsReachTheRunAndTheirAnswersComeBack) {
  RecordingSink run;
  GuiService gui(config(), run.sink());
  Client watcher;
  ASSERT_EQ(watcher.connect(gui.server().port(), "/ws?token=" + kToken), 101);
  watcher.next_json();
  const std::uint32_t replies = channel_id(watcher.next_json(), "/rilbed/console_reply");
  ASSERT_NE(replies, 0u);
  watcher.send_text({{"op", "subscribe"}, {"subscriptions", {{{"id", 3}, {"channelId", replies}}}}});
  ASSERT_TRUE(eventually([&] { return gui.server().subscribed(replies); }));

  PanelClient panel(gui.server().port());
  panel.publish(1, {{"command", "pause"}, {"args", json::array()}});
  const auto m = watcher.next();
  ASSERT_TRUE(std::holds_alternative<std::string>(m));
  const json reply = json::parse(std::get<std::string>(m).substr(13));
  EXPECT_EQ(reply["accepted"], true);
  EXPECT_EQ(reply["reason"], "pause");
  const auto calls = run.snapshot();
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].request.command, "pause");
  EXPECT_EQ(reply["client"], calls[0].request.client);
  EXPECT_EQ(gui.counters().console_commands, 1u);
  // Not a command: an error status on the sender's socket, nothing reaches the run.
  panel.publish(1, {{"verb", "pause"}});
  const json status = panel.next_json();
  EXPECT_EQ(status["op"], "status");
  EXPECT_EQ(status["level"], 2);
  EXPECT_EQ(run.snapshot().size(), 1u);
}

TEST(GuiService, ARobotDrivenByHandStopsWhenTheKeysStopComing) {
  // On a clock of the test's own: the switch's timing is exact, whatever the machine does.
  ManualClock clock;
  RecordingSink run(clock.function());
  ManualDriveConfig timing;  // the defaults: keys lapse after 300 ms; holds of 0.6 s, renewed after 0.2 s
  timing.clock = clock.function();
  GuiService gui(config(), run.sink(), timing);
  PanelClient panel(gui.server().port());
  const auto keys_from = clock.now();
  panel.drive(4, 30, 30);
  // The first key sends the hold at once.
  ASSERT_TRUE(eventually([&] { return !run.drives(4).empty(); }));
  EXPECT_EQ(run.snapshot().front().request.args, (std::vector<std::string>{"4", "30", "30", "0.6"}));
  EXPECT_EQ(run.snapshot().front().at, keys_from);
  // Keys held for 400 ms, a message every 100 ms.
  for (unsigned i = 1; i <= 4; ++i) {
    clock.advance(100ms);
    panel.drive(4, 30, 30);
    ASSERT_TRUE(eventually([&] { return gui.counters().drive_messages == i + 1; }));
  }
  const auto keys_until = clock.now();
  // Up to the keys' timeout the robot drives on (its hold renewed); a moment past it, it stops.
  clock.advance(300ms);
  gui.tick();
  EXPECT_EQ(run.drives(4).back(), "30 30");
  clock.advance(1ms);
  gui.tick();
  EXPECT_EQ(run.drives(4).back(), "0 0");
  EXPECT_EQ(run.snapshot().back().at - keys_until, 301ms);
  EXPECT_EQ(gui.counters().drive_stops, 0u);  // a hold of speed 0, not a release
  // Still held: the hold is renewed standing until it is released.
  const std::size_t before = run.drives(4).size();
  for (int i = 0; i < 2; ++i) {
    clock.advance(200ms);
    gui.tick();
  }
  EXPECT_EQ(run.drives(4).size(), before + 2);
  for (const std::string& d : run.drives(4)) {
    EXPECT_TRUE(d == "30 30" || d == "0 0") << d;
  }
  EXPECT_EQ(run.drives(4).back(), "0 0");
  panel.publish(2, {{"id", 4}, {"release", true}});
  ASSERT_TRUE(eventually([&] { return gui.counters().drive_stops == 1u; }));
  // Given back: nothing more is sent for it, however long the service looks.
  const std::size_t released = run.drives(4).size();
  clock.advance(10s);
  gui.tick();
  EXPECT_EQ(run.drives(4).size(), released);
  EXPECT_EQ(run.drives(4).back(), "0 0");
}

TEST(GuiService, ClosingTheDriversSocketStopsTheRobot) {
  RecordingSink run;
  GuiService gui(config(), run.sink());
  {
    PanelClient panel(gui.server().port());
    panel.drive(5, 40, 20);
    ASSERT_TRUE(eventually([&] { return !run.drives(5).empty(); }));
    // Keys still "held" (a message every 100 ms) when the tab closes.
    panel.drive(5, 40, 20);
    panel.ws.close(boost::beast::websocket::close_code::going_away);
  }
  ASSERT_TRUE(eventually([&] { return gui.counters().drive_stops == 1u; }));
  EXPECT_EQ(run.drives(5).back(), "0 0");
}

TEST(GuiService, AnotherClientTakesTheRobotOverAndTheFirstIsToldSo) {
  RecordingSink run;
  GuiService gui(config(), run.sink());
  PanelClient first(gui.server().port());
  first.hear_replies();
  PanelClient second(gui.server().port());
  first.drive(6, 10, 10);
  ASSERT_TRUE(eventually([&] { return !run.drives(6).empty(); }));
  const std::string first_name = run.snapshot().back().request.client;
  (void)first_name;
  second.drive(6, -10, 10);
  ASSERT_TRUE(eventually([&] {
    const auto d = run.drives(6);
    return !d.empty() && d.back() == "-10 10";
  }));
  const std::string second_name = run.snapshot().back().request.client;
  EXPECT_NE(first_name, second_name);
  // The first driver alone is told, on its own socket.
  json told;
  do {
    const auto m = first.next();
    if (std::holds_alternative<json>(m)) told = std::get<json>(m);
  } while (told.value("op", "") != "status");
  EXPECT_EQ(told["level"], 1);
  EXPECT_EQ(told["message"].get<std::string>().rfind("robot 6 taken over by ", 0), 0u) << told;
  // No stop between the two drivers: the robot went from one's speeds to the other's.
  for (const std::string& d : run.drives(6)) EXPECT_NE(d, "0 0");
  EXPECT_EQ(gui.counters().drive_stops, 0u);
  // Bad drive messages get an error status, and reach nothing.
  PanelClient third(gui.server().port());
  third.publish(2, {{"id", 6}, {"left", 500}, {"right", 0}});
  EXPECT_EQ(third.next_json()["level"], 2);
  third.publish(2, {{"id", "six"}});
  EXPECT_EQ(third.next_json()["level"], 2);
  third.publish(2, {{"id", 6}, {"release", true}});  // not its robot
  EXPECT_EQ(third.next_json()["level"], 2);
  for (const auto& c : run.snapshot()) EXPECT_NE(c.request.args.at(1), "500");
}

TEST(GuiService, TheRunsRefusalOfADriveIsToldToTheDriverOnce) {
  ManualClock clock;
  RecordingSink run(clock.function());
  ManualDriveConfig timing;
  timing.clock = clock.function();
  GuiService gui(config(), run.sink(), timing);
  PanelClient panel(gui.server().port());
  panel.hear_replies();
  for (unsigned i = 0; i < 6; ++i) {
    panel.drive(99, 10, 10);
    ASSERT_TRUE(eventually([&] { return gui.counters().drive_messages == i + 1; }));
    clock.advance(100ms);
    gui.tick();
  }
  // Refused holds keep reaching the run (which may change its mind: a paused run resumes)...
  ASSERT_TRUE(eventually([&] { return run.drives(99).size() >= 3; }));
  // ...but the driver hears the refusal once: the next answer after it is the pause's.
  panel.publish(1, {{"command", "pause"}});
  const json refusal = panel.next_reply();
  EXPECT_EQ(refusal["accepted"], false);
  EXPECT_EQ(refusal["reason"], "drive robot 99: this run has no robot 99");
  EXPECT_EQ(panel.next_reply()["reason"], "pause");
}

TEST(GuiService, DestroyingTheServiceStopsEveryHeldRobot) {
  RecordingSink run;
  {
    GuiService gui(config(), run.sink());
    PanelClient a(gui.server().port());
    PanelClient b(gui.server().port());
    a.drive(1, 20, 20);
    b.drive(2, 20, 20);
    ASSERT_TRUE(eventually([&] { return !run.drives(1).empty() && !run.drives(2).empty(); }));
  }
  EXPECT_EQ(run.drives(1).back(), "0 0");
  EXPECT_EQ(run.drives(2).back(), "0 0");
}

// The next text message with this op (binary data and other text skipped).
json next_op(Client& c, const std::string& op) {
  for (;;) {
    const auto m = c.next();
    if (std::holds_alternative<json>(m) && std::get<json>(m).value("op", "") == op) return std::get<json>(m);
  }
}

// parameterValues' list as name -> value.
std::map<std::string, json> values_of(const json& parameter_values) {
  std::map<std::string, json> out;
  for (const auto& p : parameter_values["parameters"])
    out[p["name"].get<std::string>()] = p.contains("value") ? p["value"] : json();
  return out;
}

run::StatusReport status_with(std::optional<vision::VisionSettings> settings) {
  run::StatusReport s;
  s.state = "running";
  s.vision = settings;
  return s;
}

TEST(GuiService, VisionSettingsAreParametersTheRunSetsAndReports) {
  RecordingSink run;
  GuiService gui(config(), run.sink());
  Client viewer;
  ASSERT_EQ(viewer.connect(gui.server().port(), "/ws?token=" + kToken), 101);
  const json info = viewer.next_json();
  for (const char* capability : {"parameters", "parametersSubscribe", "clientPublish"}) {
    EXPECT_NE(std::find(info["capabilities"].begin(), info["capabilities"].end(), capability),
              info["capabilities"].end())
        << capability << " " << info.dump();
  }
  // No camera yet: no parameters. (The answer also says the subscription has been read.)
  viewer.send_text({{"op", "subscribeParameterUpdates"}, {"parameterNames", {"vision.contrast"}}});
  viewer.send_text({{"op", "getParameters"}, {"parameterNames", json::array()}, {"id", "a"}});
  json answer = next_op(viewer, "parameterValues");
  EXPECT_EQ(answer["id"], "a");
  EXPECT_TRUE(answer["parameters"].empty());
  // A run with a camera reports its settings with its status.
  gui.on_status(status_with(vision::VisionSettings{}));
  json update = next_op(viewer, "parameterValues");
  EXPECT_FALSE(update.contains("id"));
  EXPECT_EQ(values_of(update), (std::map<std::string, json>{{"vision.contrast", 1.0}}));  // only what it subscribed to
  viewer.send_text({{"op", "getParameters"}, {"parameterNames", json::array()}, {"id", "b"}});
  answer = next_op(viewer, "parameterValues");
  EXPECT_EQ(answer["id"], "b");
  auto values = values_of(answer);
  EXPECT_EQ(values.size(), 6u);
  EXPECT_EQ(values["vision.threshold"], 24.0);
  EXPECT_EQ(values["vision.min_score"], 0.75);

  // Setting two at once is one console command; the answer carries the request's id.
  viewer.send_text(
      {{"op", "setParameters"},
       {"parameters", {{{"name", "vision.contrast"}, {"value", 1.5}}, {{"name", "vision.threshold"}, {"value", 30}}}},
       {"id", "c"}});
  update = next_op(viewer, "parameterValues");
  EXPECT_FALSE(update.contains("id"));  // the subscribed change first
  EXPECT_EQ(values_of(update)["vision.contrast"], 1.5);
  answer = next_op(viewer, "parameterValues");
  EXPECT_EQ(answer["id"], "c");
  EXPECT_EQ(values_of(answer), (std::map<std::string, json>{{"vision.contrast", 1.5}, {"vision.threshold", 30.0}}));
  auto calls = run.snapshot();
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].request.command, "vision");
  EXPECT_EQ(calls[0].request.args, (std::vector<std::string>{"contrast", "1.5", "threshold", "30"}));

  // Refused by the run: an error status, and the values as they are.
  viewer.send_text(
      {{"op", "setParameters"}, {"parameters", {{{"name", "vision.contrast"}, {"value", 9}}}}, {"id", "d"}});
  const json refusal = next_op(viewer, "status");
  EXPECT_EQ(refusal["level"], 2);
  EXPECT_NE(refusal["message"].get<std::string>().find("contrast 9 is outside 0.2..5"), std::string::npos)
      << refusal.dump();
  answer = next_op(viewer, "parameterValues");
  EXPECT_EQ(answer["id"], "d");
  EXPECT_EQ(values_of(answer)["vision.contrast"], 1.5);

  // Not a vision setting, or not a number: refused here, the run never hears of it.
  viewer.send_text({{"op", "setParameters"}, {"parameters", {{{"name", "gamma"}, {"value", 2}}}}, {"id", "e"}});
  EXPECT_NE(next_op(viewer, "status")["message"].get<std::string>().find("unknown parameter 'gamma'"),
            std::string::npos);
  EXPECT_EQ(next_op(viewer, "parameterValues")["id"], "e");
  viewer.send_text(
      {{"op", "setParameters"}, {"parameters", {{{"name", "vision.contrast"}, {"value", "high"}}}}, {"id", "f"}});
  EXPECT_NE(next_op(viewer, "status")["message"].get<std::string>().find("must be a number"), std::string::npos);
  EXPECT_EQ(next_op(viewer, "parameterValues")["id"], "f");
  EXPECT_EQ(run.snapshot().size(), 2u);

  // A console elsewhere changed them: the status brings the news to subscribers.
  vision::VisionSettings tuned;
  tuned.contrast = 2.0;
  gui.on_status(status_with(tuned));
  EXPECT_EQ(values_of(next_op(viewer, "parameterValues"))["vision.contrast"], 2.0);
  // A status without a camera (a new run without one) takes them away.
  gui.on_status(status_with(std::nullopt));
  update = next_op(viewer, "parameterValues");
  EXPECT_TRUE(values_of(update)["vision.contrast"].is_null());
  viewer.send_text({{"op", "getParameters"}, {"parameterNames", json::array()}, {"id", "g"}});
  EXPECT_TRUE(next_op(viewer, "parameterValues")["parameters"].empty());
}

TEST(GuiService, AViewerJoiningLaterGetsTheLatestPosesAndSceneThoughNobodyWatchedThem) {
  RecordingSink run;
  GuiService gui(config(), run.sink());
  // Reported while nobody watches: nothing is built, but the latest is kept.
  std::vector<run::PoseReport> poses{{3, false, true, Pose2{{0.5, 0.25}, 1.0}, "wander", "ok"}};
  gui.on_poses(1'000'000, poses);
  poses[0].pose.position_m = {0.75, 0.5};
  gui.on_poses(1'100'000, poses);
  ASSERT_TRUE(gui.flush(std::chrono::seconds(5)));
  Client viewer;
  ASSERT_EQ(viewer.connect(gui.server().port(), "/ws?token=" + kToken), 101);
  viewer.next_json();
  const json advertised = viewer.next_json();
  viewer.send_text({{"op", "subscribe"},
                    {"subscriptions",
                     {{{"id", 1}, {"channelId", channel_id(advertised, "/rilbed/poses")}},
                      {{"id", 2}, {"channelId", channel_id(advertised, "/rilbed/scene")}}}}});
  std::map<int, json> got;
  while (got.size() < 2) {
    const auto m = viewer.next();
    if (!std::holds_alternative<std::string>(m)) continue;
    const std::string& bytes = std::get<std::string>(m);
    got[bytes[1]] = json::parse(bytes.substr(13));
  }
  EXPECT_DOUBLE_EQ(got[1]["t_s"].get<double>(), 1.1);
  EXPECT_EQ(got[1]["robots"][0]["x_m"], 0.75);
  EXPECT_EQ(got[2]["entities"][0]["id"], "robot 3");
  // From now on each step comes as it is reported.
  poses[0].pose.position_m = {1.0, 0.5};
  gui.on_poses(1'200'000, poses);
  for (;;) {
    const auto m = viewer.next();
    if (!std::holds_alternative<std::string>(m) || std::get<std::string>(m)[1] != 1) continue;
    EXPECT_EQ(json::parse(std::get<std::string>(m).substr(13))["robots"][0]["x_m"], 1.0);
    break;
  }
}

}  // namespace
}  // namespace rilbed::gui_web
