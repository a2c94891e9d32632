// rilbed on the vision stress set: thousands of frames whose every condition is
// drawn at random from ranges wider than any one lab's (src/vision/stress_scene.hpp), scored
// full-frame and tracked: recall by marker size, blur, occlusion and floor; wrong IDs, false
// detections, headings far off; centre and heading accuracy; a bias by code. Then the speed
// of a full-frame search on textured floors beside plain ones, and AprilTag and ArUco on
// the same frames. A report, not a test: it prints Markdown and asserts nothing.
//
//   bench_stress [--scenes N] [--seed S] [--frames-per-scene K] [--threads T] [--timing-frames F]
//                [--mistakes M] [--no-peers]
//
// Without --seed it draws one (and prints it): run it again with that seed to see the same
// frames (`rilbed synth --preset stress --seed S` writes them). Scenes are rendered on T
// threads (the detector itself always runs on one); each scene is scored as soon as it is
// rendered and only the frames kept for timing stay in memory.
#include "frame_cache.hpp"
#include "machine.hpp"
#include "timing.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

#include <CLI/CLI.hpp>
#include <opencv2/aruco.hpp>
#include <opencv2/core/ocl.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "vision/marker_tracker.hpp"
#include "vision/stress_score.hpp"

namespace rv = rilbed::vision;
using rilbed::bench::Clock;
using rilbed::bench::ms_since;
using rilbed::bench::net_ms;
using rilbed::bench::thread_cpu_ms;

namespace {

struct Options {
  int scenes = 500;
  std::uint64_t seed = 0;
  bool seed_given = false;
  int frames_per_scene = 4;
  int threads = 2;
  int timing_frames = 60;  // per floor class (plain, textured)
  int mistakes = 12;
  bool peers = true;
};

// Scenes rendered on worker threads, handed to the scorer in order of their index.
class SceneQueue {
 public:
  SceneQueue(const Options& opt, const rv::StressOptions& stress) : opt_(opt), stress_(stress) {
    for (int t = 0; t < std::max(1, opt.threads); ++t) workers_.emplace_back([this] { work(); });
  }
  ~SceneQueue() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    for (auto& w : workers_) w.join();
  }
  // The next scene in index order, or nothing after the last.
  std::optional<rv::StressScene> next() {
    std::unique_lock lock(mutex_);
    if (next_out_ >= opt_.scenes) return std::nullopt;
    changed_.wait(lock, [&] { return ready_.count(next_out_) > 0; });
    rv::StressScene s = std::move(ready_.at(next_out_));
    ready_.erase(next_out_++);
    changed_.notify_all();
    return s;
  }

 private:
  void work() {
    for (;;) {
      int index;
      {
        std::unique_lock lock(mutex_);
        // At most a few scenes ahead of the scorer: frames are large.
        changed_.wait(lock,
                      [&] { return stop_ || (next_in_ < opt_.scenes && next_in_ < next_out_ + 2 * opt_.threads); });
        if (stop_ || next_in_ >= opt_.scenes) return;
        index = next_in_++;
      }
      rv::StressScene s = rv::make_stress_scene(opt_.seed, index, stress_);
      {
        std::lock_guard lock(mutex_);
        ready_.emplace(index, std::move(s));
      }
      changed_.notify_all();
    }
  }
  const Options& opt_;
  rv::StressOptions stress_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<int, rv::StressScene> ready_;
  int next_in_ = 0, next_out_ = 0;
  bool stop_ = false;
  std::vector<std::thread> workers_;
};

std::vector<int> all_ids() { return {1, 2, 3, 4, 5, 6, 7, 8}; }

std::string pct(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4f", x);
  return b;
}

struct Bucket {
  const char* label;
  std::function<bool(const rv::StressOutcome&)> keep;
};

void print_bucket_rows(const char* mode, const std::vector<rv::StressOutcome>& outcomes,
                       const std::vector<Bucket>& buckets) {
  for (const Bucket& b : buckets) {
    const auto s = rv::summarise(outcomes, b.keep);
    if (s.markers == 0) continue;
    std::printf("| %s | %s | %d | %s | %.3f | %.3f | %.3f | %.2f | %d: %+.2f |\n", mode, b.label, s.markers,
                pct(s.recall()).c_str(), s.centre_rms_px, s.centre_max_px, s.heading_rms_deg, s.heading_max_deg,
                s.worst_bias_id, s.worst_bias_deg);
  }
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * (v.size() - 1) + 0.5)];
}

struct TimedFrame {
  cv::Mat grey;
  bool textured = false;
};

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"rilbed on the vision stress set"};
  app.add_option("--scenes", opt.scenes, "Scenes (each --frames-per-scene frames)")->check(CLI::PositiveNumber);
  app.add_option("--seed", opt.seed, "The set's seed (default: drawn, and printed)")->each([&](const std::string&) {
    opt.seed_given = true;
  });
  app.add_option("--frames-per-scene", opt.frames_per_scene, "Frames per scene (the tracked clip)")
      ->check(CLI::Range(1, 64));
  app.add_option("--threads", opt.threads, "Threads rendering scenes (detection always runs on one)")
      ->check(CLI::Range(1, 64));
  app.add_option("--timing-frames", opt.timing_frames, "Frames timed per floor class (plain, textured)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--mistakes", opt.mistakes, "Mistakes listed")->check(CLI::Range(0, 100000));
  app.add_flag("!--no-peers", opt.peers, "Leave out AprilTag and ArUco");
  CLI11_PARSE(app, argc, argv);
  if (!opt.seed_given) opt.seed = std::random_device{}() | (static_cast<std::uint64_t>(std::random_device{}()) << 32);
  cv::setNumThreads(0);
  cv::ocl::setUseOpenCL(false);
  const auto timer = rilbed::bench::measure_timer_overhead();
  const auto start = Clock::now();

  rv::StressOptions stress;
  stress.frames_per_scene = opt.frames_per_scene;
  std::printf("# rilbed on the vision stress set\n\n");
  std::printf("- CPU: %s; `nproc`: %d; load average at start: %s\n", rilbed::bench::cpu_model().c_str(),
              rilbed::bench::usable_cpus(), rilbed::bench::first_line("/proc/loadavg").c_str());
  std::printf("- build: %s; sources: %s\n", rilbed::bench::env_or("RILBED_BENCH_BUILD_TYPE", "unknown").c_str(),
              rilbed::bench::env_or("RILBED_BENCH_SOURCE", "unknown").c_str());
  std::printf("- seed %llu, %d scenes of %d frames (%d frames), %dx%d; floor photographs: %zu found in %s\n",
              static_cast<unsigned long long>(opt.seed), opt.scenes, opt.frames_per_scene,
              opt.scenes * opt.frames_per_scene, stress.image_size.width, stress.image_size.height,
              rv::stress_floor_photos(stress).size(), stress.photo_dir.c_str());
  std::printf(
      "- every condition drawn per scene (src/vision/stress_scene.cpp): marker 20-64 px (outer diameter at the "
      "image centre), blur sigma 0-2 px, motion blur 0-4 px in any direction, noise 0-10, JPEG 50-95, light "
      "ratio 1-4 and vignetting 0-0.5, tilt 0-20 deg, k1 0 to -0.3 (with the matching calibration), floors "
      "plain light/dark, photographs, drawn wood/fabric/carpet/concrete; 4-14 clutter items (dark discs, "
      "rings, tape, chessboards, text, AprilTag and ArUco tags, cables); 4-8 robots of IDs 1-8, about a third "
      "touching another; a quarter of the markers partly under a cable (2-15 %% of the disc)\n");
  std::printf(
      "- the tracker lists IDs 1-8 in every scene (absent robots' IDs too); full-frame: "
      "`MarkerTracker::detect_full_frame` on each frame; tracked: a fresh `MarkerTracker::process` over each "
      "scene's clip, its first frame included\n");
  std::printf(
      "- found: the marker's ID reported within half its diameter of its centre, heading within %.0f deg; "
      "blur buckets by sqrt(sigma^2 + smear^2 / 12)\n\n",
      rv::kStressWrongHeadingDeg);
  std::fflush(stdout);

  const rv::MarkerFamily family = rv::MarkerFamily::six_ucp();
  rv::StressTally full, tracked;
  std::vector<TimedFrame> timed;
  int plain_kept = 0, textured_kept = 0;
  {
    SceneQueue queue(opt, stress);
    rv::MarkerTracker single(family, all_ids());
    while (auto scene = queue.next()) {
      rv::MarkerTracker clip(family, all_ids());
      for (int f = 0; f < static_cast<int>(scene->frames.size()); ++f) {
        const cv::Mat& frame = scene->frames[static_cast<std::size_t>(f)];
        const auto found_full = single.detect_full_frame(frame);
        full.add(*scene, f, found_full, single.last_stats().declined);
        const auto found_tracked = clip.process(frame);
        tracked.add(*scene, f, found_tracked, clip.last_stats().declined);
      }
      const bool textured = scene->conditions.floor != rv::StressFloor::kPlain;
      int& kept = textured ? textured_kept : plain_kept;
      if (kept < opt.timing_frames) {
        TimedFrame t;
        cv::cvtColor(scene->frames[0], t.grey, cv::COLOR_BGR2GRAY);
        t.textured = textured;
        timed.push_back(std::move(t));
        ++kept;
      }
    }
  }
  const double render_score_s = ms_since(start) / 1000;

  // ------------------------------------------------------------ mistakes
  std::printf(
      "## Mistakes\n\n| mode | frames | markers | recall | wrong IDs | false detections | headings > %.0f deg off | "
      "duplicates | declined (ambiguous) |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
      rv::kStressWrongHeadingDeg);
  for (const auto& [mode, t] :
       {std::pair<const char*, const rv::StressTally*>{"full-frame", &full}, {"tracked", &tracked}}) {
    const auto all = rv::summarise(t->outcomes(), [](const rv::StressOutcome&) { return true; });
    std::printf("| %s | %d | %d | %s | %d | %d | %d | %d | %d |\n", mode, t->frames(), all.markers,
                pct(all.recall()).c_str(), t->count(rv::StressMistake::Kind::kWrongId),
                t->count(rv::StressMistake::Kind::kFalseDetection), t->count(rv::StressMistake::Kind::kWrongHeading),
                t->count(rv::StressMistake::Kind::kDuplicate), t->declined());
  }
  std::printf("\n");

  // ------------------------------------------------------------ by size
  const auto unoccluded = [](const rv::StressOutcome& o) { return o.occluded == 0; };
  const std::vector<Bucket> sizes = {
      {"20-24 px", [&](const rv::StressOutcome& o) { return unoccluded(o) && o.diameter_px < 24; }},
      {"24-32 px",
       [&](const rv::StressOutcome& o) { return unoccluded(o) && o.diameter_px >= 24 && o.diameter_px < 32; }},
      {"32-48 px",
       [&](const rv::StressOutcome& o) { return unoccluded(o) && o.diameter_px >= 32 && o.diameter_px < 48; }},
      {">= 48 px", [&](const rv::StressOutcome& o) { return unoccluded(o) && o.diameter_px >= 48; }},
      {">= 24 px, occluded", [](const rv::StressOutcome& o) { return o.occluded > 0 && o.diameter_px >= 24; }},
      {">= 24 px, all", [](const rv::StressOutcome& o) { return o.diameter_px >= 24; }},
  };
  const char* head =
      "| mode | markers | n | recall | centre RMS px | centre max px | heading RMS deg | heading max deg | worst ID "
      "bias deg |\n"
      "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  std::printf("## By marker size (unoccluded unless said)\n\n%s", head);
  print_bucket_rows("full-frame", full.outcomes(), sizes);
  print_bucket_rows("tracked", tracked.outcomes(), sizes);

  const std::vector<Bucket> blurs = {
      {"blur < 0.75 px",
       [](const rv::StressOutcome& o) { return o.occluded == 0 && o.diameter_px >= 24 && o.blur_px < 0.75; }},
      {"blur 0.75-1.5 px",
       [](const rv::StressOutcome& o) {
         return o.occluded == 0 && o.diameter_px >= 24 && o.blur_px >= 0.75 && o.blur_px < 1.5;
       }},
      {"blur >= 1.5 px",
       [](const rv::StressOutcome& o) { return o.occluded == 0 && o.diameter_px >= 24 && o.blur_px >= 1.5; }},
  };
  std::printf("\n## By blur (markers >= 24 px, unoccluded)\n\n%s", head);
  print_bucket_rows("full-frame", full.outcomes(), blurs);
  print_bucket_rows("tracked", tracked.outcomes(), blurs);

  const std::vector<Bucket> cover = {
      {"not covered", [](const rv::StressOutcome& o) { return o.diameter_px >= 24 && o.occluded == 0; }},
      {"covered < 5 %",
       [](const rv::StressOutcome& o) { return o.diameter_px >= 24 && o.occluded > 0 && o.occluded < 0.05; }},
      {"covered 5-10 %",
       [](const rv::StressOutcome& o) { return o.diameter_px >= 24 && o.occluded >= 0.05 && o.occluded < 0.10; }},
      {"covered 10-15 %", [](const rv::StressOutcome& o) { return o.diameter_px >= 24 && o.occluded >= 0.10; }},
      {"touching another",
       [](const rv::StressOutcome& o) { return o.diameter_px >= 24 && o.occluded == 0 && o.touching; }},
  };
  std::printf("\n## By occlusion and contact (markers >= 24 px)\n\n%s", head);
  print_bucket_rows("full-frame", full.outcomes(), cover);
  print_bucket_rows("tracked", tracked.outcomes(), cover);

  std::vector<Bucket> floors;
  for (auto f : {rv::StressFloor::kPlain, rv::StressFloor::kPhoto, rv::StressFloor::kWood, rv::StressFloor::kFabric,
                 rv::StressFloor::kCarpet, rv::StressFloor::kConcrete})
    floors.push_back({rv::floor_name(f), [f](const rv::StressOutcome& o) {
                        return o.floor == f && o.diameter_px >= 24 && o.occluded == 0;
                      }});
  std::printf("\n## By floor (markers >= 24 px, unoccluded)\n\n%s", head);
  print_bucket_rows("full-frame", full.outcomes(), floors);
  print_bucket_rows("tracked", tracked.outcomes(), floors);

  // ------------------------------------------------------------ targets
  std::printf("\n## The stress set's targets\n\n| target | full-frame | tracked |\n| --- | ---: | ---: |\n");
  auto target_row = [&](const char* name, const std::function<std::string(const rv::StressTally&)>& value) {
    std::printf("| %s | %s | %s |\n", name, value(full).c_str(), value(tracked).c_str());
  };
  target_row("0 wrong IDs",
             [](const rv::StressTally& t) { return std::to_string(t.count(rv::StressMistake::Kind::kWrongId)); });
  target_row("0 false detections", [](const rv::StressTally& t) {
    return std::to_string(t.count(rv::StressMistake::Kind::kFalseDetection));
  });
  target_row("0 headings > 10 deg off",
             [](const rv::StressTally& t) { return std::to_string(t.count(rv::StressMistake::Kind::kWrongHeading)); });
  target_row("recall >= 0.99, unoccluded, >= 32 px", [](const rv::StressTally& t) {
    return pct(rv::summarise(t.outcomes(), [](const rv::StressOutcome& o) {
                 return o.occluded == 0 && o.diameter_px >= 32;
               }).recall());
  });
  target_row("recall >= 0.95, unoccluded, 24-32 px", [](const rv::StressTally& t) {
    return pct(rv::summarise(t.outcomes(), [](const rv::StressOutcome& o) {
                 return o.occluded == 0 && o.diameter_px >= 24 && o.diameter_px < 32;
               }).recall());
  });
  auto ge24 = [](const rv::StressOutcome& o) { return o.diameter_px >= 24; };
  target_row("centre <= 0.2 px RMS, >= 24 px", [&](const rv::StressTally& t) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3f", rv::summarise(t.outcomes(), ge24).centre_rms_px);
    return std::string(b);
  });
  target_row("heading <= 1.0 deg RMS, >= 24 px", [&](const rv::StressTally& t) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3f", rv::summarise(t.outcomes(), ge24).heading_rms_deg);
    return std::string(b);
  });
  target_row("no ID's mean heading error beyond 0.3 deg, >= 24 px", [&](const rv::StressTally& t) {
    const auto s = rv::summarise(t.outcomes(), ge24);
    char b[48];
    std::snprintf(b, sizeof b, "ID %d: %+.3f", s.worst_bias_id, s.worst_bias_deg);
    return std::string(b);
  });

  // ------------------------------------------------------------ the first mistakes
  if (opt.mistakes > 0) {
    std::printf("\n## The first mistakes (see them: `rilbed synth --preset stress --seed %llu --frames N`)\n\n",
                static_cast<unsigned long long>(opt.seed));
    std::printf(
        "| mode | scene | frame | kind | reported ID | marker's ID | u | v |\n| --- | ---: | ---: | --- | ---: | ---: "
        "| ---: | ---: |\n");
    for (const auto& [mode, t] :
         {std::pair<const char*, const rv::StressTally*>{"full-frame", &full}, {"tracked", &tracked}}) {
      int listed = 0;
      for (const auto& m : t->mistakes()) {
        if (listed++ >= opt.mistakes) break;
        std::printf("| %s | %d | %d | %s | %d | %d | %.1f | %.1f |\n", mode, m.scene, m.frame, rv::mistake_name(m.kind),
                    m.id, m.true_id, m.u, m.v);
      }
    }
  }

  // ------------------------------------------------------------ speed
  std::printf("\n## Speed: a full-frame search, one thread, CPU time per frame\n\n");
  std::printf(
      "Each scene's first frame (%d plain floors, %d textured), 8-bit grey, flushed from every cache level "
      "before each call (as a frame from a camera arrives); the detectors take turns frame by frame; the "
      "timer's own cost (%.4f ms CPU) subtracted. AprilTag 3: tag36h11, quad_decimate 2, nthreads 1; "
      "OpenCV ArUco: DICT_4X4_50, default parameters. The peers search the same frames (6UCP markers and "
      "clutter, among it their own kind of tags): their cost on them, not their recall. GLIBC_TUNABLES: %s "
      "(tools/bench.sh fixes glibc's malloc thresholds, so that no detector pays page faults for buffers "
      "mapped afresh each frame).\n\n",
      plain_kept, textured_kept, timer.cpu_ms, std::getenv("GLIBC_TUNABLES") ? std::getenv("GLIBC_TUNABLES") : "unset");
  apriltag_family_t* tag_family = tag36h11_create();
  apriltag_detector_t* td = apriltag_detector_create();
  apriltag_detector_add_family(td, tag_family);
  td->quad_decimate = 2.0f;
  td->nthreads = 1;
  const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  const auto aruco_params = cv::aruco::DetectorParameters::create();
  rv::MarkerTracker timing_tracker(family, all_ids());
  std::map<std::string, std::map<bool, std::vector<double>>> cpu;  // detector -> textured -> samples
  std::size_t sink = 0;
  const int rounds = 3;
  for (int r = 0; r < rounds; ++r) {
    for (const TimedFrame& f : timed) {
      auto time_one = [&](const std::string& name, const std::function<std::size_t()>& call) {
        rilbed::bench::evict(f.grey);
        const double c0 = thread_cpu_ms();
        sink += call();
        cpu[name][f.textured].push_back(net_ms(thread_cpu_ms() - c0, timer.cpu_ms));
      };
      time_one("rilbed full-frame", [&] { return timing_tracker.detect_full_frame(f.grey).size(); });
      if (!opt.peers) continue;
      time_one("AprilTag 3, decimate 2", [&] {
        image_u8_t im{f.grey.cols, f.grey.rows, static_cast<int32_t>(f.grey.step), f.grey.data};
        zarray_t* found = apriltag_detector_detect(td, &im);
        const std::size_t n = static_cast<std::size_t>(zarray_size(found));
        apriltag_detections_destroy(found);
        return n;
      });
      time_one("OpenCV ArUco", [&] {
        std::vector<std::vector<cv::Point2f>> corners, rejected;
        std::vector<int> ids;
        cv::aruco::detectMarkers(f.grey, dict, corners, ids, aruco_params, rejected);
        return ids.size();
      });
    }
  }
  std::printf(
      "| detector | plain floor median ms | p90 ms | textured floor median ms | p90 ms | textured / plain |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: |\n");
  for (const char* name : {"rilbed full-frame", "AprilTag 3, decimate 2", "OpenCV ArUco"}) {
    if (!cpu.count(name)) continue;
    const auto& p = cpu[name][false];
    const auto& t = cpu[name][true];
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.2f |\n", name, quantile(p, 0.5), quantile(p, 0.9),
                quantile(t, 0.5), quantile(t, 0.9), quantile(t, 0.5) / std::max(1e-9, quantile(p, 0.5)));
  }
  std::printf("\nTarget: a full-frame search on textured 1280x960 frames with 8 markers within 0.25 ms.\n");
  apriltag_detector_destroy(td);
  tag36h11_destroy(tag_family);
  std::printf("\nRendering and scoring took %.0f s, timing %.0f s (%zu timing calls kept out of the sink: %zu).\n",
              render_score_s, ms_since(start) / 1000 - render_score_s, timed.size() * rounds, sink % 2);
  return 0;
}
