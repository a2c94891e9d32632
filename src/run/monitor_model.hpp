// The run's monitor as a DEVS model: after each control step it records, counts
// collisions, checks the convoy's formation, reports the status and ends the run when it
// should.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "agents/convoy.hpp"
#include "core/worker_pool.hpp"
#include "environment/world.hpp"
#include "run/camera_model.hpp"
#include "run/run_models.hpp"
#include "run/run_observer.hpp"
#include "run/run_options.hpp"
#include "run/run_profile.hpp"
#include "run/run_recorder.hpp"
#include "run/scenario.hpp"
#include "run/world_models.hpp"
#include "sim/atomic.hpp"
#include "sim/clock.hpp"
#include "sim/coordinator.hpp"

namespace rilbed::run {

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
  explicit MonitorModel(Setup setup);
  TimeUs time_advance() const override { return state_; }
  void external_transition(TimeUs elapsed_us) override { state_ -= elapsed_us; }
  void output() override {}
  void internal_transition() override;
  bool formed() const { return formation_.formed(); }
  /// Ends the run at the end of this step, `why` becoming RunResult::ended_by.
  void end_run(const char* why) { end(why); }
  /// Records an event in the run folder and tells the observer.
  void record_event(const RunEvent& event) { record(event); }
  /// The convoy's mode now (the console may switch it).
  void set_central(bool central) { central_ = central; }
  std::optional<TimeUs> formation_time_us() const { return formation_.formation_time_us(); }

  /// Tells the observer the run's world (field, bodies, camera), as each second's first
  /// sample does. The run calls it before its first instant, so that a run the console
  /// ends before any step still announces itself to a recording or a viewer.
  void report_world(TimeUs t);

  /// The run's status now (`state`: "running" or "ended").
  StatusReport status(TimeUs t, const char* state) const;

 private:
  void end(const char* why) {
    if (s_.result->ended_by.empty()) s_.result->ended_by = why;
    (*s_.coordinator)->stop();
  }

  // An event for the run folder and for the run's observer.
  void record(const RunEvent& event) {
    if (s_.recorder) s_.recorder->add_event(event);
    if (s_.options->keep_in_memory) s_.result->events.push_back(event);
    if (s_.options->observer) s_.options->observer->on_event(event);
  }

  // Every robot with a known pose (a real robot the camera lost at its last pose, unseen),
  // then every robot's wheels and sensors.
  void report_step(TimeUs t, RunObserver& observer);

  // How far the control loop fell behind the wall clock once a step and its reports are
  // done (each step's, and the most over each second between two statuses), and the
  // camera's frame rate.
  void measure_loop(TimeUs t);
  void close_second();

  void sample(TimeUs t);

  std::vector<AgentModel*> reporting_;  // agents whose controllers report events
  std::vector<agents::ControllerEvent> controller_events_;

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
  void read_agents(TimeUs t);

  // One sample's term of the trajectory digest: of the time, id, position and heading,
  // bit for bit. The digest of a step is the sum of its samples' terms (in any order).
  static std::uint64_t sample_digest(TimeUs t, int id, const Pose2& pose);
  // A step's digest from the world's tables: each robot's pose() as its body gives it.
  std::uint64_t digest_from_world(TimeUs t) const;

  void check_formation(TimeUs t);

  // Sub-teams (paper 001 §5): maximal runs l..m of agents where each k in (l, m] follows
  // k-1 within the formed gap. Recorded whenever the set changes, as "1-3 5-6".
  void record_subteams(TimeUs t, const std::vector<agents::FormationMonitor::Sample>& team);

  Setup s_;
  bool central_ = s_.scenario->mode == ConvoyMode::kCentral;
  std::string subteams_;
  agents::FormationMonitor formation_;
  TimeUs t_us_ = 0;
  TimeUs next_report_us_ = 0;
  TimeUs next_world_us_ = 0;  // the world is told once a second, with the second's first status
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

}  // namespace rilbed::run
