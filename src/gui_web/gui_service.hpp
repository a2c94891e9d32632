// The web control panel's service: the web server, the run's channels on it, and what
// browsers send back (console commands, manual driving), handed to a console sink. One code
// path for both homes of the panel: `rilbed run --gui` (the sink acts on the run's own
// RunControl) and `rilbed gui --lcm URL` (the sink sends the command over LCM with the
// run's token).
//
// Client topics (JSON, advertised by the client):
//   /rilbed/console  {"command": "pause", "args": []}       -> answered on /rilbed/console_reply
//   /rilbed/drive    {"id": 4, "left": 20, "right": 20}    while a key is held (every <= 100 ms)
//                    {"id": 4, "release": true}             hands the robot back to its controller
//
// Vision settings are the Foxglove protocol's parameters, "vision.<name>" (see
// vision::kVisionSettingNames), present while the run has a camera: setParameters becomes
// a `vision NAME VALUE...` console command (all or none), its answer a parameterValues
// with the request's id (and the refusal as a status); every status of the run brings the
// values it has, and subscribers hear of each change.
//
// Manual driving is a dead man's switch. A client that drives robot N holds it: the robot
// goes at the client's speeds while its key-held messages keep coming, and stands still
// once they have stopped for `key_timeout_ms` (a key released, a tab frozen). The hold ends,
// with a stop, when the client releases the robot, when its socket closes, and when another
// client takes the robot over; the robot's controller drives it again a moment later
// (`hold_wall_s`). The hold is renewed on the run as short `drive ... --for S` commands, so
// a panel that dies without a word (killed, cut off) stops the robot within S as well.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "gui_web/run_channels.hpp"
#include "gui_web/web_server.hpp"
#include "run/run_observer.hpp"

namespace rilbed::gui_web {

/// A console command from a browser (the console's words: "drive", {"4", "20", "20", "0.5"}).
struct ConsoleRequest {
  std::string client;  ///< who asked (the server's name for the socket, "127.0.0.1:50312")
  std::string command;
  std::vector<std::string> args;
  /// For a setParameters: the parameters' names, to answer with parameterValues.
  std::optional<std::vector<std::string>> parameters;
  std::optional<std::string> parameters_id;  ///< and the request's id
};

/// The run's answer.
struct ConsoleAnswer {
  bool accepted = false;
  std::string reason;  ///< why not, or what was done
};

/// Hands a command to the run and returns its answer. Called on the service's own thread,
/// one at a time; may block (an LCM round trip), which delays only later commands.
using ConsoleSink = std::function<ConsoleAnswer(const ConsoleRequest&)>;

/// Manual driving's timing; each knob says what it costs.
struct ManualDriveConfig {
  /// Key-held messages older than this stop the robot. Shorter stops sooner, but a browser
  /// on a slow link (or a busy page) stutters.
  int key_timeout_ms = 300;
  /// How often the service looks at the drivers and renews their holds.
  int tick_ms = 100;
  /// Each hold on the run lasts this long (wall seconds, scaled by the run's real-time
  /// factor) and is renewed at a third of it: the longest a robot drives on after the
  /// service itself dies. Shorter costs more commands (and a robot that stutters on a
  /// late renewal).
  double hold_wall_s = 0.6;
  /// The switch's time: steady_clock's when empty. With a clock of its own (a test's) the
  /// service does not tick by itself: it looks at the drivers when a key message changes
  /// the speeds, a driver lets go or goes, and when tick() asks. Must be thread-safe.
  std::function<std::chrono::steady_clock::time_point()> clock;
};

/// Camera frames at most this often to the viewers (more would cost the run's thread, for a view that does not need
/// them).
inline constexpr double kMaxCameraFps = 10.0;

/// What the service counted.
struct GuiCounters {
  std::uint64_t console_commands = 0;  ///< console commands handed to the sink
  std::uint64_t drive_commands = 0;    ///< drive commands (holds, renewals, stops) handed to the sink
  std::uint64_t drive_stops = 0;       ///< holds ended with a stop
  std::uint64_t drive_messages = 0;    ///< drive messages taken (keys held, releases)
};

/// The panel's service. Its RunObserver side must be called from one thread.
class GuiService final : public run::RunObserver {
 public:
  /// Starts the web server (throws as WebServer does) and the service's thread.
  GuiService(WebServerConfig config, ConsoleSink sink, ManualDriveConfig drive = {});
  /// Stops every manual drive (a stop for each robot still held), then the server.
  ~GuiService() override;
  GuiService(const GuiService&) = delete;
  GuiService& operator=(const GuiService&) = delete;

  /// Looks at the drivers now, on the service's thread, and returns once it has: the holds
  /// renewed, lapsed keys turned into stops, released robots given back. The service does
  /// so every tick_ms by itself; a test with a clock of its own calls it.
  void tick();

  /// The page's address with its token, for the terminal.
  std::string url() const;
  WebServer& server() { return *server_; }
  /// Waits until everything the run reported so far has been written to every client (or
  /// dropped for one that did not keep up), at most about `timeout`; returns whether it was.
  bool flush(std::chrono::milliseconds timeout);
  GuiCounters counters() const;

  // agents::RunObserver: the run's reports, to the channels.
  bool wants_steps() const override;
  void on_world(TimeUs t_us, const run::WorldReport& world) override;
  void on_poses(TimeUs t_us, std::span<const run::PoseReport> poses) override;
  void on_wheels(TimeUs t_us, std::span<const run::WheelReport> wheels) override;
  void on_sensors(TimeUs t_us, std::span<const run::SensorReport> sensors) override;
  void on_detections(const run::FrameReport& frame) override;
  bool wants_frame_jpegs() const override { return true; }
  /// Passes at most max_camera_fps frames a second on, and only while someone watches.
  void on_frame_jpeg(TimeUs t_us, std::int64_t frame, int width_px, int height_px,
                     std::span<const std::uint8_t> jpeg) override;
  void on_event(const run::RunEvent& event) override;
  void on_status(const run::StatusReport& status) override;
  void on_summary(TimeUs t_us, const nlohmann::json& summary) override;

 private:
  using Clock = std::chrono::steady_clock;
  // One robot held by one client.
  struct Hold {
    std::string client;
    int left = 0, right = 0;                  // the client's last key-held speeds
    Clock::time_point last_key{};             // when they came
    bool ending = false;                      // released, gone or taken over: one stop, then forgotten
    std::optional<std::pair<int, int>> sent;  // the speeds of the last hold sent to the run
    Clock::time_point sent_at{};
    std::string last_refusal;  // the run's last refusal, told to the client once
  };

  std::optional<std::string> on_client_message(const std::string& client, const std::string& topic,
                                               std::string_view payload);
  std::optional<std::string> on_drive_message(const std::string& client, std::string_view payload);
  void on_client_gone(const std::string& client);
  void on_set_parameters(const std::string& client, const std::vector<foxglove::Parameter>& parameters,
                         const std::optional<std::string>& id);
  void answer(const ConsoleRequest& request, const ConsoleAnswer& answer);
  void loop();
  void drive_tick(std::unique_lock<std::mutex>& lock);
  Clock::time_point now() const { return drive_.clock ? drive_.clock() : Clock::now(); }
  // Wakes the service's loop (the caller holds mutex_): a wake-up is never lost while the
  // loop is busy, since it looks at wake_pending_ before it sleeps.
  void wake_locked() {
    wake_pending_ = true;
    wake_.notify_all();
  }

  WebServerConfig config_;
  ConsoleSink sink_;
  ManualDriveConfig drive_;
  std::unique_ptr<WebServer> server_;
  std::unique_ptr<RunChannels> channels_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool wake_pending_ = false;       // something for the loop since it last looked (wake_locked)
  std::condition_variable ticked_;  // a tick() asked for has been made
  std::uint64_t ticks_asked_ = 0;   // by tick()
  std::uint64_t ticks_done_ = 0;
  std::deque<ConsoleRequest> requests_;
  std::map<int, Hold> holds_;  // by robot ID
  double rt_factor_ = 1.0;
  Clock::time_point next_camera_frame_{};  // the RunObserver thread only
  bool had_vision_ = false;                // the RunObserver thread only: the last status had settings
  GuiCounters counts_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace rilbed::gui_web
