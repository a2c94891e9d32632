// rilbed_detect_clip FOLDER [--exact]: the overhead-camera pipeline over one folder of
// frames, for comparing builds (`./run arm` runs it on x86 and on arm64 under qemu and
// diffs the two). It needs the vision module only, so it builds in the vision-only build
// (RILBED_VISION_ONLY) as in the full one.
//
// One MarkerTracker (6UCP, IDs 1..8, default knobs) runs over the frames in order, tracked
// (`process`); a second does each frame full-frame (`detect_full_frame`). One line per
// detection, `frame mode id u v heading_deg score`, at the precision of `rilbed detect`'s
// CSV (u, v %.3f, heading %.2f, score %.4f); --exact prints every value with %.17g, so
// that two builds can be checked to the last bit as well.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "vision/frame_source.hpp"
#include "vision/marker_family.hpp"
#include "vision/marker_tracker.hpp"

namespace {

void print(int frame, const char* mode, const std::vector<rilbed::vision::MarkerDetection>& found, bool exact) {
  for (const auto& d : found) {
    if (exact) {
      std::printf("%d %s %d %.17g %.17g %.17g %.17g\n", frame, mode, d.id, d.u, d.v, d.heading_deg, d.score);
    } else {
      std::printf("%d %s %d %.3f %.3f %.2f %.4f\n", frame, mode, d.id, d.u, d.v, d.heading_deg, d.score);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string folder;
  bool exact = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--exact") == 0) {
      exact = true;
    } else if (folder.empty() && argv[i][0] != '-') {
      folder = argv[i];
    } else {
      folder.clear();
      break;
    }
  }
  if (folder.empty()) {
    std::fprintf(stderr, "usage: %s FOLDER [--exact]\n", argv[0]);
    return 2;
  }
  rilbed::vision::OpenResult opened = rilbed::vision::open_frame_source(folder);
  if (!opened.ok()) {
    std::fprintf(stderr, "%s\n", opened.error.c_str());
    return 1;
  }
  const std::vector<int> ids = {1, 2, 3, 4, 5, 6, 7, 8};
  rilbed::vision::MarkerTracker tracked(rilbed::vision::MarkerFamily::six_ucp(), ids);
  rilbed::vision::MarkerTracker full(rilbed::vision::MarkerFamily::six_ucp(), ids);
  long frames = 0, bad = 0;
  for (;;) {
    const rilbed::vision::FrameResult r = opened.source->next();
    if (r.is_end()) break;
    if (r.is_error()) {
      std::fprintf(stderr, "%s\n", r.error.c_str());
      ++bad;
      continue;
    }
    ++frames;
    print(r.index, "tracked", tracked.process(r.image), exact);
    print(r.index, "full", full.detect_full_frame(r.image), exact);
  }
  std::fprintf(stderr, "%s: %ld frames, %ld bad\n", folder.c_str(), frames, bad);
  return frames > 0 && bad == 0 ? 0 : 1;
}
