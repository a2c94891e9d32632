// A virtual robot's body: the world's robot, its virtual sensors and its wheels.
#pragma once

#include <algorithm>
#include <optional>

#include "agents/body.hpp"
#include "environment/world.hpp"

namespace rilbed::run {

/// A virtual robot's body: the world's robot, its virtual sensors and its wheels. Borrows
/// the world, which must outlive it.
class VirtualBody final : public agents::Body {
 public:
  VirtualBody(environment::World& world, int id) : world_(world), id_(id) {}
  int id() const override { return id_; }
  // Sensing reads the world (const, per-robot noise streams); driving writes this robot's
  // wheel speeds only, which nothing reads before the world's next step.
  bool concurrent() const override { return true; }
  void prefetch() const override { world_.prefetch(id_); }
  environment::SensorReadings sense(TimeUs t_us) override { return world_.sense(id_, t_us); }
  std::optional<Pose2> pose() const override { return world_.pose(id_); }
  void drive(const agents::WheelCommand& w) override {
    world_.set_wheel_speeds(id_, std::clamp(w.left, -agents::kMaxWheelUnits, agents::kMaxWheelUnits),
                            std::clamp(w.right, -agents::kMaxWheelUnits, agents::kMaxWheelUnits));
  }

 private:
  environment::World& world_;
  int id_;
};

}  // namespace rilbed::run
