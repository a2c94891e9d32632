// Sensor models from plug-in libraries (test_plugins/test_sensors.so, built against the
// SDK alone): what the loader checks, a model mounted on robots of a real World (its
// readings, its noise from the robot's stream, the mobile objects it is told of, a track
// reading it provides), and what controllers read of it (C registers, C++ classes).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "agents/c_controller.hpp"
#include "agents/library_actuator_models.hpp"
#include "agents/library_controllers.hpp"
#include "agents/library_sensor_models.hpp"
#include "environment/world.hpp"

namespace rilbed::agents {
namespace {

const std::filesystem::path kLibrary = std::filesystem::path(RILBED_TEST_PLUGIN_DIR) / "test_sensors.so";

const SensorModelEntry& model_named(const std::vector<SensorModelEntry>& entries, const std::string& name) {
  for (const SensorModelEntry& e : entries) {
    if (e.name == name) return e;
  }
  throw std::runtime_error("no model " + name);
}

environment::StaticMapConfig field() {
  environment::StaticMapConfig map;
  map.field = {2.0, 1.0, true};
  map.tracks.push_back({{{0.1, 0.5}, {1.9, 0.5}}, 0.02, false, "tape"});
  return map;
}

std::shared_ptr<const environment::SensorModel> mounted(const SensorModelEntry& e, std::vector<double> values,
                                                        const std::string& name = "") {
  auto m = mount_sensor_model(e, {name, std::move(values), 0.0, 0.0, 0.0, "test.txt"}, environment::StaticMap(field()),
                              100'000);
  EXPECT_TRUE(m) << m.error();
  return m ? *m : nullptr;
}

TEST(LibrarySensorModels, ALibraryListsItsModelsWithTheirParameters) {
  auto entries = load_library_sensor_models(kLibrary);
  ASSERT_TRUE(entries) << entries.error();
  ASSERT_EQ(entries->size(), 3u);
  const SensorModelEntry& range = entries->at(0);
  EXPECT_EQ(range.name, "beacon_range");
  EXPECT_EQ(range.value_count, 2u);
  ASSERT_EQ(range.params.size(), 3u);
  EXPECT_EQ(range.params[0].key, "Target X");
  EXPECT_FALSE(range.params[0].default_value);
  EXPECT_EQ(range.param("target_x"), &range.params[0]);  // keys match whatever their spelling
  EXPECT_EQ(range.param("TARGET  x"), &range.params[0]);
  EXPECT_EQ(range.param("target"), nullptr);
  EXPECT_TRUE(entries->at(2).provides_track);
  EXPECT_FALSE(entries->at(1).concurrent);
  EXPECT_EQ(sensor_param_key(" Cone  Angle "), "cone_angle");
  EXPECT_EQ(sensor_param_key("cone-angle"), "cone_angle");
}

TEST(LibrarySensorModels, EveryLoaderErrorNamesTheLibrary) {
  const std::filesystem::path dir = RILBED_TEST_PLUGIN_DIR;
  EXPECT_NE(load_library_sensor_models(dir / "test_classes.so").error().find("does not export rilbed_sensor_models()"),
            std::string::npos);
  EXPECT_NE(load_library_sensor_models(dir / "nothing.so").error().find("nothing.so: no such file"), std::string::npos);
  EXPECT_NE(load_library_sensor_models(dir / "broken_1.so").error().find("ABI version 999"), std::string::npos);

  auto entries = load_library_sensor_models(kLibrary);
  ASSERT_TRUE(entries) << entries.error();
  const rilbed_sensor_model& good = *model_named(*entries, "beacon_range").model;
  auto problem = [](const rilbed_sensor_model& m) {
    auto e = sensor_model_entry(m, nullptr, "x.so");
    return e ? std::string("accepted") : e.error();
  };
  rilbed_sensor_model m = good;
  m.value_count = 0;
  EXPECT_NE(problem(m).find("1 to 64 values"), std::string::npos);
  m = good;
  m.provides = "lidar";
  EXPECT_NE(problem(m).find("only \"track\""), std::string::npos);
  m = good;
  m.name = "has space";
  EXPECT_NE(problem(m).find("holds a space"), std::string::npos);
  m = good;
  m.sense = nullptr;
  EXPECT_NE(problem(m).find("lacks its create, sense or destroy"), std::string::npos);
  const rilbed_sensor_param twice[] = {{"Cone Angle", "", "", 1, 1, 0, 0, 2}, {"cone_angle", "", "", 1, 1, 0, 0, 2}};
  m = good;
  m.params = twice;
  m.param_count = 2;
  EXPECT_NE(problem(m).find("names parameter 'cone_angle' twice"), std::string::npos);
  const rilbed_sensor_param outside[] = {{"Gain", "", "", 5, 1, 0, 0, 2}};
  m.params = outside;
  m.param_count = 1;
  EXPECT_NE(problem(m).find("default that is not a finite number in its range"), std::string::npos);
}

TEST(LibrarySensorModels, AMountedModelSensesOnTheWorldsRobots) {
  auto entries = load_library_sensor_models(kLibrary);
  ASSERT_TRUE(entries) << entries.error();
  // A create() that refuses: the error names the model, the library and the file.
  const auto refused = mount_sensor_model(model_named(*entries, "beacon_range"), {"", {99, 0, 0}, 0, 0, 0, "p.txt"},
                                          environment::StaticMap(field()), 100'000);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("with p.txt: cannot be made: target x 99 is refused"), std::string::npos)
      << refused.error();

  const auto range = mounted(model_named(*entries, "beacon_range"), {1.0, 0.5, 0.0}, "to_goal");
  const auto noisy = mounted(model_named(*entries, "beacon_range"), {1.0, 0.5, 0.2}, "noisy");
  const auto cone = mounted(model_named(*entries, "cone"), {42});
  environment::World world(field());
  for (int id = 1; id <= 3; ++id) {
    environment::RobotConfig r;
    r.id = id;
    r.pose = Pose2{{0.2 + 0.4 * id, 0.3}, 0.0};
    r.sensors.models = {{range}, {noisy}, {cone}};
    world.add_robot(r);
  }
  world.sense_ahead(100'000);
  const environment::SensorReadings s = world.sense(2, 100'000);
  ASSERT_EQ(s.models.size(), 2u);  // the track-providing one is in track
  EXPECT_EQ(s.models[0].name, "to_goal");
  EXPECT_NEAR(s.models[0].values[0], std::hypot(1.0 - 1.0, 0.5 - 0.3), 1e-12);
  EXPECT_EQ(s.models[0].values[1], 3.0);  // three robots, no moving obstacles
  EXPECT_EQ(s.models[1].name, "noisy");
  EXPECT_GT(s.models[1].values[0], s.models[0].values[0]);  // uniform noise in [0, 0.2)
  ASSERT_EQ(s.track, (std::vector<int>{42}));
  EXPECT_TRUE(s.marks.empty());  // nobody watches: the models are not asked to draw
  world.set_collect_marks(true);
  world.sense_ahead(200'000);
  const environment::SensorReadings drawn = world.sense(2, 200'000);
  ASSERT_EQ(drawn.marks.size(), 4u);  // two models, each a circle and a line; the NaN circles dropped
  EXPECT_EQ(drawn.marks[0].shape, environment::SensorMark::Shape::kCircle);
  EXPECT_EQ(drawn.marks[0].radius_m, 0.01);
  EXPECT_EQ(drawn.marks[0].rgba, 0xff0000ffu);
  EXPECT_EQ(drawn.marks[1].shape, environment::SensorMark::Shape::kLine);
  EXPECT_EQ(drawn.marks[1].b_m.x, 0.1);
  // The noise comes from the robot's own stream: the same at the same instant, whoever asks.
  environment::World again(field());
  for (int id = 3; id >= 1; --id) {
    environment::RobotConfig r;
    r.id = id;
    r.pose = Pose2{{0.2 + 0.4 * id, 0.3}, 0.0};
    r.sensors.models = {{range}, {noisy}, {cone}};
    again.add_robot(r);
  }
  EXPECT_EQ(again.sense(2, 100'000).models[1].values, s.models[1].values);

  // What controllers read: the C register map in thousandths, the C++ class by name.
  ControlInput in;
  in.robot_id = 2;
  in.sensors = s;
  auto c = PluginLibrary::open(std::filesystem::path(RILBED_PLUGIN_DIR) / "braitenberg.so");
  ASSERT_TRUE(c) << c.error();
  using List = const rilbed_c_controller* const* (*)();
  CControllerAdapter adapter(*reinterpret_cast<List>((*c)->symbol("rilbed_controllers"))()[0], *c);
  adapter.step(in);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_MODEL_COUNT), 4);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_MODEL_0), std::lround(s.models[0].values[0] * 1000));
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_MODEL_0 + 1), 3000);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_COUNT), 1);
  EXPECT_EQ(adapter.registers().peek(RILBED_REG_TRACK_0), 42);
}

TEST(LibrarySensorModels, AFailingModelNamesItselfAndTheRobot) {
  auto entries = load_library_sensor_models(kLibrary);
  ASSERT_TRUE(entries) << entries.error();
  const auto failing = mounted(model_named(*entries, "failing"), {300});
  environment::World world(field());
  environment::RobotConfig r;
  r.id = 7;
  r.pose = Pose2{{1.0, 0.3}, 0.0};
  r.sensors.models = {{failing}};
  world.add_robot(r);
  EXPECT_EQ(world.sense(7, 200'000).models[0].values[0], 1.0);
  try {
    world.sense(7, 300'000);
    FAIL() << "the reading did not fail";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sensor model failing (" + kLibrary.string() +
                        ") of robot 7: its reading at t = 300 ms failed: "
                        "the lens is cracked"),
              std::string::npos)
        << what;
  }
}

// Actuator models: each robot's own instance turns its commands into its wheels' speeds,
// and the world drives the arc they make; a failing or absurd one names itself and the robot.
TEST(LibraryActuatorModels, EachRobotsDriveTurnsItsCommandsIntoMotion) {
  auto entries = load_library_actuator_models(kLibrary);
  ASSERT_TRUE(entries) << entries.error();
  ASSERT_EQ(entries->size(), 2u);
  EXPECT_EQ(entries->at(0).name, "reverse");
  EXPECT_FALSE(entries->at(1).concurrent);
  EXPECT_NE(load_library_actuator_models(std::filesystem::path(RILBED_TEST_PLUGIN_DIR) / "test_classes.so")
                .error()
                .find("does not export rilbed_actuator_models()"),
            std::string::npos);
  rilbed_actuator_model lame = *entries->at(0).model;
  lame.drive = nullptr;
  EXPECT_NE(actuator_model_entry(lame, nullptr, "x.so").error().find("lacks its create, drive or destroy"),
            std::string::npos);

  const environment::StaticMap map(field());
  environment::World world(field());
  environment::RobotConfig r;
  r.id = 4;
  r.pose = Pose2{{1.0, 0.3}, 0.0};
  r.drive = actuator_factory(entries->at(0), {0.5}, map, 20'000, "gain.txt");
  world.add_robot(r);
  world.set_wheel_speeds(4, 10, 10);  // 8 cm/s ahead, commanded
  world.step(1'000'000);
  EXPECT_NEAR(world.pose(4).position_m.x, 1.0 - 0.5 * 0.08, 1e-9);  // backwards at half the speed
  EXPECT_EQ(world.robot(4).odometer().left_pulses, 0);              // it counted nothing

  r.id = 13;
  r.pose = Pose2{{1.6, 0.7}, 0.0};
  try {
    world.add_robot(r);
    FAIL() << "robot 13 was added";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("actuator model reverse (" + kLibrary.string() +
                                         ") of robot 13: cannot be made: robot 13 has no wheels"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(world.has_robot(13));

  r.id = 5;
  r.pose = Pose2{{0.5, 0.3}, 0.0};
  r.drive = actuator_factory(entries->at(1), {1500}, map, 20'000, "");
  world.add_robot(r);
  world.set_wheel_speeds(5, 99, 10);
  try {
    world.step(100'000);
    FAIL() << "a NaN speed was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("of robot 5: its step at t = 1000 ms gave a wheel speed that is not a finite"),
              std::string::npos)
        << e.what();
  }
  world.set_wheel_speeds(5, 10, 10);
  world.step(1'000'000);  // the failed step was not taken: this one starts at 1000 ms
  try {
    world.step(1'000'000);
    FAIL() << "the drive did not fail";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("of robot 5: its step at t = 2000 ms failed: the motor burnt out"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rilbed::agents
