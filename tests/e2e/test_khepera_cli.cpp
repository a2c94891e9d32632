// End-to-end tests of `rilbed khepera` and `rilbed khepera-emu`: the emulator runs as a
// child process on a real pty, and the real binary talks to it.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "run_command.hpp"

extern char** environ;

namespace rilbed::e2e {
namespace {

using namespace std::chrono_literals;
using SteadyClock = std::chrono::steady_clock;

// `rilbed ARGS...` as a child process whose stdout the test reads through a pipe; its
// stderr goes to a file. Killed (SIGKILL) on destruction if still running.
class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& args) {
    err_path_ = std::filesystem::temp_directory_path() /
                ("rilbed_e2e_child_err_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
    int out[2];
    if (::pipe2(out, O_CLOEXEC) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, out[1], 1);
    posix_spawn_file_actions_addopen(&actions, 2, err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<std::string> argv_strings = {RILBED_BINARY};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_strings) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (::posix_spawn(&pid_, RILBED_BINARY, &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    ::close(out[1]);
    out_fd_ = out[0];
  }
  ~ChildProcess() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
    std::filesystem::remove(err_path_);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool running() const { return pid_ > 0 && !exited_; }

  // The next line of its stdout (without LF), or nullopt on end of file or timeout.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout) {
    const auto deadline = SteadyClock::now() + timeout;
    while (true) {
      const std::size_t lf = out_.find('\n');
      if (lf != std::string::npos) {
        std::string line = out_.substr(0, lf);
        out_.erase(0, lf + 1);
        return line;
      }
      if (!read_some(deadline)) return std::nullopt;
    }
  }
  // Everything it still writes to stdout until it closes it (or the timeout).
  std::string read_rest(std::chrono::milliseconds timeout) {
    const auto deadline = SteadyClock::now() + timeout;
    while (read_some(deadline)) {}
    return std::exchange(out_, {});
  }
  void send_signal(int signal) const {
    if (running()) ::kill(pid_, signal);
  }
  // Its exit status once it exits within `timeout`; -1 if it did not (then it is killed)
  // or died of a signal.
  int wait(std::chrono::milliseconds timeout) {
    const auto deadline = SteadyClock::now() + timeout;
    while (running()) {
      int status = 0;
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        exited_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      if (SteadyClock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
        exited_ = true;
        return -1;
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }
  std::string err() const { return read_file(err_path_); }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  bool read_some(SteadyClock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - SteadyClock::now()).count();
    if (left <= 0 || out_fd_ < 0) return false;
    pollfd p{out_fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left)) <= 0) return false;
    char buffer[512];
    const ssize_t n = ::read(out_fd_, buffer, sizeof buffer);
    if (n <= 0) return false;
    out_.append(buffer, static_cast<std::size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  bool exited_ = false;
  int out_fd_ = -1;
  std::string out_;
  std::filesystem::path err_path_;
};

// A `rilbed khepera-emu` child and the device it printed.
struct Emulator {
  explicit Emulator(std::vector<std::string> extra_args = {})
      : process([&] {
          std::vector<std::string> args = {"khepera-emu"};
          args.insert(args.end(), extra_args.begin(), extra_args.end());
          return args;
        }()) {
    device = process.read_line(10s).value_or("");
  }
  // Ends it with SIGTERM and returns what it printed after the device path.
  std::string finish() {
    process.send_signal(SIGTERM);
    std::string rest = process.read_rest(10s);
    exit_code = process.wait(10s);
    return rest;
  }
  ChildProcess process;
  std::string device;
  int exit_code = -1;
};

double seconds_since(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

TEST(KheperaCli, InfoPrintsVersionsProximityAndCounters) {
  Emulator emulator;
  ASSERT_EQ(emulator.device.rfind("/dev/pts/", 0), 0u) << emulator.device << emulator.process.err();
  const CommandResult r = run_rilbed("khepera --port " + emulator.device + " info");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("port " + emulator.device + ": khepera2 at 38400 baud"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("versions: bios 5, protocol 4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("proximity: 0 0 0 0 0 0 0 0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("counters: left 0 right 0 pulses"), std::string::npos) << r.out;
  const std::string rest = emulator.finish();
  EXPECT_EQ(emulator.exit_code, 0);
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
}

// A peer whose firmware words its replies otherwise (as a lab reported it: a
// Khepera answering `b,5.02,5.01`), with every other difference too: the real binary
// talks to it as to K-Team's firmware.
TEST(KheperaCli, WorksWithARobotWhoseFirmwareDiffers) {
  Emulator emulator({"--versions", "5.02,5.01", "--upper-case", "--line-end", "lf", "--extra-fields", ",0,ok",
                     "--trailing-spaces", "2", "--spaces-after-commas", "--echo"});
  ASSERT_EQ(emulator.device.rfind("/dev/pts/", 0), 0u) << emulator.device << emulator.process.err();
  CommandResult r = run_rilbed("khepera --port " + emulator.device + " info");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("versions: bios 5.02, protocol 5.01 (0,ok)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("proximity: 0 0 0 0 0 0 0 0"), std::string::npos) << r.out;
  r = run_rilbed("khepera --port " + emulator.device + " drive 10 10 --for 0.3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("stopped"), std::string::npos) << r.out;
  const std::string rest = emulator.finish();
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
}

TEST(KheperaCli, DriveMovesTheRobotThenStopsIt) {
  Emulator emulator({"--pose", "0.1,0.2,90"});
  ASSERT_FALSE(emulator.device.empty()) << emulator.process.err();
  const CommandResult r = run_rilbed("khepera --port " + emulator.device + " drive 10 10 --for 0.5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("drove 10 10 for"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("stopped"), std::string::npos) << r.out;
  const std::string rest = emulator.finish();
  EXPECT_EQ(emulator.exit_code, 0);
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
  // 10 units = 0.08 m/s for about 0.5 s, heading 90 degrees: up along +y.
  double x = 0, y = 0, theta = 0;
  const std::size_t at = rest.find("pose ");
  ASSERT_NE(at, std::string::npos) << rest;
  ASSERT_EQ(std::sscanf(rest.c_str() + at, "pose %lf %lf %lf", &x, &y, &theta), 3) << rest;
  EXPECT_NEAR(x, 0.1, 1e-3);
  EXPECT_GT(y - 0.2, 0.02) << rest;
  EXPECT_LT(y - 0.2, 0.2) << rest;
  EXPECT_NEAR(theta, 90.0, 0.01);
}

TEST(KheperaCli, SigintDuringADriveStopsTheRobotFirst) {
  Emulator emulator;
  ASSERT_FALSE(emulator.device.empty()) << emulator.process.err();
  ChildProcess drive({"khepera", "--port", emulator.device, "drive", "20", "-20", "--for", "30"});
  const auto line = drive.read_line(10s);
  ASSERT_TRUE(line.has_value()) << drive.err();
  EXPECT_EQ(*line, "driving 20 -20 for 30.00 s");
  const auto interrupted = SteadyClock::now();
  drive.send_signal(SIGINT);
  const std::string out = drive.read_rest(10s);
  EXPECT_EQ(drive.wait(10s), 130) << drive.err();
  EXPECT_LT(seconds_since(interrupted), 10.0);
  EXPECT_NE(out.find("interrupted after"), std::string::npos) << out;
  const std::string rest = emulator.finish();
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
}

TEST(KheperaCli, AMissingPortFailsFastNamingIt) {
  const auto start = SteadyClock::now();
  const CommandResult r = run_rilbed("khepera --port /nonexistent info");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("khepera /nonexistent: cannot open: No such file or directory"), std::string::npos) << r.err;
  EXPECT_LT(seconds_since(start), 5.0);
}

TEST(KheperaCli, ASilentRobotFailsWithinSecondsAndStillGetsAStop) {
  Emulator emulator({"--drop", "1"});
  ASSERT_FALSE(emulator.device.empty()) << emulator.process.err();
  const auto start = SteadyClock::now();
  const CommandResult r = run_rilbed("khepera --port " + emulator.device + " info");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_LT(seconds_since(start), 8.0);
  EXPECT_NE(r.err.find("khepera " + emulator.device + ": B (read versions) failed after 4 attempts: no reply"),
            std::string::npos)
      << r.err;
  const std::string rest = emulator.finish();
  // The robot's replies are lost, not the commands: the stop reached it.
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
}

TEST(KheperaCli, ARobotAnsweringGarbageFailsNamingThePort) {
  Emulator emulator({"--corrupt", "1"});
  ASSERT_FALSE(emulator.device.empty()) << emulator.process.err();
  const auto start = SteadyClock::now();
  const CommandResult r = run_rilbed("khepera --port " + emulator.device + " drive 10 10 --for 5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_LT(seconds_since(start), 8.0);
  EXPECT_NE(r.err.find("khepera " + emulator.device + ": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("failed after 4 attempts"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("drove"), std::string::npos) << r.out;
  const std::string rest = emulator.finish();
  EXPECT_NE(rest.find("last speed 0 0"), std::string::npos) << rest;
}

TEST(KheperaCli, BadOptionsAreUsageErrors) {
  const CommandResult bad_baud = run_rilbed("khepera --port /dev/null --baud 1234 info");
  EXPECT_NE(bad_baud.exit_code, 0);
  EXPECT_NE(bad_baud.err.find("1234"), std::string::npos) << bad_baud.err;
  const CommandResult no_port = run_rilbed("khepera info");
  EXPECT_NE(no_port.exit_code, 0);
  EXPECT_NE(no_port.err.find("--port"), std::string::npos) << no_port.err;
  EXPECT_NE(run_rilbed("khepera-emu --pose 1,2").exit_code, 0);
}

}  // namespace
}  // namespace rilbed::e2e
