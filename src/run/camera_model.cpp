#include "run/camera_model.hpp"

#include <chrono>
#include <cmath>

#include "vision/emulated_camera.hpp"
#include "vision/frame_source.hpp"

namespace rilbed::run {

void VisionModel::internal_transition() {
  t_us_ += state_;
  state_ = period_us_;
  const std::optional<cv::Mat> frame = grab_();
  if (!frame) {
    state_ = sim::kInfinity;  // the footage ended: no more sightings
    return;
  }
  frames_.fetch_add(1, std::memory_order_relaxed);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<vision::FieldObservation> seen = tracker_.process(*frame);
  const double process_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  for (const vision::FieldObservation& o : seen) {
    if (!world_.has_robot(o.id) || world_.robot(o.id).kind != environment::RobotKind::kReal) continue;
    world_.set_observed_pose(o.id, o.pose, t_us_);
    ++sightings_;
  }
  if (observer_) report(tracker_.seen_frame(), seen, process_ms);
}

CameraReport VisionModel::camera_report(const std::string& source) const {
  const vision::FieldCalibration& c = tracker_.calibration();
  CameraReport r;
  r.width_px = c.image_size.width;
  r.height_px = c.image_size.height;
  for (int i = 0; i < 9; ++i) r.image_to_field[static_cast<std::size_t>(i)] = c.homography(i / 3, i % 3);
  r.lens_distortion = c.lens.has_value();
  r.source = source;
  return r;
}

void VisionModel::report(const cv::Mat& frame, const std::vector<vision::FieldObservation>& seen, double process_ms) {
  const std::int64_t number = frames();
  if (send_images_) observer_->on_frame_image(t_us_, number, frame);
  detections_.clear();
  for (const vision::FieldObservation& o : seen) {
    const vision::MarkerDetection& d = o.detection;
    detections_.push_back({o.id, d.u, d.v, d.heading_deg, d.score, d.diameter_px, o.pose});
  }
  observer_->on_detections({t_us_, number, process_ms, detections_});
}

std::shared_ptr<VisionModel> make_camera(const Scenario& scenario, const RunOptions& options,
                                         environment::World& world) {
  const CameraSpec& cam = *scenario.camera;
  const std::string where = scenario.source.string() + ":" + std::to_string(cam.line) + ": camera";
  std::vector<int> real_ids;
  for (const RobotSpec& r : scenario.robots) {
    if (r.kind == environment::RobotKind::kReal) real_ids.push_back(r.id);
  }
  if (real_ids.empty()) return nullptr;
  vision::MarkerFamily family = vision::MarkerFamily::six_ucp();
  try {
    family = vision::MarkerFamily::by_name(cam.family);
  } catch (const std::exception& e) {
    throw ScenarioError(where + ": " + e.what());
  }
  const auto period_us = static_cast<TimeUs>(std::llround(1e6 / cam.fps));
  if (cam.emulate) {
    if (!options.emulated_markers) throw ScenarioError(where + ": an emulated camera needs emulated real robots");
    vision::EmulatedCameraConfig config;
    config.fps = cam.fps;
    config.marker_diameter_m = cam.marker_diameter_m;
    config.seed = options.seed;
    auto camera = std::make_shared<vision::EmulatedOverheadCamera>(scenario.map.field.width_m,
                                                                   scenario.map.field.height_m, family, config);
    vision::FieldTracker tracker(family, real_ids, camera->calibration());
    tracker.set_settings(cam.vision);
    auto markers = options.emulated_markers;
    const double diameter = cam.marker_diameter_m;
    VisionModel::Grab grab = [camera, markers, diameter]() -> std::optional<cv::Mat> {
      std::vector<vision::SceneMarker> scene = markers();
      for (auto& m : scene) m.diameter_m = diameter;
      return camera->render(scene);
    };
    return std::make_shared<VisionModel>(world, std::move(tracker), std::move(grab), period_us);
  }
  const auto calibration = vision::load_field_calibration(cam.calibration);
  if (!calibration.ok()) throw ScenarioError(where + ": " + calibration.error);
  auto opened = cam.device ? vision::open_camera(*cam.device) : vision::open_frame_source(cam.file);
  if (!opened.ok()) throw ScenarioError(where + ": " + opened.error);
  std::shared_ptr<vision::FrameSource> source = std::move(opened.source);
  vision::FieldTracker tracker(family, real_ids, *calibration.calibration);
  tracker.set_settings(cam.vision);
  VisionModel::Grab grab = [source]() -> std::optional<cv::Mat> {
    for (;;) {
      vision::FrameResult r = source->next();
      if (r.kind == vision::FrameResult::Kind::kFrame) return r.image;
      if (r.kind == vision::FrameResult::Kind::kEnd) return std::nullopt;
      // A bad frame is skipped (the frame source names it); the next one is tried.
    }
  };
  return std::make_shared<VisionModel>(world, std::move(tracker), std::move(grab), period_us);
}

}  // namespace rilbed::run
