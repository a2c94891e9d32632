// A robot's body as its agent sees it: sensors to read, wheels to drive, and the pose the
// test bed localises it at. The world's virtual robot implements it (VirtualBody); a real
// Khepera over its serial link implements it too, so a controller runs unchanged on either.
#pragma once

#include <optional>
#include <string_view>

#include "agents/controller.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"
#include "environment/sensor_readings.hpp"

namespace rilbed::agents {

/// Sensors and actuators of one robot. Implementations are not thread-safe: the run calls
/// one body from one thread at a time (several bodies at once on `--threads N` only when
/// they say so, concurrent()).
class Body {
 public:
  virtual ~Body() = default;
  /// The robot's ID.
  virtual int id() const = 0;
  /// Its sensors at simulated time t_us (virtual sensors are computed at the world's
  /// current state; a real robot's are its latest readings combined with virtual ones).
  virtual environment::SensorReadings sense(TimeUs t_us) = 0;
  /// Its pose as the test bed knows it: the world's truth for a virtual robot, the
  /// camera's for a real one; nullopt while unknown (a real robot not yet seen).
  virtual std::optional<Pose2> pose() const = 0;
  /// Sets its wheel speeds (Khepera units, clamped to ±127 by the body).
  virtual void drive(const WheelCommand& wheels) = 0;
  /// Stops it: wheel speeds 0.
  virtual void stop() { drive({}); }
  /// What keeps it from obeying, or "ok": a real robot reports "unseen" (the camera lost
  /// it), "geofence", "link lost", "link unresponsive". A static string; the run records
  /// every change as an event.
  virtual std::string_view health() const { return "ok"; }
  /// Whether this body's sense(), pose() and drive() may run at the same time as other
  /// concurrent bodies' (each body from one thread): they read shared state only, and
  /// write only this robot's. Default false.
  virtual bool concurrent() const { return false; }
  /// A hint, no effect on results: ask the CPU for the memory the next sense(), pose()
  /// and drive() will touch (called a few agents ahead in a swarm's step). Default: nothing.
  virtual void prefetch() const {}
};

}  // namespace rilbed::agents
