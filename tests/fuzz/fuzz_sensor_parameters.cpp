// Fuzz target for sensor models' parameter files (src/run/sensor_parameters.hpp): any
// text through parse_parameter_text (paper 000's format or YAML) and, when it parses,
// parameter_values against the keys of paper 000's track sensor.
//
// Invariants, whatever the parser accepts:
//   - a failure names the file ("fuzz.txt") at its start;
//   - every entry's value is finite, its line within the text, no two keys alike as matched;
//   - accepted values are one per declared key, each in its range (whole where it must be).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>

#include "run/sensor_parameters.hpp"

namespace {

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_sensor_parameters: invariant broken: %s\n", what);
  std::abort();
}

#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (0)

rilbed::agents::SensorModelEntry track_model() {
  rilbed::agents::SensorModelEntry e;
  e.name = "track_element";
  e.params = {{"Height", "mm", "", 8.0, false, 1e-3, 1e3},
              {"Inclination", "deg", "", 45.0, false, 0, 89},
              {"Cone Angle", "deg", "", 30.0, false, 1e-3, 178},
              {"Precision", "", "", 16.0, true, 1, 4096},
              {"Coverage", "%", "", 15.0, false, 0, 100},
              {"Max Value", "", "", 255.0, true, 1, 1e6},
              {"Error Level", "%", "", std::nullopt, false, 0, 1000}};
  return e;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto file = rilbed::run::parse_parameter_text(text, "fuzz.txt");
  if (!file) {
    FUZZ_CHECK(file.error().rfind("fuzz.txt", 0) == 0);
    return 0;
  }
  std::set<std::string> keys;
  std::size_t lines = 1;
  for (const char c : text) lines += c == '\n';
  for (const rilbed::run::ParameterEntry& e : file->entries) {
    FUZZ_CHECK(std::isfinite(e.value));
    FUZZ_CHECK(e.line >= 1 && static_cast<std::size_t>(e.line) <= lines + 1);
    FUZZ_CHECK(keys.insert(rilbed::agents::sensor_param_key(e.key)).second);
  }
  static const rilbed::agents::SensorModelEntry model = track_model();
  const auto values = rilbed::run::parameter_values(model, *file);
  if (!values) {
    FUZZ_CHECK(values.error().rfind("fuzz.txt", 0) == 0);
    return 0;
  }
  FUZZ_CHECK(values->size() == model.params.size());
  for (std::size_t i = 0; i < values->size(); ++i) {
    const double v = (*values)[i];
    FUZZ_CHECK(v >= model.params[i].min && v <= model.params[i].max);
    FUZZ_CHECK(!model.params[i].integer || v == std::floor(v));
  }
  return 0;
}
