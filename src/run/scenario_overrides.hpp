// Changes to a scenario's text by path, before it is read: what `rilbed.run(...,
// overrides={...})` applies (and a sweep's factors). A path names a key of the YAML
// document with dots between the levels, and a list's item by its index:
// `convoy.standoff_m`, `robots.0.params.speed_mps`, `duration_s`.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rilbed::run {

/// One change: the value (YAML text: `0.12`, `random`, `[0.1, 0.2, 0]`, `{a: 1}`) put at `path`.
struct ScenarioOverride {
  std::string path;
  std::string value_yaml;
};

/// `yaml_text` with every override applied in order, as YAML text. Missing keys are added
/// (a new map for a missing level); a list's item must exist. Throws ScenarioError (naming `source_name` and the path)
/// for text that is not YAML, a value that is not, or a path that leads nowhere.
std::string apply_overrides(const std::string& yaml_text, const std::vector<ScenarioOverride>& overrides,
                            const std::string& source_name);

}  // namespace rilbed::run
