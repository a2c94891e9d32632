// Fuzz target for the console's commands (src/bus/lcm_console.hpp): the input is one
// message as it would come off the bus on RILBED_CONSOLE, from anyone on the multicast
// group. It goes to a real LcmConsoleServer on the in-process bus (handled on this thread),
// whose run is a stand-in that takes every action it is handed (a mock is fine in a test).
//
// Whatever the bytes, nothing throws or crashes, and:
//   - bytes that are not a console_command_t (links::decode_checked) get no reply and no
//     action; a command gets exactly one reply, with its seq and client;
//   - a command is accepted only with the run's token, and only when parse_console_command
//     accepts it; an accepted command reaches the run as exactly one action of its kind,
//     with its arguments in range (rt-factor finite and above 0; drive: speeds within
//     -127..127, seconds in (0, 600]; vision: known names, once each, values in range);
//     a wrong token reaches it as one "refused" record;
//   - sent again (a retry after a loss), it gets the same reply and nothing more happens.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "bus/lcm_checked.hpp"
#include "bus/lcm_console.hpp"
#include "run/run_control.hpp"
#include "vision/vision_settings.hpp"

namespace {

using namespace rilbed;

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_console_command: invariant broken: %s\n", what);
  std::abort();
}
#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (false)

const char* const kToken = "t0k";

struct Replies {
  std::vector<rilbed::console_reply_t> got;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static lcm::LCM bus("memq://");
  if (!bus.good()) broken("memq:// did not open");
  const bus::Channels channels = bus::Channels::with_prefix("");
  run::RunControl control;
  std::vector<run::ControlAction> taken;
  control.attach([](const run::ControlAction&) -> std::optional<std::string> { return std::nullopt; },
                 [&taken](const run::ControlAction& a) { taken.push_back(a); });
  bus::LcmConsoleServer server(bus, channels, kToken, control, {}, false);
  Replies replies;
  bus::LcmSubscription subscription(bus, channels.console_reply,
                                    [&replies](const std::string&, const void* d, std::size_t n) {
                                      rilbed::console_reply_t r;
                                      if (bus::decode_checked(d, n, r)) replies.got.push_back(r);
                                    });

  for (int send = 0; send < 2; ++send) {
    bus.publish(channels.console, data, static_cast<unsigned>(size));
    while (bus.handleTimeout(0) > 0) {}
  }

  rilbed::console_command_t c;
  if (!bus::decode_checked(data, size, c)) {
    FUZZ_CHECK(replies.got.empty() && taken.empty());
    return 0;
  }
  FUZZ_CHECK(replies.got.size() == 2);
  const rilbed::console_reply_t& r = replies.got[0];
  // LCM strings are C strings: a client name holding a 0 byte travels up to it.
  FUZZ_CHECK(r.seq == c.seq && std::string(r.client.c_str()) == std::string(c.client.c_str()));
  FUZZ_CHECK(replies.got[1].accepted == r.accepted && replies.got[1].reason == r.reason);
  FUZZ_CHECK(taken.size() <= 1);  // the retry did nothing
  if (c.token != kToken) {
    FUZZ_CHECK(!r.accepted);
    FUZZ_CHECK(taken.size() == 1 && taken[0].kind == run::ControlAction::Kind::kRefused);
    return 0;
  }
  const auto parsed = bus::parse_console_command(c);
  FUZZ_CHECK(r.accepted == std::holds_alternative<run::ControlAction>(parsed));
  if (!r.accepted) {
    FUZZ_CHECK(taken.empty() && !r.reason.empty());
    return 0;
  }
  FUZZ_CHECK(taken.size() == 1);
  const run::ControlAction& a = taken[0];
  using Kind = run::ControlAction::Kind;
  switch (a.kind) {
    case Kind::kPause: FUZZ_CHECK(c.command == "pause" && c.args.empty()); break;
    case Kind::kResume: FUZZ_CHECK(c.command == "resume" && c.args.empty()); break;
    case Kind::kExit: FUZZ_CHECK(c.command == "exit" && c.args.empty()); break;
    case Kind::kReset: FUZZ_CHECK(c.command == "reset" && c.args.empty()); break;
    case Kind::kRtFactor:
      FUZZ_CHECK(c.command == "rt-factor" && c.args.size() == 1);
      FUZZ_CHECK(std::isfinite(a.rt_factor) && a.rt_factor > 0.0);
      break;
    case Kind::kMode:
      FUZZ_CHECK(c.command == "mode" && c.args.size() == 1);
      FUZZ_CHECK(a.central == (c.args[0] == "central"));
      break;
    case Kind::kDrive:
      FUZZ_CHECK(c.command == "drive" && c.args.size() == 4);
      FUZZ_CHECK(a.robot_id >= 0 && std::abs(a.left) <= 127 && std::abs(a.right) <= 127);
      FUZZ_CHECK(std::isfinite(a.duration_s) && a.duration_s > 0.0 && a.duration_s <= 600.0);
      break;
    case Kind::kVision: {
      FUZZ_CHECK(c.command == "vision" && !a.vision.empty() && c.args.size() == 2 * a.vision.size());
      vision::VisionSettings s;
      for (std::size_t i = 0; i < a.vision.size(); ++i) {
        FUZZ_CHECK(a.vision[i].first == c.args[2 * i]);
        FUZZ_CHECK(!vision::set_vision_setting(s, a.vision[i].first, a.vision[i].second));
        for (std::size_t j = 0; j < i; ++j) FUZZ_CHECK(a.vision[j].first != a.vision[i].first);
      }
      break;
    }
    case Kind::kRefused: broken("an accepted command became a refusal");
  }
  return 0;
}
