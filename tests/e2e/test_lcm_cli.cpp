// End-to-end tests of a run on an LCM bus: `rilbed run --lcm` and `rilbed watch` as real
// processes talking over UDP multicast inside a private network namespace (`unshare -n`,
// then loopback up with multicast; no packet leaves the namespace).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// Runs `body` (shell lines, with $R the rilbed binary and $URL the bus) in a fresh network
// namespace whose loopback carries multicast. Returns the exit status, or -1 when this
// machine cannot make a namespace (then the test is skipped).
int in_namespace(const fs::path& dir, const std::string& body) {
  const fs::path script = dir / "ns.sh";
  std::ofstream(script) << "set -e\nip link set lo up\nip link set lo multicast on\nip route add 224.0.0.0/4 dev lo\n"
                        << "R='" << RILBED_BINARY << "'\nURL='udpm://239.255.76.67:7667?ttl=0'\ncd '" << dir.string() << "'\n"
                        << body;
  const int status = std::system(("unshare -n /bin/bash '" + script.string() + "' >'" + (dir / "ns.log").string() + "' 2>&1").c_str());
  if (!WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

bool namespaces_work() {
  return std::system("unshare -n true >/dev/null 2>&1") == 0;
}

TEST(LcmCli, WatchShowsARunOverMulticastAndItsEnd) {
  if (!namespaces_work()) GTEST_SKIP() << "cannot make a network namespace here (unshare -n needs root)";
  const fs::path dir = scratch_dir("lcm_watch");
  const int status = in_namespace(dir,
      "\"$R\" watch --lcm \"$URL\" --until-ended --for 60 > watch.txt 2>&1 &\n"
      "W=$!\n"
      // A second watcher on another prefix hears nothing of this run.
      "\"$R\" watch --lcm \"$URL\" --channel-prefix OTHER_ --for 4 --silence 1 > other.txt 2>&1 &\n"
      "O=$!\n"
      "\"$R\" run " + shipped_scenario_arg("convoy_sim") + " --realtime --rt-factor 5 --stop-when-formed --lcm \"$URL\" --quiet > run.txt 2>&1\n"
      "wait $W\n"
      "set +e\nwait $O\necho \"other exit $?\" >> other.txt\n");
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log") << read_file(dir / "run.txt") << read_file(dir / "watch.txt");
  const std::string watch = read_file(dir / "watch.txt");
  EXPECT_NE(watch.find("watching convoy_sim on udpm://239.255.76.67:7667?ttl=0: 8 robots (0 real)"), std::string::npos) << watch;
  // It may join a moment after the run began: any second's status line will do.
  EXPECT_NE(watch.find("s running x5.0  1:wait"), std::string::npos) << watch;
  EXPECT_NE(watch.find("formed: convoy formed"), std::string::npos) << watch;
  EXPECT_NE(watch.find("(ended by formed)"), std::string::npos) << watch;
  EXPECT_NE(read_file(dir / "run.txt").find("formed at"), std::string::npos);
  const std::string other = read_file(dir / "other.txt");
  EXPECT_NE(other.find("no rilbed run heard on udpm://239.255.76.67:7667?ttl=0 for 1 s (channels OTHER_RILBED_*)"),
            std::string::npos) << other;
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
