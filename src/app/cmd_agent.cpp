// `rilbed agent --scenario FILE --ids 3,4 --lcm URL`: runs those robots' controllers in this
// process, for whichever run of that scenario on the bus lists them as remote (processes of their own, here or on other
// machines). The controllers are built from the scenario exactly as `rilbed run` builds them, afresh for each run; the
// run sends their inputs each control step and applies their answers.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "bus/agent_server.hpp"
#include "bus/lcm_bus.hpp"
#include "core/id_list.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"

namespace rilbed::app {

namespace {

struct AgentArgs {
  std::string scenario;
  std::string scenario_stdin;  ///< the name of the scenario read from standard input
  std::string ids;
  std::string url;
  std::string prefix;
  bool once = false;
  bool quiet = false;
};

// The scenario's text from standard input, up to a line "..." (YAML's end of document;
// trailing spaces and a CR allowed) or the end of the input; sets `lifeline` when the line
// came, the input still open.
std::optional<std::string> read_scenario_from_stdin(bool& lifeline) {
  std::string text;
  char buffer[4096];
  lifeline = false;
  std::size_t line_start = 0;  // where the line not yet looked at begins
  for (;;) {
    const ssize_t n = read(STDIN_FILENO, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::nullopt;
    if (n == 0) return text;
    text.append(buffer, static_cast<std::size_t>(n));
    // Each complete line once (a terminator split across reads is found when its line ends).
    for (std::size_t end = text.find('\n', line_start); end != std::string::npos; end = text.find('\n', line_start)) {
      std::string_view line(text.data() + line_start, end - line_start);
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.remove_suffix(1);
      if (line == "...") {
        text.resize(line_start);
        lifeline = true;
        return text;
      }
      line_start = end + 1;
    }
    if (text.size() > (1u << 24)) return std::nullopt;  // 16 MB is no scenario
  }
}

// Ends the agent (as Ctrl-C does) when its standard input closes: the launching run, or
// the ssh connection to it, is gone.
void watch_lifeline() {
  std::thread([] {
    char byte[256];
    for (;;) {
      const ssize_t n = read(STDIN_FILENO, byte, sizeof byte);
      if (n == 0 || (n < 0 && errno != EINTR)) break;
    }
    InterruptFlag::raise();
  }).detach();
}

int agent_command(const AgentArgs& args) {
  if (const auto problem = bus::check_channel_prefix(args.prefix)) {
    spdlog::error("agent: {}", *problem);
    return kExitUsage;
  }
  if (args.scenario.empty() == args.scenario_stdin.empty()) {
    spdlog::error("agent: give either --scenario FILE or --scenario-stdin NAME");
    return kExitUsage;
  }
  run::Scenario scenario;
  bool lifeline = false;
  try {
    if (!args.scenario_stdin.empty()) {
      const std::optional<std::string> text = read_scenario_from_stdin(lifeline);
      if (!text) {
        spdlog::error("agent: cannot read the scenario from standard input");
        return kExitFailure;
      }
      scenario = run::parse_scenario(*text, args.scenario_stdin);
      scenario.source = args.scenario_stdin;
    } else {
      scenario = run::load_scenario(args.scenario);
    }
  } catch (const std::exception& e) {
    spdlog::error("agent: {}", e.what());
    return kExitFailure;
  }
  const IdListResult parsed = parse_id_list(args.ids, 1, 1 << 20);
  if (!parsed.error.empty()) {
    spdlog::error("agent: --ids {}: {}", args.ids, parsed.error);
    return kExitUsage;
  }
  const std::vector<int>& ids = parsed.ids;
  // Every ID must be a robot of the scenario with a controller; each is built once here,
  // so that a bad parameter shows now rather than when a run starts.
  for (const int id : ids) {
    const auto spec =
        std::find_if(scenario.robots.begin(), scenario.robots.end(), [&](const auto& r) { return r.id == id; });
    if (spec == scenario.robots.end()) {
      spdlog::error("agent: {} has no robot {}", scenario.source.string(), id);
      return kExitUsage;
    }
    try {
      if (!run::make_controller(scenario, *spec)) {
        spdlog::error("agent: robot {} of {} has no controller (controller: none)", id, scenario.source.string());
        return kExitUsage;
      }
    } catch (const std::exception& e) {
      spdlog::error("agent: {}", e.what());
      return kExitFailure;
    }
  }
  std::string error;
  // Quanta come on the URL; answers and announcements go on the answer bus (the next port).
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.url, error);
  std::unique_ptr<lcm::LCM> answers = lcm ? bus::open_lcm(bus::agent_reply_url(args.url), error) : nullptr;
  if (!lcm || !answers) {
    spdlog::error("agent: {}", error);
    return kExitFailure;
  }
  bus::AgentServerConfig config;
  config.channels = bus::Channels::with_prefix(args.prefix);
  config.scenario_name = scenario.name;
  config.robot_ids = ids;
  config.once = args.once;
  bus::AgentServer server(*lcm, *answers, config, [&scenario](int id, agents::ControllerGroups& groups) {
    const auto spec =
        std::find_if(scenario.robots.begin(), scenario.robots.end(), [&](const auto& r) { return r.id == id; });
    return run::make_controller(scenario, *spec, &groups);
  });
  const InterruptFlag interrupt;
  if (lifeline) watch_lifeline();
  if (!args.quiet) {
    std::printf("agent %s: robots %s of %s, on %s\n", server.session().c_str(), args.ids.c_str(), scenario.name.c_str(),
                args.url.empty() ? "LCM's default bus" : args.url.c_str());
    std::fflush(stdout);
  }
  try {
    server.serve(interrupt.flag());
  } catch (const std::exception& e) {
    // A controller that failed (a plug-in's step that threw): this process ends, and the
    // run finds it lost and stops its robots.
    spdlog::error("agent: {}", e.what());
    return kExitFailure;
  }
  if (!args.quiet) {
    const auto& c = server.counters();
    std::printf("agent %s: %lld run(s), %lld steps, %lld repeated answers, %lld quanta skipped\n",
                server.session().c_str(), static_cast<long long>(c.runs), static_cast<long long>(c.steps),
                static_cast<long long>(c.repeats), static_cast<long long>(c.skipped));
  }
  return 0;
}

}  // namespace

void add_agent_command(CLI::App& app) {
  auto args = std::make_shared<AgentArgs>();
  CLI::App* cmd = app.add_subcommand(
      "agent", "Run some robots' controllers in this process, for a run on an LCM bus that lists them as remote");
  CLI::Option* file =
      cmd->add_option("--scenario", args->scenario, "The run's scenario file")->check(CLI::ExistingFile);
  cmd->add_option("--scenario-stdin", args->scenario_stdin,
                  "Read the scenario from standard input instead, up to a line '...' or its end; NAME is the file it "
                  "came from (its default name, and in messages). After a '...' line the agent ends when its input "
                  "closes (how `rilbed run` starts agents over ssh)")
      ->option_text("NAME")
      ->excludes(file);
  cmd->add_option("--ids", args->ids, "The robots whose controllers run here (e.g. 3,4 or 1-8)")->required();
  cmd->add_option("--lcm", args->url, "LCM URL of the run's bus (e.g. udpm://239.255.76.67:7667?ttl=0)")->required();
  cmd->add_option("--channel-prefix", args->prefix, "The run's channel prefix (rilbed run --channel-prefix)");
  cmd->add_flag("--once", args->once, "Exit when the first run it serves ends (default: serve runs until Ctrl-C)");
  cmd->add_flag("--quiet", args->quiet, "Print nothing but errors");
  cmd->callback([args] { exit_code() = agent_command(*args); });
}

}  // namespace rilbed::app
