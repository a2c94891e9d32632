// Behaviour names that live as long as the program, as ControlOutput::behaviour must:
// names that come from outside rilbed's own code (another process's agent, a plug-in
// library's controller) are copied in here once.
#pragma once

#include <string_view>

namespace rilbed::agents {

/// `name` as a string that lives as long as the program, NUL-terminated: the same view
/// for the same name. Names are kept up to 64 bytes of printable ASCII other than `,` and
/// `"` (they go into CSV files), at most 1,024 distinct ones, the names of rilbed's own
/// controllers among them from the start; anything else (a peer or a library sending
/// junk) is "other", and an empty name is "idle". Thread-safe.
std::string_view intern_behaviour(std::string_view name);

}  // namespace rilbed::agents
