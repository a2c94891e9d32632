// A plug-in library loaded into rilbed's process (rilbed/plugin.h): opened with every
// symbol resolved at once, its ABI version checked against rilbed's, and rilbed's host
// functions lent to it. Whatever a library made keeps a shared_ptr to its PluginLibrary,
// so the library is unloaded only after the last of them is gone.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "core/result.hpp"

namespace rilbed::agents {

/// One loaded library. Not copyable; shared by what it made.
class PluginLibrary {
 public:
  /// Opens the library at `path` (made absolute). A failure names the library and the
  /// cause, in words a lab can act on: no such file; not a loadable shared object (the
  /// loader's own words: a missing dependency, an undefined symbol, another architecture);
  /// no rilbed_abi_version() (RILBED_DEFINE_PLUGIN() missing); an ABI version other than
  /// RILBED_ABI_VERSION (rebuild against this rilbed's build/sdk).
  static core::Result<std::shared_ptr<const PluginLibrary>> open(const std::filesystem::path& path);
  ~PluginLibrary();
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;

  /// The library's absolute path, as messages name it.
  const std::filesystem::path& path() const { return path_; }
  /// The address of the exported symbol `name`, or nullptr.
  void* symbol(const char* name) const;

 private:
  PluginLibrary(std::filesystem::path path, void* handle) : path_(std::move(path)), handle_(handle) {}
  std::filesystem::path path_;
  void* handle_;
};

/// Where rilbed's own plug-in libraries are (the built-in `c:braitenberg`): the folder
/// named by the environment variable RILBED_PLUGIN_DIR if set, else `plugins/` beside
/// the running executable.
std::filesystem::path builtin_plugin_directory();

}  // namespace rilbed::agents
