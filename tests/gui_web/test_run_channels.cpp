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

}  // namespace
}  // namespace rilbed::gui_web
