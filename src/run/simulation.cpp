#include "run/simulation.hpp"

#include <algorithm>
#include <array>
#include <random>
#include <set>
#include <stop_token>
#include <thread>

#include "agents/builtin_controllers.hpp"
#include "core/id_list.hpp"
#include "run/camera_model.hpp"
#include "run/control_model.hpp"
#include "run/group_exchange.hpp"
#include "run/monitor_model.hpp"
#include "run/run_models.hpp"
#include "run/virtual_body.hpp"
#include "run/world_models.hpp"
#include "run/world_report.hpp"

namespace rilbed::run {

namespace {

// The world of a run with `seed`. Its noise has a stream of its own, apart from the initial
// poses' (start_poses), so that changing a sensor's noise does not move the starting poses.
environment::World make_world(const Scenario& scenario, std::uint64_t seed) {
  std::seed_seq noise_seed_seq{seed, std::uint64_t{0x6e6f697365}};
  std::array<std::uint32_t, 2> words{};
  noise_seed_seq.generate(words.begin(), words.end());
  environment::WorldConfig config;
  config.noise_seed = (std::uint64_t{words[0]} << 32) | words[1];
  return environment::World(scenario.map, config);
}

std::vector<int> convoy_ids_of(const Scenario& scenario) {
  std::vector<int> ids;
  const auto registry = scenario.controllers ? scenario.controllers : agents::default_controllers();
  for (const RobotSpec& r : scenario.robots) {
    const agents::ControllerEntry* entry = registry->find(r.controller.name);
    if (entry && entry->forms_convoy) ids.push_back(r.id);
  }
  return ids;
}

// Where a run's camera frames come from, as viewers are told.
std::string camera_source(const CameraSpec& cam) {
  if (cam.emulate) return "emulated";
  if (cam.device) return "device " + std::to_string(*cam.device);
  return cam.file;
}

}  // namespace

Run::Run(const Scenario& scenario, const RunOptions& options, const RealBodyFactory& real_bodies)
    : scenario_(scenario),
      options_(options),
      wall_start_(std::chrono::steady_clock::now()),
      convoy_ids_(convoy_ids_of(scenario)),
      real_ids_(real_robot_ids(scenario)),
      world_(make_world(scenario, options.seed)) {
  result_.seed = options.seed;
  check_convoy();
  result_.convoy_size = static_cast<int>(convoy_ids_.size());
  if (!real_ids_.empty() && (!options.realtime || options.rt_factor != 1.0)) {
    throw ScenarioError(scenario.source.string() + ": robots " + id_list_text(real_ids_) +
                        " are real and move in wall-clock time: they run in real time at a factor of 1");
  }
  if (options.threads < 1) throw std::invalid_argument("threads must be >= 1");
  if (options.threads > 1) {
    workers_.emplace(options.threads);
    world_.set_workers(&*workers_);
  }
  for (const auto& m : scenario.moving_obstacles) world_.add_moving_obstacle(m);
  // The camera is checked (its calibration, device or footage) before any real robot's
  // link is opened, so that a bad camera never leaves a robot started.
  if (scenario.camera) camera_ = make_camera(scenario, options, world_);
  make_bodies(real_bodies);
  // The coupled model, in the order that breaks ties (see the header).
  root_ = std::make_shared<sim::Coupled>("run");
  world_model_ = &root_->emplace<WorldModel>(world_, scenario.physics_step_us);
  // After the world (it has moved to the instant) and before the agents (they read).
  sensing_ = &root_->emplace<SensingModel>(world_, scenario.control_period_us, 0);
  add_agents();
  add_team_models();
  if (options.out_dir) {
    recorder_ = std::make_unique<RunRecorder>(*options.out_dir, field_drawing(scenario, real_ids_));
  }
  end_us_ = seconds_to_us(options.duration_s.value_or(scenario.duration_s));
  real_clock_.emplace(options.rt_factor);
  add_monitor();
  if (camera_) {
    camera_->report_to(options.observer);
    root_->add(camera_);
  }
  add_control();
  sim::Clock& clock = options.realtime ? static_cast<sim::Clock&>(*real_clock_) : fast_clock_;
  coordinator_.emplace(root_, clock);
  if (workers_) coordinator_->set_workers(&*workers_);
  coordinator_ptr_ = &*coordinator_;
  central_now_ = scenario.mode == ConvoyMode::kCentral;
  attach_control();
}

Run::~Run() {
  if (ended_) return;
  // Built but never ended (loop() or end() not called, or the caller threw): the robots
  // still stop, and the console no longer reaches a run that is going.
  if (control_attached_) options_.control->detach();
  for (AgentModel* a : agents_) a->finish();
}

void Run::check_convoy() {
  for (std::size_t k = 0; k < convoy_ids_.size(); ++k) {
    if (convoy_ids_[k] != static_cast<int>(k) + 1) {
      throw ScenarioError(scenario_.source.string() +
                          ": convoy robots must have IDs 1..N (agent k follows agent k-1); found " +
                          std::to_string(convoy_ids_[k]) + " where " + std::to_string(k + 1) + " was expected");
    }
  }
}

void Run::make_bodies(const RealBodyFactory& real_bodies) {
  const std::vector<Pose2> poses = start_poses(scenario_, options_.seed);
  for (std::size_t i = 0; i < scenario_.robots.size(); ++i) {
    const RobotSpec& spec = scenario_.robots[i];
    const std::string where = scenario_.source.string() + ":" + std::to_string(spec.line) + ": ";
    environment::RobotConfig rc;
    rc.id = spec.id;
    rc.kind = spec.kind;
    rc.pose = poses[i];
    rc.radius_m = spec.body.radius_m;
    rc.outline_m = spec.body.outline_m;
    rc.wheel_base_m = spec.body.wheel_base_m;
    rc.noise = spec.noise;
    rc.sensors = spec.sensors;
    rc.drive = spec.drive;
    try {
      world_.add_robot(rc);
    } catch (const std::invalid_argument& e) {
      throw ScenarioError(where + e.what());
    }
    if (spec.kind != environment::RobotKind::kReal) {
      bodies_.push_back(std::make_unique<VirtualBody>(world_, spec.id));
      continue;
    }
    std::unique_ptr<agents::Body> body = real_bodies ? real_bodies(spec, world_) : nullptr;
    if (!body) {
      throw ScenarioError(where + "robot " + std::to_string(spec.id) +
                          " is real, and this run has no serial links for real robots");
    }
    bodies_.push_back(std::move(body));
  }
}

void Run::make_watch() {
  watch_ = std::make_unique<ControllerWatch>();
  watch_->stop_robot_on_error = options_.on_controller_error == ControllerErrorAction::kStopRobot;
  // A step longer than the period in wall time makes a real-time run fall behind the clock.
  if (options_.realtime) watch_->step_budget_s = us_to_seconds(scenario_.control_period_us) / options_.rt_factor;
  watch_->report = [this](TimeUs t_us, int robot_id, const std::string& detail) {
    const std::lock_guard lock(watch_mutex_);
    monitor_->record_event(RunEvent{t_us, "controller", robot_id, 0, detail});
  };
}

GroupExchange& Run::group_exchange(agents::ControllerGroup& group) {
  for (const auto& g : group_exchanges_) {
    if (&g->group() == &group) return *g;
  }
  group_exchanges_.push_back(std::make_unique<GroupExchange>(group, *watch_));
  return *group_exchanges_.back();
}

void Run::add_agents() {
  make_watch();
  const bool central = scenario_.mode == ConvoyMode::kCentral;
  for (std::size_t i = 0; i < scenario_.robots.size(); ++i) {
    const int id = scenario_.robots[i].id;
    auto controller = make_controller(scenario_, scenario_.robots[i], &groups_);
    const bool commanded = central && i < convoy_ids_.size();
    // A robot another process serves runs there; a group's member steps with its group.
    AgentExchange* exchange = options_.remote_agents;
    if ((!exchange || !exchange->serves(id)) && controller && controller->group()) {
      GroupExchange& g = group_exchange(*controller->group());
      g.add_member(id);
      exchange = &g;
    }
    agents_.push_back(&root_->emplace<AgentModel>(*bodies_[i], std::move(controller), scenario_.control_period_us, 0,
                                                  commanded, exchange));
    agents_.back()->set_watch(watch_.get());
  }
  // The readings each step are kept for an observer only (the GUI and the bus report them),
  // and so are what sensor models draw.
  world_.set_collect_marks(options_.observer != nullptr);
  if (!options_.observer) {
    for (AgentModel* a : agents_) a->set_keep_sensors(false);
  }
  if (options_.profile) {
    for (AgentModel* a : agents_) a->set_profile(true);
    sensing_->set_profile(true);
  }
}

void Run::add_team_models() {
  // The remote controllers' quantum, right after every agent of the instant has stepped.
  if (options_.remote_agents &&
      std::any_of(agents_.begin(), agents_.end(), [](const AgentModel* a) { return a->is_remote(); })) {
    quantum_ = &root_->emplace<QuantumModel>(*options_.remote_agents, agents_, scenario_.control_period_us, 0);
  }
  for (const auto& g : group_exchanges_) {
    std::vector<AgentModel*> members;
    for (AgentModel* a : agents_) {
      if (g->serves(a->body().id())) members.push_back(a);
    }
    group_quanta_.push_back(&root_->emplace<QuantumModel>(*g, members, scenario_.control_period_us, 0));
  }
  // Both ways of running a convoy are built; the mode says which one drives (the console
  // may switch it while the run runs).
  if (!convoy_ids_.empty()) {
    std::vector<agents::Body*> convoy_bodies;
    for (std::size_t i = 0; i < convoy_ids_.size(); ++i) convoy_bodies.push_back(bodies_[i].get());
    central_model_ = &root_->emplace<CentralConvoyModel>(convoy_bodies, scenario_.convoy, scenario_.control_period_us,
                                                         0, scenario_.mode == ConvoyMode::kCentral);
    for (std::size_t i = 0; i < convoy_ids_.size(); ++i) {
      root_->couple(*central_model_->find_output("commands"), *agents_[i]->find_input("command"));
    }
  }
  if (std::none_of(agents_.begin(), agents_.end(), [](const AgentModel* a) { return a->wants_team(); })) return;
  // Every robot is in the broadcast (a convoy agent avoids wanderers too); only the agents
  // that read it receive it.
  auto& broadcaster = root_->emplace<TeamBroadcaster>(std::vector<const AgentModel*>(agents_.begin(), agents_.end()),
                                                      scenario_.broadcast_period_us);
  for (AgentModel* a : agents_) {
    if (a->wants_team()) root_->couple(*broadcaster.find_output("team"), *a->find_input("team"));
  }
}

void Run::add_monitor() {
  MonitorModel::Setup setup;
  setup.world = &world_;
  setup.workers = workers_ ? &*workers_ : nullptr;
  setup.world_model = world_model_;
  setup.agents = agents_;
  setup.convoy_ids = convoy_ids_;
  setup.recorder = recorder_.get();
  setup.options = &options_;
  setup.coordinator = &coordinator_ptr_;
  setup.result = &result_;
  setup.period_us = scenario_.control_period_us;
  setup.scenario = &scenario_;
  setup.wall_start = wall_start_;
  if (options_.observer) {
    setup.world_report = world_report(scenario_, real_ids_);
    if (camera_) setup.world_report.camera = camera_->camera_report(camera_source(*scenario_.camera));
  }
  if (options_.realtime) setup.clock = &*real_clock_;
  setup.camera = camera_.get();
  if (options_.profile) setup.profile = &profile_;
  monitor_ = &root_->emplace<MonitorModel>(setup);
  std::vector<QuantumModel*> quanta = group_quanta_;
  if (quantum_) quanta.push_back(quantum_);
  for (QuantumModel* q : quanta) {
    q->on_notice([monitor = monitor_](TimeUs t, const ExchangeNotice& n) {
      monitor->record_event(RunEvent{t, n.kind, n.robot_id, 0, n.detail});
    });
  }
}

void Run::add_control() {
  if (!options_.control) return;
  // The console's way in: a root input coupled to the control model.
  auto& control = root_->emplace<ControlModel>(ControlModel::Setup{
      agents_, monitor_, options_.realtime ? &*real_clock_ : nullptr, options_.observer, camera_.get()});
  control_in_ = &root_->add_input<ControlAction>("control");
  root_->couple(*control_in_, control.input());
  for (AgentModel* a : agents_) root_->couple(control.orders(), *a->find_input("console"));
  if (central_model_) root_->couple(control.orders(), *central_model_->find_input("console"));
}

void Run::attach_control() {
  if (!options_.control) return;
  ActionChecker checker;
  checker.realtime = options_.realtime;
  checker.has_real = !real_ids_.empty();
  checker.has_convoy = !convoy_ids_.empty();
  for (const RobotSpec& r : scenario_.robots) checker.robot_ids.insert(r.id);
  if (camera_) checker.vision_now = camera_->vision();
  checker.paused = &paused_;
  checker.central_now = &central_now_;
  options_.control->attach(std::move(checker), [coordinator = coordinator_ptr_, in = control_in_](
                                                   const ControlAction& a) { coordinator->inject(*in, a); });
  control_attached_ = true;
}

std::jthread Run::interrupt_watcher(std::atomic<bool>& fired) {
  // A paused real-time run sleeps in its clock, where the monitor (which checks the
  // interrupt each control step) never runs: Ctrl-C would do nothing until someone resumed.
  // This turns an interrupt while paused into a stop; end() then stops every robot.
  if (!options_.realtime || !options_.interrupt) return {};
  return std::jthread([this, &fired](const std::stop_token& stop) {
    constexpr auto kPoll = std::chrono::milliseconds(50);
    while (!stop.stop_requested()) {
      if (options_.interrupt->load() && real_clock_->paused()) {
        fired.store(true);
        coordinator_->stop();
        return;
      }
      std::this_thread::sleep_for(kPoll);
    }
  });
}

void Run::loop() {
  const environment::WorldStepTimes world_times_before = world_.step_times();
  const auto run_start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  std::atomic<bool> interrupted_paused{false};
  {
    const std::jthread watcher = interrupt_watcher(interrupted_paused);
    // Before the console's first order can end the run (it may come before the first step).
    monitor_->report_world(coordinator_->now_us());
    try {
      coordinator_->run_until(end_us_);
    } catch (const std::exception& e) {
      failure_ = std::current_exception();
      // The first line (a Python controller's traceback follows it; the error says it all).
      const std::string what = e.what();
      result_.ended_by = "error: " + what.substr(0, what.find('\n'));
    }
  }  // (the watcher is asked to stop and joined here)
  if (interrupted_paused.load() && result_.ended_by.empty()) {
    result_.ended_by = "interrupt";
    monitor_->record_event({coordinator_->now_us(), "console", 0, 0, "interrupted while paused"});
  }
  if (control_attached_) options_.control->detach();
  control_attached_ = false;
  result_.run_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
  result_.run_cpu_s = thread_cpu_seconds() - cpu_start + (workers_ ? workers_->worker_cpu_seconds() : 0.0);
  if (!options_.profile) return;
  profile_.integration_s = world_.step_times().integration_s - world_times_before.integration_s;
  profile_.collisions_s = world_.step_times().collisions_s - world_times_before.collisions_s;
}

void Run::finish_profile() {
  profile_.sensing_s += sensing_->sensing_s() * options_.threads;  // summed over threads, as the agents' are
  for (const AgentModel* a : agents_) {
    profile_.sensing_s += a->times().sensing_s;
    profile_.behaviours_s += a->times().behaviours_s;
  }
  result_.profile = profile_;
}

RunResult Run::end() {
  ended_ = true;
  if (control_attached_) options_.control->detach();
  if (options_.profile) finish_profile();
  // Every body is stopped whatever happened (a real robot must not drive on).
  for (AgentModel* a : agents_) a->finish();
  if (quantum_) options_.remote_agents->end();
  for (const auto& g : group_exchanges_) g->end();
  for (const AgentModel* a : agents_) {
    result_.controller_overruns += a->overruns();
    if (a->failed()) result_.controller_failed.push_back(a->body().id());
  }
  for (const auto& g : group_exchanges_) {
    result_.controller_overruns += g->overruns();
    for (const int id : g->failed_members()) result_.controller_failed.push_back(id);
  }
  std::sort(result_.controller_failed.begin(), result_.controller_failed.end());
  if (result_.ended_by.empty()) result_.ended_by = "duration";
  result_.simulated_s = us_to_seconds(std::min(coordinator_->now_us(), end_us_));
  result_.formed = monitor_->formed();
  for (const AgentModel* a : agents_) {
    if (!a->done()) result_.not_done.push_back(a->body().id());
  }
  if (const auto t = monitor_->formation_time_us()) result_.formation_time_s = us_to_seconds(*t);
  result_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
  report_end(summary());
  if (failure_) std::rethrow_exception(failure_);
  return std::move(result_);
}

nlohmann::json Run::summary() const {
  nlohmann::json summary = result_.summary();
  summary["scenario"] = scenario_.name;
  summary["mode"] = scenario_.mode == ConvoyMode::kCentral ? "central" : "distributed";
  summary["robots"] = scenario_.robots.size();
  summary["realtime"] = options_.realtime;
  summary["threads"] = options_.threads;
  summary["real_robots"] = real_ids_;
  summary["virtual_stand_ins"] = options_.virtual_stand_ins;
  if (options_.realtime) summary["rt_factor"] = options_.rt_factor;
  return summary;
}

void Run::report_end(const nlohmann::json& summary) {
  if (!result_.formed && !convoy_ids_.empty()) {
    const RunEvent note{coordinator_->now_us(), "note", 0, 0, "the convoy did not form"};
    if (recorder_) recorder_->add_event(note);
    if (options_.observer) options_.observer->on_event(note);
  }
  if (options_.observer) {
    const TimeUs end_t_us = std::min(coordinator_->now_us(), end_us_);
    options_.observer->on_status(monitor_->status(end_t_us, "ended"));
    options_.observer->on_summary(end_t_us, summary);
  }
  if (recorder_) recorder_->finish(summary);
}

RunResult run_scenario(const Scenario& scenario, const RunOptions& options, const RealBodyFactory& real_bodies) {
  Run run(scenario, options, real_bodies);
  run.loop();
  return run.end();
}

}  // namespace rilbed::run
