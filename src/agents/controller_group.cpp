#include "agents/controller_group.hpp"

namespace rilbed::agents {

ControllerGroup& ControllerGroups::find_or_make(const std::string& key,
                                                const std::function<std::unique_ptr<ControllerGroup>()>& make) {
  auto it = groups_.find(key);
  if (it == groups_.end()) it = groups_.emplace(key, make()).first;
  return *it->second;
}

GroupMember::GroupMember(int robot_id, ControllerGroup& group, std::shared_ptr<ControllerGroup> owned)
    : robot_id_(robot_id), group_(&group), owned_(std::move(owned)) {}

ControlOutput GroupMember::step(const ControlInput& input) {
  group_->gather(input);
  std::vector<GroupAnswer> answers = group_->step_gathered();
  for (const GroupAnswer& a : answers) {
    if (a.robot_id != robot_id_) continue;
    done_ = a.done;
    return a.output;
  }
  throw ControllerError(group_->describe() + " gave no answer for robot " + std::to_string(robot_id_));
}

std::unique_ptr<Controller> join_group(ControllerGroups* groups, const std::string& key, int robot_id,
                                       const std::function<std::unique_ptr<ControllerGroup>()>& make) {
  if (groups) {
    ControllerGroup& group = groups->find_or_make(key, make);
    group.add_member(robot_id);
    return std::make_unique<GroupMember>(robot_id, group);
  }
  std::shared_ptr<ControllerGroup> own = make();
  own->add_member(robot_id);
  ControllerGroup& ref = *own;
  return std::make_unique<GroupMember>(robot_id, ref, std::move(own));
}

}  // namespace rilbed::agents
