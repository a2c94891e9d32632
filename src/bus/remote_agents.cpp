#include "bus/remote_agents.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include <unistd.h>

#include "bus/agent_messages.hpp"
#include "bus/lcm_checked.hpp"
#include "bus/lcm_conversion.hpp"

namespace rilbed::bus {

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

RemoteAgents::RemoteAgents(lcm::LCM& quanta, lcm::LCM& answers, RemoteAgentsConfig config)
    : quanta_(quanta), answers_(answers), config_(std::move(config)), run_(make_nonce()) {
  hello_sub_ =
      std::make_unique<LcmSubscription>(answers_, config_.channels.agent_hello,
                                        [this](const std::string&, const void* d, std::size_t n) { on_hello(d, n); });
  reply_sub_ =
      std::make_unique<LcmSubscription>(answers_, config_.channels.quantum_reply,
                                        [this](const std::string&, const void* d, std::size_t n) { on_reply(d, n); });
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
  std::vector<run::RemoteOutput>* into = nullptr;
  if (reply.quantum <= s.last_answered) {
    // A second copy of an answer (agents send each twice), or a repeat's answer.
    ++counters_.duplicates;
    return;
  }
  // Real time: an answer handled after its instant's deadline is late even if the wait has
  // not returned yet (its process, or this one, was held up): the contract is the deadline.
  const bool past_deadline = config_.realtime && deadline_ && s.last_heard > *deadline_;
  if (s.awaiting && reply.quantum == *s.awaiting && !past_deadline) {
    into = &answered_;
    s.awaiting.reset();
    if (s.message < outgoing_.size() && !outgoing_[s.message].repeated) {
      const double ms =
          std::chrono::duration<double, std::milli>(s.last_heard - outgoing_[s.message].first_sent_at).count();
      s.round_trip_ms = s.round_trip_ms < 0.0 ? ms : 0.9 * s.round_trip_ms + 0.1 * ms;
    }
  } else if (config_.realtime && reply.quantum < next_quantum_ && reply.quantum > next_quantum_ - 3) {
    // Real time: the answer to an instant already gone, applied at the next one (once).
    into = &late_;
    ++counters_.late;
    if (s.awaiting && reply.quantum == *s.awaiting) s.awaiting.reset();
  } else {
    ++counters_.duplicates;
    return;
  }
  ++counters_.answers;
  s.last_answered = reply.quantum;
  for (const rilbed::agent_output_t& o : reply.outputs) {
    // Only this process's own robots.
    if (std::find(s.robot_ids.begin(), s.robot_ids.end(), o.id) == s.robot_ids.end()) continue;
    into->push_back(from_lcm(o));
  }
}

std::optional<std::string> RemoteAgents::wait_for_agents(std::chrono::milliseconds timeout,
                                                         const std::function<std::optional<std::string>()>& give_up) {
  const auto until = Clock::now() + timeout;
  for (;;) {
    if (give_up) {
      if (auto reason = give_up()) return reason;
    }
    std::vector<int> missing;
    for (const int id : config_.robot_ids) {
      if (!owner_.contains(id)) missing.push_back(id);
    }
    if (missing.empty()) return std::nullopt;
    const auto now = Clock::now();
    if (now >= until) {
      return "no agent process announced robot" + std::string(missing.size() > 1 ? "s " : " ") + join(missing) +
             " within " + std::to_string(timeout.count() / 1000.0).substr(0, 4) +
             " s (start `rilbed agent --scenario FILE --ids " + join(missing) +
             " --lcm URL` with this run's URL and channel prefix)";
    }
    answers_.handleTimeout(std::max(1, std::min(100, ms_between(now, until))));
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

rilbed::quantum_t RemoteAgents::quantum_for(const std::vector<Session*>& sessions, std::int64_t k, TimeUs t_us,
                                            bool end) const {
  rilbed::quantum_t q{};
  q.run = run_;
  q.quantum = k;
  q.utime = t_us;
  q.end = end;
  bool reads_team = false;
  for (const Session* s : sessions) {
    q.sessions.push_back(s->name);
    if (end) continue;
    for (const int id : s->robot_ids) {
      const auto it = pending_.find(id);
      if (it == pending_.end()) continue;
      q.inputs.push_back(to_lcm(it->second));
      reads_team = reads_team || config_.team_readers.contains(id);
    }
  }
  q.num_sessions = static_cast<std::int32_t>(q.sessions.size());
  q.num_inputs = static_cast<std::int32_t>(q.inputs.size());
  q.has_team = reads_team;
  if (reads_team) {
    for (const agents::TeamMessage& m : team_) q.team.push_back(to_lcm(m));
  }
  q.num_team = static_cast<std::int32_t>(q.team.size());
  return q;
}

void RemoteAgents::send(const std::vector<Session*>& sessions, std::int64_t k, TimeUs t_us, bool end) {
  if (sessions.empty()) return;
  // One message for every process when it fits in one datagram (LCM sends larger ones in
  // fragments, each a datagram that can be lost); else one per process, each with only
  // its own robots.
  constexpr int kOneDatagram = 60'000;
  std::vector<rilbed::quantum_t> messages;
  std::vector<std::vector<Session*>> addressed;
  rilbed::quantum_t all = quantum_for(sessions, k, t_us, end);
  if (sessions.size() == 1 || all.getEncodedSize() <= kOneDatagram) {
    messages.push_back(std::move(all));
    addressed.push_back(sessions);
  } else {
    for (Session* s : sessions) {
      messages.push_back(quantum_for({s}, k, t_us, end));
      addressed.push_back({s});
    }
  }
  const auto now = Clock::now();
  for (std::size_t m = 0; m < messages.size(); ++m) {
    Outgoing out;
    out.bytes.resize(static_cast<std::size_t>(messages[m].getEncodedSize()));
    const int written = messages[m].encode(out.bytes.data(), 0, static_cast<int>(out.bytes.size()));
    out.bytes.resize(static_cast<std::size_t>(std::max(0, written)));
    quanta_.publish(config_.channels.quantum, out.bytes.data(), static_cast<unsigned>(out.bytes.size()));
    ++counters_.quanta_sent;
    out.first_sent_at = out.sent_at = now;
    out.repeat_wait_ms = config_.resend_ms;
    for (Session* s : addressed[m]) {
      out.repeat_wait_ms = std::min(out.repeat_wait_ms, resend_after_ms(*s));
      if (end) continue;
      s->awaiting = k;
      s->message = outgoing_.size();
      if (!s->unanswered_since) s->unanswered_since = now;
    }
    outgoing_.push_back(std::move(out));
  }
}

int RemoteAgents::resend_after_ms(const Session& s) const {
  if (s.round_trip_ms < 0.0) return config_.resend_ms;
  return std::clamp(static_cast<int>(std::ceil(3.0 * s.round_trip_ms)), 1, config_.resend_ms);
}

void RemoteAgents::lose(Session& s, const char* why) {
  s.lost = true;
  s.awaiting.reset();
  s.unanswered_since.reset();
  ++counters_.lost_processes;
  notices_.push_back(
      {"agent", 0,
       "lost: process " + s.host + ":" + std::to_string(s.pid) + " (robots " + join(s.robot_ids) + ") " + why});
}

void RemoteAgents::handle_for(std::chrono::milliseconds wait) {
  // handleTimeout returns after one message or the timeout: drain what is there.
  answers_.handleTimeout(static_cast<int>(std::max<std::int64_t>(0, wait.count())));
  while (answers_.handleTimeout(0) > 0) {}
}

std::vector<run::RemoteOutput> RemoteAgents::exchange(TimeUs t_us) {
  const auto called = Clock::now();
  // Announcements and stale answers that arrived since the last instant.
  while (answers_.handleTimeout(0) > 0) {}
  std::vector<run::RemoteOutput> out;
  if (config_.realtime) {
    out = std::move(late_);
    late_.clear();
  }
  answered_.clear();
  outgoing_.clear();
  for (auto& [name, s] : sessions_) s.awaiting.reset();  // real time: an unanswered one is late now
  // This instant's quantum, to every live process that has inputs in it.
  std::vector<Session*> to;
  for (auto& [name, s] : sessions_) {
    if (s.lost) continue;
    if (std::any_of(s.robot_ids.begin(), s.robot_ids.end(), [&](int id) { return pending_.contains(id); }))
      to.push_back(&s);
  }
  const std::int64_t k = next_quantum_++;
  send(to, k, t_us, false);
  const auto deadline = called + std::chrono::milliseconds(config_.deadline_ms);
  deadline_ = deadline;
  for (;;) {
    const auto now = Clock::now();
    std::vector<bool> message_waits(outgoing_.size(), false);
    for (auto& [name, s] : sessions_) {
      if (s.lost || !s.awaiting) continue;
      if (s.unanswered_since && ms_between(*s.unanswered_since, now) >= config_.dead_after_ms &&
          ms_between(s.last_heard, now) >= config_.dead_after_ms) {
        lose(s, "stopped answering");
        continue;
      }
      message_waits[s.message] = true;
    }
    const bool past_deadline = config_.realtime && now >= deadline;
    bool waiting = false;
    auto next_event = now + std::chrono::milliseconds(config_.resend_ms);
    for (std::size_t m = 0; m < outgoing_.size(); ++m) {
      if (!message_waits[m] || past_deadline) continue;  // real time: late answers go to the next instant
      waiting = true;
      Outgoing& o = outgoing_[m];
      if (now - o.sent_at >= std::chrono::milliseconds(o.repeat_wait_ms)) {
        quanta_.publish(config_.channels.quantum, o.bytes.data(), static_cast<unsigned>(o.bytes.size()));
        ++counters_.repeats;
        o.repeated = true;
        o.sent_at = now;
        // Backing off: a process that is gone, or slow, is not flooded.
        o.repeat_wait_ms = std::min(config_.resend_ms, 2 * o.repeat_wait_ms);
      }
      next_event = std::min(next_event, o.sent_at + std::chrono::milliseconds(o.repeat_wait_ms));
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
    out.push_back(run::RemoteOutput{id, agents::ControlOutput{{0, 0}, "lost"}, false});
  }
  pending_.clear();
  team_.clear();
  if (config_.record_exchange_times) {
    exchange_times_ms_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - called).count());
  }
  return out;
}

std::vector<run::ExchangeNotice> RemoteAgents::take_notices() { return std::exchange(notices_, {}); }

void RemoteAgents::end() {
  // Told a few times, unanswered (a lost "end" only leaves the process waiting for the
  // next run, which its own silence timer then notices).
  pending_.clear();
  std::vector<Session*> live;
  for (auto& [name, s] : sessions_) {
    if (!s.lost) live.push_back(&s);
  }
  const std::int64_t k = next_quantum_++;
  for (int round = 0; round < 3; ++round) {
    outgoing_.clear();
    send(live, k, 0, true);
    handle_for(std::chrono::milliseconds(2));
  }
}

}  // namespace rilbed::bus
