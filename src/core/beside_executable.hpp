// Folders rilbed ships beside its binary (plug-ins, robot models), found the same way.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace rilbed::core {

/// The folder `name` beside the running executable (build/plugins for build/rilbed), or
/// the environment variable `override_variable`'s value when it is set and not empty (a
/// test, or an installed layout). When the executable's path cannot be read: `name`,
/// relative to the working directory.
inline std::filesystem::path beside_executable(const std::string& name, const char* override_variable) {
  if (const char* dir = std::getenv(override_variable); dir && *dir) return dir;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return name;
  return exe.parent_path() / name;
}

}  // namespace rilbed::core
