// rilbed: the command line. Thin subcommands over the modules; see docs/ for the manual.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <opencv2/core/utils/logger.hpp>

#include <csignal>
#include <cstdlib>
#include <exception>
#include <iostream>

#include "app/commands.hpp"

namespace rilbed::app {
int& exit_code() {
  static int code = 0;
  return code;
}
}  // namespace rilbed::app

int main(int argc, char** argv) {
  CLI::App app{"rilbed: a robot-in-the-loop test bed for teams of small mobile robots"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rilbed 0.1.0");
  // Logs go to stderr so that CSV written to stdout stays clean.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rilbed"));
  spdlog::set_pattern("rilbed: %^%l%$: %v");
  // A reader that went away (`rilbed run ... | head`, a demo's pipe closed by Ctrl-C) must
  // not kill a run before it has stopped its real robots: writes to it fail instead.
  std::signal(SIGPIPE, SIG_IGN);
  // rilbed reports unreadable inputs itself, naming them; OpenCV's backend warnings
  // (GStreamer, V4L2, FFmpeg) would only repeat that. RILBED_OPENCV_LOG=1 shows them.
  if (std::getenv("RILBED_OPENCV_LOG") == nullptr) {
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  }
  rilbed::app::add_patterns_command(app);
  rilbed::app::add_detect_command(app);
  rilbed::app::add_calibrate_command(app);
  rilbed::app::add_synth_command(app);
  rilbed::app::add_score_command(app);
  rilbed::app::add_run_command(app);
  rilbed::app::add_controllers_command(app);
  rilbed::app::add_sim_bench_command(app);
  rilbed::app::add_compare_command(app);
  rilbed::app::add_loop_bench_command(app);
  rilbed::app::add_khepera_command(app);
  rilbed::app::add_khepera_emu_command(app);
  rilbed::app::add_watch_command(app);
  rilbed::app::add_agent_command(app);
  rilbed::app::add_quantum_bench_command(app);
  rilbed::app::add_gui_command(app);
  rilbed::app::add_replay_command(app);
  rilbed::app::add_console_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the reason (or the help, exit 0); a bad option is exit 2 whatever
    // CLI11's own code for it (105 for a file that does not exist), as docs/README.md promises.
    const int code = app.exit(e);
    return code == 0 ? 0 : rilbed::app::kExitUsage;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return rilbed::app::exit_code();
}
