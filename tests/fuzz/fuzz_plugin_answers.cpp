// Fuzz target for what a plug-in library answers the loader (agents/library_controllers.hpp):
// a controller class whose every field comes from the input (its ABI version, name,
// summary, parameters with any doubles (NaN, infinities), sensors, functions present or
// not), read by class_entry; a C controller by c_controller_entry; and a step's output by
// output_from_class. The library's pointers themselves are trusted (a library that lies
// about the length of its own arrays is a crash no loader can check): the arrays here are
// as long as their counts say.
//
// Invariants, whatever the loader accepts:
//   - an accepted class is an entry a registry takes (its add() does not throw), whose
//     JSON dumps, with one ParamSpec per parameter, names non-empty and the ranges ordered;
//   - a refused class gets a reason that names the origin;
//   - an output's wheels are within +-127 and its behaviour at most 64 bytes or "other".
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "agents/library_controllers.hpp"

namespace {

using namespace rilbed::agents;

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_plugin_answers: invariant broken: %s\n", what);
  std::abort();
}

#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (0)

// Strings kept alive for the class's pointers; c_str() or NULL.
class Strings {
 public:
  const char* take(FuzzedDataProvider& in) {
    if (in.ConsumeIntegralInRange<int>(0, 15) == 0) return nullptr;
    kept_.push_back(in.ConsumeRandomLengthString(200));
    return kept_.back().c_str();
  }
  void reserve(std::size_t n) { kept_.reserve(n); }

 private:
  std::vector<std::string> kept_;
};

double any_double(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 5)) {
    case 0: return std::nan("");
    case 1: return HUGE_VAL;
    case 2: return -HUGE_VAL;
    default: return in.ConsumeFloatingPointInRange<double>(-1e6, 1e6);
  }
}

void* create(const void*, const rilbed_controller_args*, char*, std::uint32_t) { return nullptr; }
std::int32_t step(void*, const rilbed_control_input*, rilbed_control_output*, char*, std::uint32_t) { return 0; }
void destroy(void*) {}
void c_step() {}

void check_class(FuzzedDataProvider& in) {
  Strings strings;
  strings.reserve(256);  // pointers into the strings stay valid
  const std::size_t param_count = in.ConsumeIntegralInRange<std::size_t>(0, 70);
  std::vector<rilbed_param> params(param_count);
  for (rilbed_param& p : params) {
    p.name = strings.take(in);
    p.unit = strings.take(in);
    p.summary = strings.take(in);
    p.default_value = any_double(in);
    p.has_default = in.ConsumeIntegralInRange<int>(0, 2);
    p.required = in.ConsumeIntegralInRange<int>(0, 2);
    p.integer = in.ConsumeBool();
    p.min = any_double(in);
    p.max = any_double(in);
  }
  std::vector<const char*> sensors;
  const std::size_t sensor_count = in.ConsumeIntegralInRange<std::size_t>(0, 20);
  for (std::size_t i = 0; i < sensor_count; ++i) {
    const char* s = strings.take(in);
    sensors.push_back(s ? s : "proximity");  // a NULL would end the list early
  }
  sensors.push_back(nullptr);
  const std::vector<const char*> required = {in.ConsumeBool() ? "proximity" : "track", nullptr};
  rilbed_controller_class c{};
  c.abi_version = in.ConsumeBool() ? RILBED_ABI_VERSION : in.ConsumeIntegral<std::uint32_t>();
  c.name = strings.take(in);
  c.summary = strings.take(in);
  c.params = in.ConsumeIntegralInRange<int>(0, 20) == 0 ? nullptr : params.data();
  c.param_count = static_cast<std::uint32_t>(param_count);
  c.sensors = in.ConsumeBool() ? sensors.data() : nullptr;
  c.required_sensors = in.ConsumeBool() ? required.data() : nullptr;
  c.wants_team = in.ConsumeIntegral<std::int32_t>();
  c.concurrent = in.ConsumeIntegral<std::int32_t>();
  c.create = in.ConsumeIntegralInRange<int>(0, 20) ? create : nullptr;
  c.step = in.ConsumeIntegralInRange<int>(0, 20) ? step : nullptr;
  c.destroy = in.ConsumeIntegralInRange<int>(0, 20) ? destroy : nullptr;
  if (!c.params) c.param_count = in.ConsumeBool() ? 0 : c.param_count;

  const auto entry = class_entry(c, nullptr, "fuzz.so");
  if (!entry) {
    FUZZ_CHECK(entry.error().find("fuzz.so") != std::string::npos);
    return;
  }
  FUZZ_CHECK(entry->params.size() == c.param_count);
  FUZZ_CHECK(!entry->name.empty());
  for (const ParamSpec& p : entry->params) {
    FUZZ_CHECK(!p.name.empty());
    FUZZ_CHECK(p.min <= p.max);
    FUZZ_CHECK(!p.default_value || std::isfinite(*p.default_value));
  }
  ControllerRegistry registry;
  registry.add(*entry);  // throws (and so fails) if class_entry let through what add refuses
  FUZZ_CHECK(!controllers_json(registry).dump().empty());
}

void check_c_controller(FuzzedDataProvider& in) {
  Strings strings;
  strings.reserve(4);
  const rilbed_c_controller c{strings.take(in), nullptr, in.ConsumeBool() ? c_step : nullptr, nullptr};
  const auto entry = c_controller_entry(c, nullptr, "");
  if (!entry) return;
  FUZZ_CHECK(entry->name == c.name);
  FUZZ_CHECK(entry->make != nullptr);
}

void check_output(FuzzedDataProvider& in) {
  Strings strings;
  strings.reserve(4);
  const rilbed_control_output out{in.ConsumeIntegral<std::int32_t>(), in.ConsumeIntegral<std::int32_t>(),
                                  strings.take(in)};
  const rilbed::agents::ControlOutput o = output_from_class(out);
  FUZZ_CHECK(o.wheels.left >= -kMaxWheelUnits && o.wheels.left <= kMaxWheelUnits);
  FUZZ_CHECK(o.wheels.right >= -kMaxWheelUnits && o.wheels.right <= kMaxWheelUnits);
  FUZZ_CHECK(o.behaviour.size() <= 64);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  switch (in.ConsumeIntegralInRange<int>(0, 2)) {
    case 0: check_class(in); break;
    case 1: check_c_controller(in); break;
    default: check_output(in);
  }
  return 0;
}
