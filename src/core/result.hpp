// A value or the reason there is none: the expected-style result of the modules'
// functions whose failures are ordinary input (a robot's bad reply, a library that will
// not load), returned rather than thrown.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace rilbed::core {

/// The reason a Result holds no value: what was wrong, in words a user can act on.
struct Failure {
  std::string reason;
};

/// A value or the reason there is none (std::expected's role; C++20 has none): what a
/// function returns for a failure its caller should expect (bad bytes from a robot, a
/// plug-in library that will not load) rather than throwing.
template <typename T>
class Result {
 public:
  /// A success holding `value`.
  Result(T value) : value_(std::move(value)) {}  // NOLINT(google-explicit-constructor): `return value;`
  /// A failure holding `failure.reason`.
  Result(Failure failure) : error_(std::move(failure.reason)) {}  // NOLINT(google-explicit-constructor)

  /// true when it holds a value.
  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  /// The value; only valid when ok().
  const T& value() const { return *value_; }
  T& value() { return *value_; }
  const T& operator*() const { return *value_; }
  T& operator*() { return *value_; }
  const T* operator->() const { return &*value_; }
  T* operator->() { return &*value_; }
  /// Why there is no value; empty when ok().
  const std::string& error() const { return error_; }

 private:
  std::optional<T> value_;
  std::string error_;
};

}  // namespace rilbed::core
