#include "bus/lcm_console.hpp"

#include "bus/lcm_checked.hpp"
#include "vision/vision_settings.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>
#include <random>
#include <thread>
#include <variant>

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

namespace rilbed::bus {

namespace asio = boost::asio;

std::string make_run_token() {
  std::random_device device;
  std::string token;
  for (int i = 0; i < 4; ++i) {
    char part[9];
    std::snprintf(part, sizeof part, "%08x", static_cast<unsigned>(device()));
    token += part;
  }
  return token;
}

std::filesystem::path token_path(const std::string& prefix) {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  const std::filesystem::path dir = runtime && *runtime
                                        ? std::filesystem::path(runtime) / "rilbed"
                                        : std::filesystem::path("/tmp") / ("rilbed-" + std::to_string(::getuid()));
  return dir / (prefix + "token");
}

std::optional<std::string> write_token(const std::filesystem::path& path, const std::string& token) {
  const std::filesystem::path dir = path.parent_path();
  ::mkdir(dir.c_str(), 0700);  // may exist
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return "cannot make " + dir.string();
  // Someone else's folder, a link, or one others can enter: the token would not be private.
  if (!S_ISDIR(st.st_mode) || st.st_uid != ::getuid() || (st.st_mode & 077) != 0) {
    return dir.string() + " is not a private folder of this user (mode 0700)";
  }
  const std::filesystem::path temp = path.string() + ".new";
  std::filesystem::remove(temp);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return "cannot write " + temp.string();
  const std::string line = token + "\n";
  const bool written = ::write(fd, line.data(), line.size()) == static_cast<ssize_t>(line.size());
  ::close(fd);
  std::error_code ec;
  if (written) std::filesystem::rename(temp, path, ec);
  if (!written || ec) return "cannot write " + path.string();
  return std::nullopt;
}

std::optional<std::string> read_token(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string token;
  if (!in || !std::getline(in, token) || token.empty()) return std::nullopt;
  return token;
}

namespace {

// A whole number in decimal ("12", "-40"), within int's range; nullopt otherwise.
std::optional<long> whole_number(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || end == text.c_str() || *end != '\0' || errno != 0 || v < -1'000'000'000 || v > 1'000'000'000) {
    return std::nullopt;
  }
  return v;
}

}  // namespace

std::variant<run::ControlAction, std::string> parse_console_command(const rilbed::console_command_t& c) {
  run::ControlAction a;
  a.who = c.client.empty() ? std::string("an unnamed console") : c.client;
  const std::size_t args = c.args.size();
  auto no_args = [&](run::ControlAction::Kind kind) -> std::variant<run::ControlAction, std::string> {
    if (args != 0) return "'" + c.command + "' takes no arguments";
    a.kind = kind;
    return a;
  };
  if (c.command == "pause") return no_args(run::ControlAction::Kind::kPause);
  if (c.command == "resume") return no_args(run::ControlAction::Kind::kResume);
  if (c.command == "exit") return no_args(run::ControlAction::Kind::kExit);
  if (c.command == "rt-factor") {
    if (args != 1) return std::string("'rt-factor' takes one argument, the factor");
    char* end = nullptr;
    const double f = std::strtod(c.args[0].c_str(), &end);
    if (end == c.args[0].c_str() || *end != '\0' || !std::isfinite(f) || f <= 0.0) {
      return "'" + c.args[0] + "' is not a factor above 0";
    }
    a.kind = run::ControlAction::Kind::kRtFactor;
    a.rt_factor = f;
    return a;
  }
  if (c.command == "reset") return no_args(run::ControlAction::Kind::kReset);
  if (c.command == "mode") {
    if (args != 1 || (c.args[0] != "central" && c.args[0] != "distributed")) {
      return std::string("'mode' takes one argument, central or distributed");
    }
    a.kind = run::ControlAction::Kind::kMode;
    a.central = c.args[0] == "central";
    return a;
  }
  if (c.command == "drive") {
    if (args != 4) return std::string("'drive' takes ID LEFT RIGHT and the seconds (--for S)");
    const auto id = whole_number(c.args[0]);
    const auto left = whole_number(c.args[1]);
    const auto right = whole_number(c.args[2]);
    char* end = nullptr;
    const double s = std::strtod(c.args[3].c_str(), &end);
    if (!id || *id < 0) return "'" + c.args[0] + "' is not a robot ID";
    if (!left || std::abs(*left) > 127)
      return "left speed '" + c.args[1] + "' is not a whole number in -127..127 (Khepera units)";
    if (!right || std::abs(*right) > 127)
      return "right speed '" + c.args[2] + "' is not a whole number in -127..127 (Khepera units)";
    if (end == c.args[3].c_str() || *end != '\0' || !std::isfinite(s) || s <= 0.0 || s > 600.0) {
      return "'" + c.args[3] + "' is not a number of seconds in (0, 600]";
    }
    a.kind = run::ControlAction::Kind::kDrive;
    a.robot_id = static_cast<int>(*id);
    a.left = static_cast<int>(*left);
    a.right = static_cast<int>(*right);
    a.duration_s = s;
    return a;
  }
  if (c.command == "vision") {
    if (args == 0 || args % 2 != 0 || args > 2 * vision::kVisionSettingNames.size()) {
      return std::string(
          "'vision' takes NAME VALUE pairs (brightness, contrast, threshold, min_diameter_px, "
          "max_diameter_px, min_score)");
    }
    vision::VisionSettings ranges;  // each value checked against its range here, the whole by the run
    for (std::size_t i = 0; i < args; i += 2) {
      const std::string& name = c.args[i];
      char* end = nullptr;
      const double value = std::strtod(c.args[i + 1].c_str(), &end);
      if (end == c.args[i + 1].c_str() || *end != '\0') return "'" + c.args[i + 1] + "' is not a number";
      if (auto why = vision::set_vision_setting(ranges, name, value)) return *why;
      for (const auto& [earlier, v] : a.vision) {
        if (earlier == name) return "'" + name + "' is given twice";
      }
      a.vision.emplace_back(name, value);
    }
    a.kind = run::ControlAction::Kind::kVision;
    return a;
  }
  return "unknown command '" + c.command +
         "' (pause, resume, exit, reset, rt-factor F, mode central|distributed, "
         "drive ID LEFT RIGHT --for S, vision NAME VALUE...)";
}

namespace {

// Equal strings in a time that does not depend on where they differ.
bool same_token(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i % std::max<std::size_t>(b.size(), 1)]);
  return diff == 0 && !b.empty();
}

}  // namespace

struct LcmConsoleServer::Impl {
  Impl(lcm::LCM& l, Channels c, std::string t, run::RunControl& ctl, std::function<void(const std::string&)> lg)
      : lcm(l), channels(std::move(c)), token(std::move(t)), control(ctl), log(std::move(lg)) {}

  lcm::LCM& lcm;
  Channels channels;
  std::string token;
  run::RunControl& control;
  std::function<void(const std::string&)> log;
  asio::io_context io;
  asio::posix::stream_descriptor descriptor{io};
  asio::steady_timer tick{io};
  std::function<void()> while_paused;
  std::thread thread;
  std::unique_ptr<LcmSubscription> subscription;
  // Answers already given, by (client, seq), oldest first (a bounded memory).
  std::map<std::pair<std::string, std::int64_t>, rilbed::console_reply_t> answered;
  std::deque<std::pair<std::string, std::int64_t>> answered_order;
  // When the last command was answered (steady clock, ms): the server stays a moment after
  // the run, for the retries of a console whose answer was lost (`exit` ends the run).
  std::atomic<std::int64_t> last_answer_ms{std::numeric_limits<std::int64_t>::min() / 2};
  static std::int64_t now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  void wait_for_messages() {
    descriptor.async_wait(asio::posix::stream_descriptor::wait_read, [this](const boost::system::error_code& ec) {
      if (ec) return;  // closed: the server is going
      lcm.handleTimeout(0);
      wait_for_messages();
    });
  }

  void every_second() {
    tick.expires_after(std::chrono::seconds(1));
    tick.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      if (control.paused()) while_paused();
      every_second();
    });
  }

  // Raw bytes: checked before they are decoded (anyone on the multicast group can send
  // them, before any token is looked at).
  void on_message(const std::string& channel, const void* data, std::size_t size) {
    rilbed::console_command_t command;
    if (!decode_checked(data, size, command)) {
      if (log) log("console: " + channel + ": " + std::to_string(size) + " bytes that are not a command (ignored)");
      return;
    }
    on_command(&command);
  }

  void on_command(const rilbed::console_command_t* c) {
    const auto key = std::make_pair(c->client, c->seq);
    if (const auto it = answered.find(key); it != answered.end()) {
      publish_encoded(lcm, channels.console_reply, it->second);  // a retry: the same answer, nothing done again
      return;
    }
    rilbed::console_reply_t reply;
    reply.seq = c->seq;
    reply.client = c->client;
    const std::string who = c->client.empty() ? std::string("an unnamed console") : c->client;
    if (!same_token(c->token, token)) {
      reply.accepted = false;
      reply.reason = c->token.empty() ? "no token: give the run's token (--token, or its token file)"
                                      : "wrong token: this run's token was printed at its start";
      run::ControlAction refused;
      refused.kind = run::ControlAction::Kind::kRefused;
      refused.who = who;
      refused.what = "'" + c->command + "' (" + reply.reason.substr(0, reply.reason.find(':')) + ")";
      control.act(refused);
    } else {
      auto parsed = parse_console_command(*c);
      if (auto* why = std::get_if<std::string>(&parsed)) {
        reply.accepted = false;
        reply.reason = *why;
      } else if (auto refusal = control.act(std::get<run::ControlAction>(parsed))) {
        reply.accepted = false;
        reply.reason = *refusal;
      } else {
        reply.accepted = true;
        reply.reason = c->command;
        for (const std::string& arg : c->args) reply.reason += " " + arg;
      }
    }
    if (log)
      log("console: " + who + ": " + c->command + ": " + (reply.accepted ? "accepted" : "refused, " + reply.reason));
    publish_encoded(lcm, channels.console_reply, reply);
    answered[key] = reply;
    last_answer_ms = now_ms();
    answered_order.push_back(key);
    if (answered_order.size() > 1024) {
      answered.erase(answered_order.front());
      answered_order.pop_front();
    }
  }
};

LcmConsoleServer::LcmConsoleServer(lcm::LCM& lcm, Channels channels, std::string token, run::RunControl& control,
                                   std::function<void(const std::string&)> log, bool own_thread,
                                   std::function<void()> while_paused)
    : impl_(std::make_unique<Impl>(lcm, std::move(channels), std::move(token), control, std::move(log))) {
  Impl& m = *impl_;
  m.while_paused = std::move(while_paused);
  m.subscription = std::make_unique<LcmSubscription>(
      lcm, m.channels.console,
      [&m](const std::string& c, const void* data, std::size_t size) { m.on_message(c, data, size); });
  if (!own_thread) return;
  // A duplicate of LCM's descriptor: closing ours must not close LCM's.
  m.descriptor.assign(::dup(lcm.getFileno()));
  m.wait_for_messages();
  if (m.while_paused) m.every_second();
  m.thread = std::thread([&m] { m.io.run(); });
}

LcmConsoleServer::~LcmConsoleServer() {
  Impl& m = *impl_;
  if (m.thread.joinable()) {
    // A console answered less than kLingerMs ago may not have heard its answer (UDP loses
    // messages) and is sending its command again: answer it from the cache until then.
    constexpr std::int64_t kLingerMs = 1500;
    const std::int64_t left = m.last_answer_ms.load() + kLingerMs - Impl::now_ms();
    if (left > 0) std::this_thread::sleep_for(std::chrono::milliseconds(left));
    asio::post(m.io, [&m] {
      boost::system::error_code ignored;
      m.descriptor.close(ignored);
      m.tick.cancel();
      m.io.stop();
    });
    m.thread.join();
  }
  m.subscription.reset();
}

namespace {

struct ReplyCatcher {
  std::int64_t seq = 0;
  std::string client;
  std::optional<rilbed::console_reply_t> reply;
  void on_reply(const void* data, std::size_t size) {
    rilbed::console_reply_t r;
    if (decode_checked(data, size, r) && r.seq == seq && r.client == client) reply = r;
  }
};

}  // namespace

std::optional<rilbed::console_reply_t> send_console_command(lcm::LCM& lcm, const Channels& channels,
                                                            const std::string& token, const std::string& command,
                                                            const std::vector<std::string>& args, int timeout_ms,
                                                            int resend_ms, const std::string& on_behalf_of) {
  std::array<char, 256> host{};
  ::gethostname(host.data(), host.size() - 1);
  rilbed::console_command_t c;
  c.seq = static_cast<std::int64_t>(std::random_device{}()) << 20 ^
          std::chrono::steady_clock::now().time_since_epoch().count();
  c.client = std::string(host.data()) + ":" + std::to_string(::getpid());
  if (!on_behalf_of.empty()) c.client += " for " + on_behalf_of;
  c.token = token;
  c.command = command;
  c.args = args;
  c.num_args = static_cast<std::int32_t>(args.size());
  ReplyCatcher catcher{c.seq, c.client, std::nullopt};
  LcmSubscription subscription(
      lcm, channels.console_reply,
      [&catcher](const std::string&, const void* data, std::size_t size) { catcher.on_reply(data, size); });
  const auto start = std::chrono::steady_clock::now();
  auto next_send = start;
  while (!catcher.reply) {
    const auto now = std::chrono::steady_clock::now();
    if (now - start >= std::chrono::milliseconds(timeout_ms)) break;
    if (now >= next_send) {
      publish_encoded(lcm, channels.console, c);
      next_send = now + std::chrono::milliseconds(resend_ms);
    }
    lcm.handleTimeout(20);
  }
  return catcher.reply;
}

}  // namespace rilbed::bus
