// End-to-end tests of agents in other processes (issue 18): `rilbed run` with a scenario's
// `agents:` block and `rilbed agent` processes, on a multicast bus inside a private network
// namespace (lcm_namespace.hpp), with and without 10 % packet loss. A lock-step run gives
// the in-process run's folder byte for byte; an agent process killed mid-run is found lost
// and its robots stop while the rest go on, and one started again for them rejoins.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// The shipped convoy scenario with an `agents:` block added.
fs::path convoy_with_agents(const fs::path& dir, const std::string& agents_block) {
  const fs::path file = dir / "convoy_agents.yaml";
  std::ofstream out(file);
  out << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml") << "\nagents: " << agents_block << "\n";
  return file;
}

// summary.json without the wall times (which no two runs share).
std::string summary_without_wall_times(const fs::path& file) {
  std::string s = read_file(file);
  s = std::regex_replace(s, std::regex(R"("(run_)?wall_s": [0-9.e+-]+,?)"), "");
  return s;
}

void expect_same_run_folder(const fs::path& a, const fs::path& b) {
  for (const char* file : {"trajectories.csv", "events.csv", "trajectories.svg"}) {
    const std::string left = read_file(a / file);
    EXPECT_FALSE(left.empty()) << a / file;
    EXPECT_TRUE(left == read_file(b / file)) << file << " differs between " << a << " and " << b;
  }
  EXPECT_EQ(summary_without_wall_times(a / "summary.json"), summary_without_wall_times(b / "summary.json"));
}

TEST(AgentsCli, LockStepRunWithTwoAgentProcessesEqualsTheInProcessRun) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("agents_lockstep");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 2}");
  const int status = in_namespace(dir,
                                  "\"$R\" run '" + (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string() +
                                      "' --fast --seed 5 --duration 40 --out local --quiet\n"
                                      "\"$R\" run '" + scenario.string() +
                                      "' --fast --seed 5 --duration 40 --out remote --lcm \"$URL\" > run.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt");
  // 401 steps, each one message for both processes (it fits in a datagram), and the end three times.
  EXPECT_NE(read_file(dir / "run.txt").find("agents: 404 quanta sent"), std::string::npos) << read_file(dir / "run.txt");
  expect_same_run_folder(dir / "local", dir / "remote");
}

TEST(AgentsCli, EightAgentProcessesFormTheConvoyUnderTenPercentLossAsInOneProcess) {
  SKIP_WITHOUT_NFT();
  const fs::path dir = scratch_dir("agents_loss");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 8}");
  const int status = in_namespace(dir,
                                  "\"$R\" run '" + (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string() +
                                      "' --fast --seed 8 --stop-when-formed --out local --quiet\n"
                                      "\"$R\" run '" + scenario.string() +
                                      "' --fast --seed 8 --stop-when-formed --out remote --lcm \"$URL\" > run.txt 2>&1\n",
                                  /*lossy=*/true);
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt");
  const std::string run = read_file(dir / "run.txt");
  EXPECT_NE(run.find("formed at"), std::string::npos) << run;
  // Quanta and answers were lost and sent again, and no process was given up on.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(run, m, std::regex(R"((\d+) sent again, \d+ duplicate answers, \d+ late, (\d+) processes lost)")))
      << run;
  EXPECT_GT(std::stol(m[1]), 0) << run;
  EXPECT_EQ(m[2], "0") << run;
  expect_same_run_folder(dir / "local", dir / "remote");
}

TEST(AgentsCli, AKilledAgentProcessIsLostTheRestGoOnAndARestartedOneRejoins) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("agents_kill");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 0}");
  const std::string s = "'" + scenario.string() + "'";
  // Waits (polling) until `file` holds `text`, at most 60 s.
  const std::string wait_for =
      "wait_for() { for i in $(seq 1 1200); do grep -q \"$2\" \"$1\" 2>/dev/null && return 0; sleep 0.05; done; "
      "echo \"timed out waiting for $2 in $1\" >&2; return 1; }\n";
  const int status = in_namespace(
      dir, wait_for +
               "\"$R\" agent --scenario " + s + " --ids 1-4 --lcm \"$URL\" > a1.txt 2>&1 &\nA1=$!\n"
               "\"$R\" agent --scenario " + s + " --ids 5-8 --lcm \"$URL\" > a2.txt 2>&1 &\nA2=$!\n"
               "\"$R\" run " + s + " --realtime --rt-factor 10 --seed 3 --duration 90 --out run --lcm \"$URL\" --quiet > run.txt 2>&1 &\n"
               "RUN=$!\n"
               // Ten simulated seconds in (the trajectories are flushed every 100 rows), robots 5-8's process dies.
               "wait_for run/trajectories.csv '^10\\.[0-9]*,1,'\n"
               "kill -9 $A2; date +%s.%N > killed_at\n"
               "wait_for run/events.csv 'lost: process'\n"
               "date +%s.%N > lost_at\n"
               "\"$R\" agent --scenario " + s + " --ids 5-8 --lcm \"$URL\" > a3.txt 2>&1 &\nA3=$!\n"
               "wait_for run/events.csv 'rejoined'\n"
               "wait $RUN\n"
               "kill $A1 $A3; wait $A1 $A3 || true\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt") << read_file(dir / "run" / "events.csv");
  const double detection_s = std::stod(read_file(dir / "lost_at")) - std::stod(read_file(dir / "killed_at"));
  std::printf("a killed agent process was reported lost %.2f s after it died (dead_after_ms 750, the default; polled every 50 ms)\n",
              detection_s);
  const std::string events = read_file(dir / "run" / "events.csv");
  EXPECT_NE(events.find("(robots 5,6,7,8) stopped answering"), std::string::npos) << events;
  for (int id = 5; id <= 8; ++id) {
    EXPECT_NE(events.find(",agent," + std::to_string(id) + ",0,rejoined: process"), std::string::npos) << events;
  }
  // While lost, robots 5-8 stood still (marked lost) and robot 2 kept deciding.
  const std::string trajectories = read_file(dir / "run" / "trajectories.csv");
  EXPECT_NE(trajectories.find(",5,"), std::string::npos);
  std::istringstream in(trajectories);
  std::string line;
  int lost_rows = 0, robot2_after_loss = 0;
  bool seen_lost = false;
  while (std::getline(in, line)) {
    if (line.ends_with(",lost")) {
      ++lost_rows;
      seen_lost = true;
    } else if (seen_lost && line.find(",2,") != std::string::npos) {
      ++robot2_after_loss;
    }
  }
  EXPECT_GT(lost_rows, 0);
  EXPECT_GT(robot2_after_loss, 0);
}

TEST(AgentsCli, ARunWhoseAgentsNeverComeNamesTheMissingRobots) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("agents_missing");
  const fs::path scenario = convoy_with_agents(dir, "{ids: 3-4, announce_timeout_s: 0.5}");
  const int status = in_namespace(dir, "set +e\n\"$R\" run '" + scenario.string() +
                                           "' --fast --seed 1 --duration 5 --lcm \"$URL\" > run.txt 2>&1\necho $? > rc\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  EXPECT_EQ(read_file(dir / "rc"), "1\n");
  EXPECT_NE(read_file(dir / "run.txt").find("no agent process announced robots 3,4"), std::string::npos)
      << read_file(dir / "run.txt");
}

// Two "machines": network namespaces joined by a veth pair, each with an address of a
// private test range and a multicast route on its end of the pair. The run and robots 1-4's
// agent process are on one, robots 5-8's on the other; the bus crosses the pair (ttl=1).
TEST(AgentsCli, AgentsOnTwoMachinesJoinedByAVethPairGiveTheInProcessRun) {
  SKIP_WITHOUT_NAMESPACES();
  if (std::system("ip netns add rilbed_probe_$$ >/dev/null 2>&1 && ip netns del rilbed_probe_$$") != 0) {
    GTEST_SKIP() << "cannot make named network namespaces here (ip netns add needs root)";
  }
  const fs::path dir = scratch_dir("agents_two_machines");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 0}");
  const std::string s = "'" + scenario.string() + "'";
  const fs::path script = dir / "machines.sh";
  std::ofstream(script)
      << "set -e\nR='" << RILBED_BINARY << "'\ncd '" << dir.string() << "'\n"
      << "A=rilbed_a_$$; B=rilbed_b_$$\n"
      << "cleanup() { [ -n \"$AGENTS\" ] && kill $AGENTS 2>/dev/null; wait 2>/dev/null; ip netns del $A 2>/dev/null; "
         "ip netns del $B 2>/dev/null; true; }\ntrap cleanup EXIT\n"
      << "ip netns add $A; ip netns add $B\n"
      << "ip link add veth_a netns $A type veth peer name veth_b netns $B\n"
      << "ip -n $A addr add 10.203.0.1/24 dev veth_a; ip -n $B addr add 10.203.0.2/24 dev veth_b\n"
      << "for n in $A $B; do ip -n $n link set lo up; done\n"
      << "ip -n $A link set veth_a up multicast on; ip -n $B link set veth_b up multicast on\n"
      << "ip -n $A route add 224.0.0.0/4 dev veth_a; ip -n $B route add 224.0.0.0/4 dev veth_b\n"
      << "URL='udpm://239.255.76.67:7667?ttl=1'\n"
      << "\"$R\" run '" << (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string()
      << "' --fast --seed 6 --duration 30 --out local --quiet\n"
      << "ip netns exec $A \"$R\" agent --scenario " << s << " --ids 1-4 --lcm \"$URL\" > agent_a.txt 2>&1 &\nAGENTS=$!\n"
      << "ip netns exec $B \"$R\" agent --scenario " << s << " --ids 5-8 --lcm \"$URL\" > agent_b.txt 2>&1 &\n"
      << "AGENTS=\"$AGENTS $!\"\n"
      << "ip netns exec $A \"$R\" run " << s << " --fast --seed 6 --duration 30 --out remote --lcm \"$URL\" > run.txt 2>&1\n";
  const int status = std::system(("/bin/bash '" + script.string() + "' > '" + (dir / "machines.log").string() + "' 2>&1").c_str());
  ASSERT_EQ(status, 0) << read_file(dir / "machines.log") << read_file(dir / "run.txt") << read_file(dir / "agent_b.txt");
  EXPECT_NE(read_file(dir / "run.txt").find("0 processes lost"), std::string::npos) << read_file(dir / "run.txt");
  expect_same_run_folder(dir / "local", dir / "remote");
}

TEST(AgentsCli, AgentsInOtherProcessesNeedABusTheyReach) {
  const fs::path dir = scratch_dir("agents_no_bus");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 2}");
  const CommandResult r = run_rilbed("run '" + scenario.string() + "' --fast --seed 1 --duration 5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("give --lcm URL"), std::string::npos) << r.err;
  // A wrong agents block is named with its line.
  std::ofstream(dir / "bad.yaml") << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml")
                                  << "\nagents: {processes: 2, ids: 9}\n";
  const CommandResult bad = run_rilbed("run '" + (dir / "bad.yaml").string() + "' --fast");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("agents.ids: there is no robot 9"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace rilbed::e2e
