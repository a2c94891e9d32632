// What the panel's channels make of sensor models: their readings and marks on the sensors
// channel (robot frame) and the marks in the Foxglove scene (field frame).
#include <gtest/gtest.h>

#include <cmath>

#include "gui_web/run_channels.hpp"

namespace rilbed::gui_web {
namespace {

TEST(RunChannels, SensorModelMarksAreDrawnAtTheRobotInTheScene) {
  environment::SensorReadings s;
  s.models.push_back({"to_goal", {0.25, 3.0}});
  s.marks.push_back({environment::SensorMark::Shape::kCircle, {0.02, 0.0}, {}, 0.004, 0x20c0f0ffu});
  s.marks.push_back({environment::SensorMark::Shape::kLine, {0.0, 0.0}, {0.1, 0.0}, 0.0, 0xff0000ffu});
  const auto models = RunChannels::models_json(s);
  ASSERT_EQ(models.size(), 1u);
  EXPECT_EQ(models[0]["name"], "to_goal");
  EXPECT_EQ(models[0]["values"][1], 3.0);
  const auto marks = RunChannels::marks_json(s);
  ASSERT_EQ(marks.size(), 2u);
  EXPECT_EQ(marks[0]["shape"], "circle");
  EXPECT_EQ(marks[0]["radius_m"], 0.004);
  EXPECT_EQ(marks[1]["shape"], "line");
  EXPECT_EQ(marks[1]["x2_m"], 0.1);

  run::PoseReport robot;
  robot.id = 2;
  robot.pose = Pose2{{1.0, 0.5}, kPi / 2};  // facing +y: its x axis is the field's +y
  robot.behaviour = "follow";
  const std::vector<run::PoseReport> poses = {robot};
  const auto scene = RunChannels::scene_json(0, poses, std::nullopt, {{2, s.marks}});
  const auto& entity = scene["entities"][0];
  ASSERT_EQ(entity["lines"].size(), 2u);
  const auto& circle = entity["lines"][0];
  EXPECT_EQ(circle["type"], 1);  // a loop
  ASSERT_EQ(circle["points"].size(), 16u);
  double cx = 0, cy = 0;
  for (const auto& p : circle["points"]) cx += p["x"].get<double>() / 16, cy += p["y"].get<double>() / 16;
  EXPECT_NEAR(cx, 1.0, 1e-9);
  EXPECT_NEAR(cy, 0.52, 1e-9);  // 2 cm ahead of the robot is 2 cm up the field
  const auto& line = entity["lines"][1];
  EXPECT_NEAR(line["points"][1]["y"].get<double>(), 0.6, 1e-9);
  EXPECT_NEAR(line["color"]["r"].get<double>(), 1.0, 1e-9);
  EXPECT_TRUE(RunChannels::scene_json(0, poses, std::nullopt)["entities"][0]["lines"].empty());
}

// Robots are drawn with their bodies: a disc as a cylinder of its own size, an outline as
// a prism (its top face in triangles and its edge), each with its wheels; a robot the world
// does not describe is a Khepera.
TEST(RunChannels, RobotsAreDrawnWithTheirBodies) {
  run::WorldReport world;
  world.robot_ids = {1, 2, 3};
  world.bodies = {
      run::BodyDrawing{"e-puck", 0.035, {}, 0.053, 0.0205},
      run::BodyDrawing{
          "square", 0.0, {{0.035, 0.035}, {-0.035, 0.035}, {-0.035, -0.035}, {0.035, -0.035}}, 0.06, 0.016}};
  world.body_of = {{1, 0}, {2, 1}};
  std::vector<run::PoseReport> poses(3);
  for (int k = 0; k < 3; ++k) {
    poses[static_cast<std::size_t>(k)].id = k + 1;
    poses[static_cast<std::size_t>(k)].pose = Pose2{{0.5 + 0.2 * k, 0.5}, kPi / 2};
  }
  const auto scene = RunChannels::scene_json(0, poses, world, {});
  const auto& epuck = scene["entities"][1];
  ASSERT_EQ(epuck["cylinders"].size(), 1u);
  EXPECT_DOUBLE_EQ(epuck["cylinders"][0]["size"]["x"].get<double>(), 0.07);
  EXPECT_EQ(epuck["cubes"].size(), 2u);  // its wheels
  const auto& square = scene["entities"][2];
  EXPECT_TRUE(square["cylinders"].empty());
  ASSERT_EQ(square["triangles"].size(), 1u);
  ASSERT_EQ(square["triangles"][0]["points"].size(), 6u);  // two triangles
  ASSERT_EQ(square["lines"].size(), 1u);
  const auto& corner = square["lines"][0]["points"][0];  // (0.035, 0.035) turned a quarter: (-0.035, 0.035)
  EXPECT_NEAR(corner["x"].get<double>(), 0.7 - 0.035, 1e-12);
  EXPECT_NEAR(corner["y"].get<double>(), 0.5 + 0.035, 1e-12);
  // The wheels sit across the axle: facing +y, at x -/+ half the wheel base.
  EXPECT_NEAR(square["cubes"][0]["pose"]["position"]["x"].get<double>(), 0.7 + 0.03, 1e-12);
  const auto& khepera = scene["entities"][3];
  EXPECT_DOUBLE_EQ(khepera["cylinders"][0]["size"]["x"].get<double>(), 0.055);
  // The world channel gives each robot its body.
  const auto w = RunChannels::world_json(0, world);
  EXPECT_EQ(w["robots"][1]["body"]["name"], "square");
  EXPECT_EQ(w["robots"][1]["body"]["outline"].size(), 4u);
  EXPECT_FALSE(w["robots"][2].contains("body"));
}

}  // namespace
}  // namespace rilbed::gui_web
