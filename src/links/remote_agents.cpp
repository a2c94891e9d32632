#include "links/remote_agents.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include <unistd.h>

#include "links/agent_messages.hpp"
#include "links/lcm_checked.hpp"

namespace rilbed::links {

namespace {

using Clock = std::chrono::steady_clock;

std::string make_nonce() {
  std::random_device rd;
  std::ostringstream out;
  out << std::hex << rd() << rd();
  return out.str();
}

std::string join(const std::vector<int>& ids) {
  std::string s;
  for (const int id : ids) {
    if (!s.empty()) s += ',';
    s += std::to_string(id);
  }
  return s;
}

int ms_between(Clock::time_point a, Clock::time_point b) {
  return static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(b - a).count());
}

}  // namespace

RemoteAgents::RemoteAgents(lcm::LCM& lcm, RemoteAgentsConfig config)
    : lcm_(lcm), config_(std::move(config)), run_(make_nonce()) {
  hello_sub_ = std::make_unique<LcmSubscription>(
      lcm_, config_.channels.agent_hello, [this](const std::string&, const void* d, std::size_t n) { on_hello(d, n); });
  reply_sub_ = std::make_unique<LcmSubscription>(
      lcm_, config_.channels.quantum_reply, [this](const std::string&, const void* d, std::size_t n) { on_reply(d, n); });
}

RemoteAgents::~RemoteAgents() = default;

bool RemoteAgents::serves(int robot_id) const {
  return std::find(config_.robot_ids.begin(), config_.robot_ids.end(), robot_id) != config_.robot_ids.end();
}

void RemoteAgents::on_hello(const void* data, std::size_t size) {
  rilbed::agent_hello_t hello;
  if (!decode_checked(data, size, hello) || hello.session.empty()) {
    ++counters_.refused;
    return;
  }
  if (hello.scenario != config_.scenario_name) {
    ++counters_.refused;
    return;
  }
  const auto now = Clock::now();
  if (auto it = sessions_.find(hello.session); it != sessions_.end()) {
    it->second.last_heard = now;
    return;
  }
  // A new process: it takes over every listed robot it runs that has no live process.
  Session s;
  s.name = hello.session;
  s.host = hello.host;
  s.pid = hello.pid;
  s.last_heard = now;
  for (const int id : hello.ids) {
    if (!serves(id)) continue;
    const auto owner = owner_.find(id);
    if (owner != owner_.end()) {
      const Session& old = sessions_.at(owner->second);
      if (!old.lost) continue;  // still served by a live process
      ++counters_.rejoins;
      notices_.push_back({"agent", id, "rejoined: process " + s.host + ":" + std::to_string(s.pid)});
    }
    owner_[id] = s.name;
    s.robot_ids.push_back(id);
  }
  if (!s.robot_ids.empty()) sessions_.emplace(s.name, std::move(s));
}

void RemoteAgents::on_reply(const void* data, std::size_t size) {
  rilbed::quantum_reply_t reply;
  if (!decode_checked(data, size, reply)) {
    ++counters_.refused;
    return;
  }
  if (reply.run != run_) return;  // another run's (or a run before this one)
  const auto it = sessions_.find(reply.session);
  if (it == sessions_.end()) {
    ++counters_.refused;
    return;
  }
  Session& s = it->second;
  s.last_heard = Clock::now();
  if (s.lost) return;
  s.unanswered_since.reset();
  std::vector<agents::RemoteOutput>* into = nullptr;
  if (s.awaiting && reply.quantum == *s.awaiting) {
    into = &answered_;
    s.awaiting.reset();
    if (!s.repeated) {
      const double ms = std::chrono::duration<double, std::milli>(s.last_heard - s.first_sent_at).count();
      s.round_trip_ms = s.round_trip_ms < 0.0 ? ms : 0.9 * s.round_trip_ms + 0.1 * ms;
    }
  } else if (config_.realtime && reply.quantum < s.next_quantum && reply.quantum > s.next_quantum - 3) {
    // Real time: the answer to an instant already gone, applied at the next one (once).
    into = &late_;
    ++counters_.late;
  } else {
    ++counters_.duplicates;
    return;
  }
  ++counters_.answers;
  for (const rilbed::agent_output_t& o : reply.outputs) {
    // Only this process's own robots.
    if (std::find(s.robot_ids.begin(), s.robot_ids.end(), o.id) == s.robot_ids.end()) continue;
    into->push_back(from_lcm(o));
  }
}

std::optional<std::string> RemoteAgents::wait_for_agents(std::chrono::milliseconds timeout) {
  const auto until = Clock::now() + timeout;
  for (;;) {
    std::vector<int> missing;
    for (const int id : config_.robot_ids) {
      if (!owner_.contains(id)) missing.push_back(id);
    }
    if (missing.empty()) return std::nullopt;
    const auto now = Clock::now();
    if (now >= until) {
      return "no agent process announced robot" + std::string(missing.size() > 1 ? "s " : " ") + join(missing) +
             " within " + std::to_string(timeout.count() / 1000.0).substr(0, 4) + " s (start `rilbed agent --ids " +
             join(missing) + "` on the bus " + config_.channels.agent_hello + " listens on)";
    }
    lcm_.handleTimeout(std::max(1, std::min(100, ms_between(now, until))));
  }
}

RemoteAgents::Session* RemoteAgents::session_of_robot(int robot_id) {
  const auto owner = owner_.find(robot_id);
  if (owner == owner_.end()) return nullptr;
  return &sessions_.at(owner->second);
}

void RemoteAgents::submit(const agents::ControlInput& input) {
  pending_[input.robot_id] = input;
  pending_[input.robot_id].team = {};
  if (team_.empty() && !input.team.empty() && config_.team_readers.contains(input.robot_id)) {
    team_.assign(input.team.begin(), input.team.end());
  }
}

void RemoteAgents::send(Session& s, TimeUs t_us, bool end) {
  rilbed::quantum_t q;
  q.run = run_;
  q.session = s.name;
  q.quantum = s.next_quantum++;
  q.utime = t_us;
  q.end = end;
  bool reads_team = false;
  if (!end) {
    for (const int id : s.robot_ids) {
      const auto it = pending_.find(id);
      if (it == pending_.end()) continue;
      q.inputs.push_back(to_lcm(it->second));
      reads_team = reads_team || config_.team_readers.contains(id);
    }
  }
  q.num_inputs = static_cast<std::int32_t>(q.inputs.size());
  q.has_team = reads_team;
  if (reads_team) {
    for (const agents::TeamMessage& m : team_) q.team.push_back(to_lcm(m));
  }
  q.num_team = static_cast<std::int32_t>(q.team.size());
  s.bytes.resize(static_cast<std::size_t>(q.getEncodedSize()));
  const int written = q.encode(s.bytes.data(), 0, static_cast<int>(s.bytes.size()));
  s.bytes.resize(static_cast<std::size_t>(std::max(0, written)));
  lcm_.publish(config_.channels.quantum, s.bytes.data(), static_cast<unsigned>(s.bytes.size()));
  ++counters_.quanta_sent;
  s.awaiting = q.quantum;
  s.repeated = false;
  s.sent_at = s.first_sent_at = Clock::now();
  s.repeat_wait_ms = resend_after_ms(s);
  if (!s.unanswered_since) s.unanswered_since = s.sent_at;
}

int RemoteAgents::resend_after_ms(const Session& s) const {
  if (s.round_trip_ms < 0.0) return config_.resend_ms;
  return std::clamp(static_cast<int>(std::ceil(3.0 * s.round_trip_ms)), 1, config_.resend_ms);
}

void RemoteAgents::lose(Session& s, const char* why) {
  s.lost = true;
  s.awaiting.reset();
  ++counters_.lost_processes;
  notices_.push_back({"agent", 0,
                      "lost: process " + s.host + ":" + std::to_string(s.pid) + " (robots " + join(s.robot_ids) + ") " + why});
}

void RemoteAgents::handle_for(std::chrono::milliseconds wait) {
  // handleTimeout returns after one message or the timeout: drain what is there.
  lcm_.handleTimeout(static_cast<int>(std::max<std::int64_t>(0, wait.count())));
  while (lcm_.handleTimeout(0) > 0) {
  }
}

std::vector<agents::RemoteOutput> RemoteAgents::exchange(TimeUs t_us) {
  const auto called = Clock::now();
  // Announcements and stale answers that arrived since the last instant.
  while (lcm_.handleTimeout(0) > 0) {
  }
  std::vector<agents::RemoteOutput> out;
  if (config_.realtime) {
    out = std::move(late_);
    late_.clear();
  }
  answered_.clear();
  std::set<int> stopped;
  // One quantum per live process that has inputs in it.
  for (auto& [name, s] : sessions_) {
    if (s.lost) continue;
    const bool any = std::any_of(s.robot_ids.begin(), s.robot_ids.end(), [&](int id) { return pending_.contains(id); });
    if (any) send(s, t_us, false);
  }
  const auto start = Clock::now();
  const auto deadline = start + std::chrono::milliseconds(config_.deadline_ms);
  for (;;) {
    const auto now = Clock::now();
    bool waiting = false;
    auto next_event = now + std::chrono::milliseconds(config_.resend_ms);
    for (auto& [name, s] : sessions_) {
      if (s.lost || !s.awaiting) continue;
      if (s.unanswered_since && ms_between(*s.unanswered_since, now) >= config_.dead_after_ms &&
          ms_between(s.last_heard, now) >= config_.dead_after_ms) {
        lose(s, "stopped answering");
        continue;
      }
      if (config_.realtime && now >= deadline) continue;  // late: its answer goes to the next instant
      waiting = true;
      if (now - s.sent_at >= std::chrono::milliseconds(s.repeat_wait_ms)) {
        lcm_.publish(config_.channels.quantum, s.bytes.data(), static_cast<unsigned>(s.bytes.size()));
        ++counters_.repeats;
        s.repeated = true;
        s.sent_at = now;
        // Backing off: a process that is gone, or slow, is not flooded.
        s.repeat_wait_ms = std::min(config_.resend_ms, 2 * s.repeat_wait_ms);
      }
      next_event = std::min(next_event, s.sent_at + std::chrono::milliseconds(s.repeat_wait_ms));
    }
    if (!waiting) break;
    if (config_.realtime) next_event = std::min(next_event, deadline);
    // Rounded up to whole milliseconds (LCM waits in those).
    handle_for(std::chrono::ceil<std::chrono::milliseconds>(next_event - Clock::now()));
  }
  out.insert(out.end(), answered_.begin(), answered_.end());
  answered_.clear();
  // A robot whose process is lost stops (its body is driven with zero speeds).
  for (const auto& [id, input] : pending_) {
    const Session* s = session_of_robot(id);
    if (s && !s->lost) continue;
    out.push_back(agents::RemoteOutput{id, agents::ControlOutput{{0, 0}, "lost"}, false});
  }
  pending_.clear();
  team_.clear();
  if (config_.record_exchange_times) {
    exchange_times_ms_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - called).count());
  }
  return out;
}

std::vector<agents::ExchangeNotice> RemoteAgents::take_notices() { return std::exchange(notices_, {}); }

void RemoteAgents::end() {
  // Told a few times, unanswered (a lost "end" only leaves the process waiting for the
  // next run, which its own silence timer then notices).
  pending_.clear();
  for (int round = 0; round < 3; ++round) {
    for (auto& [name, s] : sessions_) {
      if (!s.lost) send(s, 0, true);
    }
    handle_for(std::chrono::milliseconds(2));
  }
}

}  // namespace rilbed::links
