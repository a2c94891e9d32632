// Fuzz target for the agent exchange's messages (src/bus/remote_agents.hpp,
// src/bus/agent_server.hpp): the first input byte picks who hears the rest, as it would
// come off the bus from anyone on the multicast group:
//   0: an agent process (a real AgentServer) on RILBED_QUANTUM, its controllers stand-ins
//      that read every field they are handed (a mock is fine in a test);
//   1: a run (a real RemoteAgents with one agent process announced) on RILBED_QUANTUM_REPLY;
//   2: the same run on RILBED_AGENT_HELLO.
// Whatever the bytes, nothing throws or crashes, and:
//   - the server steps a controller only for a well-formed, plausible quantum of a run (a
//     nonce) addressed to it, once per input of its own robots, each input's values as plausible() promises;
//     bytes that are no message, or hold implausible values, are counted refused and step
//     nothing; the same quantum again is answered again without stepping;
//   - the run refuses bytes that are no message (counted), and takes no robot it does not
//     list from an announcement.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "agents/controller.hpp"
#include "bus/agent_messages.hpp"
#include "bus/agent_server.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_checked.hpp"
#include "bus/remote_agents.hpp"

namespace {

using namespace rilbed;

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_agent_messages: invariant broken: %s\n", what);
  std::abort();
}
#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (false)

int g_steps = 0;

// Reads every field of its input (so that ASan sees a bad one) and checks the promises.
class TouchingController final : public agents::Controller {
 public:
  agents::ControlOutput step(const agents::ControlInput& in) override {
    ++g_steps;
    double sum = static_cast<double>(in.t_us + in.robot_id);
    if (in.pose) {
      FUZZ_CHECK(std::isfinite(in.pose->position_m.x) && std::isfinite(in.pose->position_m.y) &&
                 std::isfinite(in.pose->heading_rad));
      sum += in.pose->position_m.x + in.pose->heading_rad;
    }
    if (in.sensors.proximity) {
      for (const int v : *in.sensors.proximity) FUZZ_CHECK(v >= 0 && v <= environment::kProximityMax);
    }
    for (const auto& r : in.sensors.ranges) {
      FUZZ_CHECK(std::isfinite(r.distance_m));
      sum += r.distance_m;
    }
    for (const auto& b : in.sensors.beacons) FUZZ_CHECK(std::isfinite(b.bearing_rad));
    for (const int v : in.sensors.track) FUZZ_CHECK(v >= 0);
    for (const auto& m : in.sensors.models) {
      FUZZ_CHECK(!m.name.empty() && m.name.size() <= 64 && m.values.size() <= 64);
      for (const double v : m.values) FUZZ_CHECK(std::isfinite(v));
      sum += static_cast<double>(m.name.size());
    }
    for (const auto& m : in.team) {
      FUZZ_CHECK(std::isfinite(m.pose.position_m.x));
      sum += static_cast<double>(m.behaviour.size());
    }
    volatile double sink = sum;
    (void)sink;
    return {{static_cast<int>(in.robot_id % 100), -3}, "follow"};
  }
  bool wants_team() const override { return true; }
};

// One in-process bus for every input (making one costs more than the rest of an input),
// drained before each.
lcm::LCM& memq() {
  static std::unique_ptr<lcm::LCM> lcm = [] {
    std::string error;
    auto made = bus::open_lcm("memq://", error);
    if (!made) broken("memq:// did not open");
    return made;
  }();
  while (lcm->handleTimeout(0) > 0) {}
  return *lcm;
}

void fuzz_server(const std::uint8_t* data, std::size_t size) {
  lcm::LCM* lcm = &memq();
  bus::AgentServerConfig config;
  config.scenario_name = "fuzz";
  config.robot_ids = {1, 2, 3};
  bus::AgentServer server(*lcm, *lcm, config, [](int) { return std::make_unique<TouchingController>(); });
  // The bytes as they are, and again with the session set to this server's (else nearly
  // every message would be for someone else).
  g_steps = 0;
  server.handle_quantum(data, size);
  FUZZ_CHECK(server.counters().steps == 0 || g_steps > 0);
  rilbed::quantum_t q{};
  if (!bus::decode_checked(data, size, q)) {
    FUZZ_CHECK(server.counters().refused == 1 && g_steps == 0);
    return;
  }
  q.sessions.push_back(server.session());
  q.num_sessions = static_cast<std::int32_t>(q.sessions.size());
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(q.getEncodedSize()));
  const int written = q.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (written < 0) return;
  bytes.resize(static_cast<std::size_t>(written));
  const auto refused_before = server.counters().refused;
  const auto steps_before = server.counters().steps;
  g_steps = 0;
  server.handle_quantum(bytes.data(), bytes.size());
  // What the server got: the encoder cuts a string at its first 0 byte (a model's name).
  rilbed::quantum_t sent{};
  FUZZ_CHECK(bus::decode_checked(bytes.data(), bytes.size(), sent));
  q = sent;
  if (!bus::plausible(q) || q.run.empty()) {
    FUZZ_CHECK(server.counters().refused == refused_before + 1 && g_steps == 0);
    return;
  }
  int own_inputs = 0;
  for (const auto& in : q.inputs) own_inputs += in.id >= 1 && in.id <= 3;
  if (server.counters().steps > steps_before) {
    FUZZ_CHECK(!q.end);
    FUZZ_CHECK(g_steps == own_inputs);
    // A repeat: answered again, nothing stepped.
    g_steps = 0;
    server.handle_quantum(bytes.data(), bytes.size());
    FUZZ_CHECK(g_steps == 0);
  } else {
    FUZZ_CHECK(g_steps == 0);
  }
}

void fuzz_run(const std::uint8_t* data, std::size_t size, bool hello) {
  lcm::LCM* lcm = &memq();
  bus::RemoteAgentsConfig config;
  config.scenario_name = "fuzz";
  config.robot_ids = {1, 2};
  bus::RemoteAgents run(*lcm, *lcm, config);
  rilbed::agent_hello_t h{};
  h.session = "known";
  h.scenario = "fuzz";
  h.ids = {1, 2};
  h.num_ids = 2;
  h.host = "here";
  h.pid = 1;
  bus::publish_encoded(*lcm, config.channels.agent_hello, h);
  if (run.wait_for_agents(std::chrono::milliseconds(50))) broken("the known process was not taken");
  lcm->publish(hello ? config.channels.agent_hello : config.channels.quantum_reply, data, static_cast<unsigned>(size));
  while (lcm->handleTimeout(0) > 0) {}
  if (hello) {
    rilbed::agent_hello_t m{};
    const bool refused = !bus::decode_checked(data, size, m) || m.session.empty() || m.scenario != "fuzz";
    FUZZ_CHECK(run.counters().refused == (refused ? 1 : 0));
  } else {
    rilbed::quantum_reply_t m{};
    if (!bus::decode_checked(data, size, m)) FUZZ_CHECK(run.counters().refused == 1);
  }
  // Whatever came, an exchange with the process still works (it has nothing to answer:
  // no input was submitted).
  FUZZ_CHECK(run.exchange(0).empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  switch (data[0] % 3) {
    case 0: fuzz_server(data + 1, size - 1); break;
    case 1: fuzz_run(data + 1, size - 1, false); break;
    default: fuzz_run(data + 1, size - 1, true); break;
  }
  return 0;
}
