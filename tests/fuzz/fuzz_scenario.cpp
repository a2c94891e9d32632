// Fuzz target for scenario files (src/run/scenario.hpp): arbitrary text goes to
// parse_scenario. A ScenarioError is the expected answer to bad input; any other exception
// escaping, a crash, a leak or undefined behaviour is a bug. A scenario that parses must
// hold what the parser promises to have checked, and an error must name the file first.
#include <cxxabi.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <typeinfo>

#include "run/scenario.hpp"

namespace {

using rilbed::run::Scenario;
using rilbed::run::ScenarioError;

constexpr const char* kSource = "fuzz.yaml";

[[noreturn]] void broken(const std::string& what) {
  std::fprintf(stderr, "\nfuzz_scenario: %s\n", what.c_str());
  std::abort();
}
#define FUZZ_CHECK(condition)                                  \
  do {                                                         \
    if (!(condition)) broken("invariant broken: " #condition); \
  } while (false)

std::string type_name(const std::type_info& type) {
  int status = 0;
  const std::unique_ptr<char, decltype(&std::free)> name(abi::__cxa_demangle(type.name(), nullptr, nullptr, &status),
                                                         &std::free);
  return status == 0 && name ? name.get() : type.name();
}

void check(const Scenario& s) {
  FUZZ_CHECK(!s.robots.empty());
  for (std::size_t i = 0; i < s.robots.size(); ++i) {
    FUZZ_CHECK(s.robots[i].id >= 1);
    if (i > 0) FUZZ_CHECK(s.robots[i - 1].id < s.robots[i].id);  // sorted, no ID twice
    if (s.robots[i].pose) {
      FUZZ_CHECK(std::isfinite(s.robots[i].pose->position_m.x) && std::isfinite(s.robots[i].pose->position_m.y));
    }
  }
  FUZZ_CHECK(s.physics_step_us > 0 && s.control_period_us > 0 && s.broadcast_period_us > 0);
  FUZZ_CHECK(std::isfinite(s.duration_s) && s.duration_s > 0.0);
  FUZZ_CHECK(s.map.field.width_m > 0.0 && s.map.field.height_m > 0.0);
  FUZZ_CHECK(s.lost_timeout_ms > 0 && s.geofence_margin_m >= 0.0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    check(rilbed::run::parse_scenario(text, kSource));
  } catch (const ScenarioError& e) {
    // "FILE:LINE: KEY: problem" (or "FILE: problem").
    const std::string message = e.what();
    if (message.rfind(std::string(kSource) + ":", 0) != 0)
      broken("a ScenarioError that does not name the file: " + message);
  } catch (const std::exception& e) {
    broken("parse_scenario let " + type_name(typeid(e)) + " escape (only ScenarioError may): " + e.what());
  } catch (...) {
    broken("parse_scenario let a non-std exception escape");
  }
  return 0;
}
