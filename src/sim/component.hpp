// The common part of atomic and coupled DEVS models: an id and typed ports.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "sim/port.hpp"

namespace rilbed::sim {

/// A DEVS model (atomic or coupled): an id and its input and output ports.
///
/// Ports are created in the constructor of the concrete model and are owned by it;
/// the references add_input/add_output return stay valid for the component's life.
/// A component has at most one parent (the Coupled it was added to). Not copyable,
/// not movable (ports point back to it). Not thread-safe.
class Component {
 public:
  /// `id` names the component in paths and error messages; it must not be empty and
  /// must be unique among its siblings. Throws std::invalid_argument otherwise.
  explicit Component(std::string id);
  virtual ~Component();
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  /// The id given at construction.
  const std::string& id() const { return id_; }
  /// The coupled model this component was added to, or nullptr (a root).
  const Component* parent() const { return parent_; }
  /// Ids from the outermost ancestor down to this one, joined with '/': "top/mid/proc".
  std::string path() const;

  /// Creates an input port for messages of type T. Throws std::invalid_argument when
  /// an input of that name exists.
  template <class T>
  Port<T>& add_input(std::string name) {
    return add_port<T>(std::move(name), PortDirection::kInput);
  }
  /// Creates an output port for messages of type T. Throws std::invalid_argument when
  /// an output of that name exists.
  template <class T>
  Port<T>& add_output(std::string name) {
    return add_port<T>(std::move(name), PortDirection::kOutput);
  }

  /// The input port `name` as a Port<T>; throws std::invalid_argument when there is
  /// none or its type is not T.
  template <class T>
  Port<T>& input_port(std::string_view name) {
    return static_cast<Port<T>&>(checked_port(PortDirection::kInput, name, typeid(T)));
  }
  /// The output port `name` as a Port<T>; throws like input_port(). (Not named
  /// output(): that is the atomic models' output function.)
  template <class T>
  Port<T>& output_port(std::string_view name) {
    return static_cast<Port<T>&>(checked_port(PortDirection::kOutput, name, typeid(T)));
  }
  /// The input port `name`, or nullptr.
  PortBase* find_input(std::string_view name) const;
  /// The output port `name`, or nullptr.
  PortBase* find_output(std::string_view name) const;

  /// Input ports in creation order.
  const std::vector<std::unique_ptr<PortBase>>& inputs() const { return inputs_; }
  /// Output ports in creation order.
  const std::vector<std::unique_ptr<PortBase>>& outputs() const { return outputs_; }

 private:
  friend class Coupled;  // sets and clears parent_

  template <class T>
  Port<T>& add_port(std::string name, PortDirection direction) {
    check_new_port_name(direction, name);
    auto& ports = direction == PortDirection::kInput ? inputs_ : outputs_;
    // Port's constructor is private (only components create ports): no make_unique.
    auto* port = new Port<T>(std::move(name), *this, direction);
    ports.emplace_back(port);
    return *port;
  }
  void check_new_port_name(PortDirection direction, const std::string& name) const;
  PortBase& checked_port(PortDirection direction, std::string_view name, const std::type_info& type) const;

  std::string id_;
  const Component* parent_ = nullptr;
  std::vector<std::unique_ptr<PortBase>> inputs_;
  std::vector<std::unique_ptr<PortBase>> outputs_;
};

/// The readable name of a C++ type (demangled where the compiler allows), for messages.
std::string type_name(const std::type_info& type);

}  // namespace rilbed::sim
