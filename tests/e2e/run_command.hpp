// Helpers for end-to-end tests: run the real rilbed binary and capture what it prints.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rilbed::e2e {

/// What a finished command left behind.
struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< standard output
  std::string err;  ///< standard error
};

/// A fresh scratch directory under the system temp dir, removed by the caller if wanted.
inline std::filesystem::path scratch_dir(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("rilbed_e2e_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A scenario shipped in scenarios/, as a shell argument (quoted; appended piece by piece:
/// a leading `"'" + std::string` trips GCC 12's false -Wrestrict, PR 105329).
inline std::string shipped_scenario_arg(const std::string& name) {
  std::string quoted = "'";
  quoted += (std::filesystem::path(RILBED_SOURCE_DIR) / "scenarios" / (name + ".yaml")).string();
  quoted += "'";
  return quoted;
}

/// Runs `RILBED_BINARY args` through /bin/sh, capturing stdout and stderr into files.
inline CommandResult run_rilbed(const std::string& args) {
  static int counter = 0;
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const auto out_path = dir / ("rilbed_e2e_out_" + tag);
  const auto err_path = dir / ("rilbed_e2e_err_" + tag);
  const std::string cmd = std::string("'") + RILBED_BINARY + "' " + args + " >'" + out_path.string() + "' 2>'" +
                          err_path.string() + "' </dev/null";
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out_path);
  r.err = read_file(err_path);
  std::filesystem::remove(out_path);
  std::filesystem::remove(err_path);
  return r;
}

}  // namespace rilbed::e2e
