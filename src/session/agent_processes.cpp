#include "session/agent_processes.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/id_list.hpp"

extern char** environ;

namespace rilbed::session {

namespace {

// The rilbed binary the agents are: RILBED_BINARY when set (a Python process, whose own
// executable is python3: the `rilbed` package sets it to the binary of its build), else
// this process's own.
std::optional<std::string> own_binary() {
  if (const char* binary = std::getenv("RILBED_BINARY"); binary && *binary) return std::string(binary);
  char self[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return std::nullopt;
  return std::string(self, static_cast<std::size_t>(n));
}

std::optional<std::string> read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Writes all of `text` to `fd`; false on an error (the reader gone: EPIPE; main() ignores
// SIGPIPE for the whole program).
bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::string describe_status(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("was killed by signal ") + strsignal(WTERMSIG(status));
  return "ended";
}

std::string where(const AgentPlacement& p) { return p.host.empty() ? "on this machine" : "on " + p.host; }

}  // namespace

AgentProcesses::~AgentProcesses() { stop(); }

void AgentProcesses::stop() {
  for (Started& s : started_) {
    if (s.input_fd >= 0) close(s.input_fd);
    s.input_fd = -1;
    if (!s.ended) kill(s.pid, SIGTERM);
  }
  for (Started& s : started_) {
    if (!s.ended) waitpid(s.pid, nullptr, 0);
  }
  started_.clear();
}

bool AgentProcesses::spawn(const std::vector<std::string>& args, bool search_path, bool with_input,
                           const std::string& input, Started& started, std::string& error) {
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  int pipe_fds[2] = {-1, -1};
  if (with_input) {
    // The agent (or the launch command) reads the scenario from a pipe, whose write end
    // this keeps: the agent takes the end of its input for the end of the run.
    if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
      error = std::string("cannot make a pipe for an agent process: ") + std::strerror(errno);
      posix_spawn_file_actions_destroy(&actions);
      return false;
    }
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[0], STDIN_FILENO);
  }
  const int rc = search_path ? posix_spawnp(&started.pid, argv[0], &actions, nullptr, argv.data(), environ)
                             : posix_spawn(&started.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (pipe_fds[0] >= 0) close(pipe_fds[0]);
  if (rc != 0) {
    if (pipe_fds[1] >= 0) close(pipe_fds[1]);
    error = "cannot start `" + args.front() + "` for robots " + id_ranges_text(started.placement.ids) + " " +
            where(started.placement) + ": " + std::strerror(rc);
    return false;
  }
  started.input_fd = pipe_fds[1];
  // A scenario is a few kilobytes, within a pipe's buffer: this does not wait for ssh to
  // connect. The buffer is made as large as Linux allows (1 MB by default) for big ones.
  if (started.input_fd >= 0 && input.size() > 60'000) {
    fcntl(started.input_fd, F_SETPIPE_SZ, static_cast<int>(std::min<std::size_t>(input.size() + 4096, 1u << 20)));
  }
  if (started.input_fd >= 0) write_all(started.input_fd, input);
  return true;
}

bool AgentProcesses::start(const AgentLaunchConfig& config, const std::vector<AgentPlacement>& placements,
                           std::string& error) {
  const std::optional<std::string> self = own_binary();
  if (!self) {
    error = "cannot find rilbed's own binary to start the agents";
    return false;
  }
  // The scenario's text for an agent's input, read once: what the run read, ended by the
  // YAML end-of-document line (it tells the agent where the scenario ends; its input stays
  // open after it, as its lifeline).
  std::string scenario_text;
  const auto scenario_input = [&]() -> bool {
    if (!scenario_text.empty()) return true;
    if (config.scenario_text.empty()) {
      const std::optional<std::string> text = read_text(config.scenario_file);
      if (!text) {
        error = "cannot read " + config.scenario_file + " to send it to the agents";
        return false;
      }
      scenario_text = *text;
    } else {
      scenario_text = config.scenario_text;
    }
    if (!scenario_text.empty() && scenario_text.back() != '\n') scenario_text.push_back('\n');
    scenario_text.append("...\n");
    return true;
  };
  for (const AgentPlacement& placement : placements) {
    std::vector<std::string> agent = {"agent", "--ids", id_ranges_text(placement.ids), "--lcm", config.url, "--quiet"};
    if (!config.prefix.empty()) {
      agent.push_back("--channel-prefix");
      agent.push_back(config.prefix);
    }
    Started started;
    started.placement = placement;
    if (placement.host.empty()) {
      std::vector<std::string> args = {*self};
      args.insert(args.end(), agent.begin(), agent.end());
      if (config.scenario_text.empty()) {
        args.insert(args.end(), {"--scenario", config.scenario_file});
        if (!spawn(args, false, false, {}, started, error)) return false;
      } else {
        // With '=': a file name that starts with '-' stays the option's value.
        args.push_back("--scenario-stdin=" + config.scenario_file);
        if (!scenario_input() || !spawn(args, false, true, scenario_text, started, error)) return false;
      }
    } else {
      if (!scenario_input()) return false;
      std::string command = shell_quote(config.remote_rilbed.empty() ? *self : config.remote_rilbed);
      for (const std::string& a : agent) command.append(" ").append(shell_quote(a));
      command.append(" ").append(shell_quote("--scenario-stdin=" + config.scenario_file));
      if (!spawn(launch_arguments(config.launch, placement.host, command), true, true, scenario_text, started, error)) {
        return false;
      }
    }
    started_.push_back(std::move(started));
  }
  return true;
}

std::optional<std::string> AgentProcesses::ended_early() {
  for (Started& s : started_) {
    if (s.ended) continue;
    int status = 0;
    if (waitpid(s.pid, &status, WNOHANG) != s.pid) continue;
    s.ended = true;
    return "the agent process for robots " + id_ranges_text(s.placement.ids) + " " + where(s.placement) + " " +
           describe_status(status) + (s.placement.host.empty() ? "" : " (see the launch command's messages above)");
  }
  return std::nullopt;
}

std::vector<std::vector<int>> split_ids(const std::vector<int>& ids, int processes) {
  std::vector<std::vector<int>> groups(static_cast<std::size_t>(std::max(1, processes)));
  for (std::size_t i = 0; i < ids.size(); ++i) groups[i * groups.size() / ids.size()].push_back(ids[i]);
  return groups;
}

std::vector<AgentPlacement> place_agents(const std::vector<int>& ids, int processes,
                                         const std::vector<std::string>& hosts) {
  std::vector<AgentPlacement> out;
  for (std::vector<int>& group : split_ids(ids, processes)) {
    const std::string host = hosts.empty() ? std::string() : hosts[out.size() % hosts.size()];
    out.push_back({std::move(group), host});
  }
  return out;
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

std::vector<std::string> launch_arguments(const std::vector<std::string>& launch, const std::string& host,
                                          const std::string& command) {
  std::vector<std::string> out;
  for (const std::string& item : launch) {
    // One pass, so that a host's or command's text is never searched again.
    std::string word;
    for (std::size_t at = 0; at < item.size();) {
      if (item.compare(at, 6, "{host}") == 0) {
        word += host;
        at += 6;
      } else if (item.compare(at, 9, "{command}") == 0) {
        word += command;
        at += 9;
      } else {
        word += item[at++];
      }
    }
    out.push_back(std::move(word));
  }
  return out;
}

}  // namespace rilbed::session
