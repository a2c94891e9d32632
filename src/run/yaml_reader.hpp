// The strict YAML reader behind the scenario and robot model files: every error names the
// file, the line and the key path ("robots[2].link.baud"). Internal to the run module.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/geometry.hpp"
#include "run/scenario.hpp"

namespace rilbed::run::yaml_detail {

// Reads one YAML mapping with strict checks; every error names file, line and key.
class Reader {
 public:
  Reader(const YAML::Node& node, std::string source, std::string path)
      : node_(node), source_(std::move(source)), path_(std::move(path)) {
    if (!node_.IsMap()) fail(node_, "expected a mapping of keys");
  }
  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const {
    const int line = at.Mark().line >= 0 ? at.Mark().line + 1 : 0;
    throw ScenarioError(source_ + ":" + std::to_string(line) + ": " + (path_.empty() ? "(top level)" : path_) + ": " +
                        what);
  }
  [[noreturn]] void fail_key(const std::string& key, const std::string& what) const {
    throw ScenarioError(source_ + ":" + std::to_string(line_of(key)) + ": " + join(key) + ": " + what);
  }

  // Every key must be one of `allowed`.
  void allow(std::initializer_list<const char*> allowed) const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
        std::string list;
        for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
        throw ScenarioError(source_ + ":" + std::to_string(kv.first.Mark().line + 1) + ": " + join(key) +
                            ": unknown key (allowed here: " + list + ")");
      }
    }
  }
  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  YAML::Node get(const std::string& key) const { return node_[key]; }
  std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  int line_of(const std::string& key) const {
    for (const auto& kv : node_) {
      if (kv.first.as<std::string>() == key) return kv.first.Mark().line + 1;
    }
    return node_.Mark().line + 1;
  }
  Reader child(const std::string& key) const { return Reader(node_[key], source_, join(key)); }
  const std::string& source() const { return source_; }

  double number(const std::string& key, double fallback) const {
    if (!has(key)) return fallback;
    return as_number(node_[key], key);
  }
  double positive(const std::string& key, double fallback) const {
    const double v = number(key, fallback);
    if (!(v > 0.0)) fail_key(key, "must be greater than 0");
    return v;
  }
  double non_negative(const std::string& key, double fallback) const {
    const double v = number(key, fallback);
    if (!(v >= 0.0)) fail_key(key, "must not be negative");
    return v;
  }
  int integer(const std::string& key, int fallback) const {
    if (!has(key)) return fallback;
    const double v = as_number(node_[key], key);
    if (v != std::floor(v) || std::abs(v) > 1e9) fail_key(key, "must be a whole number");
    return static_cast<int>(v);
  }
  bool boolean(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    try {
      return node_[key].as<bool>();
    } catch (const YAML::Exception&) {
      fail_key(key, "must be true or false");
    }
  }
  std::string text(const std::string& key, const std::string& fallback) const {
    if (!has(key)) return fallback;
    if (!node_[key].IsScalar()) fail_key(key, "must be a text value");
    return node_[key].as<std::string>();
  }
  Vec2 point(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != 2) fail_key(key, "must be a point [x_m, y_m]");
    return {as_number(n[0], key), as_number(n[1], key)};
  }
  /// A list of text values (a single one counts as a list of one).
  std::vector<std::string> words(const std::string& key) const {
    const YAML::Node n = node_[key];
    std::vector<std::string> out;
    if (n.IsScalar()) return {n.as<std::string>()};
    if (!n.IsSequence()) fail_key(key, "must be a list of text values");
    for (const auto& w : n) {
      if (!w.IsScalar()) fail_key(key, "must be a list of text values");
      out.push_back(w.as<std::string>());
    }
    return out;
  }
  std::vector<Vec2> points(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n || !n.IsSequence()) fail_key(key, "must be a list of points [[x_m, y_m], ...]");
    std::vector<Vec2> out;
    for (const auto& p : n) out.push_back(point(p, key));
    return out;
  }

 private:
  double as_number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail_key(key, "must be a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail_key(key, "must be a number, not '" + n.as<std::string>() + "'");
    }
    if (!std::isfinite(v)) fail_key(key, "must be a finite number");
    return v;
  }

  YAML::Node node_;
  std::string source_;
  std::string path_;
};

}  // namespace rilbed::run::yaml_detail
