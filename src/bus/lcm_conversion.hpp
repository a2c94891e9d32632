// What a run reports (run_observer.hpp), as the LCM messages of src/bus/msgs and back.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "core/result.hpp"
#include "rilbed/camera_t.hpp"
#include "rilbed/detections_t.hpp"
#include "rilbed/event_t.hpp"
#include "rilbed/frame_t.hpp"
#include "rilbed/poses_t.hpp"
#include "rilbed/robot_bodies_t.hpp"
#include "rilbed/sensor_layout_t.hpp"
#include "rilbed/sensor_models_t.hpp"
#include "rilbed/sensors_t.hpp"
#include "rilbed/status_t.hpp"
#include "rilbed/summary_t.hpp"
#include "rilbed/vision_settings_t.hpp"
#include "rilbed/wheels_t.hpp"
#include "rilbed/world_t.hpp"
#include "run/run_observer.hpp"
#include "run/run_recorder.hpp"
#include "vision/vision_settings.hpp"

namespace rilbed::bus {

/// What a run reports, as LCM messages.
rilbed::poses_t to_lcm(TimeUs t_us, std::span<const run::PoseReport> poses);
/// The same into `message`, reusing its storage (a publisher keeps one between steps).
void fill(rilbed::poses_t& message, TimeUs t_us, std::span<const run::PoseReport> poses);
rilbed::event_t to_lcm(const run::RunEvent& event);
rilbed::status_t to_lcm(const run::StatusReport& status);
rilbed::world_t to_lcm(TimeUs t_us, const run::WorldReport& world);
rilbed::summary_t to_lcm(TimeUs t_us, const nlohmann::json& summary);
void fill(rilbed::wheels_t& message, TimeUs t_us, std::span<const run::WheelReport> wheels);
void fill(rilbed::sensors_t& message, TimeUs t_us, std::span<const run::SensorReport> sensors);
/// One robot's sensor-model readings, and its marks when `with_marks` (a controller has no
/// use for them; a display does).
rilbed::robot_models_t models_to_lcm(int id, const environment::SensorReadings& readings, bool with_marks);
/// The robots' sensor-model readings and marks (robots with neither left out); false when
/// no robot has any (nothing to publish).
bool fill(rilbed::sensor_models_t& message, TimeUs t_us, std::span<const run::SensorReport> sensors);
/// Why one robot's model readings and marks are unusable (see merge_models), or nullopt.
std::optional<std::string> models_problem(const rilbed::robot_models_t& message);
/// One robot's model readings and marks into `readings` (its models and marks replaced),
/// their names interned in `names` (which must outlive `readings`), or the reason the
/// message is unusable: a name that is empty, longer than 64 bytes or not printable ASCII,
/// more than 64 values, a value or a mark that is not finite, a negative radius, a shape
/// other than 0 or 1.
std::optional<std::string> merge_models(const rilbed::robot_models_t& message, environment::SensorReadings& readings,
                                        std::set<std::string, std::less<>>& names);
/// One robot's readings (counts beyond the wire's int8/int16 are cut; a robot carries a
/// handful of each sensor).
void fill(rilbed::robot_sensors_t& message, int id, const environment::SensorReadings& readings);
/// The readings back, taken at `t_us` (a proximity array of another length than 8 is left out).
environment::SensorReadings from_lcm(const rilbed::robot_sensors_t& message, TimeUs t_us);
rilbed::detections_t to_lcm(const run::FrameReport& frame);
/// A camera frame as JPEG of `quality` (1..100); an empty image gives size 0.
rilbed::frame_t to_lcm(TimeUs t_us, std::int64_t frame, const cv::Mat& image, int quality);
/// The camera's mapping onto the field.
rilbed::camera_t to_lcm(TimeUs t_us, const run::CameraReport& camera);
/// The camera's vision settings, and back (unchecked: see vision::check_vision_settings).
rilbed::vision_settings_t to_lcm(TimeUs t_us, const vision::VisionSettings& settings);
vision::VisionSettings from_lcm(const rilbed::vision_settings_t& message);
/// A world and a status message back as the run reported them.
run::WorldReport from_lcm(const rilbed::world_t& message);
run::StatusReport from_lcm(const rilbed::status_t& message);
/// The robots' sensor geometry (from a world's sensor_geometries and sensor_geometry_of).
rilbed::sensor_layout_t sensor_layout(TimeUs t_us, const run::WorldReport& world);
/// The robots' bodies of a world report (its `bodies` and `body_of`).
rilbed::robot_bodies_t robot_bodies(TimeUs t_us, const run::WorldReport& world);
/// A robot_bodies_t's bodies and which robot has which, or the reason it is unusable (a
/// body with a bad radius, wheels or outline, a robot naming a body it does not have).
core::Result<std::pair<std::vector<run::BodyDrawing>, std::map<int, int>>> from_lcm(const rilbed::robot_bodies_t& m);

}  // namespace rilbed::bus
