// profile_vision: times rilbed's marker tracker on frames saved by
// `bench_vision --save-frames DIR`, for quick before/after checks between builds and as
// the program a profiler runs (perf record, valgrind --tool=callgrind
// --toggle-collect='rilbed::vision::MarkerTracker::process*').
//
//   profile_vision DIR/64 [--mode full|tracked] [--passes N] [--runs N] [--warm]
//
// The folder's images are read in name order (all of one size, 8-bit grey). Markers:
// IDs 1..K of 6UCP when the folder holds frames of K <= 8 markers, else of 9UCP (as
// bench_vision renders them), K from --ids (default: the folder's name).
// --mode full times MarkerTracker::detect_full_frame on every frame; --mode tracked
// times MarkerTracker::process on every frame but the first of each pass (the tracker is
// reset per pass, so the first frame is a full search). Each run makes --passes passes
// over the frames and takes the median of the per-frame CPU times of the thread; the
// figure printed is the lowest median of --runs runs, the least disturbed by other
// processes on a shared machine. Frames are met cold, as bench_vision meets them (each
// frame's lines flushed from every cache level before the call), unless --warm reads
// each frame once just before it is timed.
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "frame_cache.hpp"
#include "timing.hpp"
#include "vision/marker_tracker.hpp"

namespace {

using rilbed::bench::thread_cpu_ms;
using rilbed::vision::MarkerFamily;
using rilbed::vision::MarkerTracker;

struct Options {
  std::string dir;
  std::string mode = "tracked";
  int ids = 0;
  int passes = 50;
  int runs = 3;
  bool warm = false;
  bool per_frame = false;  // a line per frame of the last run: its time and the tracker's counters
};

[[noreturn]] void usage(int code) {
  std::fprintf(
      code == 0 ? stdout : stderr,
      "usage: profile_vision DIR [--mode full|tracked] [--ids K] [--passes N] [--runs N] [--warm] [--per-frame]\n");
  std::exit(code);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(2);
      return argv[++i];
    };
    if (a == "--mode") {
      o.mode = value();
    } else if (a == "--ids") {
      o.ids = std::atoi(value().c_str());
    } else if (a == "--passes") {
      o.passes = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--runs") {
      o.runs = std::max(1, std::atoi(value().c_str()));
    } else if (a == "--warm") {
      o.warm = true;
    } else if (a == "--per-frame") {
      o.per_frame = true;
    } else if (a == "--help" || a == "-h") {
      usage(0);
    } else if (o.dir.empty() && a.rfind("--", 0) != 0) {
      o.dir = a;
    } else {
      usage(2);
    }
  }
  if (o.dir.empty() || (o.mode != "full" && o.mode != "tracked")) usage(2);
  if (o.ids <= 0) o.ids = std::atoi(std::filesystem::path(o.dir).filename().c_str());
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(opt.dir, ec)) names.push_back(entry.path().string());
  if (ec) {
    std::fprintf(stderr, "profile_vision: cannot read %s: %s\n", opt.dir.c_str(), ec.message().c_str());
    return 1;
  }
  std::sort(names.begin(), names.end());
  std::vector<cv::Mat> frames;
  for (const auto& name : names) {
    cv::Mat grey = cv::imread(name, cv::IMREAD_GRAYSCALE);
    if (grey.empty()) {
      std::fprintf(stderr, "profile_vision: skipping %s (not an image)\n", name.c_str());
      continue;
    }
    if (!frames.empty() && grey.size() != frames.front().size()) {
      std::fprintf(stderr, "profile_vision: skipping %s (another size)\n", name.c_str());
      continue;
    }
    frames.push_back(grey);
  }
  if (frames.size() < 2) {
    std::fprintf(stderr, "profile_vision: %s holds fewer than two frames\n", opt.dir.c_str());
    return 1;
  }
  if (opt.ids <= 0) {
    std::fprintf(stderr, "profile_vision: give --ids (the name of %s is not a marker count)\n", opt.dir.c_str());
    return 2;
  }
  std::vector<int> ids(opt.ids);
  std::iota(ids.begin(), ids.end(), 1);
  const MarkerFamily family = opt.ids <= 8 ? MarkerFamily::six_ucp() : MarkerFamily::by_name("9ucp");
  MarkerTracker tracker(family, ids);
  const bool full = opt.mode == "full";

  // The timer's own cost, measured and subtracted as bench_vision does.
  const double overhead_ms = rilbed::bench::measure_timer_overhead().cpu_ms;
  double best_median = 0.0, best_p90 = 0.0;
  double found = 0.0, fills = 0.0, edge_fits = 0.0;
  for (int run = 0; run < opt.runs; ++run) {
    std::vector<double> times;
    long timed = 0, found_sum = 0, fill_sum = 0, edge_sum = 0;
    for (int pass = 0; pass < opt.passes; ++pass) {
      tracker.reset();
      for (std::size_t i = 0; i < frames.size(); ++i) {
        if (opt.warm) {
          rilbed::bench::touch(frames[i]);
        } else {
          rilbed::bench::evict(frames[i]);
        }
        const double t0 = thread_cpu_ms();
        const auto detections = full ? tracker.detect_full_frame(frames[i]) : tracker.process(frames[i]);
        const double t1 = thread_cpu_ms();
        if (!full && i == 0) continue;  // the first frame of a pass is a full search
        times.push_back(rilbed::bench::net_ms(t1 - t0, overhead_ms));
        ++timed;
        found_sum += static_cast<long>(detections.size());
        fill_sum += tracker.last_stats().fills;
        edge_sum += tracker.last_stats().edge_fits;
        if (opt.per_frame && run == opt.runs - 1 && pass == opt.passes - 1) {
          const auto& s = tracker.last_stats();
          std::printf("frame %zu: %.4f ms, %zu found, %d blobs, %d decoded, %d fills, %d refits, %d nested searches\n",
                      i, times.back(), detections.size(), s.blobs, s.decoded, s.fills, s.refits, s.nested_searches);
        }
      }
    }
    std::sort(times.begin(), times.end());
    const double median = times[times.size() / 2], p90 = times[times.size() * 9 / 10];
    if (run == 0 || median < best_median) {
      best_median = median;
      best_p90 = p90;
    }
    found = static_cast<double>(found_sum) / timed;
    fills = static_cast<double>(fill_sum) / timed;
    edge_fits = static_cast<double>(edge_sum) / timed;
  }
  std::printf(
      "%s, %d markers (%s), %zu frames %dx%d, %s: median %.4f ms CPU per frame (lowest of %d runs of %d "
      "passes; timer overhead %.2f us subtracted), p90 %.4f; per frame %.2f found, %.2f fills, %.2f edge fits\n",
      opt.mode.c_str(), opt.ids, opt.ids <= 8 ? "6UCP" : "9UCP", frames.size(), frames.front().cols,
      frames.front().rows, opt.warm ? "warm" : "cold", best_median, opt.runs, opt.passes, overhead_ms * 1e3, best_p90,
      found, fills, edge_fits);
  return 0;
}
