// Fuzz target for reading a recording (`rilbed replay FILE --out DIR`, src/app/cmd_replay.cpp):
// the input is an LCM log file's bytes. They are written to a temporary file, which
// links::LcmLogReader reads event by event (as replay does: liblcm's own reader trusts the
// lengths in the file); RunReportDecoder (src/bus/lcm_bus.hpp) decodes each
// event of the run's channels into a run folder (agents::RunFolderWriter, the real one,
// writing into a temporary folder), and a recording without its summary is finished as
// cmd_replay finishes it. Both temporaries (in TMPDIR, else /dev/shm, else /tmp; named
// after the process ID) are removed after each input, and those of earlier runs that
// crashed when the target starts. Every report also goes to an observer that reads every
// field (touching_observer.hpp), so that ASan sees any read it should not.
//
// Crashes, leaks and undefined behaviour (in the decoder, the folder writer and liblcm's
// reader) are left to the sanitizers; besides, whatever the bytes:
//   - nothing throws (replay would stop with an error instead of writing the folder);
//   - the reader hands over events within its limits (a channel name of 1..255 bytes);
//   - the folder is complete: summary.json holds a JSON object, the run's summary when
//     the recording had one, else one that says "truncated"; trajectories.svg is whole.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "bus/lcm_bus.hpp"
#include "bus/lcm_log_reader.hpp"
#include "bus/report_decoder.hpp"
#include "run/run_folder_writer.hpp"
#include "touching_observer.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rilbed;

[[noreturn]] void broken(const std::string& what) {
  std::fprintf(stderr, "\nfuzz_lcm_log: %s\n", what.c_str());
  std::abort();
}
#define FUZZ_CHECK(condition)                                  \
  do {                                                         \
    if (!(condition)) broken("invariant broken: " #condition); \
  } while (false)

// Hands every report to the touching observer, then to the folder writer.
class Tee final : public run::RunObserver {
 public:
  Tee(run::RunObserver& a, run::RunObserver& b) : a_(a), b_(b) {}
  void on_world(TimeUs t_us, const run::WorldReport& world) override {
    a_.on_world(t_us, world);
    b_.on_world(t_us, world);
  }
  void on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) override {
    a_.on_poses(t_us, poses);
    b_.on_poses(t_us, poses);
  }
  void on_event(const run::RunEvent& event) override {
    a_.on_event(event);
    b_.on_event(event);
  }
  void on_status(const run::StatusReport& status) override {
    a_.on_status(status);
    b_.on_status(status);
  }
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override {
    a_.on_summary(t_us, summary);
    b_.on_summary(t_us, summary);
  }
  void on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) override {
    a_.on_wheels(t_us, wheels);
    b_.on_wheels(t_us, wheels);
  }
  void on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) override {
    a_.on_sensors(t_us, sensors);
    b_.on_sensors(t_us, sensors);
  }
  void on_detections(const run::FrameReport& frame) override {
    a_.on_detections(frame);
    b_.on_detections(frame);
  }

 private:
  run::RunObserver& a_;
  run::RunObserver& b_;
};

struct TempPaths {
  fs::path log, folder;
};

// In TMPDIR when set, else in /dev/shm when there is one (memory: several times faster
// than a disk, which the files of every input would otherwise go to), else in /tmp.
const TempPaths& temp_paths() {
  static const TempPaths paths = [] {
    const std::string base = "rilbed_fuzz_lcm_log_" + std::to_string(::getpid());
    fs::path dir = fs::temp_directory_path();
    const char* tmpdir = std::getenv("TMPDIR");
    if ((tmpdir == nullptr || *tmpdir == '\0') && ::access("/dev/shm", W_OK | X_OK) == 0) dir = "/dev/shm";
    return TempPaths{dir / (base + ".lcm"), dir / (base + "_run")};
  }();
  return paths;
}

// What a run of this target that crashed left (its files are removed only after an input
// that passes): the files of processes that are gone.
void remove_leftovers(const fs::path& dir) {
  const std::string prefix = "rilbed_fuzz_lcm_log_";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::size_t digits = name.find_first_not_of("0123456789", prefix.size());
    if (digits == prefix.size() || digits == std::string::npos) continue;
    const std::string rest = name.substr(digits);
    if (rest != ".lcm" && rest != "_run") continue;
    if (fs::exists("/proc/" + name.substr(prefix.size(), digits - prefix.size()), ec)) continue;
    std::error_code ignored;
    fs::remove_all(it->path(), ignored);
  }
}

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What `rilbed replay --out` does with the recording (cmd_replay.cpp, write_folder).
void replay(const TempPaths& paths) {
  bus::LcmLogReader log(paths.log.string());
  FUZZ_CHECK(log.good());
  rilbed_fuzz::TouchingObserver seen;
  run::RunFolderWriter writer(paths.folder);
  Tee tee(seen, writer);
  bus::RunReportDecoder decoder(bus::Channels::with_prefix(""), tee);
  bool truncated = false;
  try {
    while (const auto e = log.next()) {
      FUZZ_CHECK(!e->channel.empty() && e->channel.size() <= 255);
      (void)decoder.decode(e->channel, e->data.data(), e->data.size());
    }
    // Cut short: no summary, or a run started over (a world after a summary) that has none.
    if (!writer.finished()) {
      truncated = true;
      writer.finish_without_summary(decoder.cut_short_summary());
    }
  } catch (const std::exception& e) {
    broken(std::string("replay would stop with an error: ") + e.what());
  }
  FUZZ_CHECK(writer.finished());

  const nlohmann::json written = nlohmann::json::parse(read_all(paths.folder / "summary.json"), nullptr, false);
  FUZZ_CHECK(written.is_object());
  if (truncated) {
    FUZZ_CHECK(written.value("truncated", false) == true);
  } else {
    FUZZ_CHECK(seen.calls.summary >= 1);
    // A single summary is the run's (with several, runs started over or stray summaries).
    FUZZ_CHECK(seen.calls.summary > 1 || written == seen.last_summary);
  }
  const std::string svg = read_all(paths.folder / "trajectories.svg");
  FUZZ_CHECK(svg.rfind("<svg ", 0) == 0 && svg.ends_with("</svg>\n"));
  FUZZ_CHECK(fs::exists(paths.folder / "trajectories.csv") && fs::exists(paths.folder / "events.csv"));
  if (seen.sink == 0x5eed5eed5eed5eedULL) std::fputc('\0', stderr);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  remove_leftovers(temp_paths().log.parent_path());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const TempPaths& paths = temp_paths();
  {
    std::ofstream out(paths.log, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) broken("cannot write " + paths.log.string());
  }
  std::error_code ec;
  fs::remove_all(paths.folder, ec);  // left by an earlier input that broke
  replay(paths);
  fs::remove_all(paths.folder, ec);
  if (ec) broken("cannot remove " + paths.folder.string() + ": " + ec.message());
  fs::remove(paths.log, ec);
  if (ec) broken("cannot remove " + paths.log.string() + ": " + ec.message());
  return 0;
}
