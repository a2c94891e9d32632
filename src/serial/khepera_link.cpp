#include "serial/khepera_link.hpp"

#include <sys/file.h>
#include <termios.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <future>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/serial_port.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>

namespace rilbed::serial {

namespace asio = boost::asio;
using SteadyClock = std::chrono::steady_clock;

namespace {

constexpr std::array<unsigned, 5> kSupportedBauds = {9600, 19200, 38400, 57600, 115200};

std::string supported_bauds_text() {
  std::string text;
  for (const unsigned b : kSupportedBauds) text += (text.empty() ? "" : ", ") + std::to_string(b);
  return text;
}

// One request for the line: a command and who wants its reply.
struct Job {
  Command command{};
  std::function<void(const Result<Reply>&)> done{};  // may be empty (polls, wished speeds)
  bool is_poll = false;                              // queued by a poll or request_*(), deduplicated
  bool is_wished_speeds = false;                     // from set_speeds() / stop()
  std::uint64_t wish_serial = 0;                     // which wish it carries
  // Set by query() when its caller stopped waiting: a command nobody waits for any more
  // is not sent (a late "set speeds" could override a stop sent since).
  std::shared_ptr<std::atomic<bool>> abandoned{};
};

// The command on the line now.
struct InFlight {
  Job job;
  std::shared_ptr<const std::string> bytes;  // shared with the write in progress
  int attempt = 0;                           // 1 for the first
  std::uint64_t attempt_id = 0;              // tells a stale timer from the current one
};

}  // namespace

std::string_view link_state_name(LinkState state) {
  switch (state) {
    case LinkState::kConnecting: return "connecting";
    case LinkState::kOk: return "ok";
    case LinkState::kUnresponsive: return "unresponsive";
    case LinkState::kLost: return "lost";
    case LinkState::kStopped: return "stopped";
  }
  return "unknown";
}

struct KheperaLink::Impl {
  explicit Impl(LinkConfig c) : config(std::move(c)), prefix("khepera " + config.port + ": ") {}

  LinkConfig config;
  const std::string prefix;  // every message names the port

  asio::io_context io;
  asio::executor_work_guard<asio::io_context::executor_type> work = asio::make_work_guard(io);
  asio::serial_port serial{io};
  asio::steady_timer reply_timer{io};
  asio::steady_timer reopen_timer{io};
  asio::steady_timer proximity_timer{io};
  asio::steady_timer counters_timer{io};
  std::thread thread;
  std::atomic<bool> kick_posted{false};

  // Link thread only (and start(), before the thread exists).
  std::array<char, 256> read_buffer{};
  LineAssembler assembler;
  std::vector<std::string> lines;
  std::deque<Job> queue;
  std::optional<InFlight> in_flight;
  std::array<bool, kCommandKindCount> poll_pending{};
  std::uint64_t next_attempt_id = 0;
  std::uint64_t port_generation = 0;  // handlers of a closed port's operations are ignored
  bool port_open = false;
  bool last_speeds_failed = false;
  bool shutting_down = false;
  bool clamp_reported = false;

  // Shared with callers, guarded by `mutex`.
  mutable std::mutex mutex;
  std::condition_variable changed;
  LinkStatus status;
  std::optional<WheelSpeeds> wished;
  bool wish_pending = false;
  std::uint64_t wish_serial = 0;
  std::uint64_t acknowledged_wish_serial = 0;
  std::optional<WheelSpeeds> acknowledged;
  std::optional<Stamped<environment::ProximityValues>> proximity;
  std::optional<Stamped<environment::OdometryReading>> counters;
  std::optional<FirmwareVersions> versions;
  bool started = false;
  bool stopping = false;
  std::optional<bool> stop_result;

  int command_budget_ms() const { return config.reply_timeout_ms * (config.retries + 1); }

  void log(LogLevel level, const std::string& message) const {
    if (config.log) config.log(level, prefix + message);
  }

  std::string command_label(const Command& command) const {
    return std::string(1, config.model.command_letter(command.kind)) + " (" +
           std::string(command_kind_name(command.kind)) + ")";
  }

  void set_state(LinkState state, const std::string& error = {}) {
    std::lock_guard lock(mutex);
    status.state = state;
    if (!error.empty()) status.last_error = error;
    changed.notify_all();
  }

  template <typename F>
  void count(F&& f) {
    std::lock_guard lock(mutex);
    f(status.counters);
  }

  // ------------------------------------------------------------ port

  // Opens and configures the port; returns the reason on failure.
  std::optional<std::string> try_open() {
    boost::system::error_code ec;
    serial.open(config.port, ec);
    if (ec) return prefix + "cannot open: " + ec.message();
    // One program per robot: two runs driving the same robot would fight over it, and a
    // reply read by the other would look lost to each. An advisory lock (released when the
    // port closes, however the program ends) rather than TIOCEXCL, which root ignores and
    // which outlives our descriptor on a pty whose other side stays open.
    if (::flock(serial.native_handle(), LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      boost::system::error_code ignored;
      serial.close(ignored);
      return prefix + "cannot open: " +
             (error == EWOULDBLOCK ? std::string("another program is using it") : std::string(std::strerror(error)));
    }
    using base = asio::serial_port_base;
    serial.set_option(base::baud_rate(config.baud), ec);
    if (!ec) serial.set_option(base::character_size(8), ec);
    if (!ec) serial.set_option(base::parity(base::parity::none), ec);
    if (!ec) serial.set_option(base::stop_bits(base::stop_bits::two), ec);
    if (!ec) serial.set_option(base::flow_control(base::flow_control::none), ec);
    if (ec) {
      boost::system::error_code ignored;
      serial.close(ignored);
      return prefix + "cannot configure as a serial port (" + std::to_string(config.baud) +
             " baud, 8N2): " + ec.message();
    }
    // Bytes left from before (a reply nobody read) would glue onto the first reply.
    ::tcflush(serial.native_handle(), TCIOFLUSH);
    assembler.discard_partial();
    ++port_generation;
    port_open = true;
    last_speeds_failed = false;
    {
      std::lock_guard lock(mutex);
      status.state = LinkState::kConnecting;
      wish_pending = wished.has_value();  // the robot may have missed them, or rebooted
      changed.notify_all();
    }
    start_read();
    enqueue_poll(CommandKind::kReadVersions, /*front=*/true);  // handshake
    return std::nullopt;
  }

  void port_lost(const std::string& reason) {
    if (!port_open) return;
    port_open = false;
    boost::system::error_code ignored;
    serial.close(ignored);
    reply_timer.cancel();
    const std::string error = prefix + "port lost: " + reason;
    count([](LinkCounters& c) { ++c.port_losses; });
    set_state(LinkState::kLost, error);
    log(LogLevel::kError,
        "port lost (" + reason + "); reopening every " + std::to_string(config.reopen_interval_ms) + " ms");
    fail_all(error);
    schedule_reopen();
  }

  void schedule_reopen() {
    reopen_timer.expires_after(std::chrono::milliseconds(config.reopen_interval_ms));
    reopen_timer.async_wait([this](const boost::system::error_code& ec) {
      if (ec || shutting_down || port_open) return;
      if (const auto failure = try_open()) {
        count([](LinkCounters& c) { ++c.reopen_failures; });
        log(LogLevel::kDebug, "still cannot reopen: " + *failure);
        schedule_reopen();
        return;
      }
      count([](LinkCounters& c) { ++c.reopens; });
      log(LogLevel::kInfo, "port is back; resuming");
      schedule_next();
    });
  }

  void start_read() {
    serial.async_read_some(asio::buffer(read_buffer),
                           [this, generation = port_generation](const boost::system::error_code& ec, std::size_t n) {
                             if (ec == asio::error::operation_aborted || generation != port_generation || !port_open)
                               return;
                             if (ec) {
                               port_lost(ec == asio::error::eof ? std::string("end of file") : ec.message());
                               return;
                             }
                             lines.clear();
                             assembler.feed(std::string_view(read_buffer.data(), n), lines);
                             count([this](LinkCounters& c) {
                               c.noise_bytes = assembler.counters().noise_bytes;
                               c.overlong_lines = assembler.counters().overlong_lines;
                             });
                             for (const std::string& line : lines) {
                               on_line(line);
                               if (!port_open) return;
                             }
                             start_read();
                           });
  }

  // ------------------------------------------------------------ commands

  void enqueue_poll(CommandKind kind, bool front = false) {
    const auto k = static_cast<std::size_t>(kind);
    if (!port_open || poll_pending[k]) return;
    poll_pending[k] = true;
    Job job{Command{kind}, {}, /*is_poll=*/true};
    if (front) {
      queue.push_front(std::move(job));
    } else {
      queue.push_back(std::move(job));
    }
    schedule_next();
  }

  void finish_job(Job& job, const Result<Reply>& result) {
    if (job.is_poll) poll_pending[static_cast<std::size_t>(job.command.kind)] = false;
    if (job.done) job.done(result);
  }

  void fail_all(const std::string& error) {
    if (in_flight) {
      Job job = std::move(in_flight->job);
      in_flight.reset();
      finish_job(job, Failure{error});
    }
    std::deque<Job> jobs = std::move(queue);
    queue.clear();
    for (Job& job : jobs) finish_job(job, Failure{error});
  }

  // Puts the next command on the line if it is free.
  void schedule_next() {
    while (!in_flight && port_open && !shutting_down) {
      Job job;
      bool skip = false;
      {
        std::lock_guard lock(mutex);
        const bool take_speeds = wish_pending && !(last_speeds_failed && !queue.empty());
        if (take_speeds) {
          job.command = Command::set_speeds(wished->left_units, wished->right_units);
          job.is_wished_speeds = true;
          job.wish_serial = wish_serial;
          wish_pending = false;
        } else if (!queue.empty()) {
          job = std::move(queue.front());
          queue.pop_front();
        } else {
          return;
        }
        skip = stopping && !job.is_wished_speeds && job.command.kind == CommandKind::kSetSpeeds;
      }
      if (skip || (job.abandoned && job.abandoned->load())) {
        // Once stopping, the stop is the last speeds the robot gets.
        finish_job(job, Failure{prefix + command_label(job.command) +
                                (skip ? " dropped: the link is stopping" : " abandoned")});
        continue;
      }
      Result<EncodedCommand> encoded = encode_command(config.model, job.command);
      if (!encoded) {
        finish_job(job, Failure{prefix + encoded.error()});
        continue;
      }
      if (encoded->clamped) {
        count([](LinkCounters& c) { ++c.clamped_speeds; });
        // Once at warning level: a controller asking too much does so at every step.
        log(clamp_reported ? LogLevel::kDebug : LogLevel::kWarning,
            "speeds " + std::to_string(job.command.first) + ", " + std::to_string(job.command.second) +
                " clamped to +-" + std::to_string(config.model.max_speed_units));
        clamp_reported = true;
      }
      in_flight = InFlight{std::move(job), std::make_shared<const std::string>(encoded->bytes)};
      send_attempt();
    }
  }

  void send_attempt() {
    InFlight& f = *in_flight;
    ++f.attempt;
    f.attempt_id = ++next_attempt_id;
    count([&](LinkCounters& c) {
      ++c.commands_sent;
      if (f.attempt > 1) ++c.retries;
    });
    const std::optional<Command> speeds =
        f.job.command.kind == CommandKind::kSetSpeeds ? std::optional<Command>(f.job.command) : std::nullopt;
    asio::async_write(serial, asio::buffer(*f.bytes),
                      [this, bytes = f.bytes, generation = port_generation, speeds](const boost::system::error_code& ec,
                                                                                    std::size_t) {
                        if (ec == asio::error::operation_aborted || generation != port_generation) return;
                        if (ec) {
                          port_lost("write failed: " + ec.message());
                          return;
                        }
                        if (speeds && config.on_speeds_written)
                          config.on_speeds_written(*speeds, std::chrono::steady_clock::now());
                      });
    reply_timer.expires_after(std::chrono::milliseconds(config.reply_timeout_ms));
    reply_timer.async_wait([this, id = f.attempt_id](const boost::system::error_code& ec) {
      if (ec || !in_flight || in_flight->attempt_id != id) return;  // cancelled, or a reply won the race
      count([](LinkCounters& c) { ++c.timeouts; });
      // Resynchronise: a reply cut short must not glue onto the next one.
      assembler.discard_partial();
      retry_or_fail("no reply within " + std::to_string(config.reply_timeout_ms) + " ms");
    });
  }

  void retry_or_fail(const std::string& reason) {
    InFlight& f = *in_flight;
    const int attempts = config.retries + 1;
    if (f.attempt < attempts) {
      log(LogLevel::kWarning, command_label(f.job.command) + ": " + reason + "; sending again (attempt " +
                                  std::to_string(f.attempt + 1) + " of " + std::to_string(attempts) + ")");
      send_attempt();
      return;
    }
    Job job = std::move(f.job);
    in_flight.reset();
    const std::string error = prefix + command_label(job.command) + " failed after " + std::to_string(attempts) +
                              (attempts == 1 ? " attempt: " : " attempts: ") + reason;
    count([](LinkCounters& c) { ++c.failed_commands; });
    set_state(LinkState::kUnresponsive, error);
    log(LogLevel::kError, error.substr(prefix.size()));
    if (job.is_wished_speeds) last_speeds_failed = true;
    if (config.stop_on_failure) {
      std::lock_guard lock(mutex);
      // A robot we cannot talk to must not keep driving: stop it unless the controller
      // has already wished something newer.
      if (!wish_pending) {
        wished = WheelSpeeds{};
        wish_pending = true;
        ++wish_serial;
      }
    }
    finish_job(job, Failure{error});
    schedule_next();
  }

  void on_line(const std::string& line) {
    if (!in_flight) {
      count([](LinkCounters& c) { ++c.stray_lines; });
      log(LogLevel::kDebug, "ignoring a line while no command is in flight: " + printable(line));
      return;
    }
    const CommandKind kind = in_flight->job.command.kind;
    if (is_echo_of(config.model, in_flight->job.command, line)) {
      // Our own command coming back (a firmware or terminal server that echoes): never
      // its reply, however much it looks like one.
      count([](LinkCounters& c) { ++c.echoed_lines; });
      return;
    }
    Result<Reply> reply = decode_reply(config.model, kind, line);
    if (reply) {
      reply_timer.cancel();
      complete(std::move(reply.value()));
      return;
    }
    if (looks_like_reply_to(config.model, kind, line)) {
      // Our reply, damaged on the way (or the firmware's protocol error): ask again now
      // rather than wait for the timeout.
      count([](LinkCounters& c) { ++c.bad_replies; });
      reply_timer.cancel();
      retry_or_fail(reply.error());
      return;
    }
    count([](LinkCounters& c) { ++c.stray_lines; });
    log(LogLevel::kDebug,
        "ignoring a stray line while waiting for " + command_label(in_flight->job.command) + ": " + printable(line));
  }

  void complete(Reply reply) {
    Job job = std::move(in_flight->job);
    in_flight.reset();
    if (job.is_wished_speeds) last_speeds_failed = false;
    {
      std::lock_guard lock(mutex);
      ++status.counters.replies_ok;
      status.state = LinkState::kOk;
      const auto now = SteadyClock::now();
      switch (job.command.kind) {
        case CommandKind::kReadVersions: versions = reply.versions; break;
        case CommandKind::kReadProximity: proximity = Stamped<environment::ProximityValues>{reply.sensors, now}; break;
        case CommandKind::kReadCounters:
          counters = Stamped<environment::OdometryReading>{{reply.wheels.left, reply.wheels.right}, now};
          break;
        case CommandKind::kSetSpeeds: {
          const auto limit = static_cast<std::int64_t>(config.model.max_speed_units);
          acknowledged = WheelSpeeds{static_cast<int>(std::clamp(job.command.first, -limit, limit)),
                                     static_cast<int>(std::clamp(job.command.second, -limit, limit))};
          if (job.is_wished_speeds) acknowledged_wish_serial = std::max(acknowledged_wish_serial, job.wish_serial);
          break;
        }
        default: break;
      }
      changed.notify_all();
    }
    finish_job(job, reply);
    schedule_next();
  }

  // ------------------------------------------------------------ polls

  void arm_poll(asio::steady_timer& timer, int period_ms, CommandKind kind) {
    if (period_ms <= 0) return;
    timer.expires_after(std::chrono::milliseconds(period_ms));
    timer.async_wait([this, &timer, period_ms, kind](const boost::system::error_code& ec) {
      if (ec || shutting_down) return;
      enqueue_poll(kind);
      arm_poll(timer, period_ms, kind);
    });
  }

  // Wakes the link thread to send wished speeds; at most one wake-up waits at a time.
  void kick() {
    if (!kick_posted.exchange(true)) {
      asio::post(io, [this] {
        kick_posted = false;
        schedule_next();
      });
    }
  }

  // Wishes speeds 0, 0 and waits (up to `timeout_ms`, default: the command on the line and
  // the stop with all their retries) until the robot acknowledges them or the port is
  // lost. `lock` holds `mutex` on entry and on return. Whether the robot acknowledged.
  bool wish_stop_and_wait(std::unique_lock<std::mutex>& lock, std::optional<int> timeout_ms) {
    wished = WheelSpeeds{};
    wish_pending = true;
    const std::uint64_t stop_serial = ++wish_serial;
    lock.unlock();
    kick();
    const auto wait = std::chrono::milliseconds(timeout_ms.value_or(2 * command_budget_ms() + 100));
    lock.lock();
    return changed.wait_for(lock, wait, [&] {
      return acknowledged_wish_serial >= stop_serial || status.state == LinkState::kLost;
    }) && acknowledged_wish_serial >= stop_serial;
  }

  void shutdown_on_link_thread() {
    shutting_down = true;
    port_open = false;
    boost::system::error_code ignored;
    serial.close(ignored);
    reply_timer.cancel();
    reopen_timer.cancel();
    proximity_timer.cancel();
    counters_timer.cancel();
    fail_all(prefix + "link stopped");
    work.reset();
    io.stop();
  }
};

KheperaLink::KheperaLink(LinkConfig config) {
  if (config.port.empty()) throw std::invalid_argument("khepera: no serial port given");
  const std::string prefix = "khepera " + config.port + ": ";
  if (config.baud == 0) config.baud = config.model.default_baud;
  if (std::find(kSupportedBauds.begin(), kSupportedBauds.end(), config.baud) == kSupportedBauds.end()) {
    throw std::invalid_argument(prefix + "baud rate " + std::to_string(config.baud) + " is not one of " +
                                supported_bauds_text());
  }
  if (config.reply_timeout_ms <= 0) throw std::invalid_argument(prefix + "reply timeout must be > 0 ms");
  if (config.retries < 0) throw std::invalid_argument(prefix + "retries must be >= 0");
  if (config.reopen_interval_ms <= 0) throw std::invalid_argument(prefix + "reopen interval must be > 0 ms");
  if (config.proximity_period_ms < 0 || config.counters_period_ms < 0) {
    throw std::invalid_argument(prefix + "poll periods must be >= 0 ms");
  }
  impl_ = std::make_unique<Impl>(std::move(config));
}

KheperaLink::~KheperaLink() { stop(); }

std::optional<std::string> KheperaLink::start() {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.mutex);
    if (m.started || m.stop_result) return m.prefix + "start() called twice";
    m.started = true;
  }
  // The thread does not exist yet, so touching the link thread's members here is safe.
  std::optional<std::string> failure = m.try_open();
  if (failure) {
    m.set_state(LinkState::kLost, *failure);
    m.log(LogLevel::kError,
          failure->substr(m.prefix.size()) + "; retrying every " + std::to_string(m.config.reopen_interval_ms) + " ms");
    m.schedule_reopen();
  } else {
    m.log(LogLevel::kInfo,
          "open at " + std::to_string(m.config.baud) + " baud, 8N2, " + std::string(m.config.model.name));
    m.schedule_next();
  }
  m.arm_poll(m.proximity_timer, m.config.proximity_period_ms, CommandKind::kReadProximity);
  m.arm_poll(m.counters_timer, m.config.counters_period_ms, CommandKind::kReadCounters);
  m.thread = std::thread([&m] { m.io.run(); });
  return failure;
}

bool KheperaLink::stop(std::optional<int> timeout_ms) {
  Impl& m = *impl_;
  std::unique_lock lock(m.mutex);
  if (m.stop_result) return *m.stop_result;
  if (!m.started) {
    m.stop_result = false;
    m.status.state = LinkState::kStopped;
    return false;
  }
  m.stopping = true;
  const bool port_was_lost = m.status.state == LinkState::kLost;
  const bool acknowledged = m.wish_stop_and_wait(lock, timeout_ms);
  lock.unlock();

  asio::post(m.io, [&m] { m.shutdown_on_link_thread(); });
  if (m.thread.joinable()) m.thread.join();
  lock.lock();
  m.status.state = LinkState::kStopped;
  m.stop_result = acknowledged;
  lock.unlock();
  if (acknowledged) {
    m.log(LogLevel::kInfo, "stopped (the robot acknowledged D,0,0)");
  } else if (port_was_lost) {
    m.log(LogLevel::kWarning, "stopped without sending a stop: the port is not open");
  } else {
    m.log(LogLevel::kWarning, "stopped; the robot did not acknowledge a stop");
  }
  return acknowledged;
}

bool KheperaLink::halt(std::optional<int> timeout_ms) {
  Impl& m = *impl_;
  std::unique_lock lock(m.mutex);
  if (!m.started || m.stop_result || m.stopping) return false;
  const bool acknowledged = m.wish_stop_and_wait(lock, timeout_ms);
  const bool lost = m.status.state == LinkState::kLost;
  lock.unlock();
  if (!acknowledged) {
    // The stop stays wished: the link sends it again until the robot acknowledges it.
    m.log(LogLevel::kWarning, lost ? "halt: the port is lost; the stop goes first when it is back"
                                   : "halt: the robot has not acknowledged D,0,0 yet; it is sent until it does");
  }
  return acknowledged;
}

void KheperaLink::set_speeds(int left_units, int right_units) {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.mutex);
    if (m.stopping) return;  // the stop wins
    m.wished = WheelSpeeds{left_units, right_units};
    m.wish_pending = true;
    ++m.wish_serial;
    if (!m.started) return;  // sent once the port opens
  }
  m.kick();
}

std::optional<WheelSpeeds> KheperaLink::wished_speeds() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->wished;
}

std::optional<WheelSpeeds> KheperaLink::acknowledged_speeds() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->acknowledged;
}

void KheperaLink::request_proximity() {
  asio::post(impl_->io, [m = impl_.get()] { m->enqueue_poll(CommandKind::kReadProximity); });
}

void KheperaLink::request_counters() {
  asio::post(impl_->io, [m = impl_.get()] { m->enqueue_poll(CommandKind::kReadCounters); });
}

std::optional<Stamped<environment::ProximityValues>> KheperaLink::latest_proximity() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->proximity;
}

std::optional<Stamped<environment::OdometryReading>> KheperaLink::latest_counters() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->counters;
}

std::optional<FirmwareVersions> KheperaLink::versions() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->versions;
}

Result<Reply> KheperaLink::query(const Command& command, std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.mutex);
    if (!m.started || m.stop_result) return Failure{m.prefix + "the link is not running"};
    if (m.status.state == LinkState::kLost) return Failure{m.status.last_error};
  }
  if (std::this_thread::get_id() == m.thread.get_id()) {
    return Failure{m.prefix + "query() called on the link's own thread (from the log callback?)"};
  }
  auto promise = std::make_shared<std::promise<Result<Reply>>>();
  std::future<Result<Reply>> future = promise->get_future();
  auto abandoned = std::make_shared<std::atomic<bool>>(false);
  Job job{command, [promise](const Result<Reply>& r) { promise->set_value(r); }};
  job.abandoned = abandoned;
  asio::post(m.io, [&m, job = std::move(job)]() mutable {
    if (!m.port_open) {
      m.finish_job(job, Failure{m.prefix + "port is not open"});
      return;
    }
    m.queue.push_back(std::move(job));
    m.schedule_next();
  });
  if (future.wait_for(timeout) != std::future_status::ready) {
    abandoned->store(true);
    return Failure{m.prefix + "no answer to " + m.command_label(command) + " within " +
                   std::to_string(timeout.count()) + " ms"};
  }
  return future.get();
}

LinkState KheperaLink::state() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->status.state;
}

LinkStatus KheperaLink::status() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->status;
}

const std::string& KheperaLink::port() const { return impl_->config.port; }

const LinkConfig& KheperaLink::config() const { return impl_->config; }

int KheperaLink::command_budget_ms() const { return impl_->command_budget_ms(); }

}  // namespace rilbed::serial
