#include "serial/khepera_emulator.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <system_error>

#include "environment/kinematics.hpp"

namespace rilbed::serial {

namespace {

using Clock = std::chrono::steady_clock;

std::system_error errno_error(const std::string& what) { return {errno, std::generic_category(), what}; }

// A file descriptor closed when it goes out of scope.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() { reset(); }
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

// One open pseudo-terminal pair: the master we serve on, and our own descriptor of the
// slave, held so that a client closing the slave does not hang the pty up.
struct PtyPair {
  FileDescriptor master;
  FileDescriptor slave;
  std::string slave_path;
};

PtyPair open_pty_pair() {
  PtyPair pty;
  pty.master = FileDescriptor(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pty.master.valid()) throw errno_error("emulated Khepera: posix_openpt");
  if (::grantpt(pty.master.get()) != 0) throw errno_error("emulated Khepera: grantpt");
  if (::unlockpt(pty.master.get()) != 0) throw errno_error("emulated Khepera: unlockpt");
  std::array<char, 128> name{};
  if (::ptsname_r(pty.master.get(), name.data(), name.size()) != 0) throw errno_error("emulated Khepera: ptsname_r");
  pty.slave_path = name.data();
  pty.slave = FileDescriptor(::open(name.data(), O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pty.slave.valid()) throw errno_error("emulated Khepera: open " + pty.slave_path);
  // Raw mode: no echo, no line editing, no CR/LF translation. A client configures the
  // tty again when it opens it (Asio does), but a plain `cat` or `screen` then sees the
  // firmware's bytes unchanged.
  termios tio{};
  if (::tcgetattr(pty.slave.get(), &tio) != 0) throw errno_error("emulated Khepera: tcgetattr " + pty.slave_path);
  ::cfmakeraw(&tio);
  tio.c_cflag |= CSTOPB | CLOCAL | CREAD;  // 8N2 as the firmware uses
  ::cfsetspeed(&tio, B38400);
  if (::tcsetattr(pty.slave.get(), TCSANOW, &tio) != 0)
    throw errno_error("emulated Khepera: tcsetattr " + pty.slave_path);
  // Never block the serving thread on a client that does not read.
  const int flags = ::fcntl(pty.master.get(), F_GETFL);
  if (flags < 0 || ::fcntl(pty.master.get(), F_SETFL, flags | O_NONBLOCK) != 0) {
    throw errno_error("emulated Khepera: fcntl O_NONBLOCK");
  }
  return pty;
}

void check_faults(const EmulatorFaults& f) {
  auto probability = [](double p, const char* name) {
    if (!(p >= 0.0 && p <= 1.0))
      throw std::invalid_argument(std::string("emulated Khepera: ") + name + " must be in 0..1");
  };
  probability(f.drop_probability, "drop probability");
  probability(f.garbage_probability, "garbage probability");
  probability(f.corrupt_probability, "corrupt probability");
  if (f.reply_delay_ms < 0) throw std::invalid_argument("emulated Khepera: reply delay must be >= 0 ms");
  if (!(f.disconnect_after_s >= 0.0) || !(f.replug_after_s >= 0.0)) {
    throw std::invalid_argument("emulated Khepera: disconnect and replug times must be >= 0 s");
  }
}

void check_style(const ReplyStyle& style) {
  if (style.line_end.empty() || style.line_end.find_first_not_of("\r\n") != std::string::npos) {
    throw std::invalid_argument("emulated Khepera: a reply's line end must be CR, LF or both");
  }
  if (style.extra_fields.find_first_of("\r\n") != std::string::npos) {
    throw std::invalid_argument("emulated Khepera: extra reply fields must not end the line");
  }
  if (style.trailing_spaces < 0) throw std::invalid_argument("emulated Khepera: trailing spaces must be >= 0");
}

// A reply waiting for its moment (the fault's reply delay).
struct PendingReply {
  Clock::time_point due;
  std::string bytes;
};

}  // namespace

struct KheperaEmulator::State {
  explicit State(EmulatorConfig c) : config(std::move(c)), faults(config.faults), rng(config.seed) {}

  const EmulatorConfig config;
  // The emulated robot's time: the config's clock, or the wall's.
  Clock::time_point now() const { return config.clock ? config.clock() : Clock::now(); }

  // Everything below is guarded by `mutex`. The pty is changed only by the serving thread
  // (and the constructor and destructor, while that thread does not run), always under
  // the mutex, so the serving thread may read its descriptors without it.
  mutable std::mutex mutex;
  std::condition_variable requests_done;

  // The robot.
  Pose2 pose;
  double left_counter_pulses = 0.0;
  double right_counter_pulses = 0.0;
  WheelSpeeds speeds;
  Clock::time_point integrated_until = now();
  environment::ProximityValues proximity{};
  environment::ProximityValues ambient{};
  std::array<std::uint64_t, kCommandKindCount> received{};
  std::uint64_t bad_commands = 0;

  // Faults.
  EmulatorFaults faults;
  std::mt19937_64 rng;
  const Clock::time_point started = now();
  bool timed_disconnect_done = false;
  std::optional<Clock::time_point> replug_at;

  // Requests from other threads, served by the thread in order.
  enum class Request { kNone, kUnplug, kReplug };
  Request request = Request::kNone;
  std::uint64_t requests_made = 0;
  std::uint64_t requests_served = 0;
  std::string request_error;  // a failed replug's reason
  bool quit = false;

  std::string slave_path;  // copy of pty.slave_path for readers; empty while unplugged

  PtyPair pty;
  // Serving thread only.
  std::array<FileDescriptor, 2> wake_pipe;
  LineAssembler assembler;
  std::deque<PendingReply> outbox;

  // Advances the pose and counters to `now` with the current wheel speeds (exact arc).
  void integrate_locked(Clock::time_point now) {
    const double dt_s = std::chrono::duration<double>(now - integrated_until).count();
    integrated_until = now;
    if (dt_s <= 0.0 || (speeds.left_units == 0 && speeds.right_units == 0)) return;
    const RobotModel& m = config.model;
    pose = environment::integrate_diff_drive(pose, speeds.left_units * m.speed_unit_mps,
                                             speeds.right_units * m.speed_unit_mps, m.wheel_base_m, dt_s);
    const double pulses_per_unit_second = m.speed_unit_mps / m.counter_pulse_m;
    left_counter_pulses += speeds.left_units * pulses_per_unit_second * dt_s;
    right_counter_pulses += speeds.right_units * pulses_per_unit_second * dt_s;
  }

  void wake() const {
    const char byte = 1;
    // A full pipe already holds a wake-up; nothing is lost by ignoring EAGAIN.
    [[maybe_unused]] const ssize_t n = ::write(wake_pipe[1].get(), &byte, 1);
  }

  // Points the stable symlink at the current slave (or removes it while unplugged).
  std::error_code update_stable_link_locked() {
    std::error_code ec;
    if (config.stable_path.empty()) return ec;
    if (slave_path.empty()) {
      std::filesystem::remove(config.stable_path, ec);
      return ec;
    }
    // Create beside it and rename over it: a client never sees a missing or half-made link.
    const std::string temp = config.stable_path + ".new";
    std::filesystem::remove(temp, ec);
    std::filesystem::create_symlink(slave_path, temp, ec);
    if (!ec) std::filesystem::rename(temp, config.stable_path, ec);
    return ec;
  }

  void unplug_locked(Clock::time_point now) {
    pty = PtyPair{};
    slave_path.clear();
    outbox.clear();
    assembler.discard_partial();
    update_stable_link_locked();
    if (faults.replug_after_s > 0.0) {
      replug_at =
          now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(faults.replug_after_s));
    }
  }

  // Opens a fresh pty (throws std::system_error if none); returns the symlink's error.
  std::error_code replug_locked() {
    replug_at.reset();
    if (pty.master.valid()) return {};
    pty = open_pty_pair();
    slave_path = pty.slave_path;
    return update_stable_link_locked();
  }

  // The firmware's answer to one line: acts on it and returns the reply bytes.
  std::string answer_locked(const std::string& line, Clock::time_point now) {
    const RobotModel& m = config.model;
    const Result<Command> command = decode_command(m, line);
    if (!command) {
      ++bad_commands;
      return std::string(kProtocolErrorReply);
    }
    ++received[static_cast<std::size_t>(command->kind)];
    integrate_locked(now);
    Reply reply;
    reply.kind = command->kind;
    switch (command->kind) {
      case CommandKind::kReadVersions: reply.versions = config.versions; break;
      case CommandKind::kSetSpeeds:
        speeds = {static_cast<int>(command->first), static_cast<int>(command->second)};
        break;
      case CommandKind::kReadSpeeds: reply.wheels = {speeds.left_units, speeds.right_units}; break;
      case CommandKind::kSetCounters:
        left_counter_pulses = static_cast<double>(command->first);
        right_counter_pulses = static_cast<double>(command->second);
        break;
      case CommandKind::kReadCounters:
        reply.wheels = {std::llround(left_counter_pulses), std::llround(right_counter_pulses)};
        break;
      case CommandKind::kReadProximity: reply.sensors = proximity; break;
      case CommandKind::kReadAmbient: reply.sensors = ambient; break;
      case CommandKind::kSetLed: break;
    }
    return encode_reply(m, reply);
  }

  bool roll(double probability) {
    return probability > 0.0 && std::uniform_real_distribution<double>(0.0, 1.0)(rng) < probability;
  }

  std::string garbage() {
    std::string bytes;
    const int length = std::uniform_int_distribution<int>(1, 12)(rng);
    std::uniform_int_distribution<int> byte(0, 255);
    while (static_cast<int>(bytes.size()) < length) {
      const int b = byte(rng);
      if (b != '\r' && b != '\n') bytes += static_cast<char>(b);
    }
    if (roll(0.5)) bytes += "\r\n";
    return bytes;
  }

  std::string corrupt(std::string reply) {
    std::string body = reply.substr(0, reply.size() - 2);  // without CR LF
    const std::size_t last_comma = body.rfind(',');
    // An acknowledgement carries no value to spoil (whatever follows its letter is
    // ignored), so only its letter can be wrong.
    const int how = last_comma == std::string::npos ? 0 : std::uniform_int_distribution<int>(0, 2)(rng);
    switch (how) {
      case 0:  // wrong letter
        body[0] = body[0] == 'a' ? 'b' : static_cast<char>(body[0] - 1);
        break;
      case 1:  // the last value missing
        body.erase(last_comma);
        break;
      default:  // a value that is not a number
        body = body.substr(0, last_comma + 1) + "x1";
        break;
    }
    return body + "\r\n";
  }

  // A K-Team reply ("n,1,2\r\n") in the configured style.
  std::string styled(const std::string& reply) const {
    const ReplyStyle& style = config.style;
    std::string body = reply.substr(0, reply.size() - 2);  // without CR LF
    if (style.upper_case_letter && !body.empty())
      body[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(body[0])));
    if (style.spaces_after_commas) {
      std::string spaced;
      for (const char c : body) spaced += c == ',' ? std::string(", ") : std::string(1, c);
      body = std::move(spaced);
    }
    return body + style.extra_fields + std::string(static_cast<std::size_t>(style.trailing_spaces), ' ') +
           style.line_end;
  }

  void queue_locked(Clock::time_point due, std::string bytes) {
    if (!outbox.empty()) due = std::max(due, outbox.back().due);  // replies keep their order
    outbox.push_back({due, std::move(bytes)});
  }

  void handle_line_locked(const std::string& line, Clock::time_point now) {
    if (config.style.echo) queue_locked(now, line + config.style.line_end);
    std::string reply = answer_locked(line, now);
    if (roll(faults.drop_probability)) return;
    if (roll(faults.corrupt_probability)) reply = corrupt(std::move(reply));
    reply = styled(reply);
    if (roll(faults.garbage_probability)) reply = garbage() + reply;
    queue_locked(now + std::chrono::milliseconds(faults.reply_delay_ms), std::move(reply));
  }

  void send_due_locked(Clock::time_point now) {
    while (!outbox.empty() && outbox.front().due <= now && pty.master.valid()) {
      const std::string& bytes = outbox.front().bytes;
      // A client that stops reading fills the pty's buffer; the rest of the reply is
      // lost, as bytes on a wire nobody listens to.
      [[maybe_unused]] const ssize_t n = ::write(pty.master.get(), bytes.data(), bytes.size());
      outbox.pop_front();
    }
  }
};

KheperaEmulator::KheperaEmulator(EmulatorConfig config) : state_(std::make_unique<State>(std::move(config))) {
  State& s = *state_;
  check_faults(s.faults);
  check_style(s.config.style);
  s.pose = s.config.initial_pose;
  s.proximity = s.config.proximity;
  s.ambient = s.config.ambient;
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC | O_NONBLOCK) != 0) throw errno_error("emulated Khepera: pipe2");
  s.wake_pipe[0] = FileDescriptor(pipe_fds[0]);
  s.wake_pipe[1] = FileDescriptor(pipe_fds[1]);
  if (const std::error_code ec = s.replug_locked()) {
    throw std::system_error(ec, "emulated Khepera: cannot make the symlink " + s.config.stable_path);
  }
  thread_ = std::thread([this] { serve(); });
}

KheperaEmulator::~KheperaEmulator() {
  {
    std::lock_guard lock(state_->mutex);
    state_->quit = true;
  }
  state_->wake();
  thread_.join();
  state_->pty = PtyPair{};
  state_->slave_path.clear();
  state_->update_stable_link_locked();
}

void KheperaEmulator::serve() {
  State& s = *state_;
  std::array<char, 512> buffer{};
  std::vector<std::string> lines;
  while (true) {
    int timeout_ms = -1;
    bool master_open = false;
    {
      std::unique_lock lock(s.mutex);
      if (s.quit) return;
      const Clock::time_point now = s.now();
      if (s.request != State::Request::kNone) {
        try {
          if (s.request == State::Request::kUnplug) {
            if (s.pty.master.valid()) s.unplug_locked(now);
          } else {
            s.replug_locked();
          }
        } catch (const std::system_error& e) {
          s.request_error = e.what();
        }
        s.request = State::Request::kNone;
        s.requests_served = s.requests_made;
        s.requests_done.notify_all();
      }
      if (!s.timed_disconnect_done && s.faults.disconnect_after_s > 0.0 &&
          now - s.started >= std::chrono::duration<double>(s.faults.disconnect_after_s)) {
        s.timed_disconnect_done = true;
        if (s.pty.master.valid()) s.unplug_locked(now);
      }
      if (s.replug_at && now >= *s.replug_at) {
        try {
          s.replug_locked();
        } catch (const std::system_error&) {
          // Out of ptys: try again a little later rather than end the emulator.
          s.replug_at = now + std::chrono::milliseconds(100);
        }
      }
      s.send_due_locked(now);

      // Sleep until the next thing due: a reply, the timed unplug, the replug.
      std::optional<Clock::time_point> next;
      auto consider = [&](Clock::time_point t) { next = next ? std::min(*next, t) : t; };
      if (!s.outbox.empty()) consider(s.outbox.front().due);
      if (!s.timed_disconnect_done && s.faults.disconnect_after_s > 0.0) {
        consider(s.started + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(s.faults.disconnect_after_s)));
      }
      if (s.replug_at) consider(*s.replug_at);
      if (next) {
        const auto wait = std::chrono::ceil<std::chrono::milliseconds>(*next - now).count();
        timeout_ms = static_cast<int>(std::clamp<long long>(wait, 0, 60'000));
      }
      master_open = s.pty.master.valid();
    }

    // Only this thread changes the pty, so its descriptor is stable while we poll it.
    std::array<pollfd, 2> fds{};
    fds[0] = {s.wake_pipe[0].get(), POLLIN, 0};
    fds[1] = {master_open ? s.pty.master.get() : -1, POLLIN, 0};
    const int ready = ::poll(fds.data(), fds.size(), timeout_ms);
    if (ready < 0) continue;  // EINTR (a signal for the process): go round
    if (fds[0].revents & POLLIN) {
      while (::read(s.wake_pipe[0].get(), buffer.data(), buffer.size()) > 0) {}
    }
    if (master_open && (fds[1].revents & (POLLIN | POLLHUP | POLLERR))) {
      const ssize_t n = ::read(s.pty.master.get(), buffer.data(), buffer.size());
      if (n > 0) {
        lines.clear();
        std::lock_guard lock(s.mutex);
        s.assembler.feed(std::string_view(buffer.data(), static_cast<std::size_t>(n)), lines);
        const Clock::time_point now = s.now();
        for (const std::string& line : lines) s.handle_line_locked(line, now);
      } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
        // We hold the slave open, so this should not happen; if it does, the pty is
        // unusable: behave as unplugged rather than spin on the error.
        std::lock_guard lock(s.mutex);
        s.unplug_locked(s.now());
      } else if (n == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // no spinning on a hang-up
      }
    }
  }
}

std::string KheperaEmulator::device_path() const {
  std::lock_guard lock(state_->mutex);
  return state_->config.stable_path.empty() ? state_->slave_path : state_->config.stable_path;
}

std::string KheperaEmulator::slave_path() const {
  std::lock_guard lock(state_->mutex);
  return state_->slave_path;
}

Pose2 KheperaEmulator::true_pose() const {
  std::lock_guard lock(state_->mutex);
  state_->integrate_locked(state_->now());
  return state_->pose;
}

environment::OdometryReading KheperaEmulator::counters() const {
  std::lock_guard lock(state_->mutex);
  state_->integrate_locked(state_->now());
  return {std::llround(state_->left_counter_pulses), std::llround(state_->right_counter_pulses)};
}

WheelSpeeds KheperaEmulator::last_speeds() const {
  std::lock_guard lock(state_->mutex);
  return state_->speeds;
}

std::uint64_t KheperaEmulator::commands_received(CommandKind kind) const {
  std::lock_guard lock(state_->mutex);
  return state_->received[static_cast<std::size_t>(kind)];
}

std::uint64_t KheperaEmulator::bad_commands() const {
  std::lock_guard lock(state_->mutex);
  return state_->bad_commands;
}

void KheperaEmulator::set_proximity(const environment::ProximityValues& values) {
  std::lock_guard lock(state_->mutex);
  state_->proximity = values;
}

void KheperaEmulator::place(const Pose2& pose) {
  std::lock_guard lock(state_->mutex);
  state_->integrate_locked(state_->now());
  state_->pose = pose;
}

void KheperaEmulator::set_ambient(const environment::ProximityValues& values) {
  std::lock_guard lock(state_->mutex);
  state_->ambient = values;
}

void KheperaEmulator::set_faults(const EmulatorFaults& faults) {
  check_faults(faults);
  {
    std::lock_guard lock(state_->mutex);
    state_->faults = faults;
  }
  state_->wake();
}

bool KheperaEmulator::plugged() const {
  std::lock_guard lock(state_->mutex);
  return state_->pty.master.valid();
}

// unplug() and replug() hand a request to the serving thread (the only one that changes
// the pty) and wait until it is done, so that the caller sees its effect (a vanished or a
// new device) when the call returns.
void KheperaEmulator::unplug() {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  s.request = State::Request::kUnplug;
  const std::uint64_t ticket = ++s.requests_made;
  s.wake();
  s.requests_done.wait(lock, [&] { return s.requests_served >= ticket || s.quit; });
}

void KheperaEmulator::replug() {
  State& s = *state_;
  std::unique_lock lock(s.mutex);
  s.request = State::Request::kReplug;
  s.request_error.clear();
  const std::uint64_t ticket = ++s.requests_made;
  s.wake();
  s.requests_done.wait(lock, [&] { return s.requests_served >= ticket || s.quit; });
  if (!s.request_error.empty()) throw std::system_error(std::make_error_code(std::errc::io_error), s.request_error);
}

}  // namespace rilbed::serial
