// Components, coupled models and their checks. Everything here runs while a model is
// built, never per event, so clarity wins over speed.
#include <cxxabi.h>

#include <cstdlib>
#include <stdexcept>

#include "sim/atomic.hpp"
#include "sim/coupled.hpp"

namespace rilbed::sim {

std::string type_name(const std::type_info& type) {
  int status = 0;
  char* demangled = abi::__cxa_demangle(type.name(), nullptr, nullptr, &status);
  std::string name = status == 0 && demangled ? demangled : type.name();
  std::free(demangled);
  return name;
}

std::string PortBase::describe() const {
  // Appended piece by piece: `"'" + std::string` trips GCC 12's false -Wrestrict (PR 105329).
  std::string text = "'";
  text += owner().path();
  text += '.';
  text += name_;
  text += "' (";
  text += type_name(*type_);
  text += ')';
  return text;
}

namespace {

const char* direction_word(PortDirection direction) { return direction == PortDirection::kInput ? "input" : "output"; }

PortBase* find_by_name(const std::vector<std::unique_ptr<PortBase>>& ports, std::string_view name) {
  for (const auto& port : ports)
    if (port->name() == name) return port.get();
  return nullptr;
}

}  // namespace

Component::Component(std::string id) : id_(std::move(id)) {
  if (id_.empty()) throw std::invalid_argument("sim: a component id must not be empty");
}

Component::~Component() = default;

std::string Component::path() const { return parent_ ? parent_->path() + "/" + id_ : id_; }

PortBase* Component::find_input(std::string_view name) const { return find_by_name(inputs_, name); }
PortBase* Component::find_output(std::string_view name) const { return find_by_name(outputs_, name); }

void Component::check_new_port_name(PortDirection direction, const std::string& name) const {
  const auto& ports = direction == PortDirection::kInput ? inputs_ : outputs_;
  if (name.empty()) throw std::invalid_argument("sim: '" + path() + "': a port name must not be empty");
  if (find_by_name(ports, name))
    throw std::invalid_argument("sim: '" + path() + "' already has an " + direction_word(direction) + " port '" + name +
                                "'");
}

PortBase& Component::checked_port(PortDirection direction, std::string_view name, const std::type_info& type) const {
  PortBase* port = find_by_name(direction == PortDirection::kInput ? inputs_ : outputs_, name);
  if (!port)
    throw std::invalid_argument("sim: '" + path() + "' has no " + direction_word(direction) + " port '" +
                                std::string(name) + "'");
  if (port->type() != std::type_index(type))
    throw std::invalid_argument("sim: port " + port->describe() + " does not carry " + type_name(type));
  return *port;
}

void Atomic::confluent_transition(TimeUs /*elapsed_us*/) {
  internal_transition();
  external_transition(0);
}

Coupled::~Coupled() {
  for (auto& child : children_) child->parent_ = nullptr;
}

void Coupled::add_child(std::shared_ptr<Component> child) {
  if (!child) throw std::invalid_argument("sim: '" + path() + "': cannot add a null child");
  if (child.get() == this) throw std::invalid_argument("sim: '" + path() + "' cannot contain itself");
  if (child->parent_) throw std::invalid_argument("sim: '" + child->path() + "' already belongs to a coupled model");
  if (!child_ids_.insert(child->id()).second)
    throw std::invalid_argument("sim: '" + path() + "' already has a child '" + child->id() + "'");
  child->parent_ = this;
  children_.push_back(std::move(child));
}

bool Coupled::owns_directly(const PortBase& port) const {
  return &port.owner() == this || port.owner().parent() == this;
}

void Coupled::couple(PortBase& from, PortBase& to) {
  const auto fail = [&](const std::string& why) {
    throw std::invalid_argument("sim: in '" + path() + "', cannot couple " + from.describe() + " to " + to.describe() +
                                ": " + why);
  };
  if (from.type() != to.type()) fail("the message types differ");
  if (!owns_directly(from) || !owns_directly(to))
    fail("both ports must belong to this model or to its direct children");
  const bool from_self = &from.owner() == this;
  const bool to_self = &to.owner() == this;
  const bool external_input =
      from_self && from.direction() == PortDirection::kInput && !to_self && to.direction() == PortDirection::kInput;
  const bool from_child_output = !from_self && from.direction() == PortDirection::kOutput;
  const bool internal = from_child_output && !to_self && to.direction() == PortDirection::kInput;
  const bool external_output = from_child_output && to_self && to.direction() == PortDirection::kOutput;
  if (!external_input && !internal && !external_output)
    fail(
        "expected own input -> child input, child output -> child input, "
        "or child output -> own output");
  if (!coupled_.insert({&from, &to}).second) fail("this coupling exists already");
  couplings_.push_back({&from, &to});
}

}  // namespace rilbed::sim
