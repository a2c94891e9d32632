// End-to-end tests of agents in other processes: `rilbed run` with a scenario's
// `agents:` block and `rilbed agent` processes, on a multicast bus inside a private network
// namespace (lcm_namespace.hpp), with and without 10 % packet loss. A lock-step run gives
// the in-process run's folder byte for byte; an agent process killed mid-run is found lost
// and its robots stop while the rest go on, and one started again for them rejoins.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>

#include "lcm_namespace.hpp"
#include "run_command.hpp"
#include "session/agent_processes.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// The shipped convoy scenario with an `agents:` block added.
fs::path convoy_with_agents(const fs::path& dir, const std::string& agents_block) {
  const fs::path file = dir / "convoy_agents.yaml";
  std::ofstream out(file);
  out << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml") << "\nagents: " << agents_block
      << "\n";
  return file;
}

// How often `needle` occurs in `text`.
int count_of(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
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
  const int status = in_namespace(
      dir, "\"$R\" run '" + (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string() +
               "' --fast --seed 5 --duration 40 --out local --quiet\n"
               "\"$R\" run '" +
               scenario.string() + "' --fast --seed 5 --duration 40 --out remote --lcm \"$URL\" > run.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt");
  // 401 steps, each one message for both processes (it fits in a datagram), and the end three times.
  EXPECT_NE(read_file(dir / "run.txt").find("agents: 404 quanta sent"), std::string::npos)
      << read_file(dir / "run.txt");
  expect_same_run_folder(dir / "local", dir / "remote");
}

// Safety: a real robot whose agent process dies is stopped over its serial link.
// convoy_mixed's real (emulated) Kheperas 4 and 5 have their controllers in an agent
// process, killed mid-run; from then on the camera sees both stand still.
TEST(AgentsCli, RealRobotsWhoseAgentProcessDiesAreStoppedOverTheirLinks) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("agents_real_lost");
  const fs::path scenario = dir / "mixed_agents.yaml";
  std::ofstream(scenario) << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_mixed.yaml")
                          << "\nagents: {ids: 4-5, processes: 0}\n";
  const std::string s = "'" + scenario.string() + "'";
  const std::string wait_for =
      "wait_for() { for i in $(seq 1 1200); do grep -q \"$2\" \"$1\" 2>/dev/null && return 0; sleep 0.05; done; "
      "echo \"timed out waiting for $2 in $1\" >&2; return 1; }\n";
  const int status =
      in_namespace(dir, wait_for + "\"$R\" agent --scenario " + s +
                            " --ids 4-5 --lcm \"$URL\" > agent.txt 2>&1 &\nA=$!\n" + "\"$R\" run " + s +
                            " --realtime --seed 2 --duration 12 --no-place --out run --lcm \"$URL\" > run.txt 2>&1 &\n"
                            "RUN=$!\n"
                            "wait_for run/trajectories.csv '^4\\.[0-9]*,4,'\n"
                            "kill -9 $A\n"
                            "wait_for run/events.csv 'lost: process'\n"
                            "wait $RUN\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt")
                       << read_file(dir / "run" / "events.csv");
  const std::string run = read_file(dir / "run.txt");
  EXPECT_NE(run.find("robot 4 (emulated): last speed 0 0"), std::string::npos) << run;
  EXPECT_NE(run.find("robot 5 (emulated): last speed 0 0"), std::string::npos) << run;
  // Poses of robots 4 and 5 as the camera saw them: t, x, y, and whether marked lost.
  struct Row {
    double t_s, x_m, y_m;
    bool lost;
  };
  std::map<int, std::vector<Row>> rows;
  std::istringstream in(read_file(dir / "run" / "trajectories.csv"));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) f.push_back(cell);
    if (f.size() < 6 || (f[1] != "4" && f[1] != "5")) continue;
    rows[std::stoi(f[1])].push_back({std::stod(f[0]), std::stod(f[2]), std::stod(f[3]), f[5] == "lost"});
  }
  double moved_before_m = 0.0;
  for (const int id : {4, 5}) {
    const std::vector<Row>& r = rows[id];
    const auto first_lost = std::find_if(r.begin(), r.end(), [](const Row& row) { return row.lost; });
    ASSERT_NE(first_lost, r.end()) << "robot " << id << " was never marked lost";
    // Every row from then on is lost, and after half a second (the last command's effect,
    // the camera's latency) the robot stands still.
    std::optional<Row> settled;
    double drift_m = 0.0;
    for (auto it = first_lost; it != r.end(); ++it) {
      EXPECT_TRUE(it->lost) << "robot " << id << " at " << it->t_s;
      if (it->t_s < first_lost->t_s + 0.5) continue;
      if (!settled) settled = *it;
      drift_m = std::max(drift_m, std::hypot(it->x_m - settled->x_m, it->y_m - settled->y_m));
    }
    ASSERT_TRUE(settled) << "robot " << id << ": no rows half a second after its loss";
    EXPECT_GT(r.back().t_s - settled->t_s, 2.0) << "robot " << id;
    EXPECT_LT(drift_m, 0.004) << "robot " << id << " moved after its stop";
    // Before the loss, for comparison: how far it was from where it was lost (a convoy
    // follower may be waiting in the last second, so the whole time before counts).
    for (auto it = r.begin(); it != first_lost; ++it)
      moved_before_m = std::max(moved_before_m, std::hypot(it->x_m - first_lost->x_m, it->y_m - first_lost->y_m));
  }
  EXPECT_GT(moved_before_m, 0.01) << "neither real robot moved before its agent died: the test shows nothing";
}

// A batch of seeds through the same agent processes (each run a new nonce, its controllers
// built afresh), one of them a C controller (wander.yaml's robot 6, peek/poke): every seed's
// folder is the in-process batch's.
TEST(AgentsCli, ABatchWithACControllerInAgentProcessesEqualsTheInProcessBatch) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("agents_batch");
  const fs::path wander = fs::path(RILBED_SOURCE_DIR) / "scenarios" / "wander.yaml";
  const fs::path scenario = dir / "wander_agents.yaml";
  std::ofstream(scenario) << read_file(wander) << "\nagents: {processes: 2}\n";
  const int status =
      in_namespace(dir, "\"$R\" run '" + wander.string() +
                            "' --fast --seeds 3 --jobs 1 --duration 20 --out local --quiet\n"
                            "\"$R\" run '" +
                            scenario.string() +
                            "' --fast --seeds 3 --jobs 1 --duration 20 --out remote --lcm \"$URL\" > run.txt 2>&1\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt");
  const std::string run = read_file(dir / "run.txt");
  // Three runs, each 201 steps and its end (sent three times).
  EXPECT_EQ(count_of(run, "agents: 204 quanta sent"), 3) << run;
  for (const char* seed : {"seed_1", "seed_2", "seed_3"})
    expect_same_run_folder(dir / "local" / seed, dir / "remote" / seed);
}

TEST(AgentsCli, EightAgentProcessesFormTheConvoyUnderTenPercentLossAsInOneProcess) {
  SKIP_WITHOUT_NFT();
  const fs::path dir = scratch_dir("agents_loss");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 8}");
  const int status = in_namespace(
      dir,
      "\"$R\" run '" + (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string() +
          "' --fast --seed 8 --stop-when-formed --out local --quiet\n"
          "\"$R\" run '" +
          scenario.string() + "' --fast --seed 8 --stop-when-formed --out remote --lcm \"$URL\" > run.txt 2>&1\n",
      /*lossy=*/true);
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt");
  const std::string run = read_file(dir / "run.txt");
  EXPECT_NE(run.find("formed at"), std::string::npos) << run;
  // Quanta and answers were lost and sent again, and no process was given up on.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      run, m, std::regex(R"((\d+) sent again, \d+ duplicate answers, \d+ late, (\d+) processes lost)")))
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
  // Eight agent processes, one per robot, started by hand (so that the test knows robot
  // 5's); the run in real time, ten times faster than the wall clock.
  const int status = in_namespace(
      dir, wait_for +
               "AGENTS=\nfor id in 1 2 3 4 5 6 7 8; do\n"
               "  \"$R\" agent --scenario " +
               s +
               " --ids $id --lcm \"$URL\" > agent_$id.txt 2>&1 &\n"
               "  [ $id = 5 ] && A5=$! || AGENTS=\"$AGENTS $!\"\ndone\n"
               "\"$R\" run " +
               s +
               " --realtime --rt-factor 10 --seed 3 --duration 90 --out run --lcm \"$URL\" --quiet > run.txt 2>&1 &\n"
               "RUN=$!\n"
               // Three simulated seconds in, before the convoy forms (the trajectories are flushed
               // every 100 rows), robot 5's process dies.
               "wait_for run/trajectories.csv '^3\\.[0-9]*,1,'\n"
               "kill -9 $A5; date +%s.%N > killed_at\n"
               "wait_for run/events.csv 'lost: process'\n"
               "date +%s.%N > lost_at\n"
               "\"$R\" agent --scenario " +
               s +
               " --ids 5 --lcm \"$URL\" > agent_5_again.txt 2>&1 &\nAGENTS=\"$AGENTS $!\"\n"
               "wait_for run/events.csv 'rejoined'\n"
               "wait $RUN\n"
               "kill $AGENTS; wait $AGENTS || true\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt")
                       << read_file(dir / "run" / "events.csv");
  const double detection_s = std::stod(read_file(dir / "lost_at")) - std::stod(read_file(dir / "killed_at"));
  std::printf(
      "a killed agent process was reported lost %.2f s after it died (dead_after_ms 750, the default; polled every 50 "
      "ms)\n",
      detection_s);
  const std::string events = read_file(dir / "run" / "events.csv");
  EXPECT_NE(events.find("(robots 5) stopped answering"), std::string::npos) << events;
  EXPECT_EQ(count_of(events, "lost: process"), 1) << events;
  EXPECT_NE(events.find(",agent,5,0,rejoined: process"), std::string::npos) << events;
  EXPECT_EQ(count_of(events, "rejoined: process"), 1) << events;
  // The convoy formed all the same, robot 5 with it once it rejoined.
  EXPECT_NE(read_file(dir / "run" / "summary.json").find("\"formed\": true"), std::string::npos)
      << read_file(dir / "run" / "summary.json");
  // While lost, robot 5 stood still (marked lost) and robot 2 kept deciding.
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
  const int status =
      in_namespace(dir, "set +e\n\"$R\" run '" + scenario.string() +
                            "' --fast --seed 1 --duration 5 --lcm \"$URL\" > run.txt 2>&1\necho $? > rc\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  EXPECT_EQ(read_file(dir / "rc"), "1\n");
  EXPECT_NE(read_file(dir / "run.txt").find("no agent process announced robots 3,4"), std::string::npos)
      << read_file(dir / "run.txt");
}

// Two "machines": network namespaces joined by a veth pair, each with an address of a
// private test range (A 10.203.0.1, B 10.203.0.2) and a multicast route on its end of the
// pair; the start of a bash script that makes them ($A, $B, $R the binary, $URL the bus,
// ttl=1 so that it crosses the pair) and removes them when it ends, with every process
// whose pid it added to $KEEP_PIDS.
std::string two_machines_script(const fs::path& dir) {
  std::ostringstream script;
  script << "set -e\nR='" << RILBED_BINARY << "'\ncd '" << dir.string() << "'\n"
         << "A=rilbed_a_$$; B=rilbed_b_$$; KEEP_PIDS=\n"
         << "cleanup() { [ -n \"$KEEP_PIDS\" ] && kill $KEEP_PIDS 2>/dev/null; wait 2>/dev/null; ip netns del $A "
            "2>/dev/null; "
            "ip netns del $B 2>/dev/null; true; }\ntrap cleanup EXIT\n"
         << "ip netns add $A; ip netns add $B\n"
         << "ip link add veth_a netns $A type veth peer name veth_b netns $B\n"
         << "ip -n $A addr add 10.203.0.1/24 dev veth_a; ip -n $B addr add 10.203.0.2/24 dev veth_b\n"
         << "for n in $A $B; do ip -n $n link set lo up; done\n"
         << "ip -n $A link set veth_a up multicast on; ip -n $B link set veth_b up multicast on\n"
         << "ip -n $A route add 224.0.0.0/4 dev veth_a; ip -n $B route add 224.0.0.0/4 dev veth_b\n"
         << "URL='udpm://239.255.76.67:7667?ttl=1'\n";
  return script.str();
}

#define SKIP_WITHOUT_NAMED_NAMESPACES()                                                                   \
  SKIP_WITHOUT_NAMESPACES();                                                                              \
  if (std::system("ip netns add rilbed_probe_$$ >/dev/null 2>&1 && ip netns del rilbed_probe_$$") != 0) { \
    GTEST_SKIP() << "cannot make named network namespaces here (ip netns add needs root)";                \
  }

// The run and robots 1-4's agent process are on one machine, robots 5-8's on the other.
TEST(AgentsCli, AgentsOnTwoMachinesJoinedByAVethPairGiveTheInProcessRun) {
  SKIP_WITHOUT_NAMED_NAMESPACES();
  const fs::path dir = scratch_dir("agents_two_machines");
  const fs::path scenario = convoy_with_agents(dir, "{processes: 0}");
  const std::string s = "'" + scenario.string() + "'";
  const fs::path script = dir / "machines.sh";
  std::ofstream(script) << two_machines_script(dir) << "\"$R\" run '"
                        << (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string()
                        << "' --fast --seed 6 --duration 30 --out local --quiet\n"
                        << "ip netns exec $A \"$R\" agent --scenario " << s
                        << " --ids 1-4 --lcm \"$URL\" > agent_a.txt 2>&1 &\nKEEP_PIDS=$!\n"
                        << "ip netns exec $B \"$R\" agent --scenario " << s
                        << " --ids 5-8 --lcm \"$URL\" > agent_b.txt 2>&1 &\n"
                        << "KEEP_PIDS=\"$KEEP_PIDS $!\"\n"
                        << "ip netns exec $A \"$R\" run " << s
                        << " --fast --seed 6 --duration 30 --out remote --lcm \"$URL\" > run.txt 2>&1\n";
  const int status =
      std::system(("/bin/bash '" + script.string() + "' > '" + (dir / "machines.log").string() + "' 2>&1").c_str());
  ASSERT_EQ(status, 0) << read_file(dir / "machines.log") << read_file(dir / "run.txt")
                       << read_file(dir / "agent_b.txt");
  EXPECT_NE(read_file(dir / "run.txt").find("0 processes lost"), std::string::npos) << read_file(dir / "run.txt");
  expect_same_run_folder(dir / "local", dir / "remote");
}

// `hosts:` starts the agent processes on another machine over ssh: a real OpenSSH server,
// started by the test on machine B's address with a throwaway host key and user key, and a
// launch command (the scenario's `launch:`) that uses that key and port. The run on machine
// A gives the in-process run's folder; when it ends, the agents on B end too (their input,
// the ssh connection, closed). A host whose ssh cannot connect fails the run at once,
// named, not after the announce timeout.
TEST(AgentsCli, HostsStartTheAgentsOnAnotherMachineOverSsh) {
  SKIP_WITHOUT_NAMED_NAMESPACES();
  if (!fs::exists("/usr/sbin/sshd") ||
      std::system("command -v ssh > /dev/null && command -v ssh-keygen > /dev/null") != 0) {
    GTEST_SKIP() << "OpenSSH (openssh-server, openssh-client) is not installed; ./run installs it";
  }
  const fs::path dir = scratch_dir("agents_ssh");
  const auto launch = [&](int port) {
    return "[ssh, -i, '" + (dir / "id").string() + "', -p, '" + std::to_string(port) +
           "', -o, StrictHostKeyChecking=no, -o, UserKnownHostsFile=/dev/null, -o, BatchMode=yes, -o, LogLevel=ERROR, "
           "-T, '{host}', '{command}']";
  };
  const fs::path scenario =
      convoy_with_agents(dir, "{hosts: [10.203.0.2], processes: 2, launch: " + launch(2222) + "}");
  // A port nothing listens on, and a timeout that would make the test wait a minute.
  std::ofstream(dir / "refused.yaml") << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml")
                                      << "\nagents: {hosts: [10.203.0.2], announce_timeout_s: 60, launch: "
                                      << launch(2223) << "}\n";
  const fs::path script = dir / "ssh.sh";
  std::ofstream(script)
      << two_machines_script(dir) << "\"$R\" run '"
      << (fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml").string()
      << "' --fast --seed 6 --duration 30 --out local --quiet\n"
      << "ssh-keygen -q -t ed25519 -N '' -f host_key; ssh-keygen -q -t ed25519 -N '' -f id; cp id.pub authorized_keys\n"
      << "printf '%s\\n' 'ListenAddress 10.203.0.2:2222' \"HostKey $PWD/host_key\" \"AuthorizedKeysFile "
         "$PWD/authorized_keys\" "
         "\"PidFile $PWD/sshd.pid\" 'UsePAM no' 'StrictModes no' 'PasswordAuthentication no' "
         "'KbdInteractiveAuthentication no' 'PermitRootLogin prohibit-password' > sshd_config\n"
      << "mkdir -p /run/sshd\n"  // sshd's privilege separation directory (systemd makes it)
      << "ip netns exec $B /usr/sbin/sshd -D -e -f \"$PWD/sshd_config\" > sshd.log 2>&1 &\nKEEP_PIDS=$!\n"
      << "for i in $(seq 200); do ip netns exec $B ss -Hltn 'sport = :2222' | grep -q . && break; sleep 0.05; done\n"
      << "ip netns exec $A \"$R\" run '" << scenario.string()
      << "' --fast --seed 6 --duration 30 --out remote --lcm \"$URL\" > run.txt 2>&1\n"
      // The agents end with their connection: machine B comes down to the listening sshd.
      << "for i in $(seq 200); do [ \"$(ip netns pids $B | wc -l)\" -le 1 ] && break; sleep 0.05; done\n"
      << "ip netns pids $B | wc -l > left_on_b.txt\n"
      << "set +e\nip netns exec $A \"$R\" run '" << (dir / "refused.yaml").string()
      << "' --fast --seed 6 --duration 30 --lcm \"$URL\" > refused.txt 2>&1\necho $? > refused_rc.txt\n";
  const int status =
      std::system(("/bin/bash '" + script.string() + "' > '" + (dir / "ssh_test.log").string() + "' 2>&1").c_str());
  ASSERT_EQ(status, 0) << read_file(dir / "ssh_test.log") << read_file(dir / "run.txt") << read_file(dir / "sshd.log");
  const std::string run = read_file(dir / "run.txt");
  EXPECT_NE(run.find("0 processes lost"), std::string::npos) << run;
  expect_same_run_folder(dir / "local", dir / "remote");
  // Both agent processes logged in to B's sshd with the throwaway key.
  const std::string sshd = read_file(dir / "sshd.log");
  EXPECT_EQ(count_of(sshd, "Accepted publickey"), 2) << sshd;
  EXPECT_EQ(read_file(dir / "left_on_b.txt"), "1\n") << "agent processes outlived the run on machine B";
  EXPECT_EQ(read_file(dir / "refused_rc.txt"), "1\n");
  const std::string refused = read_file(dir / "refused.txt");
  EXPECT_NE(refused.find("the agent process for robots 1-8 on 10.203.0.2 exited with status 255"), std::string::npos)
      << refused;
  EXPECT_NE(refused.find("Connection refused"), std::string::npos) << refused;
}

// The agent's command line crosses a remote shell (ssh hands `{command}` to the login
// shell's -c): every argument must arrive as it was, whatever it holds.
TEST(AgentLaunch, TheCommandReachesTheRemoteShellWordForWord) {
  const std::vector<std::string> words = {"/opt/lab's rilbed/rilbed", "--lcm", "udpm://239.255.76.67:7667?ttl=1",
                                          "$HOME `id` \"x\" \\ ;|&*", "",      "a\nb"};
  std::string command = "printf '<%s>'";
  for (const std::string& w : words) command.append(" ").append(session::shell_quote(w));
  const std::vector<std::string> argv =
      session::launch_arguments({"ssh", "-p", "22", "{host}", "{command}"}, "pi@h{command}", command);
  ASSERT_EQ(argv.size(), 5u);
  EXPECT_EQ(argv[3], "pi@h{command}");  // a host's text is put in, never searched again
  EXPECT_EQ(argv[4], command);
  FILE* shell = popen(argv[4].c_str(), "r");  // /bin/sh -c, as the login shell at the far end
  ASSERT_NE(shell, nullptr);
  std::string out;
  char buffer[256];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, shell)) > 0;) out.append(buffer, n);
  ASSERT_EQ(pclose(shell), 0);
  std::string expected;
  for (const std::string& w : words) expected.append("<").append(w).append(">");
  EXPECT_EQ(out, expected);
}

// How an agent started over ssh reads its scenario: up to YAML's end-of-document line
// (here with CRLF line ends and trailing spaces), then it ends when its input closes.
TEST(AgentLaunch, AScenarioOnStandardInputEndsAtItsDocumentEndAndTheAgentWithItsInput) {
  const fs::path dir = scratch_dir("agent_stdin");
  std::istringstream yaml(read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml"));
  std::ofstream crlf(dir / "crlf.yaml", std::ios::binary);
  for (std::string line; std::getline(yaml, line);) crlf << line << "\r\n";
  crlf << "...  \r\n";
  crlf.close();
  const std::string command =
      std::string("cd '") + dir.string() + "' && '" + RILBED_BINARY +
      "' agent --scenario-stdin=convoy_sim.yaml --ids 1,2 --lcm memq:// < crlf.yaml > out.txt 2>&1;"
      " echo $? > rc";
  ASSERT_EQ(std::system(command.c_str()), 0);
  EXPECT_EQ(read_file(dir / "rc"), "0\n") << read_file(dir / "out.txt");
  EXPECT_NE(read_file(dir / "out.txt").find("robots 1,2 of convoy_sim"), std::string::npos)
      << read_file(dir / "out.txt");
}

TEST(AgentLaunch, ProcessesTakeTheHostsInTurn) {
  const std::vector<session::AgentPlacement> p = session::place_agents({1, 2, 3, 4, 5, 6, 7, 8}, 3, {"a", "b"});
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].ids, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(p[0].host, "a");
  EXPECT_EQ(p[1].ids, (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(p[1].host, "b");
  EXPECT_EQ(p[2].ids, (std::vector<int>{7, 8}));
  EXPECT_EQ(p[2].host, "a");
  EXPECT_TRUE(session::place_agents({1, 2}, 2, {})[1].host.empty());
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
  // A host that would be read as an option of ssh is refused.
  std::ofstream(dir / "bad_host.yaml") << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml")
                                       << "\nagents: {hosts: [lab-pc, -oProxyCommand=touch /tmp/x]}\n";
  const CommandResult host = run_rilbed("run '" + (dir / "bad_host.yaml").string() + "' --fast");
  EXPECT_EQ(host.exit_code, 1);
  EXPECT_NE(host.err.find("agents.hosts: '-oProxyCommand=touch /tmp/x' is not a host name"), std::string::npos)
      << host.err;
  std::ofstream(dir / "bad_launch.yaml") << read_file(fs::path(RILBED_SOURCE_DIR) / "scenarios" / "convoy_sim.yaml")
                                         << "\nagents: {hosts: [lab-pc], launch: [ssh, '{host}']}\n";
  const CommandResult launch = run_rilbed("run '" + (dir / "bad_launch.yaml").string() + "' --fast");
  EXPECT_EQ(launch.exit_code, 1);
  EXPECT_NE(launch.err.find("agents.launch: must have a {command} item"), std::string::npos) << launch.err;
}

}  // namespace
}  // namespace rilbed::e2e
