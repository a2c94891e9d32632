#include "run/monitor_model.hpp"

#include <algorithm>
#include <bit>
#include <mutex>
#include <sstream>

#include "environment/random.hpp"
#include "run/virtual_body.hpp"

namespace rilbed::run {

namespace {

int party_code(const environment::BodyRef& b) {
  switch (b.kind) {
    case environment::BodyKind::kRobot: return b.id;
    case environment::BodyKind::kWall: return -1;
    case environment::BodyKind::kObstacle: return -2;
    case environment::BodyKind::kMovingObstacle: return -3;
  }
  return 0;
}

}  // namespace

MonitorModel::MonitorModel(Setup setup)
    : sim::AtomicModel<TimeUs>("monitor", 1),
      s_(std::move(setup)),
      formation_(std::max<int>(1, static_cast<int>(s_.convoy_ids.size()))) {
  last_behaviour_.assign(s_.agents.size(), {});
  last_health_.assign(s_.agents.size(), "ok");
  // The samples in one list only for those who read them (a swarm's benchmark has none).
  listed_ = s_.recorder || s_.options->keep_in_memory || !s_.convoy_ids.empty();
  all_concurrent_ =
      std::all_of(s_.agents.begin(), s_.agents.end(), [](const AgentModel* a) { return a->transitions_concurrent(); });
  for (AgentModel* a : s_.agents)
    if (a->reports_events()) reporting_.push_back(a);
  world_bodies_ = std::all_of(s_.agents.begin(), s_.agents.end(), [](const AgentModel* a) {
    return dynamic_cast<const VirtualBody*>(&a->body()) != nullptr;
  });
}

void MonitorModel::internal_transition() {
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

StatusReport MonitorModel::status(TimeUs t, const char* state) const {
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

void MonitorModel::report_step(TimeUs t, RunObserver& observer) {
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

void MonitorModel::measure_loop(TimeUs t) {
  if (s_.clock && !s_.clock->paused()) {
    const double behind_ms = static_cast<double>(s_.clock->now_us() - t) / 1000.0 / s_.clock->factor();
    latency_window_ms_ = std::max(latency_window_ms_, behind_ms);
    s_.result->loop_latency_ms.push_back(static_cast<float>(behind_ms));
  }
}

void MonitorModel::close_second() {
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

void MonitorModel::report_world(TimeUs t) {
  RunObserver* const o = s_.options->observer;
  if (!o) return;
  o->on_world(t, s_.world_report);
  next_world_us_ = (t / 1'000'000 + 1) * 1'000'000;
}

void MonitorModel::sample(TimeUs t) {
  RunResult& r = *s_.result;
  RunObserver* const o = s_.options->observer;
  const bool new_second = t >= next_report_us_;
  // The world first, so that a viewer can draw whatever follows.
  if (o && t >= next_world_us_) report_world(t);
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
  for (AgentModel* a : reporting_) {
    controller_events_.clear();
    a->take_events(controller_events_);
    for (agents::ControllerEvent& e : controller_events_)
      record({t, std::move(e.kind), a->body().id(), e.other, std::move(e.detail)});
  }
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

void MonitorModel::read_agents(TimeUs t) {
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

std::uint64_t MonitorModel::sample_digest(TimeUs t, int id, const Pose2& pose) {
  std::uint64_t h = 0x6a09e667f3bcc909ULL;
  for (const std::uint64_t word :
       {static_cast<std::uint64_t>(t), static_cast<std::uint64_t>(id), std::bit_cast<std::uint64_t>(pose.position_m.x),
        std::bit_cast<std::uint64_t>(pose.position_m.y), std::bit_cast<std::uint64_t>(pose.heading_rad)})
    h = environment::mix64(h ^ word) + 0x9e3779b97f4a7c15ULL;
  return h;
}

std::uint64_t MonitorModel::digest_from_world(TimeUs t) const {
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

void MonitorModel::check_formation(TimeUs t) {
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

void MonitorModel::record_subteams(TimeUs t, const std::vector<agents::FormationMonitor::Sample>& team) {
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

}  // namespace rilbed::run
