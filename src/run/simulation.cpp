#include "run/simulation.hpp"

#include "environment/random.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "agents/builtin_controllers.hpp"
#include "agents/convoy.hpp"
#include "core/id_list.hpp"
#include "core/statistics.hpp"
#include "environment/track_sensor.hpp"
#include "run/run_control.hpp"
#include "run/run_models.hpp"
#include "sim/clock.hpp"
#include "sim/coordinator.hpp"
#include "sim/coupled.hpp"
#include "vision/emulated_camera.hpp"
#include "vision/field_tracker.hpp"
#include "vision/frame_source.hpp"

namespace rilbed::run {

namespace {

// A virtual robot's body: the world's robot, its virtual sensors and its wheels.
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

// The world as a DEVS model: one integration step every physics step. Collisions are
// kept for the monitor, which drains them.
class WorldModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next step
 public:
  WorldModel(environment::World& world, TimeUs step_us)
      : sim::AtomicModel<TimeUs>("world", step_us), world_(world), step_us_(step_us) {}
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override {
    for (const auto& e : world_.step(step_us_)) collisions_.push_back(e);
    state_ = step_us_;
  }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  std::vector<environment::CollisionEvent> drain() { return std::exchange(collisions_, {}); }

 private:
  environment::World& world_;
  TimeUs step_us_;
  std::vector<environment::CollisionEvent> collisions_;
};

// The world's sensors swept at every control instant, before the agents read them
// (World::sense_ahead): one pass over the robots in memory order, spread over the
// workers, instead of each agent computing its own reading where it happens to be. The
// readings are the same either way; the sweep keeps neighbours in cache.
class SensingModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next sweep
 public:
  SensingModel(environment::World& world, TimeUs period_us, TimeUs first_us)
      : sim::AtomicModel<TimeUs>("sensing", first_us), world_(world), period_us_(period_us), t_us_(first_us) {}
  TimeUs time_advance() const override { return state_; }
  void internal_transition() override {
    using Clock = std::chrono::steady_clock;
    const Clock::time_point start = profiled_ ? Clock::now() : Clock::time_point{};
    world_.sense_ahead(t_us_);
    if (profiled_) sensing_s_ += std::chrono::duration<double>(Clock::now() - start).count();
    t_us_ += period_us_;
    state_ = period_us_;
  }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void set_profile(bool on) { profiled_ = on; }
  double sensing_s() const { return sensing_s_; }

 private:
  environment::World& world_;
  TimeUs period_us_;
  TimeUs t_us_;  // the instant of the next sweep
  bool profiled_ = false;
  double sensing_s_ = 0.0;
};

// The overhead camera as a DEVS model: every frame period it takes a frame, tracks the
// real robots' markers and places them in the world (World::set_observed_pose). Virtual
// robots are not on camera; they live only in the world model (paper 001).
class VisionModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next frame
 public:
  using Grab = std::function<std::optional<cv::Mat>()>;
  VisionModel(environment::World& world, vision::FieldTracker tracker, Grab grab, TimeUs period_us)
      : sim::AtomicModel<TimeUs>("camera", 0),
        world_(world),
        tracker_(std::move(tracker)),
        grab_(std::move(grab)),
        period_us_(period_us) {}
  /// Tells `observer` (may be null) what every frame shows; `observer` outlives the run.
  void report_to(RunObserver* observer) {
    observer_ = observer;
    send_images_ = observer && observer->wants_frame_images();
  }
  TimeUs time_advance() const override { return state_; }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void internal_transition() override {
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
    const double process_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    for (const vision::FieldObservation& o : seen) {
      if (!world_.has_robot(o.id) || world_.robot(o.id).kind != environment::RobotKind::kReal) continue;
      world_.set_observed_pose(o.id, o.pose, t_us_);
      ++sightings_;
    }
    if (observer_) report(tracker_.seen_frame(), seen, process_ms);
  }
  long frames() const { return frames_.load(std::memory_order_relaxed); }
  /// The vision settings in use; set_vision() changes them from the next frame on (the
  /// run's thread only).
  const vision::VisionSettings& vision() const { return tracker_.settings(); }
  void set_vision(const vision::VisionSettings& settings) { tracker_.set_settings(settings); }
  long sightings() const { return sightings_; }
  /// What viewers need to draw the field over its frames.
  CameraReport camera_report(const std::string& source) const {
    const vision::FieldCalibration& c = tracker_.calibration();
    CameraReport r;
    r.width_px = c.image_size.width;
    r.height_px = c.image_size.height;
    for (int i = 0; i < 9; ++i) r.image_to_field[static_cast<std::size_t>(i)] = c.homography(i / 3, i % 3);
    r.lens_distortion = c.lens.has_value();
    r.source = source;
    return r;
  }

 private:
  void report(const cv::Mat& frame, const std::vector<vision::FieldObservation>& seen, double process_ms) {
    const std::int64_t number = frames();
    if (send_images_) observer_->on_frame_image(t_us_, number, frame);
    detections_.clear();
    for (const vision::FieldObservation& o : seen) {
      const vision::MarkerDetection& d = o.detection;
      detections_.push_back({o.id, d.u, d.v, d.heading_deg, d.score, d.diameter_px, o.pose});
    }
    observer_->on_detections({t_us_, number, process_ms, detections_});
  }

  environment::World& world_;
  vision::FieldTracker tracker_;
  Grab grab_;
  TimeUs period_us_;
  TimeUs t_us_ = 0;
  std::atomic<long> frames_{0};  // read by the monitor for the status' frame rate
  long sightings_ = 0;
  RunObserver* observer_ = nullptr;
  bool send_images_ = false;
  std::vector<DetectionReport> detections_;
};

// The camera of a scenario with real robots, ready to add to the run.
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

int party_code(const environment::BodyRef& b) {
  switch (b.kind) {
    case environment::BodyKind::kRobot: return b.id;
    case environment::BodyKind::kWall: return -1;
    case environment::BodyKind::kObstacle: return -2;
    case environment::BodyKind::kMovingObstacle: return -3;
  }
  return 0;
}

// Watches the run after each control step: records, counts collisions, checks the
// convoy's formation, prints the status, and ends the run when it should.
class MonitorModel final : public sim::AtomicModel<TimeUs> {  // state: time to the next sample
 public:
  struct Setup {
    environment::World* world = nullptr;
    WorldModel* world_model = nullptr;
    std::vector<AgentModel*> agents;  // by ID order
    std::vector<int> convoy_ids;      // 1..N, empty when there is no convoy
    RunRecorder* recorder = nullptr;
    const RunOptions* options = nullptr;
    sim::Coordinator** coordinator = nullptr;  // set once built
    RunResult* result = nullptr;
    TimeUs period_us = 100'000;
    const Scenario* scenario = nullptr;
    WorldReport world_report;  // for the observer
    std::chrono::steady_clock::time_point wall_start;
    const sim::RealTimeClock* clock = nullptr;  // a realtime run's clock (for the loop's latency)
    const VisionModel* camera = nullptr;        // the overhead camera, if any (for its frame rate)
    RunProfile* profile = nullptr;              // times its samples when set
    core::WorkerPool* workers = nullptr;        // reads the agents on these threads when set
  };
  explicit MonitorModel(Setup setup)
      : sim::AtomicModel<TimeUs>("monitor", 1),
        s_(std::move(setup)),
        formation_(std::max<int>(1, static_cast<int>(s_.convoy_ids.size()))) {
    last_behaviour_.assign(s_.agents.size(), {});
    last_health_.assign(s_.agents.size(), "ok");
    // The samples in one list only for those who read them (a swarm's benchmark has none).
    listed_ = s_.recorder || s_.options->keep_in_memory || !s_.convoy_ids.empty();
    all_concurrent_ = std::all_of(s_.agents.begin(), s_.agents.end(),
                                  [](const AgentModel* a) { return a->transitions_concurrent(); });
    world_bodies_ = std::all_of(s_.agents.begin(), s_.agents.end(), [](const AgentModel* a) {
      return dynamic_cast<const VirtualBody*>(&a->body()) != nullptr;
    });
  }
  TimeUs time_advance() const override { return state_; }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void internal_transition() override {
    t_us_ += state_;
    state_ = s_.period_us;
    const TimeUs t = t_us_ - 1;  // the control step just taken
    if (s_.profile) {
      const auto start = std::chrono::steady_clock::now();
      sample(t);
      s_.profile->monitor_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    } else {
      sample(t);
    }
    if (s_.options->interrupt && s_.options->interrupt->load()) end("interrupt");
  }
  bool formed() const { return formation_.formed(); }
  /// Ends the run at the end of this step, `why` becoming RunResult::ended_by.
  void end_run(const char* why) { end(why); }
  /// Records an event in the run folder and tells the observer.
  void record_event(const RunEvent& event) { record(event); }
  /// The convoy's mode now (the console may switch it).
  void set_central(bool central) { central_ = central; }
  std::optional<TimeUs> formation_time_us() const { return formation_.formation_time_us(); }

  /// The run's status now (`state`: "running" or "ended").
  StatusReport status(TimeUs t, const char* state) const {
    StatusReport st;
    st.t_us = t;
    st.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - s_.wall_start).count();
    st.scenario = s_.scenario->name;
    st.seed = s_.options->seed;
    st.mode = central_ ? "central" : "distributed";
    st.realtime = s_.options->realtime;
    st.rt_factor = s_.clock ? s_.clock->factor() : s_.options->rt_factor;
    st.state = state;
    st.ended_by = s_.result->ended_by;
    st.robots = static_cast<int>(s_.agents.size());
    st.real_robots = static_cast<int>(s_.world_report.field.real_robot_ids.size());
    st.formed = formation_.formed();
    if (const auto f = formation_.formation_time_us()) st.formation_time_s = us_to_seconds(*f);
    st.collisions = s_.result->collisions;
    st.loop_latency_ms = worst_latency_ms_;
    st.camera_fps = camera_fps_;
    st.frames = s_.camera ? s_.camera->frames() : 0;
    if (s_.camera) st.vision = s_.camera->vision();
    return st;
  }

 private:
  void end(const char* why) {
    if (s_.result->ended_by.empty()) s_.result->ended_by = why;
    (*s_.coordinator)->stop();
  }

  // An event for the run folder and for the run's observer.
  void record(const RunEvent& event) {
    if (s_.recorder) s_.recorder->add_event(event);
    if (s_.options->observer) s_.options->observer->on_event(event);
  }

  // Every robot with a known pose (a real robot the camera lost at its last pose, unseen),
  // then every robot's wheels and sensors.
  void report_step(TimeUs t, RunObserver& observer) {
    reports_.clear();
    wheel_reports_.clear();
    sensor_reports_.clear();
    for (const AgentModel* a : s_.agents) {
      const int id = a->body().id();
      wheel_reports_.push_back({id, a->wheels()});
      sensor_reports_.push_back({id, &a->sensors()});
      const environment::RobotState& state = s_.world->robot(id);
      const auto pose = a->body().pose();
      if (!pose && !state.observed && state.kind == environment::RobotKind::kReal) continue;  // never seen
      reports_.push_back({id, state.kind == environment::RobotKind::kReal, pose.has_value(), pose.value_or(state.pose),
                          a->behaviour(), a->body().health()});
    }
    observer.on_poses(t, reports_);
    observer.on_wheels(t, wheel_reports_);
    observer.on_sensors(t, sensor_reports_);
  }

  // How far the control loop fell behind the wall clock once a step and its reports are
  // done (each step's, and the most over each second between two statuses), and the
  // camera's frame rate.
  void measure_loop(TimeUs t) {
    if (s_.clock && !s_.clock->paused()) {
      const double behind_ms = static_cast<double>(s_.clock->now_us() - t) / 1000.0 / s_.clock->factor();
      latency_window_ms_ = std::max(latency_window_ms_, behind_ms);
      s_.result->loop_latency_ms.push_back(static_cast<float>(behind_ms));
    }
  }
  void close_second() {
    worst_latency_ms_ = latency_window_ms_;
    latency_window_ms_ = 0.0;
    if (!s_.camera) return;
    const auto now = std::chrono::steady_clock::now();
    const long frames = s_.camera->frames();
    const double wall_s = std::chrono::duration<double>(now - fps_since_).count();
    if (wall_s > 0.0 && fps_frames_ >= 0) camera_fps_ = static_cast<double>(frames - fps_frames_) / wall_s;
    fps_since_ = now;
    fps_frames_ = frames;
  }

  void sample(TimeUs t) {
    RunResult& r = *s_.result;
    RunObserver* const o = s_.options->observer;
    const bool new_second = t >= next_report_us_;
    // The world first, so that a viewer can draw whatever follows.
    if (o && new_second) o->on_world(t, s_.world_report);
    for (const auto& e : s_.world_model->drain()) {
      ++r.collisions;
      if (e.second.kind == environment::BodyKind::kRobot) ++r.robot_collisions;
      record({e.t_us, "collision", party_code(e.first), party_code(e.second),
              to_string(e.first) + " touched " + to_string(e.second)});
    }
    if (t >= next_overlap_check_us_) {
      r.max_overlap_m = std::max(r.max_overlap_m, s_.world->max_overlap_m());
      const TimeUs every = s_.options->overlap_check_us;
      next_overlap_check_us_ = every > 0 ? (t / every + 1) * every : t + 1;
    }
    read_agents(t);
    r.trajectory_digest += step_digest_;
    // Changes of health and behaviour, in agent order.
    for (const AgentChange& change : changed_) {
      if (change.health != change.old_health) {
        record({t, "health", change.id, 0, std::string(change.old_health) + " -> " + std::string(change.health)});
      }
      if (change.behaviour != change.old_behaviour && !change.old_behaviour.empty()) {
        record(
            {t, "behaviour", change.id, 0, std::string(change.old_behaviour) + " -> " + std::string(change.behaviour)});
      }
    }
    samples_.clear();
    if (listed_) {
      for (const std::optional<TrajectorySample>& sample : read_samples_)
        if (sample) samples_.push_back(*sample);
    }
    if (s_.recorder) s_.recorder->add_samples(samples_);
    if (s_.options->keep_in_memory) r.trajectory.insert(r.trajectory.end(), samples_.begin(), samples_.end());
    if (o) {
      if (o->wants_steps()) report_step(t, *o);
      measure_loop(t);
      if (new_second) {
        next_report_us_ = (t / 1'000'000 + 1) * 1'000'000;
        close_second();
        o->on_status(status(t, "running"));
      }
    }
    if (!s_.convoy_ids.empty()) check_formation(t);
    if (s_.options->stop_when_done &&
        std::all_of(s_.agents.begin(), s_.agents.end(), [](const AgentModel* a) { return a->done(); })) {
      end("done");
    }
  }

  // An agent whose health or behaviour changed, as read_agents read it (static strings),
  // and what they were before.
  struct AgentChange {
    std::size_t agent = 0;  // index in s_.agents
    int id = 0;             // its robot's
    std::string_view behaviour, health;
    std::string_view old_behaviour, old_health;
  };
  // How many agents ahead read_agents asks for an agent's body (and twice that for the agent).
  static constexpr std::size_t kReadAhead = 8;
  // Reads every agent (on the workers when they may), and sums the samples' digests and
  // lists the agents whose health or behaviour changed (in agent order) as it goes: the
  // run's thread then has no pass over every agent left (at 10,000 robots it held the
  // other threads up). The samples themselves are kept only when listed_ (a swarm's
  // benchmark keeps none: at 100,000 robots writing them was 7 MB a step).
  void read_agents(TimeUs t) {
    read_samples_.resize(listed_ ? s_.agents.size() : 0);
    std::mutex merge_mutex;
    step_digest_ = 0;
    changed_.clear();
    // Changes become events, which only a recorder or an observer takes (a swarm's
    // benchmark changes behaviour at thousands of agents a step).
    const bool track_changes = s_.recorder || s_.options->observer;
    if (!listed_ && !track_changes && world_bodies_ && s_.agents.size() == s_.world->ids_in_added_order().size()) {
      // Only the digest is wanted, and every body is one of the world's robots (all of
      // them), whose pose() is the world's: the same terms, summed from the world's
      // tables in memory order, without visiting 100,000 agents scattered in memory.
      step_digest_ = digest_from_world(t);
      return;
    }
    auto read = [&](std::size_t begin, std::size_t end) {
      std::uint64_t digest = 0;  // a sum: the same whatever thread made each term
      std::vector<AgentChange> changed;
      for (std::size_t i = begin; i < end; ++i) {
        // A swarm's agents are far apart in memory: ask for them ahead (two rounds).
        if (i + 2 * kReadAhead < end) s_.agents[i + 2 * kReadAhead]->prefetch_view(0);
        if (i + kReadAhead < end) s_.agents[i + kReadAhead]->prefetch_view(1);
        const AgentModel& a = *s_.agents[i];
        const auto pose = a.body().pose();
        const int id = a.body().id();
        const std::string_view behaviour = a.behaviour(), health = a.body().health();
        // Brought up to date here, where each agent's entries are read anyway (each
        // thread its own agents): a pass of the run's thread over the changes read them
        // from memory again, one miss each at 100,000 robots.
        if (track_changes && (health != last_health_[i] || behaviour != last_behaviour_[i])) {
          changed.push_back({i, id, behaviour, health, last_behaviour_[i], last_health_[i]});
          last_behaviour_[i] = behaviour, last_health_[i] = health;
        }
        if (listed_) read_samples_[i].reset();
        if (!pose) continue;  // a real robot with no pose: no sample
        if (listed_) read_samples_[i] = TrajectorySample{t, id, *pose, behaviour};
        digest += sample_digest(t, id, *pose);
      }
      std::lock_guard lock(merge_mutex);
      step_digest_ += digest;
      changed_.insert(changed_.end(), changed.begin(), changed.end());
    };
    // Real bodies read their links' state: only runs whose agents all step concurrently
    // (virtual bodies, in-process controllers) read on the workers.
    if (s_.workers && s_.workers->threads() > 1 && all_concurrent_) {
      s_.workers->for_chunks(s_.agents.size(), read);
    } else {
      read(0, s_.agents.size());
    }
    // Chunks merge in any order; the events follow agent order.
    std::sort(changed_.begin(), changed_.end(),
              [](const AgentChange& x, const AgentChange& y) { return x.agent < y.agent; });
  }

  // One sample's term of the trajectory digest: of the time, id, position and heading,
  // bit for bit. The digest of a step is the sum of its samples' terms (in any order).
  static std::uint64_t sample_digest(TimeUs t, int id, const Pose2& pose) {
    std::uint64_t h = 0x6a09e667f3bcc909ULL;
    for (const std::uint64_t word :
         {static_cast<std::uint64_t>(t), static_cast<std::uint64_t>(id),
          std::bit_cast<std::uint64_t>(pose.position_m.x), std::bit_cast<std::uint64_t>(pose.position_m.y),
          std::bit_cast<std::uint64_t>(pose.heading_rad)})
      h = environment::mix64(h ^ word) + 0x9e3779b97f4a7c15ULL;
    return h;
  }
  // A step's digest from the world's tables: each robot's pose() as its body gives it.
  std::uint64_t digest_from_world(TimeUs t) const {
    const std::span<const int> ids = s_.world->ids_in_added_order();
    const std::span<const Pose2> poses = s_.world->poses_in_added_order();
    std::mutex merge_mutex;
    std::uint64_t total = 0;
    auto sum = [&](std::size_t begin, std::size_t end) {
      std::uint64_t digest = 0;
      for (std::size_t k = begin; k < end; ++k) digest += sample_digest(t, ids[k], poses[k]);
      std::lock_guard lock(merge_mutex);
      total += digest;
    };
    if (s_.workers && s_.workers->threads() > 1) {
      s_.workers->for_chunks(ids.size(), sum);
    } else {
      sum(0, ids.size());
    }
    return total;
  }

  void check_formation(TimeUs t) {
    std::vector<agents::FormationMonitor::Sample> team;
    for (const TrajectorySample& s : samples_) {
      if (s.id >= 1 && s.id <= static_cast<int>(s_.convoy_ids.size())) team.push_back({s.id, s.pose, s.behaviour});
    }
    record_subteams(t, team);
    const bool was_holding = formation_.holding();
    if (formation_.update(t, team)) {
      std::ostringstream text;  // "6.1 s", not std::to_string's "6.100000 s"
      text << "convoy formed; the hold began at " << us_to_seconds(*formation_.formation_time_us()) << " s";
      record({t, "formed", 0, 0, text.str()});
    }
    if (was_holding && !formation_.holding() && formation_.formed()) {
      record({t, "broken", 0, 0, "the formed convoy broke"});
    }
    if (s_.options->stop_when_formed && formation_.formed() &&
        t >= *formation_.formed_at_us() + seconds_to_us(s_.options->after_formed_s)) {
      end("formed");
    }
  }

  // Sub-teams (paper 001 §5): maximal runs l..m of agents where each k in (l, m] follows
  // k-1 within the formed gap. Recorded whenever the set changes, as "1-3 5-6".
  void record_subteams(TimeUs t, const std::vector<agents::FormationMonitor::Sample>& team) {
    const int n = static_cast<int>(s_.convoy_ids.size());
    std::vector<const agents::FormationMonitor::Sample*> by_rank(n + 1, nullptr);
    for (const auto& m : team) by_rank[m.id] = &m;
    auto linked = [&](int k) {
      if (!by_rank[k] || !by_rank[k - 1] || by_rank[k]->behaviour != "follow") return false;
      const double gap = (by_rank[k]->pose.position_m - by_rank[k - 1]->pose.position_m).norm();
      return gap >= 0.06 && gap <= 0.30;
    };
    std::string text;
    for (int k = 2, start = 1; k <= n + 1; ++k) {
      if (k <= n && linked(k)) continue;
      if (k - 1 > start) {
        if (!text.empty()) text += ' ';
        text += std::to_string(start);
        text += '-';
        text += std::to_string(k - 1);
      }
      start = k;
    }
    if (text != subteams_) record({t, "subteams", 0, 0, text.empty() ? "none" : text});
    subteams_ = text;
  }

  Setup s_;
  bool central_ = s_.scenario->mode == ConvoyMode::kCentral;
  std::string subteams_;
  agents::FormationMonitor formation_;
  TimeUs t_us_ = 0;
  TimeUs next_report_us_ = 0;
  TimeUs next_overlap_check_us_ = 0;
  std::vector<std::optional<TrajectorySample>> read_samples_;  // read_agents, when listed_: per agent
  std::uint64_t step_digest_ = 0;                              // read_agents: the sum of this step's sample digests
  std::vector<AgentChange> changed_;  // read_agents: agents whose health or behaviour changed, in order
  bool all_concurrent_ = false;
  bool listed_ = false;  // the samples are recorded, kept or watched by the formation monitor
  std::vector<PoseReport> reports_;
  std::vector<WheelReport> wheel_reports_;
  std::vector<SensorReport> sensor_reports_;
  double latency_window_ms_ = 0.0, worst_latency_ms_ = 0.0;
  double camera_fps_ = 0.0;
  std::chrono::steady_clock::time_point fps_since_;
  long fps_frames_ = -1;  // frames at the last status; -1 before the first
  std::vector<TrajectorySample> samples_;
  bool world_bodies_ = false;  // every agent's body is a VirtualBody (its pose the world's)
  std::vector<std::string_view> last_behaviour_;
  std::vector<std::string_view> last_health_;
};

// The console's actions as a DEVS model: they arrive on its input (injected from the
// console's thread) and are applied here, on the run's thread, between two steps. Those
// for the agents (drive one by hand, switch the convoy's mode) go out on its "orders"
// output at the same instant.
class ControlModel final : public sim::AtomicModel<std::vector<ConsoleOrder>> {  // state: orders to send now
 public:
  struct Setup {
    std::vector<AgentModel*> agents;
    MonitorModel* monitor = nullptr;
    sim::RealTimeClock* clock = nullptr;  // null in a fast run
    RunObserver* observer = nullptr;
    VisionModel* camera = nullptr;  // the overhead camera, if any (its settings)
  };
  explicit ControlModel(Setup setup)
      : sim::AtomicModel<std::vector<ConsoleOrder>>("control", {}),
        s_(std::move(setup)),
        in_(add_input<ControlAction>("action")),
        out_(add_output<ConsoleOrder>("orders")) {}
  TimeUs time_advance() const override { return state_.empty() ? sim::kInfinity : 0; }
  void internal_transition() override { state_.clear(); }
  void output() override {
    for (const ConsoleOrder& o : state_) out_.add(o);
  }
  void external_transition(TimeUs elapsed_us) override {
    t_us_ += elapsed_us;
    for (const ControlAction& a : in_.messages()) apply(a);
  }
  sim::Port<ControlAction>& input() { return in_; }
  sim::Port<ConsoleOrder>& orders() { return out_; }

 private:
  void apply(const ControlAction& a) {
    switch (a.kind) {
      case ControlAction::Kind::kPause:
        // Safety: a paused run stops every robot; nothing drives them until it resumes.
        for (AgentModel* agent : s_.agents) agent->body().stop();
        s_.monitor->record_event({t_us_, "console", 0, 0, "paused by " + a.who});
        if (s_.observer) s_.observer->on_status(s_.monitor->status(t_us_, "paused"));
        if (s_.clock) s_.clock->pause();
        break;
      case ControlAction::Kind::kResume:
        s_.monitor->record_event({t_us_, "console", 0, 0, "resumed by " + a.who});
        if (s_.clock) s_.clock->resume();
        break;
      case ControlAction::Kind::kRtFactor: {
        if (s_.clock) s_.clock->set_factor(a.rt_factor);
        std::ostringstream text;
        text << "real-time factor " << a.rt_factor << " set by " << a.who;
        s_.monitor->record_event({t_us_, "console", 0, 0, text.str()});
        break;
      }
      case ControlAction::Kind::kExit:
        s_.monitor->record_event({t_us_, "console", 0, 0, "ended by " + a.who});
        s_.monitor->end_run("console");
        break;
      case ControlAction::Kind::kReset:
        s_.monitor->record_event({t_us_, "console", 0, 0, "reset by " + a.who + ": the run starts over"});
        s_.monitor->end_run("reset");
        break;
      case ControlAction::Kind::kMode: {
        ConsoleOrder o;
        o.kind = ConsoleOrder::Kind::kMode;
        o.central = a.central;
        state_.push_back(o);
        s_.monitor->set_central(a.central);
        s_.monitor->record_event({t_us_, "console", 0, 0,
                                  std::string("mode ") + (a.central ? "central" : "distributed") + " set by " + a.who});
        break;
      }
      case ControlAction::Kind::kDrive: {
        ConsoleOrder o;
        o.kind = ConsoleOrder::Kind::kDrive;
        o.robot_id = a.robot_id;
        o.wheels = {a.left, a.right};
        o.until_us = t_us_ + seconds_to_us(a.duration_s);
        state_.push_back(o);
        // A held drive (the web panel's, renewed every few tenths of a second) is one
        // event while its speeds stay and it does not lapse, not one per renewal.
        const auto last = drives_.find(a.robot_id);
        const bool renewal = last != drives_.end() && last->second.wheels == o.wheels &&
                             last->second.until_us >= t_us_ && last->second.who == a.who;
        drives_[a.robot_id] = {o.wheels, o.until_us, a.who};
        if (renewal) break;
        std::ostringstream text;
        text << "robot " << a.robot_id << " driven " << a.left << " " << a.right << " for " << a.duration_s << " s by "
             << a.who;
        s_.monitor->record_event({t_us_, "console", a.robot_id, 0, text.str()});
        break;
      }
      case ControlAction::Kind::kVision: {
        if (!s_.camera) break;  // checked before: the run has a camera
        vision::VisionSettings settings = s_.camera->vision();
        std::ostringstream text;
        text << "vision";
        for (const auto& [name, value] : a.vision) {
          if (vision::set_vision_setting(settings, name, value)) return;  // checked before
          text << " " << name << " " << value;
        }
        if (vision::check_vision_settings(settings)) return;
        s_.camera->set_vision(settings);
        text << " set by " << a.who;
        s_.monitor->record_event({t_us_, "console", 0, 0, text.str()});
        // Viewers see the new settings at once, not at the next second's status.
        if (s_.observer)
          s_.observer->on_status(s_.monitor->status(t_us_, s_.clock && s_.clock->paused() ? "paused" : "running"));
        break;
      }
      case ControlAction::Kind::kRefused:
        s_.monitor->record_event({t_us_, "console", 0, 0, "refused " + a.what + " from " + a.who});
        break;
    }
  }

  // The last hand drive of each robot (to tell a renewal from a new drive).
  struct LastDrive {
    agents::WheelCommand wheels;
    TimeUs until_us = 0;
    std::string who;
  };

  Setup s_;
  sim::Port<ControlAction>& in_;
  sim::Port<ConsoleOrder>& out_;
  TimeUs t_us_ = 0;
  std::map<int, LastDrive> drives_;
};

// The field as the run folder's picture and a watcher draw it.
FieldDrawing field_drawing(const Scenario& scenario, const std::vector<int>& real_ids) {
  FieldDrawing drawing{scenario.map.field.width_m, scenario.map.field.height_m, {}, {}, {}, {}};
  for (const auto& o : scenario.map.obstacles) drawing.obstacles.push_back(o.vertices_m);
  for (const auto& t : scenario.map.tracks) {
    auto points = t.points_m;
    if (t.closed && !points.empty()) points.push_back(points.front());
    drawing.tracks.emplace_back(points, t.width_m);
  }
  for (const auto& b : scenario.map.beacons) drawing.beacons.push_back(b.position_m);
  drawing.real_robot_ids = {real_ids.begin(), real_ids.end()};
  return drawing;
}

// A robot's sensors as a viewer draws them.
SensorGeometry sensor_geometry(const environment::SensorSuiteConfig& c) {
  SensorGeometry g;
  if (c.proximity) g.ir_range_m = c.proximity->range_m;
  for (const auto& r : c.range_finders) g.ranges.push_back({r.mount_angle_rad, r.opening_angle_rad, r.max_range_m});
  if (c.beacon_finder) {
    g.beacon_finder = true;
    g.beacon_fov_rad = c.beacon_finder->field_of_view_rad;
  }
  for (const auto& t : c.track_sensors) g.track_points_m.push_back(environment::track_footprint(t).points_m);
  return g;
}

WorldReport world_report(const Scenario& scenario, const std::vector<int>& real_ids) {
  WorldReport w;
  w.scenario = scenario.name;
  w.field = field_drawing(scenario, real_ids);
  w.walls = scenario.map.field.boundary_walls;
  for (const RobotSpec& r : scenario.robots) {
    w.robot_ids.push_back(r.id);
    const SensorGeometry g = sensor_geometry(r.sensors);
    auto it = std::find(w.sensor_geometries.begin(), w.sensor_geometries.end(), g);
    if (it == w.sensor_geometries.end()) it = w.sensor_geometries.insert(it, g);
    w.sensor_geometry_of[r.id] = static_cast<int>(it - w.sensor_geometries.begin());
  }
  return w;
}

}  // namespace

nlohmann::json RunResult::summary() const {
  nlohmann::json j;
  j["seed"] = seed;
  j["convoy_size"] = convoy_size;
  j["formed"] = formed;
  j["formation_time_s"] = formation_time_s ? nlohmann::json(*formation_time_s) : nlohmann::json(nullptr);
  j["collisions"] = collisions;
  j["robot_collisions"] = robot_collisions;
  j["max_overlap_m"] = max_overlap_m;
  j["simulated_s"] = simulated_s;
  j["wall_s"] = wall_s;
  j["run_wall_s"] = run_wall_s;
  j["ended_by"] = ended_by;
  if (!loop_latency_ms.empty()) {
    const std::vector<double> ms(loop_latency_ms.begin(), loop_latency_ms.end());
    j["loop_latency_ms"] = {{"p50", percentile(ms, 0.5)},
                            {"p99", percentile(ms, 0.99)},
                            {"max", *std::max_element(ms.begin(), ms.end())},
                            {"steps", ms.size()}};
  }
  return j;
}

std::unique_ptr<agents::Controller> make_controller(const Scenario& scenario, const RobotSpec& spec) {
  const std::string where =
      scenario.source.string() + ":" + std::to_string(spec.line) + ": robot " + std::to_string(spec.id);
  const std::shared_ptr<const agents::ControllerRegistry> registry =
      scenario.controllers ? scenario.controllers : agents::default_controllers();
  const agents::ControllerEntry* entry = registry->find(spec.controller.name);
  if (!entry) {
    throw ScenarioError(where + ": unknown controller '" + spec.controller.name +
                        "' (known: " + registry->names_text() + ")");
  }
  // A scenario read from a file was checked already; one built in code is checked here.
  if (const auto problem = agents::check_params(*entry, spec.controller.params)) {
    throw ScenarioError(where + ": " + (problem->key.empty() ? "" : "params." + problem->key + ": ") +
                        problem->problem);
  }
  if (const auto sensor = agents::missing_sensor(*entry, spec.sensors)) {
    throw ScenarioError(where + ": " + entry->name + " needs `sensors: " + *sensor + ":`");
  }
  const agents::ControllerParams params(entry->params, spec.controller.params);
  try {
    return entry->make(agents::ControllerContext{spec.id, params, spec.sensors, scenario.convoy});
  } catch (const std::invalid_argument& e) {
    throw ScenarioError(where + ": controller " + entry->name + ": " + e.what());
  }
}

std::vector<Pose2> start_poses(const Scenario& scenario, std::uint64_t seed) {
  std::seed_seq pose_seed{seed, std::uint64_t{0x706f736573}};
  std::mt19937_64 pose_rng(pose_seed);
  return draw_initial_poses(scenario, pose_rng);
}

RunResult run_scenario(const Scenario& scenario, const RunOptions& options, const RealBodyFactory& real_bodies) {
  const auto wall_start = std::chrono::steady_clock::now();
  RunResult result;
  result.seed = options.seed;
  // Separate streams for the initial poses and for the run's noise, both from the seed,
  // so that changing a sensor's noise does not move the starting poses.
  std::seed_seq noise_seed_seq{options.seed, std::uint64_t{0x6e6f697365}};
  std::array<std::uint32_t, 2> noise_seed_words{};
  noise_seed_seq.generate(noise_seed_words.begin(), noise_seed_words.end());
  const std::uint64_t noise_seed = (std::uint64_t{noise_seed_words[0]} << 32) | noise_seed_words[1];

  // The convoy: robots with the convoy controller, numbered 1..N.
  std::vector<int> convoy_ids;
  for (const RobotSpec& r : scenario.robots) {
    if (r.controller.name == "convoy") convoy_ids.push_back(r.id);
  }
  for (std::size_t k = 0; k < convoy_ids.size(); ++k) {
    if (convoy_ids[k] != static_cast<int>(k) + 1) {
      throw ScenarioError(scenario.source.string() +
                          ": convoy robots must have IDs 1..N (agent k follows agent k-1); found " +
                          std::to_string(convoy_ids[k]) + " where " + std::to_string(k + 1) + " was expected");
    }
  }

  result.convoy_size = static_cast<int>(convoy_ids.size());
  const std::vector<int> real_ids = real_robot_ids(scenario);
  if (!real_ids.empty() && (!options.realtime || options.rt_factor != 1.0)) {
    throw ScenarioError(scenario.source.string() + ": robots " + id_list_text(real_ids) +
                        " are real and move in wall-clock time: they run in real time at a factor of 1");
  }
  environment::WorldConfig world_config;
  world_config.noise_seed = noise_seed;
  environment::World world(scenario.map, world_config);
  if (options.threads < 1) throw std::invalid_argument("threads must be >= 1");
  std::optional<core::WorkerPool> workers;
  if (options.threads > 1) {
    workers.emplace(options.threads);
    world.set_workers(&*workers);
  }
  for (const auto& m : scenario.moving_obstacles) world.add_moving_obstacle(m);
  const std::vector<Pose2> poses = start_poses(scenario, options.seed);
  // The camera is checked (its calibration, device or footage) before any real robot's
  // link is opened, so that a bad camera never leaves a robot started.
  std::shared_ptr<VisionModel> camera = scenario.camera ? make_camera(scenario, options, world) : nullptr;
  std::vector<std::unique_ptr<agents::Body>> bodies;
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    const RobotSpec& spec = scenario.robots[i];
    environment::RobotConfig rc;
    rc.id = spec.id;
    rc.kind = spec.kind;
    rc.pose = poses[i];
    rc.noise = spec.noise;
    rc.sensors = spec.sensors;
    try {
      world.add_robot(rc);
    } catch (const std::invalid_argument& e) {
      throw ScenarioError(scenario.source.string() + ":" + std::to_string(spec.line) + ": " + e.what());
    }
    if (spec.kind == environment::RobotKind::kReal) {
      std::unique_ptr<agents::Body> body = real_bodies ? real_bodies(spec, world) : nullptr;
      if (!body) {
        throw ScenarioError(scenario.source.string() + ":" + std::to_string(spec.line) + ": robot " +
                            std::to_string(spec.id) + " is real, and this run has no serial links for real robots");
      }
      bodies.push_back(std::move(body));
    } else {
      bodies.push_back(std::make_unique<VirtualBody>(world, spec.id));
    }
  }

  // The coupled model, in the order that breaks ties (see the header).
  auto root = std::make_shared<sim::Coupled>("run");
  auto& world_model = root->emplace<WorldModel>(world, scenario.physics_step_us);
  // After the world (it has moved to the instant) and before the agents (they read).
  auto& sensing = root->emplace<SensingModel>(world, scenario.control_period_us, 0);
  std::vector<AgentModel*> agents;
  const bool central = scenario.mode == ConvoyMode::kCentral;
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    auto controller = make_controller(scenario, scenario.robots[i]);
    const bool commanded = central && i < convoy_ids.size();
    agents.push_back(&root->emplace<AgentModel>(*bodies[i], std::move(controller), scenario.control_period_us, 0,
                                                commanded, options.remote_agents));
  }
  // The readings each step are kept for an observer only (the GUI and the bus report them).
  if (!options.observer)
    for (AgentModel* a : agents) a->set_keep_sensors(false);
  RunProfile profile;
  if (options.profile) {
    for (AgentModel* a : agents) a->set_profile(true);
    sensing.set_profile(true);
  }
  // The remote controllers' quantum, right after every agent of the instant has stepped.
  QuantumModel* quantum = nullptr;
  if (options.remote_agents &&
      std::any_of(agents.begin(), agents.end(), [](const AgentModel* a) { return a->is_remote(); })) {
    quantum = &root->emplace<QuantumModel>(*options.remote_agents, agents, scenario.control_period_us, 0);
  }
  // Both ways of running a convoy are built; the mode says which one drives (the console
  // may switch it while the run runs).
  CentralConvoyModel* central_model = nullptr;
  if (!convoy_ids.empty()) {
    std::vector<agents::Body*> convoy_bodies;
    for (std::size_t i = 0; i < convoy_ids.size(); ++i) convoy_bodies.push_back(bodies[i].get());
    central_model =
        &root->emplace<CentralConvoyModel>(convoy_bodies, scenario.convoy, scenario.control_period_us, 0, central);
    for (std::size_t i = 0; i < convoy_ids.size(); ++i) {
      root->couple(*central_model->find_output("commands"), *agents[i]->find_input("command"));
    }
  }
  if (std::any_of(agents.begin(), agents.end(), [](const AgentModel* a) { return a->wants_team(); })) {
    // Every robot is in the broadcast (a convoy agent avoids wanderers too); only the
    // agents that read it receive it.
    auto& broadcaster = root->emplace<TeamBroadcaster>(std::vector<const AgentModel*>(agents.begin(), agents.end()),
                                                       scenario.broadcast_period_us);
    for (AgentModel* a : agents) {
      if (a->wants_team()) root->couple(*broadcaster.find_output("team"), *a->find_input("team"));
    }
  }
  std::unique_ptr<RunRecorder> recorder;
  if (options.out_dir) recorder = std::make_unique<RunRecorder>(*options.out_dir, field_drawing(scenario, real_ids));
  const double duration_s = options.duration_s.value_or(scenario.duration_s);
  const TimeUs end_us = seconds_to_us(duration_s);
  sim::Coordinator* coordinator_ptr = nullptr;
  MonitorModel::Setup setup;
  setup.world = &world;
  setup.workers = workers ? &*workers : nullptr;
  setup.world_model = &world_model;
  setup.agents = agents;
  setup.convoy_ids = convoy_ids;
  setup.recorder = recorder.get();
  setup.options = &options;
  setup.coordinator = &coordinator_ptr;
  setup.result = &result;
  setup.period_us = scenario.control_period_us;
  setup.scenario = &scenario;
  setup.wall_start = wall_start;
  if (options.observer) {
    setup.world_report = world_report(scenario, real_ids);
    if (camera) {
      const CameraSpec& cam = *scenario.camera;
      setup.world_report.camera = camera->camera_report(cam.emulate  ? "emulated"
                                                        : cam.device ? "device " + std::to_string(*cam.device)
                                                                     : cam.file);
    }
  }
  sim::FastClock fast_clock;
  sim::RealTimeClock real_clock(options.rt_factor);
  if (options.realtime) setup.clock = &real_clock;
  setup.camera = camera.get();
  if (options.profile) setup.profile = &profile;
  auto& monitor = root->emplace<MonitorModel>(setup);
  if (quantum) {
    quantum->on_notice([&monitor](TimeUs t, const ExchangeNotice& n) {
      monitor.record_event(RunEvent{t, n.kind, n.robot_id, 0, n.detail});
    });
  }
  if (camera) {
    camera->report_to(options.observer);
    root->add(camera);
  }

  sim::Clock& clock = options.realtime ? static_cast<sim::Clock&>(real_clock) : static_cast<sim::Clock&>(fast_clock);
  // The console's way in: a root input coupled to the control model.
  sim::Port<ControlAction>* control_in = nullptr;
  if (options.control) {
    auto& control = root->emplace<ControlModel>(ControlModel::Setup{
        agents, &monitor, options.realtime ? &real_clock : nullptr, options.observer, camera.get()});
    control_in = &root->add_input<ControlAction>("control");
    root->couple(*control_in, control.input());
    for (AgentModel* a : agents) root->couple(control.orders(), *a->find_input("console"));
    if (central_model) root->couple(control.orders(), *central_model->find_input("console"));
  }
  sim::Coordinator coordinator(root, clock);
  if (workers) coordinator.set_workers(&*workers);
  coordinator_ptr = &coordinator;
  std::atomic<bool> paused{false};
  std::atomic<bool> central_now{central};
  if (options.control) {
    const bool realtime = options.realtime;
    const bool has_real = !real_ids.empty();
    const bool has_convoy = !convoy_ids.empty();
    std::set<int> ids;
    for (const RobotSpec& r : scenario.robots) ids.insert(r.id);
    // The settings as the accepted actions leave them. RunControl checks and hands on one
    // action at a time, so the checks see them in the order the run applies them.
    std::optional<vision::VisionSettings> vision_now;
    if (camera) vision_now = camera->vision();
    options.control->attach(
        [&paused, &central_now, realtime, has_real, has_convoy, ids,
         vision_now](const ControlAction& a) mutable -> std::optional<std::string> {
          switch (a.kind) {
            case ControlAction::Kind::kPause:
              if (!realtime) return "a fast run cannot be paused (it is not paced to the clock)";
              if (paused.exchange(true)) return "the run is paused already";
              return std::nullopt;
            case ControlAction::Kind::kResume:
              if (!paused.exchange(false)) return "the run is not paused";
              return std::nullopt;
            case ControlAction::Kind::kRtFactor:
              if (!realtime) return "a fast run has no real-time factor";
              if (has_real && a.rt_factor != 1.0) return "a run with real robots runs at a factor of 1";
              if (!(a.rt_factor > 0.0) || !std::isfinite(a.rt_factor)) return "the factor must be a number above 0";
              return std::nullopt;
            case ControlAction::Kind::kMode:
              if (!has_convoy) return "this run has no convoy, so no mode to switch";
              if (central_now.exchange(a.central) == a.central) {
                return std::string("the convoy is in ") + (a.central ? "central" : "distributed") + " mode already";
              }
              return std::nullopt;
            case ControlAction::Kind::kDrive:
              if (!ids.contains(a.robot_id)) return "this run has no robot " + std::to_string(a.robot_id);
              if (paused.load()) return "the run is paused: resume it first";
              if (std::abs(a.left) > 127 || std::abs(a.right) > 127)
                return "wheel speeds are -127..127 (Khepera units)";
              if (!(a.duration_s > 0.0) || !std::isfinite(a.duration_s)) return "the seconds must be above 0";
              return std::nullopt;
            case ControlAction::Kind::kVision: {
              if (!vision_now) return std::string("this run has no camera, so no vision settings");
              if (a.vision.empty()) return std::string("no vision setting given");
              vision::VisionSettings s = *vision_now;
              for (const auto& [name, value] : a.vision) {
                if (auto why = vision::set_vision_setting(s, name, value)) return why;
              }
              if (auto why = vision::check_vision_settings(s)) return why;
              vision_now = s;
              return std::nullopt;
            }
            case ControlAction::Kind::kExit:
            case ControlAction::Kind::kReset:
            case ControlAction::Kind::kRefused: return std::nullopt;
          }
          return "unknown action";
        },
        [&coordinator, control_in](const ControlAction& a) { coordinator.inject(*control_in, a); });
  }
  std::exception_ptr failure;
  const environment::WorldStepTimes world_times_before = world.step_times();
  const auto run_start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  try {
    coordinator.run_until(end_us);
  } catch (const std::exception& e) {
    failure = std::current_exception();
    result.ended_by = std::string("error: ") + e.what();
  }
  if (options.control) options.control->detach();
  result.run_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
  result.run_cpu_s = thread_cpu_seconds() - cpu_start + (workers ? workers->worker_cpu_seconds() : 0.0);
  if (options.profile) {
    profile.sensing_s += sensing.sensing_s() * options.threads;  // summed over threads, as the agents' are
    for (const AgentModel* a : agents) {
      profile.sensing_s += a->times().sensing_s;
      profile.behaviours_s += a->times().behaviours_s;
    }
    profile.integration_s = world.step_times().integration_s - world_times_before.integration_s;
    profile.collisions_s = world.step_times().collisions_s - world_times_before.collisions_s;
    result.profile = profile;
  }
  // Every body is stopped whatever happened (a real robot must not drive on).
  for (AgentModel* a : agents) a->finish();
  if (quantum) options.remote_agents->end();
  if (result.ended_by.empty()) result.ended_by = "duration";
  result.simulated_s = us_to_seconds(std::min(coordinator.now_us(), end_us));
  result.formed = monitor.formed();
  for (const AgentModel* a : agents) {
    if (!a->done()) result.not_done.push_back(a->body().id());
  }
  if (const auto t = monitor.formation_time_us()) result.formation_time_s = us_to_seconds(*t);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  nlohmann::json summary = result.summary();
  summary["scenario"] = scenario.name;
  summary["mode"] = scenario.mode == ConvoyMode::kCentral ? "central" : "distributed";
  summary["robots"] = scenario.robots.size();
  summary["realtime"] = options.realtime;
  summary["threads"] = options.threads;
  summary["real_robots"] = real_ids;
  summary["virtual_stand_ins"] = options.virtual_stand_ins;
  if (options.realtime) summary["rt_factor"] = options.rt_factor;
  if (!result.formed && !convoy_ids.empty()) {
    const RunEvent note{coordinator.now_us(), "note", 0, 0, "the convoy did not form"};
    if (recorder) recorder->add_event(note);
    if (options.observer) options.observer->on_event(note);
  }
  if (options.observer) {
    const TimeUs end_t_us = std::min(coordinator.now_us(), end_us);
    options.observer->on_status(monitor.status(end_t_us, "ended"));
    options.observer->on_summary(end_t_us, summary);
  }
  if (recorder) {
    recorder->finish(summary);
  }
  if (failure) std::rethrow_exception(failure);
  return result;
}

}  // namespace rilbed::run
