#include "app/agent_processes.hpp"

#include "core/id_list.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

extern char** environ;

namespace rilbed::app {


AgentProcesses::~AgentProcesses() { stop(); }

void AgentProcesses::stop() {
  for (const pid_t pid : pids_) kill(pid, SIGTERM);
  for (const pid_t pid : pids_) waitpid(pid, nullptr, 0);
  pids_.clear();
}

bool AgentProcesses::start(const std::string& scenario_file, const std::vector<std::vector<int>>& groups,
                           const std::string& url, const std::string& prefix, std::string& error) {
  char self[4096] = {};
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) {
    error = "cannot find rilbed's own binary to start the agents";
    return false;
  }
  for (const std::vector<int>& group : groups) {
    std::vector<std::string> args = {self, "agent", "--scenario", scenario_file, "--ids", id_list_text(group),
                                     "--lcm", url, "--quiet"};
    if (!prefix.empty()) {
      args.push_back("--channel-prefix");
      args.push_back(prefix);
    }
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (const int rc = posix_spawn(&pid, self, nullptr, nullptr, argv.data(), environ); rc != 0) {
      error = std::string("cannot start an agent process: ") + std::strerror(rc);
      return false;
    }
    pids_.push_back(pid);
  }
  return true;
}

std::vector<std::vector<int>> split_ids(const std::vector<int>& ids, int processes) {
  std::vector<std::vector<int>> groups(static_cast<std::size_t>(std::max(1, processes)));
  for (std::size_t i = 0; i < ids.size(); ++i) groups[i * groups.size() / ids.size()].push_back(ids[i]);
  return groups;
}

}  // namespace rilbed::app
