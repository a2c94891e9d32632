// Controllers that decide for many robots in one call: a vectorised Python class's
// step_all gets every robot it controls at once, as arrays. Each robot still has its own
// Controller (a GroupMember) so that everything that handles one robot's controller works
// unchanged; a run that knows about groups gathers the members' inputs at a control
// instant and steps each group once.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "agents/controller.hpp"

namespace rilbed::agents {

/// One robot's answer from a group's step.
struct GroupAnswer {
  int robot_id = 0;
  ControlOutput output;  ///< its behaviour points to a string that lives as long as the program
  bool done = false;     ///< the group's done() after the step
};

/// Robots whose controllers decide together. Not thread-safe: a run steps it from one thread.
class ControllerGroup {
 public:
  virtual ~ControllerGroup() = default;
  /// Adds robot `robot_id` to the group (when its controller is made).
  virtual void add_member(int robot_id) = 0;
  /// Keeps a copy of one member's input for the next step_gathered() (input.team is copied).
  virtual void gather(const ControlInput& input) = 0;
  /// Steps every member gathered since the last call, in one call, and returns their
  /// answers in the order gathered; nothing when nothing was gathered. Throws
  /// ControllerError (naming the group and its robots) when the step fails.
  virtual std::vector<GroupAnswer> step_gathered() = 0;
  /// The run ended: tells the controller once (later calls do nothing).
  virtual void finish() = 0;
  /// Whether its members read the team broadcast.
  virtual bool wants_team() const = 0;
  /// What it is, for messages ("swarm.py: Wander (robots 1-1000)").
  virtual std::string describe() const = 0;
};

/// A run's groups, by a key its factories choose (the file, the class and the parameters:
/// robots with the same controller and the same parameters share one group). Owned by the
/// run; the members' controllers point into it, so it must outlive them.
class ControllerGroups {
 public:
  /// The group for `key`, made with `make` the first time.
  ControllerGroup& find_or_make(const std::string& key, const std::function<std::unique_ptr<ControllerGroup>()>& make);

 private:
  std::map<std::string, std::unique_ptr<ControllerGroup>> groups_;
};

/// One robot's controller inside a group: step() alone steps the group for this robot
/// only (a group of one); a run that knows groups steps the group instead.
class GroupMember final : public Controller {
 public:
  /// `group` must outlive the member (it lives in the run's ControllerGroups, or is
  /// shared with the member when there are none).
  GroupMember(int robot_id, ControllerGroup& group, std::shared_ptr<ControllerGroup> owned = {});
  ControlOutput step(const ControlInput& input) override;
  void finish() override { group_->finish(); }
  bool wants_team() const override { return group_->wants_team(); }
  bool done() const override { return done_; }
  bool concurrent() const override { return false; }
  ControllerGroup* group() override { return group_; }

 private:
  int robot_id_;
  ControllerGroup* group_;
  std::shared_ptr<ControllerGroup> owned_;  // its own group when the run has none
  bool done_ = false;
};

/// The member controller for robot `robot_id` of the group `key` in `groups` (made with
/// `make` when it is new); with no `groups`, a group of its own.
std::unique_ptr<Controller> join_group(ControllerGroups* groups, const std::string& key, int robot_id,
                                       const std::function<std::unique_ptr<ControllerGroup>()>& make);

}  // namespace rilbed::agents
