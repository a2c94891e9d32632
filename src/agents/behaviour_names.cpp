#include "agents/behaviour_names.hpp"

#include <mutex>
#include <set>
#include <string>

namespace rilbed::agents {

std::string_view intern_behaviour(std::string_view name) {
  constexpr std::size_t kMaxLength = 64, kMaxNames = 1024;
  // Nodes of a std::set never move: a view of one stays valid for the program's life. The
  // names rilbed's own controllers use are there from the start, so that a peer sending
  // junk names cannot make them "other".
  static std::mutex mutex;
  static std::set<std::string, std::less<>> names = {"idle",  "console", "lost",   "search",  "follow", "wait",
                                                     "avoid", "unknown", "cruise", "arrived", "home",   "placed",
                                                     "yield", "place",   "align",  "c0",      "c1",     "c2",
                                                     "c3",    "c4",      "c5",     "c6",      "c7",     "c?"};
  if (name.empty()) return "idle";  // an empty field would read as a missing one in CSV files
  if (name.size() > kMaxLength) return "other";
  // Names go into CSV files, JSON and terminals: printable ASCII without , and ".
  for (const char c : name) {
    if (c < 0x20 || c > 0x7e || c == ',' || c == '"') return "other";
  }
  std::lock_guard lock(mutex);
  if (const auto it = names.find(name); it != names.end()) return *it;
  if (names.size() >= kMaxNames) return "other";
  return *names.emplace(name).first;
}

}  // namespace rilbed::agents
