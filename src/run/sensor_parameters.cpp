#include "run/sensor_parameters.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace rilbed::run {

namespace {

std::string trimmed(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return std::string(s.substr(first, last - first + 1));
}

// A line without its comment (from `#` to its end).
std::string without_comment(const std::string& line) { return trimmed(line.substr(0, line.find('#'))); }

std::optional<double> finite_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  double v = 0.0;
  in >> v;
  if (in.fail() || !in.eof() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string at(const std::string& source, int line) { return source + ":" + std::to_string(line) + ": "; }

// Paper 000's format: `Name = {`, `Key = number` lines, `}`.
core::Result<ParameterFile> parse_paper_format(const std::vector<std::string>& lines, const std::string& source) {
  ParameterFile file{source, {}};
  bool open = false, closed = false;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i) + 1;
    const std::string text = without_comment(lines[i]);
    if (text.empty()) continue;
    if (closed) return core::Failure{at(source, line) + "text after the closing }"};
    if (!open) {
      const auto eq = text.find('=');
      if (eq == std::string::npos || trimmed(text.substr(eq + 1)) != "{" || trimmed(text.substr(0, eq)).empty())
        return core::Failure{at(source, line) + "expected `Name = {`"};
      open = true;
      continue;
    }
    if (text == "}") {
      closed = true;
      continue;
    }
    const auto eq = text.find('=');
    if (eq == std::string::npos) return core::Failure{at(source, line) + "expected `Key = number` or `}`"};
    const std::string key = trimmed(text.substr(0, eq));
    const std::string value = trimmed(text.substr(eq + 1));
    if (key.empty()) return core::Failure{at(source, line) + "a value without a key"};
    const std::optional<double> number = finite_number(value);
    if (!number) return core::Failure{at(source, line) + key + ": '" + value + "' is not a finite number"};
    if (!seen.insert(agents::sensor_param_key(key)).second)
      return core::Failure{at(source, line) + key + ": given twice"};
    file.entries.push_back({key, *number, line});
  }
  if (!open) return core::Failure{source + ": empty: expected `Name = {`, `Key = number` lines and `}`"};
  if (!closed) return core::Failure{source + ": no closing }"};
  return file;
}

core::Result<ParameterFile> parse_yaml_format(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return core::Failure{at(source, e.mark.line + 1) + "not valid YAML: " + e.msg};
  }
  if (root.IsMap() && root.size() == 1 && root.begin()->second.IsMap()) root = root.begin()->second;
  if (!root.IsMap()) return core::Failure{source + ": expected a mapping of keys to numbers (or paper 000's format)"};
  ParameterFile file{source, {}};
  std::set<std::string> seen;
  for (const auto& kv : root) {
    const int line = kv.first.Mark().line + 1;
    if (!kv.first.IsScalar()) return core::Failure{at(source, line) + "a key that is not text"};
    const std::string key = kv.first.Scalar();
    if (!kv.second.IsScalar()) return core::Failure{at(source, line) + key + ": must be a number"};
    const std::optional<double> number = finite_number(trimmed(kv.second.Scalar()));
    if (!number) return core::Failure{at(source, line) + key + ": '" + kv.second.Scalar() + "' is not a finite number"};
    if (!seen.insert(agents::sensor_param_key(key)).second)
      return core::Failure{at(source, line) + key + ": given twice"};
    file.entries.push_back({key, *number, line});
  }
  return file;
}

std::string number_text(double v) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << v;
  return out.str();
}

}  // namespace

core::Result<ParameterFile> parse_parameter_text(const std::string& text, const std::string& source) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (const std::string& line : lines) {
    const std::string first = without_comment(line);
    if (first.empty()) continue;
    const auto eq = first.find('=');
    const bool paper = eq != std::string::npos && trimmed(first.substr(eq + 1)) == "{";
    return paper ? parse_paper_format(lines, source) : parse_yaml_format(text, source);
  }
  return ParameterFile{source, {}};  // an empty file: every parameter from its default
}

core::Result<ParameterFile> read_parameter_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return core::Failure{path.string() + ": cannot open the parameter file"};
  std::stringstream text;
  text << in.rdbuf();
  if (text.str().size() > (1u << 20)) return core::Failure{path.string() + ": larger than 1 MB: no parameter file"};
  return parse_parameter_text(text.str(), path.string());
}

core::Result<std::vector<double>> parameter_values(const agents::SensorModelEntry& model, const ParameterFile& file) {
  return parameter_values("sensor model " + model.name, model.params, file);
}

core::Result<std::vector<double>> parameter_values(const std::string& model,
                                                   const std::vector<agents::SensorParamSpec>& params,
                                                   const ParameterFile& file) {
  auto declared = [&](const std::string& key) -> const agents::SensorParamSpec* {
    const std::string wanted = agents::sensor_param_key(key);
    for (const agents::SensorParamSpec& p : params) {
      if (agents::sensor_param_key(p.key) == wanted) return &p;
    }
    return nullptr;
  };
  for (const ParameterEntry& e : file.entries) {
    const agents::SensorParamSpec* p = declared(e.key);
    if (!p) {
      std::string keys;
      for (const agents::SensorParamSpec& q : params) keys += (keys.empty() ? "" : ", ") + q.key;
      return core::Failure{at(file.source, e.line) + e.key + ": the " + model + " has no such parameter (it takes " +
                           (keys.empty() ? std::string("none") : keys) + ")"};
    }
    if (p->integer && e.value != std::floor(e.value))
      return core::Failure{at(file.source, e.line) + e.key + ": must be a whole number"};
    if (e.value < p->min || e.value > p->max) {
      return core::Failure{at(file.source, e.line) + e.key + ": must be " + number_text(p->min) + " to " +
                           number_text(p->max) + (p->unit.empty() ? "" : " (" + p->unit + ")") + ", not " +
                           number_text(e.value)};
    }
  }
  std::vector<double> values;
  for (const agents::SensorParamSpec& p : params) {
    const std::string key = agents::sensor_param_key(p.key);
    const auto given = std::find_if(file.entries.begin(), file.entries.end(),
                                    [&](const ParameterEntry& e) { return agents::sensor_param_key(e.key) == key; });
    if (given != file.entries.end()) {
      values.push_back(given->value);
    } else if (p.default_value) {
      values.push_back(*p.default_value);
    } else {
      return core::Failure{file.source + ": " + p.key + ": missing: the " + model + " needs it" +
                           (p.summary.empty() ? std::string() : " (" + p.summary + ")")};
    }
  }
  return values;
}

}  // namespace rilbed::run
