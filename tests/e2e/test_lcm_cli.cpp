// End-to-end tests of a run on an LCM bus: `rilbed run --lcm` and `rilbed watch` as real
// processes talking over UDP multicast inside a private network namespace (`unshare -n`,
// then loopback up with multicast; no packet leaves the namespace).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

TEST(LcmCli, WatchShowsARunOverMulticastAndItsEnd) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("lcm_watch");
  const int status =
      in_namespace(dir,
                   "\"$R\" watch --lcm \"$URL\" --until-ended --for 60 > watch.txt 2>&1 &\n"
                   "W=$!\n"
                   // A second watcher on another prefix hears nothing of this run.
                   "\"$R\" watch --lcm \"$URL\" --channel-prefix OTHER_ --for 4 --silence 1 > other.txt 2>&1 &\n"
                   "O=$!\n"
                   "\"$R\" run " +
                       shipped_scenario_arg("convoy_sim") +
                       " --realtime --rt-factor 5 --stop-when-formed --lcm \"$URL\" --quiet > run.txt 2>&1\n"
                       "wait $W\n"
                       "set +e\nwait $O\necho \"other exit $?\" >> other.txt\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt") << read_file(dir / "watch.txt");
  const std::string watch = read_file(dir / "watch.txt");
  EXPECT_NE(watch.find("watching convoy_sim on udpm://239.255.76.67:7667?ttl=0: 8 robots (0 real)"), std::string::npos)
      << watch;
  // It may join a moment after the run began: any second's status line will do.
  EXPECT_NE(watch.find("s running x5.0  1:wait"), std::string::npos) << watch;
  EXPECT_NE(watch.find("formed: convoy formed"), std::string::npos) << watch;
  EXPECT_NE(watch.find("(ended by formed)"), std::string::npos) << watch;
  EXPECT_NE(read_file(dir / "run.txt").find("formed at"), std::string::npos);
  const std::string other = read_file(dir / "other.txt");
  EXPECT_NE(other.find("no rilbed run heard on udpm://239.255.76.67:7667?ttl=0 for 1 s (channels OTHER_RILBED_*)"),
            std::string::npos)
      << other;
  EXPECT_NE(other.find("other exit 1"), std::string::npos) << other;
  fs::remove_all(dir);
}

TEST(LcmCli, BadBusesAndPrefixesAreClearErrors) {
  CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --duration 1 --lcm nosuch://x");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot open the LCM bus 'nosuch://x'"), std::string::npos) << r.err;
  r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --duration 1 --lcm memq:// --channel-prefix 'a b'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("may hold only letters, digits and '_'"), std::string::npos) << r.err;
  // The in-process bus with nobody listening: the run is as without it.
  r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --stop-when-formed --seed 2 --lcm memq://");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("seed 2: formed at"), std::string::npos) << r.out;
  r = run_rilbed("watch --lcm nosuch://x --for 1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot open the LCM bus"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace rilbed::e2e

namespace rilbed::e2e {
namespace {

// A run recorded with --record, then its folder written again from the recording alone.
TEST(LcmCli, RecordThenReplayGivesTheSameRunFolder) {
  const fs::path dir = scratch_dir("lcm_record");
  const std::string log = (dir / "run.lcm").string();
  CommandResult r =
      run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --all-virtual --stop-when-formed --seed 9 --out '" +
                 (dir / "live").string() + "' --record '" + log + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_rilbed("replay '" + log + "' --out '" + (dir / "replayed").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote "), std::string::npos) << r.out;
  for (const char* file : {"trajectories.csv", "events.csv", "summary.json", "trajectories.svg"}) {
    const std::string live = read_file(dir / "live" / file);
    EXPECT_FALSE(live.empty()) << file;
    EXPECT_EQ(live, read_file(dir / "replayed" / file)) << file;
  }
  // A recording cut short: the folder holds what it has, and replay says so (exit 1).
  const std::string whole = read_file(log);
  std::ofstream(dir / "cut.lcm", std::ios::binary) << whole.substr(0, whole.size() / 2);
  r = run_rilbed("replay '" + (dir / "cut.lcm").string() + "' --out '" + (dir / "cut").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("ends before the run did"), std::string::npos) << r.err;
  const std::string rows = read_file(dir / "cut" / "trajectories.csv");
  EXPECT_GT(rows.size(), 1000u);
  EXPECT_EQ(read_file(dir / "live" / "trajectories.csv").rfind(rows.substr(0, rows.rfind('\n', rows.size() - 2)), 0),
            0u);
  // Not a log at all.
  std::ofstream(dir / "junk.lcm") << "this is not an LCM log\n";
  r = run_rilbed("replay '" + (dir / "junk.lcm").string() + "' --out '" + (dir / "junk").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("holds no LCM events"), std::string::npos) << r.err;
  r = run_rilbed("replay '" + log + "'");
  EXPECT_EQ(r.exit_code, 2);
  r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --seeds 2 --record '" + log + "'");
  EXPECT_EQ(r.exit_code, 2);
  fs::remove_all(dir);
}

// Other programs: lcm-logplayer plays a rilbed recording that `rilbed watch` shows, and a
// run recorded by lcm-logger replays to the run's own folder.
TEST(LcmCli, LcmsOwnToolsPlayAndRecordARun) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("lcm_tools");
  const int status = in_namespace(
      dir,
      // Recorded in (scaled) real time, so that the player paces it as it was: a burst of a
      // whole run at once would overflow the watcher's socket buffer, as UDP does.
      "\"$R\" run " + shipped_scenario_arg("convoy_sim") +
          " --realtime --rt-factor 5 --stop-when-formed --seed 4 --record run.lcm --quiet > run.txt\n"
          "\"$R\" watch --lcm \"$URL\" --until-ended --for 60 > watch.txt 2>&1 &\n"
          "W=$!\n"
          // The watcher must be listening before the player starts: wait until it has subscribed
          // (it says nothing until it hears), by polling its socket.
          "for i in $(seq 1 100); do ss -lun 2>/dev/null | grep -q 7667 && break; sleep 0.05; done\n"
          "lcm-logplayer --lcm-url=\"$URL\" run.lcm > player.txt 2>&1\n"
          "wait $W\n"
          "lcm-logger --lcm-url=\"$URL\" logged.lcm > logger.txt 2>&1 &\n"
          "L=$!\n"
          "for i in $(seq 1 100); do ss -lun 2>/dev/null | grep -q 7667 && break; sleep 0.05; done\n"
          "\"$R\" run " +
          shipped_scenario_arg("convoy_sim") +
          " --realtime --rt-factor 20 --stop-when-formed --seed 4 --lcm \"$URL\" --out live --quiet > run2.txt\n"
          "kill -INT $L; wait $L || true\n"
          "\"$R\" replay logged.lcm --out from_logger > replay.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "watch.txt") << read_file(dir / "replay.txt");
  const std::string watch = read_file(dir / "watch.txt");
  EXPECT_NE(watch.find("watching convoy_sim"), std::string::npos) << watch;
  EXPECT_NE(watch.find("(ended by formed)"), std::string::npos) << watch;
  for (const char* file : {"trajectories.csv", "events.csv", "summary.json"}) {
    EXPECT_EQ(read_file(dir / "live" / file), read_file(dir / "from_logger" / file)) << file;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e

namespace rilbed::e2e {
namespace {

// `rilbed console` against a running mixed run over multicast: pause stops the real
// robots where they are (they do not move while the run is paused), resume goes on, a
// wrong token and bad commands are refused with the reason, exit ends the run; every
// command is answered, and the run records them as events.
// A mixed run recorded with its camera's frames: `rilbed detect` on the recording finds
// what the run's camera found, frame by frame (the frames went through JPEG, so to within
// a fraction of a pixel), and finds less when told to ask more of a marker.
TEST(LcmCli, ARecordingsFramesGoThroughTheVisionPipelineAgain) {
  const fs::path dir = scratch_dir("lcm_frames");
  const std::string rec = (dir / "rec.lcm").string();
  CommandResult r = run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --duration 3 --quiet --record '" +
                               rec + "' --record-frames --out '" + (dir / "run").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_rilbed("detect '" + rec + "' --ids 4-5 -q --csv '" + (dir / "again.csv").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("camera frames"), std::string::npos) << r.err;
  // The run's own detections (its folder's detections.csv, frames from 1) against the new
  // ones (frames from 0).
  std::map<std::pair<int, int>, std::array<double, 3>> live;
  std::istringstream rows(read_file(dir / "run" / "detections.csv"));
  std::string row;
  std::getline(rows, row);
  ASSERT_EQ(row, "frame,t_s,id,u_px,v_px,heading_deg,score,diameter_px,x_m,y_m,theta_deg");
  while (std::getline(rows, row)) {
    int frame = 0, id = 0;
    double t = 0, u = 0, v = 0, heading = 0;
    ASSERT_EQ(std::sscanf(row.c_str(), "%d,%lf,%d,%lf,%lf,%lf", &frame, &t, &id, &u, &v, &heading), 6) << row;
    live[{frame - 1, id}] = {u, v, heading};
  }
  ASSERT_GE(live.size(), 2u * 60u);  // 30 fps for 3 s, two real robots
  std::istringstream again(read_file(dir / "again.csv"));
  std::getline(again, row);
  std::size_t matched = 0;
  while (std::getline(again, row)) {
    int frame = 0, id = 0;
    double u = 0, v = 0, heading = 0;
    ASSERT_EQ(std::sscanf(row.c_str(), "%d,%d,%lf,%lf,%lf", &frame, &id, &u, &v, &heading), 5) << row;
    const auto it = live.find({frame, id});
    if (it == live.end()) continue;
    ++matched;
    EXPECT_NEAR(u, it->second[0], 0.5) << row;
    EXPECT_NEAR(v, it->second[1], 0.5) << row;
    EXPECT_NEAR(std::remainder(heading - it->second[2], 360.0), 0.0, 3.0) << row;
  }
  EXPECT_GE(matched, live.size() * 95 / 100);
  // The recording gives the same folder again, detections too (the frames are skipped).
  r = run_rilbed("replay '" + rec + "' --out '" + (dir / "replayed").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* file : {"trajectories.csv", "events.csv", "summary.json", "detections.csv", "trajectories.svg"}) {
    EXPECT_EQ(read_file(dir / "run" / file), read_file(dir / "replayed" / file)) << file;
  }
  // Other settings give another result: a score no marker reaches finds nothing.
  r = run_rilbed("detect '" + rec + "' --ids 4-5 -q --min-score 0.999 --csv '" + (dir / "strict.csv").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(read_file(dir / "strict.csv").size(), read_file(dir / "again.csv").size() / 2);
  // A recording without frames says how to make one.
  r = run_rilbed("run " + shipped_scenario_arg("convoy_mixed") + " --duration 1 --quiet --record '" +
                 (dir / "plain.lcm").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_rilbed("detect '" + (dir / "plain.lcm").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("holds no camera frames"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--record-frames"), std::string::npos) << r.err;
  // --record-frames needs a recording, and a camera.
  r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --duration 1 --record-frames");
  EXPECT_EQ(r.exit_code, 2);
  r = run_rilbed("run " + shipped_scenario_arg("convoy_sim") + " --duration 1 --record-frames --record '" +
                 (dir / "x.lcm").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("has no camera"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

TEST(LcmCli, TheConsoleDrivesARobotSwitchesTheModeAndResetsTheRun) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("lcm_console_more");
  const int status = in_namespace(
      dir,
      "\"$R\" run " + shipped_scenario_arg("convoy_mixed") +
          " --duration 120 --lcm \"$URL\" --out run --record rec.lcm --quiet > run.txt 2> run.err &\n"
          "P=$!\n"
          "set +e\n"
          "for i in $(seq 1 100); do \"$R\" console --lcm \"$URL\" --timeout-ms 200 --token x pause 2>/dev/null; "
          "grep -q 'refused' run.err && break; sleep 0.1; done\n"
          // A real (emulated) robot driven by hand, backwards on one wheel. The console answers
          // before the run has placed its robots and started: ask until the run itself answers.
          "for i in $(seq 1 300); do \"$R\" console --lcm \"$URL\" drive 4 30 -30 --for 1 > d1.txt 2>&1; c=$?; "
          "grep -q 'no run is running' d1.txt || break; sleep 0.1; done\n"
          "echo \"drive $c\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" drive 42 30 30 --for 1 > d2.txt 2>&1; echo \"drive-none $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" drive 4 30 30 > d3.txt 2>&1; echo \"drive-nofor $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" mode central > m1.txt 2>&1; echo \"central $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" mode central > m2.txt 2>&1; echo \"central-again $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" mode distributed > m3.txt 2>&1; echo \"distributed $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" vision threshold 30 contrast 1.2 > v1.txt 2>&1; echo \"vision $?\" >> "
          "codes.txt\n"
          "\"$R\" console --lcm \"$URL\" vision contrast 9 > v2.txt 2>&1; echo \"vision-bad $?\" >> codes.txt\n"
          "\"$R\" console --lcm \"$URL\" reset > r1.txt 2>&1; echo \"reset $?\" >> codes.txt\n"
          // The run starts over (its real robots placed again): ask until the new one answers.
          "for i in $(seq 1 300); do \"$R\" console --lcm \"$URL\" --timeout-ms 300 exit > e1.txt 2>&1 && break; sleep "
          "0.1; done\n"
          "echo \"exit $?\" >> codes.txt\n"
          "wait $P; echo \"run $?\" >> codes.txt\n"
          "\"$R\" replay rec.lcm --out replayed > replay.txt 2>&1; echo \"replay $?\" >> codes.txt\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  for (const char* line : {"drive 0", "drive-none 1", "drive-nofor 2", "central 0", "central-again 1", "distributed 0",
                           "vision 0", "vision-bad 1", "reset 0", "exit 0", "run 0", "replay 0"}) {
    EXPECT_NE(codes.find(line), std::string::npos) << line << "\n" << codes << read_file(dir / "run.err");
  }
  EXPECT_NE(read_file(dir / "d1.txt").find("accepted: drive 4 30 -30 1"), std::string::npos)
      << read_file(dir / "d1.txt");
  EXPECT_NE(read_file(dir / "d2.txt").find("refused: this run has no robot 42"), std::string::npos);
  EXPECT_NE(read_file(dir / "d3.txt").find("drive takes ID LEFT RIGHT and --for SECONDS"), std::string::npos);
  EXPECT_NE(read_file(dir / "m2.txt").find("refused: the convoy is in central mode already"), std::string::npos);
  EXPECT_NE(read_file(dir / "v2.txt").find("refused: contrast 9 is outside 0.2..5"), std::string::npos)
      << read_file(dir / "v2.txt");
  const std::string err = read_file(dir / "run.err");
  EXPECT_NE(err.find("reset from the console: the run starts over"), std::string::npos) << err;
  // The folder holds the run that went on to its end; the recording holds both.
  const std::string events = read_file(dir / "run" / "events.csv");
  EXPECT_EQ(events.find("reset by"), std::string::npos) << events;
  EXPECT_NE(events.find(",console,0,0,ended by "), std::string::npos) << events;
  EXPECT_EQ(events, read_file(dir / "replayed" / "events.csv"));
  EXPECT_EQ(read_file(dir / "run" / "trajectories.csv"), read_file(dir / "replayed" / "trajectories.csv"));
  EXPECT_NE(read_file(dir / "run.txt").find("robot 4 (emulated): last speed 0 0"), std::string::npos);
  // The first run's events are in the recording: replay up to the reset.
  std::ifstream rec(dir / "rec.lcm", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(rec)), std::istreambuf_iterator<char>());
  for (const char* text : {"robot 4 driven 30 -30 for 1 s by ", "mode central set by ", "mode distributed set by ",
                           "vision threshold 30 contrast 1.2 set by ", "reset by ", "RILBED_VISION"}) {
    EXPECT_NE(bytes.find(text), std::string::npos) << text;
  }
  fs::remove_all(dir);
}

TEST(LcmCli, TheConsoleSteersARunAndPauseStopsItsRealRobots) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("lcm_console");
  const int status = in_namespace(
      dir, "\"$R\" run " + shipped_scenario_arg("convoy_mixed") +
               " --duration 60 --lcm \"$URL\" --out run --quiet > run.txt 2> run.err &\n"
               "P=$!\n"
               "set +e\n"
               // The run answers once it is up: ask until it does (a refused command proves it is there).
               "for i in $(seq 1 100); do \"$R\" console --lcm \"$URL\" --timeout-ms 200 --token x pause 2>/dev/null; "
               "grep -q 'refused' run.err && break; sleep 0.1; done\n"
               // The console answers before the run has placed its robots: pause once the run itself answers.
               "for i in $(seq 1 300); do \"$R\" console --lcm \"$URL\" pause > c1.txt 2>&1; c=$?; "
               "grep -q 'no run is running' c1.txt || break; sleep 0.1; done\n"
               "echo \"pause $c\" >> codes.txt\n"
               "sleep 1.5\n"
               "\"$R\" console --lcm \"$URL\" resume > c2.txt 2>&1; echo \"resume $?\" >> codes.txt\n"
               "\"$R\" console --lcm \"$URL\" rt-factor 2 > c3.txt 2>&1; echo \"rt $?\" >> codes.txt\n"
               "\"$R\" console --lcm \"$URL\" --token 00 exit > c4.txt 2>&1; echo \"badtoken $?\" >> codes.txt\n"
               "sleep 1\n"
               "\"$R\" console --lcm \"$URL\" exit > c5.txt 2>&1; echo \"exit $?\" >> codes.txt\n"
               "wait $P; echo \"run $?\" >> codes.txt\n"
               "\"$R\" console --lcm \"$URL\" --timeout-ms 300 pause > c6.txt 2>&1; echo \"gone $?\" >> codes.txt\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  for (const char* line : {"pause 0", "resume 0", "rt 1", "badtoken 1", "exit 0", "run 0", "gone 1"}) {
    EXPECT_NE(codes.find(line), std::string::npos) << line << "\n" << codes << read_file(dir / "run.err");
  }
  EXPECT_NE(read_file(dir / "c3.txt").find("refused: a run with real robots runs at a factor of 1"), std::string::npos);
  EXPECT_NE(read_file(dir / "c4.txt").find("refused: wrong token"), std::string::npos);
  EXPECT_NE(read_file(dir / "c6.txt").find("no run answered"), std::string::npos);
  EXPECT_NE(read_file(dir / "run.txt").find("ended by console"), std::string::npos) << read_file(dir / "run.txt");
  EXPECT_NE(read_file(dir / "run.err").find("run token "), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "xdg" / "rilbed" / "token"));  // a finished run's token opens nothing
  EXPECT_NE(read_file(dir / "run.txt").find("robot 4 (emulated): last speed 0 0"), std::string::npos);
  const std::string events = read_file(dir / "run" / "events.csv");
  EXPECT_NE(events.find(",console,0,0,paused by "), std::string::npos) << events;
  EXPECT_NE(events.find(",console,0,0,resumed by "), std::string::npos) << events;
  EXPECT_NE(events.find(",console,0,0,refused 'exit' (wrong token) from "), std::string::npos) << events;
  EXPECT_NE(events.find(",console,0,0,ended by "), std::string::npos) << events;
  // Across the pause (1.5 s of wall time, no simulated time) the real robots stood still:
  // between the samples before and after it each moved less than it would have in half a
  // second at the speed it had before (had it driven on, it would have moved 1.5 s worth;
  // the half second leaves room for the stop's way to the robot on a slow, sanitized build).
  const std::size_t paused_at = events.find(",console,0,0,paused by ");
  const double t_pause = std::stod(events.substr(events.rfind('\n', paused_at) + 1));
  std::istringstream rows(read_file(dir / "run" / "trajectories.csv"));
  std::string row;
  std::map<int, std::vector<std::pair<double, std::pair<double, double>>>> real;  // t, (x, y) of robots 4 and 5
  std::getline(rows, row);
  while (std::getline(rows, row)) {
    std::istringstream f(row);
    std::string t, id, x, y;
    std::getline(f, t, ',');
    std::getline(f, id, ',');
    std::getline(f, x, ',');
    std::getline(f, y, ',');
    if (id == "4" || id == "5") real[std::stoi(id)].push_back({std::stod(t), {std::stod(x), std::stod(y)}});
  }
  auto distance = [](const auto& a, const auto& b) {
    return std::hypot(b.second.first - a.second.first, b.second.second - a.second.second);
  };
  for (const auto& [id, samples] : real) {
    for (std::size_t k = 2; k < samples.size(); ++k) {
      if (samples[k - 1].first <= t_pause && samples[k].first > t_pause) {
        const double speed_mps =
            distance(samples[k - 2], samples[k - 1]) / (samples[k - 1].first - samples[k - 2].first);
        const double moved = distance(samples[k - 1], samples[k]);
        EXPECT_LT(moved, 0.5 * speed_mps + 0.005)
            << "robot " << id << " moved " << moved << " m across the pause, at " << speed_mps << " m/s before it";
      }
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rilbed::e2e
