// The run's side of the agent exchange over LCM: the robots whose controllers
// run in `rilbed agent` processes, on this machine or others of the LAN.
//
// Each agent process announces itself (agent_hello_t, with its robots). At each control
// instant the run sends the processes their robots' inputs (and the team broadcast when one
// of those robots reads it) in one quantum_t when that fits in one datagram, else one per
// process (a world of 1,000 robots: each gets only its own), and waits for the answers.
// Quanta go on one bus; answers and announcements come back on another (agent_reply_url),
// so that no agent process hears the others' answers:
// - lock-step (fast runs): until every process has answered; a quantum not answered
//   within `resend_ms` is sent again, unchanged (UDP multicast loses messages; the
//   process answers a repeat without stepping again);
// - real time: until `deadline_ms` of wall time; an answer that comes later is counted
//   late and applied at the next instant.
// A process that answers nothing for `dead_after_ms` is lost: its robots are stopped
// (a real robot through its body, as any stop) and the run goes on without them; a
// process that announces itself for them later takes them over (a rejoin). Both become
// events. Everything runs on the calling (run's) thread, through `lcm`.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "bus/lcm_bus.hpp"
#include "rilbed/quantum_t.hpp"
#include "run/agent_exchange.hpp"

namespace rilbed::bus {

/// Knobs of the exchange.
struct RemoteAgentsConfig {
  Channels channels;           ///< RILBED_AGENT_HELLO, RILBED_QUANTUM, RILBED_QUANTUM_REPLY (with the run's prefix)
  std::string scenario_name;   ///< agents announcing another scenario are refused
  std::vector<int> robot_ids;  ///< the robots whose controllers run elsewhere
  std::set<int> team_readers;  ///< among them, those whose controllers read the team broadcast
  bool realtime = false;       ///< real-time mode (see the file comment), else lock-step
  /// A quantum not answered within this is sent again, at most: once a process has
  /// answered, the wait is three times its usual round trip (at least 1 ms), so that a
  /// lost datagram on a fast network costs a millisecond or two, not this. Lower recovers
  /// sooner from a loss before the first answer, and repeats more to a slow process.
  int resend_ms = 20;
  /// A process that has answered nothing for this long is lost. Lower notices a dead
  /// process sooner, and gives up sooner on one paused by its machine.
  int dead_after_ms = 750;
  /// Real time: how long an instant waits for its answers (wall time).
  int deadline_ms = 20;
  /// Keep the wall time of every exchange() (exchange_times_ms(); for benchmarks: one
  /// number per control step).
  bool record_exchange_times = false;
};

/// What the exchange has counted since it was made.
struct RemoteAgentsCounters {
  std::int64_t quanta_sent = 0;     ///< quantum messages sent, repeats not included
  std::int64_t repeats = 0;         ///< quantum messages sent again (no answer in time)
  std::int64_t answers = 0;         ///< answers taken
  std::int64_t duplicates = 0;      ///< answers to a quantum already answered, or stale ones
  std::int64_t late = 0;            ///< real time: answers that missed their instant
  std::int64_t refused = 0;         ///< messages that were not well formed, or not for this run
  std::int64_t lost_processes = 0;  ///< processes found dead
  std::int64_t rejoins = 0;         ///< robots taken over by a new process after their process was lost
};

class RemoteAgents final : public run::AgentExchange {
 public:
  /// `quanta` (published on only) and `answers` (handled here) must outlive the exchange
  /// and be handled by no other thread; they may be one instance (an in-process bus).
  RemoteAgents(lcm::LCM& quanta, lcm::LCM& answers, RemoteAgentsConfig config);
  ~RemoteAgents() override;

  /// Waits until every listed robot's process has announced itself (handling the bus).
  /// Returns nothing when all have, else the error naming the robots still missing after
  /// `timeout`. `give_up`, called every tenth of a second or so, ends the wait early with
  /// the error it returns (an agent process that could not start).
  std::optional<std::string> wait_for_agents(std::chrono::milliseconds timeout,
                                             const std::function<std::optional<std::string>()>& give_up = {});

  bool serves(int robot_id) const override;
  void submit(const agents::ControlInput& input) override;
  std::vector<run::RemoteOutput> exchange(TimeUs t_us) override;
  std::vector<run::ExchangeNotice> take_notices() override;
  void end() override;

  const RemoteAgentsCounters& counters() const { return counters_; }
  /// With config.record_exchange_times: each exchange()'s wall time, milliseconds.
  const std::vector<double>& exchange_times_ms() const { return exchange_times_ms_; }
  /// The run's nonce, in every quantum (new for each RemoteAgents).
  const std::string& run_nonce() const { return run_; }

 private:
  struct Session {
    std::string name;  // agent_hello_t.session
    std::string host;
    int pid = 0;
    std::vector<int> robot_ids;
    bool lost = false;
    std::chrono::steady_clock::time_point last_heard;
    std::optional<std::int64_t> awaiting;  // the quantum in flight, unanswered
    std::int64_t last_answered = -1;       // the latest quantum it answered (copies of it are duplicates)
    std::size_t message = 0;               // which of outgoing_ carried it
    // Since when a quantum to it has gone unanswered (real time sends the next one
    // without waiting); cleared by any answer.
    std::optional<std::chrono::steady_clock::time_point> unanswered_since;
    double round_trip_ms = -1.0;  // smoothed, from answers to quanta sent once; < 0: none yet
  };
  // One quantum message in flight: its bytes (sent again unchanged) and its repeats.
  struct Outgoing {
    std::vector<std::uint8_t> bytes;
    std::chrono::steady_clock::time_point first_sent_at, sent_at;
    int repeat_wait_ms = 0;  // the wait before the next repeat (doubles with each)
    bool repeated = false;
  };
  int resend_after_ms(const Session& s) const;
  // Encodes and sends quantum `k` at `t_us` for `sessions` (their pending inputs).
  void send(const std::vector<Session*>& sessions, std::int64_t k, TimeUs t_us, bool end);
  void on_hello(const void* data, std::size_t size);
  void on_reply(const void* data, std::size_t size);
  Session* session_of_robot(int robot_id);
  rilbed::quantum_t quantum_for(const std::vector<Session*>& sessions, std::int64_t k, TimeUs t_us, bool end) const;
  void lose(Session& s, const char* why);
  void handle_for(std::chrono::milliseconds wait);

  lcm::LCM& quanta_;
  lcm::LCM& answers_;
  RemoteAgentsConfig config_;
  std::string run_;
  std::int64_t next_quantum_ = 0;
  std::vector<Outgoing> outgoing_;                                 // the messages of the quantum in flight
  std::map<std::string, Session> sessions_;                        // by session name
  std::map<int, std::string> owner_;                               // robot -> session name
  std::map<int, agents::ControlInput> pending_;                    // submitted for the coming quantum, by robot
  std::vector<agents::TeamMessage> team_;                          // the team broadcast of the pending inputs
  std::vector<run::RemoteOutput> answered_;                        // answers taken for the quantum in flight
  std::vector<run::RemoteOutput> late_;                            // real time: answers that missed their instant
  std::optional<std::chrono::steady_clock::time_point> deadline_;  // real time: the current instant's deadline
  std::vector<run::ExchangeNotice> notices_;
  RemoteAgentsCounters counters_;
  std::vector<double> exchange_times_ms_;
  std::unique_ptr<LcmSubscription> hello_sub_, reply_sub_;
};

}  // namespace rilbed::bus
