// Registration of rilbed's subcommands. Each subcommand lives in its own cmd_*.cpp,
// parses its options with CLI11 and calls into the modules; it holds no logic of its own
// beyond turning options into configs and results into output.
#pragma once

#include <CLI/CLI.hpp>

namespace rilbed::app {

/// `rilbed patterns`: printable marker files (SVG, PDF, PNG).
void add_patterns_command(CLI::App& app);
/// `rilbed detect`: the overhead-camera pipeline over a video, images or a camera.
void add_detect_command(CLI::App& app);
/// `rilbed calibrate intrinsics|field`: camera and field calibration.
void add_calibrate_command(CLI::App& app);
/// `rilbed synth`: renders footage with ground truth from the synthetic overhead camera.
void add_synth_command(CLI::App& app);
/// `rilbed score`: compares detections with ground truth.
void add_score_command(CLI::App& app);
/// `rilbed run`: runs a scenario once or over a batch of seeds.
void add_run_command(CLI::App& app);
/// `rilbed controllers [--json]`: the controllers a scenario can name, with their parameters.
void add_controllers_command(CLI::App& app);
/// `rilbed sim-bench`: times the simulation with many virtual robots.
void add_sim_bench_command(CLI::App& app);
/// `rilbed compare`: the difference of two run folders (sim-to-real comparison).
void add_compare_command(CLI::App& app);
/// `rilbed loop-bench`: loop latency from a camera frame to the `D` on the serial port.
void add_loop_bench_command(CLI::App& app);
/// `rilbed khepera --port DEV info|drive`: talks to one real (or emulated) Khepera.
void add_khepera_command(CLI::App& app);
/// `rilbed khepera-emu`: an emulated Khepera on a pseudo-terminal.
void add_khepera_emu_command(CLI::App& app);

/// `rilbed agent --scenario FILE --ids 3,4 --lcm URL`: runs those robots' controllers for a run on the bus.
void add_agent_command(CLI::App& app);
/// `rilbed quantum-bench`: time per lock-step quantum with the controllers in agent processes.
void add_quantum_bench_command(CLI::App& app);

/// `rilbed watch --lcm URL`: a terminal display of a run on an LCM bus.
void add_watch_command(CLI::App& app);

/// `rilbed replay FILE.lcm --out DIR | --lcm URL`: a recorded run again.
void add_replay_command(CLI::App& app);

/// `rilbed console --lcm URL pause|resume|exit|rt-factor F`: steers a running run.
void add_console_command(CLI::App& app);
/// `rilbed gui --lcm URL`: the web control panel for a run on an LCM bus.
void add_gui_command(CLI::App& app);

/// Exit code a subcommand's callback stores for main() to return.
int& exit_code();

/// Exit status for input that could not be used or output that could not be written.
inline constexpr int kExitFailure = 1;
/// Exit status for a malformed option value (a usage error).
inline constexpr int kExitUsage = 2;

}  // namespace rilbed::app
