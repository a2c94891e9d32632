// Coupled DEVS models: children plus the couplings between their ports.
#pragma once

#include <concepts>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "sim/component.hpp"

namespace rilbed::sim {

/// A coupled DEVS model: children (atomic or coupled, shared ownership) and couplings
/// of three kinds, all checked when made:
///  - external input (EIC): an input of this model -> an input of a child;
///  - internal (IC): an output of a child -> an input of a child (the same child too);
///  - external output (EOC): an output of a child -> an output of this model.
/// Both ports must carry the same message type. The structure must not change once a
/// Coordinator has been built on it. Not thread-safe.
class Coupled : public Component {
 public:
  /// One coupling, from a port to a port (non-owning; both live in this model).
  struct Coupling {
    PortBase* from;
    PortBase* to;
  };

  using Component::Component;
  /// Detaches the children (their parent() becomes nullptr).
  ~Coupled() override;

  /// Adds a child and returns it. Throws std::invalid_argument when `child` is null,
  /// already has a parent, is this model, or its id is taken by a sibling.
  template <std::derived_from<Component> C>
  C& add(std::shared_ptr<C> child) {
    add_child(child);
    return *child;
  }
  /// Builds a C from `args` and adds it.
  template <std::derived_from<Component> C, class... Args>
  C& emplace(Args&&... args) {
    return add(std::make_shared<C>(std::forward<Args>(args)...));
  }

  /// Couples `from` to `to` (EIC, IC or EOC, see above). Throws std::invalid_argument,
  /// naming both ports, when the message types differ, when a port belongs neither to
  /// this model nor to a direct child, when the directions fit no coupling kind, or
  /// when the coupling exists already.
  void couple(PortBase& from, PortBase& to);

  /// Children in insertion order.
  const std::vector<std::shared_ptr<Component>>& children() const { return children_; }
  /// Couplings in the order they were made.
  const std::vector<Coupling>& couplings() const { return couplings_; }

 private:
  void add_child(std::shared_ptr<Component> child);
  bool owns_directly(const PortBase& port) const;

  std::vector<std::shared_ptr<Component>> children_;
  std::vector<Coupling> couplings_;
  std::set<std::string> child_ids_;                                // lookups only
  std::set<std::pair<const PortBase*, const PortBase*>> coupled_;  // lookups only
};

}  // namespace rilbed::sim
