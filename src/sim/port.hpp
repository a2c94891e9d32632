// Typed ports: each holds the bag of messages that crosses it at the current instant.
#pragma once

#include <cstddef>
#include <string>
#include <typeindex>
#include <typeinfo>
#include <utility>
#include <vector>

namespace rilbed::sim {

class Component;

/// Whether a port receives messages (input) or emits them (output).
enum class PortDirection { kInput, kOutput };

/// The untyped face of a port, as couplings and the coordinator see it.
///
/// A port is created by, owned by and lives as long as its Component
/// (Component::add_input / add_output); it can be neither copied nor moved, so
/// references to it stay valid. Not thread-safe: only the thread that runs the
/// coordinator touches bags.
class PortBase {
 public:
  virtual ~PortBase() = default;
  PortBase(const PortBase&) = delete;
  PortBase& operator=(const PortBase&) = delete;

  /// The port's name, unique among its owner's ports of the same direction.
  const std::string& name() const { return name_; }
  /// The component that owns this port.
  Component& owner() const { return *owner_; }
  /// Input or output.
  PortDirection direction() const { return direction_; }
  /// The message type, compared when ports are coupled.
  std::type_index type() const { return *type_; }
  /// "<owner path>.<name> (<message type>)"-style name for error messages.
  std::string describe() const;

  /// True when no message is in the bag.
  virtual bool empty() const = 0;
  /// Number of messages in the bag.
  virtual std::size_t size() const = 0;
  /// Empties the bag (the coordinator does this after every step).
  virtual void clear() = 0;
  /// Appends copies of every message of `source`. Precondition: `source` has the same
  /// message type (couplings check it) and is not this port.
  virtual void append_from(const PortBase& source) = 0;

 protected:
  PortBase(std::string name, Component& owner, PortDirection direction, const std::type_info& type)
      : name_(std::move(name)), owner_(&owner), direction_(direction), type_(&type) {}

 private:
  std::string name_;
  Component* owner_;
  PortDirection direction_;
  const std::type_info* type_;
};

/// A port carrying messages of type T (copyable: a message is copied to every
/// destination). The bag keeps messages in arrival order.
template <class T>
class Port final : public PortBase {
 public:
  /// The message type.
  using Message = T;

  /// Puts one message in the bag (an atomic's output(), or a test).
  void add(T message) { bag_.push_back(std::move(message)); }
  /// The messages of the current instant, in arrival order.
  const std::vector<T>& messages() const { return bag_; }

  bool empty() const override { return bag_.empty(); }
  std::size_t size() const override { return bag_.size(); }
  void clear() override { bag_.clear(); }
  void append_from(const PortBase& source) override {
    // The type was checked when the coupling was made; no check per message.
    const auto& typed = static_cast<const Port<T>&>(source);
    bag_.insert(bag_.end(), typed.bag_.begin(), typed.bag_.end());
  }

 private:
  friend class Component;  // only a component creates ports, so the owner is always right
  Port(std::string name, Component& owner, PortDirection direction)
      : PortBase(std::move(name), owner, direction, typeid(T)) {}

  std::vector<T> bag_;
};

}  // namespace rilbed::sim
