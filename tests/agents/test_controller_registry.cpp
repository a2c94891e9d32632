#include <gtest/gtest.h>

#include <string>

#include "agents/builtin_controllers.hpp"
#include "agents/controller_registry.hpp"
#include "support/spinner_controller.hpp"

namespace rilbed::agents {
namespace {

using rilbed::testing::spinner_entry;

TEST(ControllerRegistry, ParametersAreCheckedForRangeWholeNumbersAndPresence) {
  const auto registry = default_controllers();
  const ControllerEntry& beacon = *registry->find("beacon_homing");
  EXPECT_FALSE(check_params(beacon, {{"beacon_id", 2}, {"speed_mps", 0.2}}));
  EXPECT_EQ(check_params(beacon, {{"beacon_id", 2.5}})->problem, "must be a whole number");
  EXPECT_EQ(check_params(beacon, {{"speed_mps", 2.0}})->key, "speed_mps");
  EXPECT_EQ(check_params(beacon, {{"speed_mps", -0.1}})->problem, "must be 0 to 1.016 (m/s), not -0.1");
  const ControllerEntry& go = *registry->find("goto");
  const auto missing = check_params(go, {{"x_m", 0.3}});
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->key, "");
  EXPECT_NE(missing->problem.find("needs parameter 'y_m'"), std::string::npos);
  EXPECT_FALSE(check_params(go, {{"x_m", 0.3}, {"y_m", 0.4}}));
  environment::SensorSuiteConfig sensors;
  EXPECT_EQ(missing_sensor(*registry->find("track_follow"), sensors), "track");
  sensors.track_sensors.emplace_back();
  EXPECT_FALSE(missing_sensor(*registry->find("track_follow"), sensors));
}

TEST(ControllerRegistry, EveryBuiltInEntrySaysWhatItsControllersDo) {
  const auto registry = default_controllers();
  ASSERT_NE(registry->find("convoy"), nullptr);
  ASSERT_NE(registry->find("c:braitenberg"), nullptr);
  ASSERT_NE(registry->find("none"), nullptr);
  environment::SensorSuiteConfig sensors;
  for (const double y_m : {0.012, 0.0, -0.012}) {  // a row across the front, as track_explore needs
    environment::TrackSensorConfig element;
    element.mount_y_m = y_m;
    sensors.track_sensors.push_back(element);
  }
  sensors.beacon_finder = environment::BeaconFinderConfig{};
  const ConvoyConfig convoy;
  for (const ControllerEntry& e : registry->entries()) {
    SCOPED_TRACE(e.name);
    EXPECT_FALSE(e.summary.empty());
    std::map<std::string, double> given;
    for (const ParamSpec& p : e.params) {
      EXPECT_FALSE(p.summary.empty()) << p.name;
      if (p.required) given[p.name] = std::isfinite(p.min) ? std::max(p.min, 0.0) : 0.0;
    }
    ASSERT_FALSE(check_params(e, given));
    const ControllerParams params(e.params, given);
    const auto controller = e.make(ControllerContext{1, params, sensors, convoy});
    if (e.name == "none") {
      EXPECT_EQ(controller, nullptr);
      continue;
    }
    ASSERT_NE(controller, nullptr);
    // The entry says what the controller itself says (the JSON and the run agree).
    EXPECT_EQ(controller->wants_team(), e.wants_team);
    EXPECT_EQ(controller->concurrent(), e.concurrent);
  }
}

TEST(ControllerRegistry, RefusesEntriesThatCannotBeUsed) {
  ControllerRegistry r = builtin_controllers();
  EXPECT_THROW(r.add(r.entries().front()), std::invalid_argument);  // the name is taken
  ControllerEntry e = spinner_entry();
  e.params[0].default_value = 7.0;  // outside 0..5
  EXPECT_THROW(r.add(e), std::invalid_argument);
  e = spinner_entry();
  e.sensors = {"sonar"};
  EXPECT_THROW(r.add(e), std::invalid_argument);
  e = spinner_entry();
  e.make = nullptr;
  EXPECT_THROW(r.add(e), std::invalid_argument);
  e = spinner_entry();
  e.params.push_back(e.params[0]);
  EXPECT_THROW(r.add(e), std::invalid_argument);
  r.add(spinner_entry());
  EXPECT_EQ(r.entries().back().name, "spinner");
}

}  // namespace
}  // namespace rilbed::agents
