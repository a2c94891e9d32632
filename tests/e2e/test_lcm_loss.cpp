// End-to-end tests of a run on a lossy LCM bus: `rilbed watch` and `rilbed
// console` with 10 % of LCM's packets dropped, and a watcher that stalls. Everything runs
// inside a private network namespace (`unshare -n`, loopback with multicast), where an
// nftables rule on the input hook drops one UDP packet to LCM's port in ten at random:
// every packet on loopback passes that hook once, so the run's messages, the console's
// commands and the run's answers each lose 10 %, silently (no sender sees an error). The
// drop happens before the kernel hands a packet to any socket, so every listener in the
// namespace (the watcher, lcm-logger) gets exactly the same packets: what lcm-logger heard
// is what the watcher should show.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "lcm_namespace.hpp"
#include "run_command.hpp"

namespace rilbed::e2e {
namespace {

namespace fs = std::filesystem;

// The two counters of the loss rules: packets to port 7667 and those dropped.
struct Loss {
  long packets = -1;
  long dropped = -1;
  double rate() const { return packets > 0 ? static_cast<double>(dropped) / static_cast<double>(packets) : -1.0; }
};

Loss read_loss(const fs::path& nft_listing) {
  std::istringstream in(read_file(nft_listing));
  std::string line;
  std::vector<long> counts;
  const std::regex counter(R"(counter packets (\d+) bytes)");
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, counter)) counts.push_back(std::stol(m[1]));
  }
  Loss loss;
  if (counts.size() == 2) {
    loss.packets = counts[0];
    loss.dropped = counts[1];
  }
  return loss;
}

// One event of a standard LCM log (as lcm-logger and `rilbed run --record` write them).
struct LogEvent {
  std::string channel;
  std::string data;
};

std::uint64_t big_endian(const std::string& bytes, std::size_t at, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v = v << 8 | static_cast<unsigned char>(bytes.at(at + i));
  return v;
}

std::vector<LogEvent> read_lcm_log(const fs::path& path) {
  const std::string bytes = read_file(path);
  std::vector<LogEvent> events;
  std::size_t at = 0;
  // Each event: sync word, event number, timestamp, channel length, data length, channel, data.
  while (at + 28 <= bytes.size() && big_endian(bytes, at, 4) == 0xEDA1DA01u) {
    const std::size_t channel_len = big_endian(bytes, at + 20, 4);
    const std::size_t data_len = big_endian(bytes, at + 24, 4);
    if (at + 28 + channel_len + data_len > bytes.size()) break;
    events.push_back({bytes.substr(at + 28, channel_len), bytes.substr(at + 28 + channel_len, data_len)});
    at += 28 + channel_len + data_len;
  }
  return events;
}

// Reads LCM's encoding of a message's leading fields: after the 8-byte fingerprint,
// integers are big-endian and a string is its length (with the NUL) and its bytes.
class Fields {
 public:
  explicit Fields(const std::string& data) : data_(data) {}
  std::int64_t int64() { return static_cast<std::int64_t>(take(8)); }
  double float64() {
    const std::uint64_t bits = take(8);
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  bool boolean() { return take(1) != 0; }
  std::string string() {
    const std::size_t n = take(4);
    std::string s = data_.substr(at_, n - 1);
    at_ += n;
    return s;
  }

 private:
  std::uint64_t take(std::size_t n) {
    const std::uint64_t v = big_endian(data_, at_, n);
    at_ += n;
    return v;
  }
  const std::string& data_;
  std::size_t at_ = 8;  // past the fingerprint
};

std::string one_decimal_seconds(std::int64_t utime) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", static_cast<double>(utime) / 1e6);
  return buf;
}

// The statuses in a log, as `rilbed watch` shows them: "t=<seconds> <state>".
std::vector<std::string> statuses_in_log(const std::vector<LogEvent>& log) {
  std::vector<std::string> out;
  for (const LogEvent& e : log) {
    if (e.channel != "RILBED_STATUS") continue;
    Fields f(e.data);
    const std::int64_t utime = f.int64();
    f.int64();    // wall_utime
    f.string();   // scenario
    f.int64();    // seed
    f.string();   // mode
    f.boolean();  // realtime
    f.float64();  // rt_factor
    std::string status = "t=" + one_decimal_seconds(utime) + "s " + f.string();
    // The run publishes its end three times; a watcher shows a status once.
    if (out.empty() || out.back() != status) out.push_back(std::move(status));
  }
  return out;
}

// The events in a log that `rilbed watch` shows (not behaviour changes and collisions),
// as "<seconds> <kind>".
std::vector<std::string> shown_events_in_log(const std::vector<LogEvent>& log) {
  std::vector<std::string> out;
  for (const LogEvent& e : log) {
    if (e.channel != "RILBED_EVENTS") continue;
    Fields f(e.data);
    const std::int64_t utime = f.int64();
    const std::string kind = f.string();
    if (kind != "behaviour" && kind != "collision") out.push_back(one_decimal_seconds(utime) + " " + kind);
  }
  return out;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The watcher's status lines ("t=12.0s running x4.0  1:wait ..."), as "t=12.0s running".
std::vector<std::string> watched_statuses(const std::string& watch) {
  std::vector<std::string> out;
  for (const std::string& line : lines_of(watch)) {
    if (line.rfind("t=", 0) == 0) out.push_back(line.substr(0, line.find(' ', line.find(' ') + 1)));
  }
  return out;
}

// The watcher's event lines ("     12.3s  formed: convoy formed ..."), as "12.3 formed".
std::vector<std::string> watched_events(const std::string& watch) {
  std::vector<std::string> out;
  const std::regex event(R"(^ +(-?[0-9]+\.[0-9])s  ([a-z_]+)[ :])");
  std::smatch m;
  for (const std::string& line : lines_of(watch)) {
    if (std::regex_search(line, m, event)) out.push_back(m[1].str() + " " + m[2].str());
  }
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += x + "\n";
  return s;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// A realtime run with 10 % of its packets lost: the watcher shows it from its world (the
// "watching" line) and, because a loss only costs the message lost, every status and
// event that did reach the host: exactly those lcm-logger heard beside it (a watcher that
// stalled or stopped after a loss, or waited for a lost message, would show fewer). Then
// its end: the run's last status if it came, else (it was the one lost) the watcher says
// that no run is heard any more.
TEST(LcmLoss, TheWatcherShowsEveryMessageThatCameThroughATenPercentLoss) {
  SKIP_WITHOUT_NFT();
  const fs::path dir = scratch_dir("lcm_loss_watch");
  const int status =
      in_namespace(dir,
                   "lcm-logger --lcm-url=\"$URL\" heard.lcm > logger.txt 2>&1 &\n"
                   "L=$!\n"
                   "\"$R\" watch --lcm \"$URL\" --until-ended --silence 1 --for 120 > watch.txt 2>&1 &\n"
                   "W=$!\n"
                   "listening 2\n"
                   "set +e\n"
                   "\"$R\" run " +
                       shipped_scenario_arg("convoy_sim") +
                       " --realtime --rt-factor 4 --stop-when-formed --seed 1 --lcm \"$URL\" "
                       "--record sent.lcm --out run --quiet > run.txt 2> run.err\n"
                       "echo \"run $?\" >> codes.txt\n"
                       // The watcher ends by itself once it has shown the run's end; if that was lost, it says
                       // the bus went silent (then it is stopped here).
                       "for i in $(seq 1 400); do kill -0 $W 2>/dev/null || break; tail -n 1 watch.txt | grep -q 'no "
                       "rilbed run heard' && break; "
                       "sleep 0.05; done\n"
                       "if kill -0 $W 2>/dev/null; then echo 'watch stopped' >> codes.txt; kill -INT $W; wait $W; "
                       "else wait $W; echo \"watch $?\" >> codes.txt; fi\n"
                       "kill -INT $L; wait $L\n",
                   true);
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  const std::string watch = read_file(dir / "watch.txt");
  ASSERT_NE(codes.find("run 0"), std::string::npos) << codes << read_file(dir / "run.err");
  EXPECT_NE(read_file(dir / "run.txt").find("(ended by formed)"), std::string::npos) << read_file(dir / "run.txt");

  // The loss was there, at about its rate.
  const Loss loss = read_loss(dir / "nft.txt");
  EXPECT_GT(loss.packets, 200) << read_file(dir / "nft.txt");
  EXPECT_GE(loss.rate(), 0.03) << loss.dropped << " of " << loss.packets;
  EXPECT_LE(loss.rate(), 0.20) << loss.dropped << " of " << loss.packets;
  const std::vector<LogEvent> sent = read_lcm_log(dir / "sent.lcm");
  const std::vector<LogEvent> heard = read_lcm_log(dir / "heard.lcm");
  ASSERT_GT(sent.size(), 200u);
  EXPECT_LT(heard.size(), sent.size());
  std::printf("[ loss     ] %ld of %ld packets dropped (%.1f %%); lcm-logger heard %zu of %zu messages\n", loss.dropped,
              loss.packets, 100.0 * loss.rate(), heard.size(), sent.size());

  EXPECT_NE(watch.find("watching convoy_sim on udpm://239.255.76.67:7667?ttl=0: 8 robots (0 real)"), std::string::npos)
      << watch;
  // Every status and event that came through, in order, none twice.
  const std::vector<std::string> statuses = statuses_in_log(heard);
  ASSERT_GT(statuses.size(), 5u);
  EXPECT_EQ(joined(watched_statuses(watch)), joined(statuses)) << watch;
  EXPECT_EQ(joined(watched_events(watch)), joined(shown_events_in_log(heard))) << watch;

  // The end: its status and summary go out three times each, so a watcher hears of it
  // unless all six were lost.
  const bool summary_heard =
      std::any_of(heard.begin(), heard.end(), [](const LogEvent& e) { return e.channel == "RILBED_SUMMARY"; });
  if (statuses.back().find(" ended") != std::string::npos) {
    EXPECT_NE(watch.find("(ended by formed)"), std::string::npos) << watch;
    EXPECT_NE(codes.find("watch 0"), std::string::npos) << codes << watch;
  } else if (summary_heard) {
    // Every ended status was lost, a summary was not: the watcher says so, and ends.
    EXPECT_NE(watch.find("run ended (ended by formed; its last status was not heard)"), std::string::npos) << watch;
    EXPECT_NE(codes.find("watch 0"), std::string::npos) << codes << watch;
    std::printf("[ loss     ] the run's ended statuses were lost; the watcher ended on its summary\n");
  } else {
    // The run's end was lost on the way: the watcher must not pretend it saw it, and must
    // say that the run went silent before its end.
    EXPECT_EQ(watch.find("(ended by"), std::string::npos) << watch;
    const std::size_t silent = watch.rfind("no rilbed run heard on udpm://239.255.76.67:7667?ttl=0 for 1 s");
    EXPECT_NE(silent, std::string::npos) << watch;
    EXPECT_NE(watch.find("the run went silent before its end was heard", silent), std::string::npos) << watch;
    EXPECT_GT(silent, watch.rfind("\nt=")) << watch;
    std::printf("[ loss     ] the run's end was lost; the watcher said the bus went silent\n");
  }
  if (!HasFailure()) fs::remove_all(dir);  // kept to look at when it failed
}

// Console commands across a 10 % loss each way: `rilbed console` sends again until the
// run answers, and the run applies a command that came twice only once. 23 commands are
// accepted (exit 0), each applied once (events.csv); without resending, each would miss
// its answer one time in five and this test would fail nearly always. A wrong token is
// refused, also answered through the loss.
TEST(LcmLoss, ConsoleCommandsAreAnsweredThroughATenPercentLoss) {
  SKIP_WITHOUT_NFT();
  const fs::path dir = scratch_dir("lcm_loss_console");
  std::string factors;
  std::vector<std::string> factor_list;
  for (int k = 0; k < 20; ++k) {
    factor_list.push_back(std::to_string(2 + k / 2) + (k % 2 ? ".5" : ""));
    factors += " " + factor_list.back();
  }
  const int status = in_namespace(dir,
                                  "\"$R\" run " + shipped_scenario_arg("convoy_sim") +
                                      " --realtime --duration 600 --lcm \"$URL\" --out run --quiet "
                                      "> run.txt 2> run.err &\n"
                                      "P=$!\n"
                                      "for i in $(seq 1 400); do [ -s xdg/rilbed/token ] && break; sleep 0.05; done\n"
                                      "set +e\n"
                                      "n=0\n"
                                      "c() { name=$1; shift; n=$((n+1)); \"$R\" console --lcm \"$URL\" --timeout-ms "
                                      "10000 \"$@\" > c_$name.txt 2>&1; "
                                      "echo \"$name $?\" >> codes.txt; }\n"
                                      "c pause pause\n"
                                      "c pause_again pause\n"
                                      "c resume resume\n"
                                      "for f in" +
                                      factors +
                                      "; do c rt_$f rt-factor $f; done\n"
                                      "c badtoken --token 0123456789abcdef pause\n"
                                      "c exit exit\n"
                                      "wait $P; echo \"run $?\" >> codes.txt\n",
                                  true);
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  const std::string run_err = read_file(dir / "run.err");
  const std::string events = read_file(dir / "run" / "events.csv");
  const Loss loss = read_loss(dir / "nft.txt");
  EXPECT_GT(loss.packets, 100) << read_file(dir / "nft.txt");
  EXPECT_GT(loss.dropped, 0) << read_file(dir / "nft.txt");
  EXPECT_GE(loss.rate(), 0.03) << loss.dropped << " of " << loss.packets;
  EXPECT_LE(loss.rate(), 0.20) << loss.dropped << " of " << loss.packets;
  std::printf("[ loss     ] %ld of %ld packets dropped (%.1f %%)\n", loss.dropped, loss.packets, 100.0 * loss.rate());

  for (const char* line : {"pause 0", "pause_again 1", "resume 0", "badtoken 1", "exit 0", "run 0"}) {
    EXPECT_NE(codes.find(std::string(line) + "\n"), std::string::npos) << line << "\n" << codes << run_err;
  }
  EXPECT_NE(read_file(dir / "c_pause.txt").find("accepted: pause"), std::string::npos)
      << read_file(dir / "c_pause.txt");
  EXPECT_NE(read_file(dir / "c_pause_again.txt").find("refused: the run is paused already"), std::string::npos)
      << read_file(dir / "c_pause_again.txt");
  EXPECT_NE(read_file(dir / "c_resume.txt").find("accepted: resume"), std::string::npos);
  EXPECT_NE(read_file(dir / "c_badtoken.txt").find("refused: wrong token"), std::string::npos)
      << read_file(dir / "c_badtoken.txt");
  EXPECT_NE(read_file(dir / "c_exit.txt").find("accepted: exit"), std::string::npos);
  for (const std::string& f : factor_list) {
    EXPECT_NE(codes.find("rt_" + f + " 0\n"), std::string::npos) << f << "\n" << codes;
    EXPECT_NE(read_file(dir / ("c_rt_" + f + ".txt")).find("accepted: rt-factor " + f), std::string::npos) << f;
    // Applied once, however often it came.
    EXPECT_EQ(count_of(events, ",console,0,0,real-time factor " + f + " set by "), 1u) << f << "\n" << events;
  }
  EXPECT_EQ(count_of(events, ",console,0,0,paused by "), 1u) << events;
  EXPECT_EQ(count_of(events, ",console,0,0,resumed by "), 1u) << events;
  EXPECT_EQ(count_of(events, ",console,0,0,refused 'pause' (wrong token) from "), 1u) << events;
  EXPECT_EQ(count_of(events, ",console,0,0,ended by "), 1u) << events;
  EXPECT_NE(read_file(dir / "run.txt").find("ended by console"), std::string::npos) << read_file(dir / "run.txt");
  if (!HasFailure()) fs::remove_all(dir);  // kept to look at when it failed
}

// A watcher that stops reading (SIGSTOP) while a realtime run goes on: its socket fills and
// the kernel drops what does not fit, but the run never waits for it: it runs to its end,
// with its status line every simulated second and its run folder. Continued (SIGCONT),
// the watcher shows what it had and then the run's end, or, when the end did not fit,
// says that no run is heard, and shows the next run to its end.
TEST(LcmLoss, AStalledWatcherNeverHoldsUpTheRun) {
  SKIP_WITHOUT_NAMESPACES();
  const fs::path dir = scratch_dir("lcm_loss_stall");
  const int status = in_namespace(
      dir,
      "\"$R\" watch --lcm \"$URL\" --until-ended --silence 1 --for 120 > watch.txt 2>&1 &\n"
      "W=$!\n"
      "listening 1\n"
      "kill -STOP $W\n"
      "set +e\n"
      // A safety bound only: a run held up by its watcher would hang, and fail here instead.
      "timeout -k 5 120 \"$R\" run " +
          shipped_scenario_arg("convoy_sim") +
          " --realtime --rt-factor 4 --stop-when-formed --seed 1 --lcm \"$URL\" --out run > run.txt 2> run.err\n"
          "echo \"run $?\" >> codes.txt\n"
          "ss -lunm > sockets.txt\n"
          "kill -CONT $W\n"
          "for i in $(seq 1 400); do kill -0 $W 2>/dev/null || break; tail -n 1 watch.txt | grep -q 'no rilbed run "
          "heard' && break; "
          "sleep 0.05; done\n"
          "if kill -0 $W 2>/dev/null; then echo 'missed the end' >> codes.txt; "
          "\"$R\" run " +
          shipped_scenario_arg("wander") +
          " --realtime --rt-factor 4 --duration 2 --lcm \"$URL\" --quiet > run2.txt 2>&1; "
          "echo \"run2 $?\" >> codes.txt; fi\n"
          "wait $W; echo \"watch $?\" >> codes.txt\n",
      false);
  ASSERT_EQ(status, 0) << read_file(dir / "ns.log");
  const std::string codes = read_file(dir / "codes.txt");
  const std::string run = read_file(dir / "run.txt");
  const std::string watch = read_file(dir / "watch.txt");
  // The run ran to its end as without a watcher.
  EXPECT_NE(codes.find("run 0\n"), std::string::npos) << codes << read_file(dir / "run.err");
  EXPECT_NE(run.find("seed 1: formed at"), std::string::npos) << run;
  EXPECT_NE(run.find("(ended by formed)"), std::string::npos) << run;
  EXPECT_TRUE(fs::exists(dir / "run" / "summary.json"));
  EXPECT_NE(read_file(dir / "run" / "summary.json").find("\"formed\": true"), std::string::npos)
      << read_file(dir / "run" / "summary.json");
  // Its own status line every simulated second, from 0 to its end.
  const std::vector<std::string> run_statuses = watched_statuses(run);
  ASSERT_GT(run_statuses.size(), 10u) << run;
  for (std::size_t k = 0; k < run_statuses.size(); ++k) {
    EXPECT_EQ(run_statuses[k].substr(0, run_statuses[k].find(' ')), "t=" + std::to_string(k) + ".0s") << run;
  }
  // The watcher, continued, went on and ended by itself on a run's end.
  EXPECT_NE(codes.find("watch 0\n"), std::string::npos) << codes << watch;
  EXPECT_NE(watch.find("watching convoy_sim on udpm://239.255.76.67:7667?ttl=0: 8 robots (0 real)"), std::string::npos)
      << watch;
  if (codes.find("missed the end") == std::string::npos) {
    EXPECT_NE(watch.find("(ended by formed)"), std::string::npos) << watch;
  } else {
    std::printf("[ stall    ] the stalled watcher's socket overflowed: %s\n", read_file(dir / "sockets.txt").c_str());
    EXPECT_EQ(watch.find("(ended by formed)"), std::string::npos) << watch;
    const std::size_t silent = watch.find("no rilbed run heard on udpm://239.255.76.67:7667?ttl=0 for 1 s");
    EXPECT_NE(silent, std::string::npos) << watch;
    EXPECT_NE(codes.find("run2 0\n"), std::string::npos) << codes << read_file(dir / "run2.txt");
    const std::size_t next = watch.find("watching wander on udpm://239.255.76.67:7667?ttl=0", silent);
    EXPECT_NE(next, std::string::npos) << watch;
    EXPECT_NE(watch.find("(ended by duration)", next == std::string::npos ? 0 : next), std::string::npos) << watch;
  }
  if (!HasFailure()) fs::remove_all(dir);  // kept to look at when it failed
}

}  // namespace
}  // namespace rilbed::e2e
