// `rilbed gui --lcm URL` against a real run on UDP multicast inside a private namespace,
// with a Foxglove WebSocket client (ws_probe): the page's door needs the token, the run's
// poses arrive as JSON on /rilbed/poses with every robot, and a pause published on
// /rilbed/console reaches the run and comes back accepted on /rilbed/console_reply.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// A namespace script: `rilbed run RUN_ARGS --lcm $URL` and `rilbed gui --lcm $URL` in the
// background, $HOSTPORT and $TOKEN read from the URL the gui prints, $P2 the WebSocket
// probe; then `body` (errors no longer end the script: each step writes its exit code to
// codes.txt), then the console's exit, the run's and the gui's exit codes ("exit N", "run
// N", "gui N").
std::string gui_on_the_bus_script(const std::string& run_args, const std::string& body) {
  return "P2='" RILBED_WS_PROBE
         "'\n"
         "\"$R\" run " +
         run_args +
         " --lcm \"$URL\" --out run --quiet > run.txt 2> run.err &\n"
         "P=$!\n"
         "\"$R\" gui --lcm \"$URL\" --gui-port 0 > gui.txt 2> gui.err &\n"
         "G=$!\n"
         "for i in $(seq 1 200); do grep -q 'token=' gui.txt && break; sleep 0.05; done\n"
         "HOSTPORT=$(sed -n 's|.*http://\\([^/]*\\)/?token=.*|\\1|p' gui.txt)\n"
         "TOKEN=$(sed -n 's|.*?token=\\([0-9a-f]*\\).*|\\1|p' gui.txt)\n"
         "set +e\n" +
         body +
         "\"$R\" console --lcm \"$URL\" exit > exit.txt 2>&1; echo \"exit $?\" >> codes.txt\n"
         "wait $P; echo \"run $?\" >> codes.txt\n"
         "kill -INT $G; wait $G; echo \"gui $?\" >> codes.txt\n";
}

TEST(GuiCli, ServesARunOnTheBusAndSendsItsConsoleCommands) {
  SKIP_WITHOUT_NAMESPACES();
  const auto dir = scratch_dir("gui_cli");
  const int status = in_namespace(
      dir, gui_on_the_bus_script(
               shipped_scenario_arg("convoy_sim") + " --realtime --duration 120",
               "\"$P2\" \"ws://$HOSTPORT/ws?token=wrong\" --topics /rilbed/poses --count 1 --timeout 5 > wrong.txt "
               "2>&1; echo \"wrong $?\" >> codes.txt\n"
               "\"$P2\" \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/poses,/rilbed/console_reply --count 1000 "
               "--until /rilbed/console_reply --timeout 60 "
               "--send '/rilbed/console={\"command\":\"pause\"}' > probe.txt 2>&1; echo \"probe $?\" >> codes.txt\n"));
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  const std::string probe = read_file(dir / "probe.txt");
  for (const char* line : {"wrong 1", "probe 0", "exit 0", "run 0", "gui 0"}) {
    EXPECT_NE(codes.find(line), std::string::npos) << line << "\n" << codes << probe << read_file(dir / "gui.err");
  }
  EXPECT_NE(read_file(dir / "wrong.txt").find("declined"), std::string::npos) << read_file(dir / "wrong.txt");
  // Poses: every robot of the run, as the run's folder has them.
  const std::size_t first = probe.find("/rilbed/poses {");
  ASSERT_NE(first, std::string::npos) << probe;
  const auto poses = nlohmann::json::parse(probe.substr(first + 14, probe.find('\n', first) - first - 14));
  EXPECT_EQ(poses["robots"].size(), 8u);
  EXPECT_TRUE(poses["robots"][0].contains("behaviour"));
  // The pause was accepted by the run, and the run recorded who asked.
  EXPECT_NE(probe.find(R"(/rilbed/console_reply {"accepted":true)"), std::string::npos) << probe;
  EXPECT_NE(probe.find(R"("reason":"pause")"), std::string::npos) << probe;
  EXPECT_NE(read_file(dir / "run" / "events.csv").find(",console,0,0,paused by "), std::string::npos);
  std::filesystem::remove_all(dir);
}

// What a robot is and what its sensor models see reach a panel in another process: square
// robots' outlines on /rilbed/world (robot_bodies_t on the bus), a plug-in model's readings
// and marks on /rilbed/sensors (sensor_models_t).
TEST(GuiCli, BodiesAndSensorModelMarksReachAPanelOnTheBus) {
  SKIP_WITHOUT_NAMESPACES();
  const auto dir = scratch_dir("gui_cli_models");
  std::ofstream(dir / "point.txt") << "Sensor = {\nTarget X = 1.0\nTarget Y = 0.5\nNoise = 0\n}\n";
  const std::string library = (fs::path(RILBED_BINARY).parent_path() / "test_plugins" / "test_sensors.so").string();
  std::ofstream(dir / "squares.yaml") << "name: squares\nfield: {width_m: 1.5, height_m: 1.2}\nrobots:\n"
                                         "  - ids: 1-3\n    model: square\n    controller: wander\n"
                                         "    sensors:\n      proximity: {}\n      models:\n"
                                         "        - {library: " +
                                             library + ", name: beacon_range, parameters: point.txt}\n";
  const int status = in_namespace(
      dir, gui_on_the_bus_script("squares.yaml --realtime --duration 120",
                                 "\"$P2\" \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/world,/rilbed/sensors "
                                 "--count 12 --timeout 60 > probe.txt 2>&1; echo \"probe $?\" >> codes.txt\n"));
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt"), probe = read_file(dir / "probe.txt");
  for (const char* line : {"probe 0", "exit 0", "run 0", "gui 0"})
    EXPECT_NE(codes.find(line), std::string::npos) << line << "\n" << codes << probe << read_file(dir / "gui.err");
  bool outline = false, marks = false, readings = false;
  std::istringstream lines(probe);
  for (std::string line; std::getline(lines, line);) {
    const auto space = line.find(' ');
    if (space == std::string::npos || line.find('{') != space + 1) continue;
    const auto message = nlohmann::json::parse(line.substr(space + 1));
    for (const auto& robot : message["robots"]) {
      if (line.rfind("/rilbed/world ", 0) == 0 && robot.contains("body"))
        outline = outline || robot["body"]["outline"].size() == 4u;
      if (line.rfind("/rilbed/sensors ", 0) == 0) {
        // The model's two marks (a third, not finite, is dropped at the source).
        marks = marks || robot["marks"].size() == 2u;
        for (const auto& m : robot["models"]) readings = readings || m["name"] == "beacon_range";
      }
    }
  }
  EXPECT_TRUE(outline) << probe;
  EXPECT_TRUE(marks) << probe;
  EXPECT_TRUE(readings) << probe;
  std::filesystem::remove_all(dir);
}

TEST(GuiCli, VisionSettingsSetInTheBrowserReachARunOnTheBus) {
  SKIP_WITHOUT_NAMESPACES();
  const auto dir = scratch_dir("gui_cli_vision");
  const int status = in_namespace(
      dir,
      gui_on_the_bus_script(
          shipped_scenario_arg("convoy_mixed") + " --duration 120",
          // Once the run's poses come (it is running), one setParameters; its answer ends the probe.
          "\"$P2\" \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/poses --count 100000 --until parameterValues "
          "--timeout 60 "
          "--set-parameters "
          "'[{\"name\":\"vision.threshold\",\"value\":30},{\"name\":\"vision.contrast\",\"value\":1.25}]' "
          "> probe.txt 2>&1; echo \"probe $?\" >> codes.txt\n"
          "\"$P2\" \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/poses --count 100000 --until parameterValues "
          "--timeout 60 "
          "--set-parameters '[{\"name\":\"vision.contrast\",\"value\":9}]' > refused.txt 2>&1; echo \"refused $?\" >> "
          "codes.txt\n"
          // A viewer joining later: the settings as the run's status says (not only those set here).
          "for i in $(seq 1 100); do \"$P2\" \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/poses --count 100000 "
          "--until parameterValues --timeout 60 --get-parameters all > get.txt 2>&1; grep -q min_score get.txt && "
          "break; sleep 0.1; done\n"));
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  const std::string probe = read_file(dir / "probe.txt");
  for (const char* line : {"probe 0", "refused 0", "exit 0", "run 0", "gui 0"}) {
    EXPECT_NE(codes.find(line), std::string::npos) << line << "\n" << codes << probe << read_file(dir / "gui.err");
  }
  // The answer carries the values the run took; the run logged who set them.
  const std::size_t answer = probe.rfind("parameterValues {");
  ASSERT_NE(answer, std::string::npos) << probe;
  const auto values = nlohmann::json::parse(probe.substr(answer + 16, probe.find('\n', answer) - answer - 16));
  EXPECT_EQ(values["id"], "probe");
  std::map<std::string, double> by_name;
  for (const auto& p : values["parameters"]) by_name[p["name"]] = p["value"].get<double>();
  EXPECT_EQ(by_name["vision.threshold"], 30.0) << values.dump();
  EXPECT_EQ(by_name["vision.contrast"], 1.25) << values.dump();
  EXPECT_NE(read_file(dir / "run" / "events.csv").find("vision threshold 30 contrast 1.25 set by "), std::string::npos)
      << read_file(dir / "run" / "events.csv");
  // Refused by the run: said, and the values stay.
  const std::string refused = read_file(dir / "refused.txt");
  EXPECT_NE(refused.find("status 2 vision settings refused: contrast 9 is outside 0.2..5"), std::string::npos)
      << refused;
  EXPECT_NE(refused.find(R"("value":1.25)"), std::string::npos) << refused;
  const std::string got = read_file(dir / "get.txt");
  EXPECT_NE(got.find(R"({"name":"vision.min_score","value":0.75})"), std::string::npos) << got;
  EXPECT_NE(got.find(R"({"name":"vision.threshold","value":30.0})"), std::string::npos) << got;
  std::filesystem::remove_all(dir);
}

TEST(RunGui, ServesItsOwnRunAndADrivenRobotStopsWhenItsKeysStopAndItsDriverGoes) {
  // `rilbed run --gui`: the panel in the run's own process (its in-process bus). A client
  // drives emulated real robot 4 with one key-held message and leaves; the robot is
  // stopped 300 ms later (the keys stopped), then handed back; a second client ends the run.
  const fs::path dir = scratch_dir("run_gui");
  const fs::path script = dir / "drive.sh";
  std::ofstream(script)
      << "cd '" << dir.string()
      << "'\n"
         "'" RILBED_BINARY "' run "
      << shipped_scenario_arg("convoy_mixed")
      << " --duration 120 --gui --gui-port 0 --out run --quiet > run.txt 2> run.err &\n"
         "P=$!\n"
         "for i in $(seq 1 400); do grep -q 'token=' run.txt && break; sleep 0.05; done\n"
         "HOSTPORT=$(sed -n 's|.*http://\\([^/]*\\)/?token=.*|\\1|p' run.txt)\n"
         "TOKEN=$(sed -n 's|.*?token=\\([0-9a-f]*\\).*|\\1|p' run.txt)\n"
         "'" RILBED_WS_PROBE
         "' \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/poses --count 20 --timeout 60 "
         "--send '/rilbed/drive={\"id\":4,\"left\":40,\"right\":40}' > drive.txt 2>&1; echo \"drive $?\" >> codes.txt\n"
         // Wait for the hand drive's end in the run's events (a held stop, then given back).
         "for i in $(seq 1 400); do grep -q 'robot 4 driven 0 0' run/events.csv 2>/dev/null && break; sleep 0.05; "
         "done\n"
         "'" RILBED_WS_PROBE
         "' \"ws://$HOSTPORT/ws?token=$TOKEN\" --topics /rilbed/status,/rilbed/console_reply --until "
         "/rilbed/console_reply "
         "--count 1000 --timeout 60 --send '/rilbed/console={\"command\":\"exit\"}' > exit.txt 2>&1; echo \"exit $?\" "
         ">> codes.txt\n"
         "wait $P; echo \"run $?\" >> codes.txt\n";
  ASSERT_EQ(std::system(("/bin/sh '" + script.string() + "'").c_str()), 0);
  const std::string codes = read_file(dir / "codes.txt");
  const std::string printed = read_file(dir / "run.txt") + read_file(dir / "run.err");
  for (const char* line : {"drive 0", "exit 0", "run 0"}) {
    EXPECT_NE(codes.find(line), std::string::npos)
        << line << "\n"
        << codes << printed << read_file(dir / "exit.txt") << read_file(dir / "drive.txt");
  }
  const std::string events = read_file(dir / "run" / "events.csv");
  const std::size_t driven = events.find("robot 4 driven 40 40 for ");
  ASSERT_NE(driven, std::string::npos) << events;
  EXPECT_NE(events.find(" by gui 127.0.0.1:", driven), std::string::npos) << events;
  const std::size_t stopped = events.find("robot 4 driven 0 0 for ", driven);
  EXPECT_NE(stopped, std::string::npos) << events;
  // One event per change of speeds, not one per renewal of the hold.
  std::size_t holds = 0;
  for (std::size_t at = events.find("robot 4 driven 0 0"); at != std::string::npos;
       at = events.find("robot 4 driven 0 0", at + 1))
    ++holds;
  EXPECT_LE(holds, 2u) << events;
  EXPECT_NE(events.find("ended by gui 127.0.0.1:"), std::string::npos) << events;
  EXPECT_NE(read_file(dir / "exit.txt").find(R"("accepted":true,"client")"), std::string::npos)
      << read_file(dir / "exit.txt");
  EXPECT_NE(printed.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << printed;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e
