#include "run/scenario_overrides.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>

#include "run/scenario.hpp"

namespace rilbed::run {

namespace {

std::vector<std::string> path_keys(const std::string& path) {
  std::vector<std::string> keys;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    keys.push_back(path.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return keys;
}

std::optional<std::size_t> list_index(const std::string& key) {
  std::size_t index = 0;
  const auto [end, error] = std::from_chars(key.data(), key.data() + key.size(), index);
  if (error != std::errc() || end != key.data() + key.size() || key.empty()) return std::nullopt;
  return index;
}

// The node at `keys[level]` under `node` (a reference into the document), or a failure.
YAML::Node child(YAML::Node node, const std::string& key, bool last, const std::string& where) {
  if (node.IsSequence()) {
    const std::optional<std::size_t> index = list_index(key);
    if (!index || *index >= node.size()) {
      throw ScenarioError(where + ": '" + key + "' is not an index of its list (it has " + std::to_string(node.size()) +
                          " items)");
    }
    return node[*index];
  }
  if (!node.IsMap()) throw ScenarioError(where + ": the level before '" + key + "' is not a map or a list");
  // A missing level is a new map (`convoy.standoff_m` in a scenario without `convoy:`);
  // a misspelt key is then the parser's to name, as in a file.
  if (!last && !node[key]) node[key] = YAML::Node(YAML::NodeType::Map);
  return node[key];
}

}  // namespace

std::string apply_overrides(const std::string& yaml_text, const std::vector<ScenarioOverride>& overrides,
                            const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(source_name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw ScenarioError(source_name + ": the scenario is not a map of keys");
  for (const ScenarioOverride& o : overrides) {
    const std::string where = source_name + ": override '" + o.path + "'";
    YAML::Node value;
    try {
      value = YAML::Load(o.value_yaml);
    } catch (const YAML::ParserException& e) {
      throw ScenarioError(where + ": the value is not valid YAML: " + e.msg);
    }
    const std::vector<std::string> keys = path_keys(o.path);
    for (const std::string& k : keys) {
      if (k.empty()) throw ScenarioError(where + ": a path is keys with dots between them (convoy.standoff_m)");
    }
    YAML::Node node = root;
    for (std::size_t i = 0; i + 1 < keys.size(); ++i) node.reset(child(node, keys[i], false, where));
    YAML::Node target = child(node, keys.back(), true, where);
    target = value;
  }
  YAML::Emitter out;
  out << root;
  return out.c_str();
}

}  // namespace rilbed::run
