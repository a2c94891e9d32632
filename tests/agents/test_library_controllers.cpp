// Controllers from plug-in libraries: rilbed's own c:braitenberg (plugins/braitenberg.so),
// a C++ library of classes built against the SDK (test_plugins/test_classes.so), and
// libraries wrong in one way each (test_plugins/broken_N.so): every error the loader gives.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "agents/behaviour_names.hpp"
#include "agents/builtin_controllers.hpp"
#include "agents/c_controller.hpp"
#include "agents/library_controllers.hpp"
#include "agents/plugin_library.hpp"

namespace rilbed::agents {
namespace {

const std::filesystem::path kPlugins = RILBED_PLUGIN_DIR;
const std::filesystem::path kTestPlugins = RILBED_TEST_PLUGIN_DIR;

ControlInput with_proximity(const environment::ProximityValues& p, TimeUs t_us = 0) {
  ControlInput in;
  in.t_us = t_us;
  in.robot_id = 3;
  in.sensors.proximity = p;
  in.pose = Pose2{{0.5, 0.5}, 0.0};
  return in;
}

// The C controller `name` of the library at `path`, with the library it keeps loaded.
std::pair<std::shared_ptr<const PluginLibrary>, const rilbed_c_controller*> c_controller(
    const std::filesystem::path& path, std::string_view name) {
  auto library = PluginLibrary::open(path);
  EXPECT_TRUE(library) << library.error();
  if (!library) return {};
  using List = const rilbed_c_controller* const* (*)();
  auto list = reinterpret_cast<List>((*library)->symbol("rilbed_controllers"));
  for (const rilbed_c_controller* const* c = list(); *c; ++c) {
    if (name == (*c)->name) return {*library, *c};
  }
  return {*library, nullptr};
}

std::string load_error(const std::filesystem::path& path) {
  auto entries = load_library_controllers(path);
  EXPECT_FALSE(entries) << path << " loaded";
  return entries ? std::string() : entries.error();
}

TEST(CController, BraitenbergDrivesThroughTheRegisters) {
  auto [library, c] = c_controller(kPlugins / "braitenberg.so", "braitenberg");
  ASSERT_NE(c, nullptr);
  CControllerAdapter robot(*c, library);
  ControlOutput open = robot.step(with_proximity({}));
  EXPECT_EQ(open.wheels, (WheelCommand{10, 10}));
  EXPECT_EQ(open.behaviour, "c0");
  ControlOutput left = robot.step(with_proximity({900, 900, 400, 0, 0, 0, 0, 0}));
  EXPECT_GT(left.wheels.left, left.wheels.right);
  EXPECT_EQ(left.behaviour, "c1");
  EXPECT_EQ(robot.registers().peek(RILBED_REG_ID), 3);
  EXPECT_EQ(robot.registers().peek(RILBED_REG_PROX_0), 900);
  EXPECT_EQ(robot.registers().peek(RILBED_REG_USER_0), 2);  // init zeroed it, two steps counted
  robot.finish();
  EXPECT_EQ(robot.registers().peek(RILBED_REG_MOTOR_LEFT), 0);  // cleanup stopped the motors
}

TEST(CController, EachRobotHasItsOwnRegisters) {
  auto [library, c] = c_controller(kPlugins / "braitenberg.so", "braitenberg");
  ASSERT_NE(c, nullptr);
  CControllerAdapter a(*c, library), b(*c, library);
  for (int i = 0; i < 3; ++i) a.step(with_proximity({}));
  b.step(with_proximity({}));
  EXPECT_EQ(a.registers().peek(RILBED_REG_USER_0), 3);
  EXPECT_EQ(b.registers().peek(RILBED_REG_USER_0), 1);
}

TEST(CController, TheBuiltInEntryLoadsTheLibraryBesideRilbed) {
  const ControllerEntry* e = default_controllers()->find("c:braitenberg");
  ASSERT_NE(e, nullptr);
  EXPECT_FALSE(e->concurrent);
  const ControllerParams none(e->params, {});
  const environment::SensorSuiteConfig sensors;
  const ConvoyConfig convoy;
  std::unique_ptr<Controller> c = e->make({3, none, sensors, convoy});
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->step(with_proximity({})).wheels, (WheelCommand{10, 10}));
}

TEST(RegisterMap, ControllerWritesOnlyWhereAllowed) {
  RegisterMap r;
  r.poke(RILBED_REG_PROX_0, 5);
  r.poke(RILBED_REG_COUNT + 10, 5);
  EXPECT_EQ(r.peek(RILBED_REG_PROX_0), 0);
  EXPECT_EQ(r.rejected_writes(), 2);
  r.poke(RILBED_REG_MOTOR_RIGHT, -40);
  EXPECT_EQ(r.peek(RILBED_REG_MOTOR_RIGHT), -40);
  EXPECT_EQ(r.peek(0xFFFFFFFFu), 0);
  EXPECT_EQ(plugin_host().peek(RILBED_REG_ID), 0);  // outside any controller call: no current robot
}

TEST(LibraryControllers, ALibraryListsItsCAndCppControllers) {
  auto c = load_library_controllers(kPlugins / "braitenberg.so");
  ASSERT_TRUE(c) << c.error();
  ASSERT_EQ(c->size(), 1u);
  EXPECT_EQ(c->front().name, "braitenberg");
  EXPECT_EQ(c->front().library, (kPlugins / "braitenberg.so").string());
  EXPECT_EQ(c->front().origin, c->front().library);

  auto classes = load_library_controllers(kTestPlugins / "test_classes.so");
  ASSERT_TRUE(classes) << classes.error();
  ASSERT_EQ(classes->size(), 3u);
  const ControllerEntry& cruise = classes->at(0);
  EXPECT_EQ(cruise.name, "cruise");
  EXPECT_EQ(cruise.summary, "drives straight ahead at its speed");
  ASSERT_EQ(cruise.params.size(), 2u);
  EXPECT_EQ(cruise.params[0].name, "speed_mps");
  EXPECT_EQ(cruise.params[0].unit, "m/s");
  EXPECT_EQ(cruise.params[0].default_value, 0.1);
  EXPECT_EQ(cruise.params[0].max, 1.016);
  EXPECT_TRUE(cruise.params[1].integer);
  EXPECT_EQ(cruise.sensors, (std::vector<std::string>{"proximity", "pose"}));
  EXPECT_TRUE(cruise.wants_team);
  EXPECT_TRUE(cruise.concurrent);
  EXPECT_TRUE(classes->at(1).params[0].required);
  EXPECT_EQ(classes->at(2).required_sensors, (std::vector<std::string>{"track"}));
  EXPECT_FALSE(classes->at(2).concurrent);
  // The registry takes them, and its JSON says where they come from.
  ControllerRegistry registry = builtin_controllers();
  for (ControllerEntry& e : *classes) registry.add(std::move(e));
  const auto json = controllers_json(registry);
  EXPECT_EQ(json.back()["library"], (kTestPlugins / "test_classes.so").string());
  EXPECT_TRUE(json.front()["library"].is_null());
}

TEST(LibraryControllers, AClassStepsWithItsParametersAndTheTeam) {
  auto classes = load_library_controllers(kTestPlugins / "test_classes.so");
  ASSERT_TRUE(classes) << classes.error();
  const ControllerEntry& e = classes->at(0);
  const ControllerParams params(e.params, {{"speed_mps", 0.08}, {"stop_after_steps", 2}});
  const environment::SensorSuiteConfig sensors;
  const ConvoyConfig convoy;
  std::unique_ptr<Controller> c = e.make({5, params, sensors, convoy});
  ASSERT_NE(c, nullptr);
  EXPECT_TRUE(c->wants_team());
  ControlInput in = with_proximity({});
  const std::vector<TeamMessage> team = {{1, {}, "follow", 0}, {2, {}, "search", 0}};
  in.team = team;
  const ControlOutput out = c->step(in);
  EXPECT_EQ(out.wheels, (WheelCommand{10, 10}));  // 0.08 m/s is 10 units of 8 mm/s
  EXPECT_EQ(out.behaviour, "team2");
  EXPECT_EQ(out.behaviour.data(), intern_behaviour("team2").data());  // lives as long as the program
  EXPECT_FALSE(c->done());
  c->step(in);
  EXPECT_TRUE(c->done());
}

TEST(LibraryControllers, AClassThatFailsIsAnErrorNamingTheRobotAndTheLibrary) {
  auto classes = load_library_controllers(kTestPlugins / "test_classes.so");
  ASSERT_TRUE(classes) << classes.error();
  const ControllerEntry& e = classes->at(1);
  const ControllerParams params(e.params, {{"fail_at_ms", 200}});
  const environment::SensorSuiteConfig sensors;
  const ConvoyConfig convoy;
  std::unique_ptr<Controller> c = e.make({4, params, sensors, convoy});
  EXPECT_EQ(c->step(with_proximity({}, 100'000)).behaviour, "cruise");
  try {
    c->step(with_proximity({}, 200'000));
    FAIL() << "the step did not fail";
  } catch (const std::runtime_error& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("controller failing of robot 4"), std::string::npos) << what;
    EXPECT_NE(what.find("test_classes.so"), std::string::npos) << what;
    EXPECT_NE(what.find("the gyro is gone"), std::string::npos) << what;
  }
  // A constructor that throws: the factory's std::invalid_argument, with the message.
  try {
    e.make({13, params, sensors, convoy});
    FAIL() << "robot 13's controller was made";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("robot 13 is unlucky"), std::string::npos) << error.what();
  }
}

TEST(LibraryControllers, OutputIsClampedAndItsBehaviourBounded) {
  const ControlOutput o = output_from_class({500, -500, nullptr});
  EXPECT_EQ(o.wheels, (WheelCommand{kMaxWheelUnits, -kMaxWheelUnits}));
  EXPECT_EQ(o.behaviour, "idle");
  const std::string long_name(300, 'x');
  EXPECT_EQ(output_from_class({0, 0, long_name.c_str()}).behaviour, "other");
  EXPECT_EQ(output_from_class({0, 0, "a,b"}).behaviour, "other");  // it would split a CSV row
  EXPECT_EQ(output_from_class({0, 0, "line\nbreak"}).behaviour, "other");
}

// Every error the loader gives, each from a library that is wrong in that way.
TEST(LibraryControllers, EveryLoaderErrorNamesTheLibraryAndTheCause) {
  struct Case {
    std::filesystem::path library;
    std::string cause;
  };
  const std::filesystem::path text = std::filesystem::path(testing::TempDir()) / "not_a_library.so";
  std::ofstream(text) << "this is text\n";
  const std::vector<Case> cases = {
      {kTestPlugins / "no_such_library.so", "no such file"},
      {kTestPlugins, "is a folder"},
      {text, "cannot be loaded"},
      {kTestPlugins / "broken_1.so", "ABI version 999, this rilbed loads version 1"},
      {kTestPlugins / "broken_2.so", "undefined symbol: lab_helper_from_elsewhere"},
      {kTestPlugins / "broken_3.so", "does not export rilbed_abi_version()"},
      {kTestPlugins / "broken_4.so", "exports neither rilbed_controllers() nor rilbed_controller_classes()"},
      {kTestPlugins / "broken_5.so", "rilbed_controllers() returned NULL"},
      {kTestPlugins / "broken_6.so", "two controllers named 'twin'"},
      {kTestPlugins / "broken_7.so", "has min above max"},
      {kTestPlugins / "broken_8.so", "'lame' has no step function"},
  };
  for (const Case& c : cases) {
    const std::string error = load_error(c.library);
    EXPECT_NE(error.find(std::filesystem::absolute(c.library).lexically_normal().string()), std::string::npos) << error;
    EXPECT_NE(error.find(c.cause), std::string::npos) << c.library << ": " << error;
  }
}

TEST(LibraryControllers, AClassIsCheckedBeforeItIsUsed) {
  auto create = [](const void*, const rilbed_controller_args*, char*, std::uint32_t) -> void* { return nullptr; };
  auto step = [](void*, const rilbed_control_input*, rilbed_control_output*, char*, std::uint32_t) -> std::int32_t {
    return 0;
  };
  auto destroy = [](void*) {};
  rilbed_param param{"gain", "", "a gain", 0.5, 1, 0, 0, 0.0, 1.0};
  const rilbed_controller_class good{RILBED_ABI_VERSION,
                                     "ok",
                                     "fine",
                                     &param,
                                     1,
                                     nullptr,
                                     nullptr,
                                     0,
                                     1,
                                     nullptr,
                                     create,
                                     step,
                                     nullptr,
                                     nullptr,
                                     destroy};
  ASSERT_TRUE(class_entry(good, nullptr, "x.so")) << class_entry(good, nullptr, "x.so").error();
  auto problem = [&](rilbed_controller_class c) {
    const auto e = class_entry(c, nullptr, "x.so");
    return e ? std::string("accepted") : e.error();
  };
  rilbed_controller_class c = good;
  c.abi_version = 0;
  EXPECT_NE(problem(c).find("ABI version 0"), std::string::npos);
  c = good;
  c.name = nullptr;
  EXPECT_NE(problem(c).find("name is NULL"), std::string::npos);
  c.name = "has space";
  EXPECT_NE(problem(c).find("holds a character"), std::string::npos);
  c = good;
  c.summary = "\x82 not UTF-8";
  EXPECT_NE(problem(c).find("not UTF-8 text"), std::string::npos);
  c.summary = "a tab\there";
  EXPECT_NE(problem(c).find("not UTF-8 text"), std::string::npos);
  c.summary = "UTF-8 is fine: 55 \xc2\xb5m";
  EXPECT_TRUE(class_entry(c, nullptr, "x.so")) << problem(c);
  c = good;
  c.step = nullptr;
  EXPECT_NE(problem(c).find("lacks its create, step or destroy"), std::string::npos);
  c = good;
  c.param_count = 65;
  EXPECT_NE(problem(c).find("more than 64 parameters"), std::string::npos);
  c = good;
  c.params = nullptr;
  EXPECT_NE(problem(c).find("list is NULL"), std::string::npos);
  rilbed_param nan_default = param;
  nan_default.default_value = std::nan("");
  c = good;
  c.params = &nan_default;
  EXPECT_NE(problem(c).find("not finite"), std::string::npos);
  rilbed_param outside = param;
  outside.default_value = 2.0;
  c.params = &outside;
  EXPECT_NE(problem(c).find("default outside its range"), std::string::npos);
}

}  // namespace
}  // namespace rilbed::agents
