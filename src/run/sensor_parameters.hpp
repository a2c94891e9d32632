// A sensor model's parameter file (paper 000 §8.2), read as printed there
//
//   Sensor = {
//       Height      = 8
//       Cone Angle  = 30
//   }
//
// (a name, `= {`, one `Key = number` a line with spaces allowed in keys, `}`; blank lines
// and `#` comments anywhere) or as YAML (a mapping of keys to numbers, optionally under
// one top-level name as `Sensor: {...}`), and checked against the keys the model declares.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "agents/library_sensor_models.hpp"
#include "core/result.hpp"

namespace rilbed::run {

/// One `key = value` of a parameter file.
struct ParameterEntry {
  std::string key;  ///< as written: "Cone Angle"
  double value = 0.0;
  int line = 0;  ///< 1-based
};

/// A parameter file's entries, in the file's order.
struct ParameterFile {
  std::string source;  ///< its name, for messages
  std::vector<ParameterEntry> entries;
};

/// Reads parameter text (paper 000's format or YAML; the first line that is not blank or
/// a comment tells which). A failure is "SOURCE:LINE: what is wrong" (a line that is no
/// `Key = number`, a value that is not a finite number, a key given twice, no closing `}`).
core::Result<ParameterFile> parse_parameter_text(const std::string& text, const std::string& source);

/// Reads the file at `path` (as parse_parameter_text).
core::Result<ParameterFile> read_parameter_file(const std::filesystem::path& path);

/// The values of `model`'s parameters from `file`, in the model's order, defaults filled
/// in. A failure names the file, the line and the key: a key the model does not declare
/// (with the keys it does), one it needs that the file leaves out, a value out of range
/// or not whole where it must be.
core::Result<std::vector<double>> parameter_values(const agents::SensorModelEntry& model, const ParameterFile& file);

/// As above, for any model's declared keys (an actuator model's); `model` names it in
/// messages ("actuator model differential_drive").
core::Result<std::vector<double>> parameter_values(const std::string& model,
                                                   const std::vector<agents::SensorParamSpec>& params,
                                                   const ParameterFile& file);

}  // namespace rilbed::run
