// rilbed's own controllers as registry entries: the convoy (paper 001), the wanderer, the
// track follower, the beacon homer, going to a pose, the built-in C controllers and
// `none`. A run that takes only these uses builtin_controllers() as its registry.
#pragma once

#include <memory>

#include "agents/controller_registry.hpp"

namespace rilbed::agents {

/// A registry holding rilbed's own controllers, in the order `rilbed controllers` lists
/// them: convoy, wander, track_follow, beacon_homing, goto, the C controllers (`c:<name>`)
/// and none.
ControllerRegistry builtin_controllers();

/// The same registry, made once and never changed: what a scenario is read against when
/// the caller names no registry of its own.
std::shared_ptr<const ControllerRegistry> default_controllers();

}  // namespace rilbed::agents
