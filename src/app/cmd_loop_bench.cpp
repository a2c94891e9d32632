// `rilbed loop-bench`: loop latency of the robot-in-the-loop path, from a camera frame's
// arrival to the `D` command written on each real robot's serial port.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "agents/basic_controllers.hpp"
#include "app/commands.hpp"
#include "core/statistics.hpp"
#include "environment/world.hpp"
#include "run/real_body.hpp"
#include "run/scenario.hpp"
#include "serial/khepera_emulator.hpp"
#include "serial/khepera_link.hpp"
#include "vision/emulated_camera.hpp"
#include "vision/field_tracker.hpp"

namespace rilbed::app {

namespace {

using Clock = std::chrono::steady_clock;

struct LoopArgs {
  int real = 8;
  int virtual_robots = 100;
  int frames = 300;
  double field_w = 3.0, field_h = 2.4;
  int width = 1920, height = 1080;
};

// What a link reports when the bytes of a `D` command are on the port.
struct WriteStamp {
  std::atomic<std::uint64_t> count{0};
  std::atomic<std::int64_t> last_ns{0};
};

// The loop's measures, ms, one entry per frame (to_port_ms: per robot and frame).
struct LoopTimes {
  std::vector<double> processing_ms, processing_cpu_ms, to_port_ms, other_ms;
  int seen_total = 0;
};

// One loop-bench: the world, the emulated real robots over their links, the camera, and
// the frames timed.
class LoopBench {
 public:
  explicit LoopBench(const LoopArgs& args) : args_(args), controllers_(args.real + args.virtual_robots) {}

  int run() {
    build_world();
    if (!connect_real_robots()) return kExitFailure;
    vision::EmulatedCameraConfig cam;
    cam.image_size = {args_.width, args_.height};
    vision::EmulatedOverheadCamera camera(args_.field_w, args_.field_h, vision::MarkerFamily::six_ucp(), cam);
    std::vector<int> ids;
    for (int i = 1; i <= args_.real; ++i) ids.push_back(i);
    vision::FieldTracker tracker(vision::MarkerFamily::six_ucp(), ids, camera.calibration());
    for (int frame = 0; frame < args_.frames; ++frame) run_frame(frame, camera, cam.marker_diameter_m, tracker);
    bodies_.clear();  // every robot stopped
    int stopped = 0;
    for (const auto& e : emulators_) stopped += e->last_speeds() == serial::WheelSpeeds{0, 0};
    print_table(stopped);
    return 0;
  }

 private:
  // Real robots on a grid in the middle (the camera sees them), virtual ones at random free
  // places, every robot with its 8 IR sensors.
  void build_world() {
    const LoopArgs& args = args_;
    environment::StaticMapConfig map;
    map.field.width_m = args.field_w;
    map.field.height_m = args.field_h;
    environment::World& world = world_.emplace(map);
    std::vector<Pose2>& real_poses = real_poses_;
    std::mt19937_64 rng(1);
    for (int i = 0; i < args.real; ++i) {
      const int cols = 4;
      real_poses.push_back(
          {{args.field_w * (0.2 + 0.6 * (i % cols) / (cols - 1)), args.field_h * (0.3 + 0.15 * (i / cols))}, 0.5 * i});
      environment::RobotConfig rc;
      rc.id = i + 1;
      rc.kind = environment::RobotKind::kReal;
      rc.pose = real_poses.back();
      world.add_robot(rc);
    }
    run::Scenario layout;
    layout.map = map;
    for (int i = 0; i < args.real + args.virtual_robots; ++i) {
      run::RobotSpec spec;
      spec.id = i + 1;
      if (i < args.real) spec.pose = real_poses[i];
      layout.robots.push_back(spec);
    }
    const std::vector<Pose2> poses = run::draw_initial_poses(layout, rng);
    for (int i = args.real; i < args.real + args.virtual_robots; ++i) {
      environment::RobotConfig rc;
      rc.id = i + 1;
      rc.pose = poses[i];
      world.add_robot(rc);
    }
  }

  // The real robots: emulated Kheperas on pseudo-terminals, each reached over a link, each
  // link's handshake done.
  bool connect_real_robots() {
    for (int i = 0; i < args_.real; ++i) {
      serial::EmulatorConfig emu;
      emu.initial_pose = real_poses_[i];
      emulators_.push_back(std::make_unique<serial::KheperaEmulator>(emu));
      stamps_.push_back(std::make_unique<WriteStamp>());
      serial::LinkConfig lc;
      lc.port = emulators_.back()->device_path();
      WriteStamp* stamp = stamps_.back().get();
      lc.on_speeds_written = [stamp](const serial::Command&, Clock::time_point at) {
        stamp->last_ns.store(at.time_since_epoch().count());
        stamp->count.fetch_add(1);
      };
      auto link = std::make_unique<serial::KheperaLink>(lc);
      if (const auto error = link->start()) {
        spdlog::error("{}", *error);
        return false;
      }
      run::RealBodyConfig bc;
      bc.lost_timeout_ms = 1000;
      bodies_.push_back(std::make_unique<run::RealBody>(i + 1, *world_, std::move(link), bc));
    }
    // Timed from the first frame: every link answers before (its versions read).
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    for (const auto& body : bodies_) {
      while (body->link().state() != serial::LinkState::kOk && Clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      if (body->link().state() != serial::LinkState::kOk) {
        spdlog::error("loop-bench: robot {}'s emulated link did not answer within 5 s", body->id());
        return false;
      }
    }
    return true;
  }

  // One frame: rendered (the camera's time, not ours), then detect, place the real robots,
  // run their controllers, drive, and wait for each `D` on its port; then the rest of the
  // frame's work in the run.
  void run_frame(int frame, vision::EmulatedOverheadCamera& camera, double marker_diameter_m,
                 vision::FieldTracker& tracker) {
    const LoopArgs& args = args_;
    environment::World& world = *world_;
    const TimeUs frame_us = 33'333;
    const TimeUs t_us = frame * frame_us;
    std::vector<vision::SceneMarker> markers;
    for (int i = 0; i < args.real; ++i) {
      const Pose2 p = emulators_[i]->true_pose();
      markers.push_back({i + 1, p.position_m.x, p.position_m.y, p.heading_rad, marker_diameter_m});
    }
    const cv::Mat image = camera.render(markers);
    std::vector<std::uint64_t> before(args.real);
    for (int i = 0; i < args.real; ++i) before[i] = stamps_[i]->count.load();
    const auto arrival = Clock::now();
    const double cpu0 = thread_cpu_seconds();
    for (const vision::FieldObservation& o : tracker.process(image)) {
      world.set_observed_pose(o.id, o.pose, world.time_us());
      ++times_.seen_total;
    }
    for (int i = 0; i < args.real; ++i) {
      agents::ControlInput in;
      in.t_us = t_us;
      in.robot_id = i + 1;
      in.sensors = bodies_[i]->sense(t_us);
      in.pose = bodies_[i]->pose();
      bodies_[i]->drive(controllers_[i].step(in).wheels);
    }
    const auto processed = Clock::now();
    times_.processing_cpu_ms.push_back(1e3 * (thread_cpu_seconds() - cpu0));
    times_.processing_ms.push_back(std::chrono::duration<double, std::milli>(processed - arrival).count());
    wait_for_ports(before, arrival);
    const auto rest = Clock::now();
    world.step(frame_us);
    if (frame % 3 == 0) {
      for (int i = args.real; i < args.real + args.virtual_robots; ++i) {
        agents::ControlInput in;
        in.t_us = t_us;
        in.robot_id = i + 1;
        in.sensors = world.sense(i + 1, t_us);
        const agents::ControlOutput out = controllers_[i].step(in);
        world.set_wheel_speeds(i + 1, out.wheels.left, out.wheels.right);
      }
    }
    times_.other_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - rest).count());
  }

  // Each robot's `D` on its port (one not written within 0.5 s is left out).
  void wait_for_ports(const std::vector<std::uint64_t>& before, Clock::time_point arrival) {
    const auto deadline = Clock::now() + std::chrono::milliseconds(500);
    for (int i = 0; i < args_.real; ++i) {
      while (stamps_[i]->count.load() == before[i] && Clock::now() < deadline) std::this_thread::yield();
      if (stamps_[i]->count.load() == before[i]) continue;
      const auto written = Clock::time_point(Clock::duration(stamps_[i]->last_ns.load()));
      times_.to_port_ms.push_back(std::chrono::duration<double, std::milli>(written - arrival).count());
    }
  }

  void print_table(int stopped) const {
    const LoopArgs& args = args_;
    const auto& [processing_ms, processing_cpu_ms, to_port_ms, other_ms, seen_total] = times_;
    std::printf("## Loop latency (rilbed loop-bench)\n\n");
    std::printf(
        "%d real robots (emulated Kheperas on pseudo-terminals, reached over the serial link) and %d virtual ones "
        "on a %.1f x %.1f m field, 8 IR sensors each, the wander controller. Per frame (%d frames, %dx%d, rendered "
        "by the emulated camera before the clock starts): detect and track the real robots, place them in the world, "
        "sense (virtual + the robot's own N values), decide and drive; then wait for each link to write its `D` on "
        "the port. One thread for the loop (each link has its own I/O thread). Markers seen: %.1f of %d per frame.\n\n",
        args.real, args.virtual_robots, args.field_w, args.field_h, args.frames, args.width, args.height,
        static_cast<double>(seen_total) / args.frames, args.real);
    std::printf("| measure | median ms | p99 ms | max ms |\n| --- | ---: | ---: | ---: |\n");
    auto row = [](const char* name, const std::vector<double>& v) {
      std::printf("| %s | %.3f | %.3f | %.3f |\n", name, percentile(v, 0.5), percentile(v, 0.99),
                  v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
    };
    row("processing: frame arrival to the last `D` handed to its link (wall)", processing_ms);
    row("processing, CPU time of the loop thread", processing_cpu_ms);
    row("frame arrival to `D` written on the port (per robot)", to_port_ms);
    row("the rest of the frame: world step, 100 virtual controllers every 3rd frame", other_ms);
    std::printf(
        "\nTarget: <= 2 ms median processing on one core. `D` written for %zu of %d robot-frames; "
        "%d of %d robots stopped at the end.\n",
        to_port_ms.size(), args.real * args.frames, stopped, args.real);
  }

  const LoopArgs& args_;
  std::optional<environment::World> world_;
  std::vector<Pose2> real_poses_;
  std::vector<std::unique_ptr<serial::KheperaEmulator>> emulators_;
  std::vector<std::unique_ptr<WriteStamp>> stamps_;
  std::vector<std::unique_ptr<run::RealBody>> bodies_;
  std::vector<agents::WanderController> controllers_;
  LoopTimes times_;
};

int loop_bench(const LoopArgs& args) { return LoopBench(args).run(); }

}  // namespace

void add_loop_bench_command(CLI::App& app) {
  auto args = std::make_shared<LoopArgs>();
  CLI::App* cmd =
      app.add_subcommand("loop-bench", "Loop latency from a camera frame to the D command on the serial port");
  cmd->add_option("--real", args->real, "Real (emulated) robots")->check(CLI::Range(1, 16))->default_val(args->real);
  cmd->add_option("--virtual", args->virtual_robots, "Virtual robots")
      ->check(CLI::Range(0, 10000))
      ->default_val(args->virtual_robots);
  cmd->add_option("--frames", args->frames, "Frames to time")->check(CLI::PositiveNumber)->default_val(args->frames);
  cmd->callback([args] { exit_code() = loop_bench(*args); });
}

}  // namespace rilbed::app
