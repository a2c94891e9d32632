#include "agents/plugin_library.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <mutex>
#include <system_error>

#include "agents/c_controller.hpp"
#include "core/beside_executable.hpp"
#include "rilbed/plugin.h"

namespace rilbed::agents {

namespace {

// dlerror() is one per process on glibc before 2.34: its message must be read under the
// same lock as the call that set it.
std::mutex& loader_mutex() {
  static std::mutex m;
  return m;
}

std::string loader_error() {
  const char* text = dlerror();
  return text ? text : "unknown error";
}

}  // namespace

core::Result<std::shared_ptr<const PluginLibrary>> PluginLibrary::open(const std::filesystem::path& given) {
  std::error_code ec;
  const std::filesystem::path path = std::filesystem::absolute(given, ec).lexically_normal();
  const std::string who = "plug-in library " + path.string();
  if (ec || !std::filesystem::exists(path, ec)) return core::Failure{who + ": no such file"};
  if (std::filesystem::is_directory(path, ec)) return core::Failure{who + ": is a folder, not a library"};
  void* handle = nullptr;
  {
    std::lock_guard lock(loader_mutex());
    // RTLD_NOW: an undefined symbol is an error here, not a crash in the middle of a run.
    // RTLD_LOCAL: two libraries' symbols never mix.
    handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const std::string why = loader_error();
      const bool needs_host = why.find("undefined symbol: rilbed_") != std::string::npos;
      return core::Failure{
          who + ": cannot be loaded: " + why +
          (needs_host ? " (write RILBED_DEFINE_PLUGIN() once in one of its sources; see rilbed/plugin.h)" : "")};
    }
  }
  std::shared_ptr<PluginLibrary> library(new PluginLibrary(path, handle));
  using VersionFunction = std::uint32_t (*)();
  auto version = reinterpret_cast<VersionFunction>(library->symbol("rilbed_abi_version"));
  if (!version) {
    return core::Failure{who +
                         ": does not export rilbed_abi_version(), so it is no rilbed plug-in or was built without "
                         "RILBED_DEFINE_PLUGIN() (write it once in one of its sources; see rilbed/plugin.h)"};
  }
  if (const std::uint32_t v = version(); v != RILBED_ABI_VERSION) {
    return core::Failure{who + ": was built against rilbed's SDK ABI version " + std::to_string(v) +
                         ", this rilbed loads version " + std::to_string(RILBED_ABI_VERSION) +
                         ": rebuild it against this rilbed's build/sdk"};
  }
  using BindFunction = void (*)(const rilbed_host*);
  auto bind = reinterpret_cast<BindFunction>(library->symbol("rilbed_plugin_bind"));
  if (!bind) return core::Failure{who + ": exports rilbed_abi_version() but not rilbed_plugin_bind()"};
  bind(&plugin_host());
  return std::shared_ptr<const PluginLibrary>(std::move(library));
}

PluginLibrary::~PluginLibrary() {
  std::lock_guard lock(loader_mutex());
  dlclose(handle_);
}

void* PluginLibrary::symbol(const char* name) const {
  std::lock_guard lock(loader_mutex());
  dlerror();
  return dlsym(handle_, name);
}

std::filesystem::path builtin_plugin_directory() { return core::beside_executable("plugins", "RILBED_PLUGIN_DIR"); }

}  // namespace rilbed::agents
