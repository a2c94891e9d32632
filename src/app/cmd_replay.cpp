// `rilbed replay FILE.lcm`: a recorded run (rilbed run --record) again. With --out it writes
// the run folder from the recording (the same files the run wrote); with --lcm it
// publishes the recording on a bus at the recorded pace (or --speed times it), so that
// `rilbed watch` shows a past run as if it were live.
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "app/commands.hpp"
#include "app/interrupt.hpp"
#include "bus/lcm_bus.hpp"
#include "bus/lcm_log_reader.hpp"
#include "bus/report_decoder.hpp"
#include "run/run_folder_writer.hpp"

namespace rilbed::app {

namespace {

struct ReplayArgs {
  std::string log;
  std::string out;
  std::string lcm_url;
  std::string prefix;
  double speed = 1.0;
  double from_s = 0.0;
  double to_s = 0.0;  // 0: to the end
};

int write_folder(const ReplayArgs& args) {
  bus::LcmLogReader log(args.log);
  if (!log.good()) {
    spdlog::error("replay: cannot read {}", args.log);
    return kExitFailure;
  }
  run::RunFolderWriter writer(args.out);
  bus::RunReportDecoder decoder(bus::Channels::with_prefix(args.prefix), writer);
  long events = 0, bad = 0;
  bool cut_short = false;
  try {
    while (const auto e = log.next()) {
      ++events;
      if (const auto problem = decoder.decode(e->channel, e->data.data(), e->data.size())) {
        if (++bad <= 5) spdlog::warn("replay: {}: event {}: {} (skipped)", args.log, e->eventnum, *problem);
      }
    }
    if (log.skipped_bytes() > 0) {
      spdlog::warn("replay: {}: {} bytes that are not events were skipped{}", args.log, log.skipped_bytes(),
                   log.truncated() ? " (the last event is cut short)" : "");
    }
    if (!writer.finished()) {
      // Cut short (a crash, a full disk, a truncated copy): keep what it holds, and say so.
      spdlog::warn("replay: {} ends before the run did (no summary after {} messages): the folder holds what it has",
                   args.log, events);
      writer.finish_without_summary(decoder.cut_short_summary());
      cut_short = true;
    }
  } catch (const std::exception& e) {
    spdlog::error("replay: {}", e.what());
    return kExitFailure;
  }
  if (events == 0) {
    spdlog::error("replay: {} holds no LCM events", args.log);
    return kExitFailure;
  }
  std::printf("wrote %s from %ld messages of %s%s\n", args.out.c_str(), events, args.log.c_str(),
              bad > 0 ? (" (" + std::to_string(bad) + " bad ones skipped)").c_str() : "");
  // A folder without the run's end is written, but is not a whole run.
  return cut_short ? kExitFailure : 0;
}

int publish(const ReplayArgs& args) {
  bus::LcmLogReader log(args.log);
  if (!log.good()) {
    spdlog::error("replay: cannot read {}", args.log);
    return kExitFailure;
  }
  std::string error;
  std::unique_ptr<lcm::LCM> lcm = bus::open_lcm(args.lcm_url, error);
  if (!lcm) {
    spdlog::error("replay: {}", error);
    return kExitFailure;
  }
  const InterruptFlag interrupt;
  std::int64_t first_us = -1;
  const auto start = std::chrono::steady_clock::now();
  long published = 0;
  while (const auto e = log.next()) {
    if (interrupt.raised()) break;
    if (first_us < 0) first_us = e->timestamp_us;
    const double at_s = static_cast<double>(e->timestamp_us - first_us) * 1e-6;
    if (at_s < args.from_s) continue;
    if (args.to_s > 0.0 && at_s > args.to_s) break;
    // The recorded pace, from --from on, divided by --speed; absolute deadlines, no drift.
    const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>((at_s - args.from_s) / args.speed));
    std::this_thread::sleep_until(due);
    if (lcm->publish(e->channel, e->data.data(), static_cast<unsigned>(e->data.size())) == 0) ++published;
  }
  std::printf("published %ld messages of %s on %s\n", published, args.log.c_str(), args.lcm_url.c_str());
  return published > 0 ? 0 : kExitFailure;
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd =
      app.add_subcommand("replay", "A recorded run again: its run folder (--out), or published on a bus (--lcm)");
  cmd->add_option("log", args->log, "LCM log written by rilbed run --record")->required()->check(CLI::ExistingFile);
  auto* out = cmd->add_option("--out", args->out, "Write the run folder here (as the run wrote it)");
  auto* url = cmd->add_option("--lcm", args->lcm_url, "Publish the recording on this LCM bus at the recorded pace");
  out->excludes(url);
  cmd->add_option("--channel-prefix", args->prefix, "The recorded run's channel prefix (with --out)");
  cmd->add_option("--speed", args->speed, "With --lcm: this many times the recorded pace")
      ->check(CLI::PositiveNumber)
      ->needs(url);
  cmd->add_option("--from", args->from_s, "With --lcm: start this many seconds into the recording")
      ->check(CLI::NonNegativeNumber)
      ->needs(url);
  cmd->add_option("--to", args->to_s, "With --lcm: stop this many seconds into the recording")
      ->check(CLI::PositiveNumber)
      ->needs(url);
  cmd->callback([args, out, url] {
    if (out->count() == 0 && url->count() == 0) {
      spdlog::error("replay: give --out DIR (write the run folder) or --lcm URL (publish it)");
      exit_code() = kExitUsage;
      return;
    }
    exit_code() = out->count() > 0 ? write_folder(*args) : publish(*args);
  });
}

}  // namespace rilbed::app
