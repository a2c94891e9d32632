// rilbed web panel benchmark: what viewers of a run cost it and what they get.
//
// A real-time run (factor 1) of N wandering Kheperas (sim-bench's scenario, 100 by default)
// is published as `rilbed run --gui` publishes it: on the in-process LCM bus, the panel's
// GuiService a local subscriber of the very bytes, its WebServer on a loopback port. V
// viewers connect to it as browsers do (the Foxglove WebSocket protocol, token in the URL)
// and subscribe to the channels rilbed's page subscribes to; they are Beast WebSocket
// clients on one thread of this process, reading as fast as the socket gives. For each
// viewer count the table gives:
//   - poses messages (the live view's frames) and all messages delivered per second to each
//     viewer, the slowest viewer and the median one, over the run's wall time;
//   - WebSocket bytes per second per viewer (frames' payloads and headers, median viewer);
//   - messages the server dropped for viewers that did not keep up;
//   - the run's loop latency: how far behind the wall clock each 100 ms control step
//     finished with its reports handed on (RunResult::loop_latency_ms), p50 and p99 over
//     every step of every repeat, and the most;
//   - the process's CPU time per wall second (all threads: the run, the server, the viewers).
// "no panel" is the run with its bus and no web server at all; "0" has the server and no
// viewer. Configurations take turns within each repeat, so that other load on the machine
// falls on all alike. Printed, never asserted: a report, not a test.
//
// Usage: bench_gui [--robots 100] [--seconds 10] [--viewers 0,1,10,50] [--repeat 3]
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "bus/lcm_bus.hpp"
#include "bus/run_publisher.hpp"
#include "core/id_list.hpp"
#include "core/statistics.hpp"
#include "gui_web/gui_service.hpp"
#include "machine.hpp"
#include "run/scenario.hpp"
#include "run/simulation.hpp"

namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using nlohmann::json;
using namespace rilbed;
using bench::cpu_model;
using bench::env_or;
using bench::first_line;

const std::string kToken = "bench";
// What rilbed's page subscribes to (web/app.js).
const std::set<std::string> kPageTopics = {
    "/rilbed/world",  "/rilbed/status",  "/rilbed/poses",         "/rilbed/sensors", "/rilbed/detections",
    "/rilbed/events", "/rilbed/summary", "/rilbed/console_reply", "/rilbed/camera",  "/rilbed/camera_calibration"};

// One viewer: connects, subscribes to the page's topics, counts what comes. Async on the
// viewers' shared io_context.
class Viewer : public std::enable_shared_from_this<Viewer> {
 public:
  explicit Viewer(asio::io_context& io) : ws_(io) {}
  void start(std::uint16_t port) {
    tcp::resolver resolver(ws_.get_executor());
    beast::get_lowest_layer(ws_).connect(resolver.resolve("127.0.0.1", std::to_string(port)));
    ws_.set_option(websocket::stream_base::decorator([](websocket::request_type& r) {
      r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
    }));
    ws_.handshake("127.0.0.1:" + std::to_string(port), "/ws?token=" + kToken);
    read();
  }
  void close() {
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
  }
  std::uint64_t poses = 0, messages = 0, bytes = 0;

 private:
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t n) {
      if (ec) return;
      self->bytes += n + 4;  // the WebSocket frame's header: 2 bytes, 4 from 126 bytes of payload on
      self->on_message();
      self->buffer_.consume(self->buffer_.size());
      self->read();
    });
  }
  void on_message() {
    const std::string data = beast::buffers_to_string(buffer_.data());
    if (ws_.got_binary()) {
      if (data.size() < 5) return;
      std::uint32_t sub = 0;
      for (int i = 0; i < 4; ++i) sub |= static_cast<std::uint32_t>(static_cast<unsigned char>(data[1 + i])) << (8 * i);
      ++messages;
      if (sub == poses_subscription_) ++poses;
      return;
    }
    const json j = json::parse(data, nullptr, false);
    if (j.is_discarded() || j.value("op", "") != "advertise") return;
    json subscriptions = json::array();
    for (const auto& c : j["channels"]) {
      const std::string topic = c["topic"].get<std::string>();
      if (!kPageTopics.contains(topic)) continue;
      const std::uint32_t id = next_subscription_++;
      if (topic == "/rilbed/poses") poses_subscription_ = id;
      subscriptions.push_back({{"id", id}, {"channelId", c["id"]}});
    }
    if (subscriptions.empty()) return;
    // Written synchronously from the read's handler: the only write this viewer makes.
    ws_.text(true);
    ws_.write(asio::buffer(json{{"op", "subscribe"}, {"subscriptions", subscriptions}}.dump()));
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  std::uint32_t next_subscription_ = 1;
  std::uint32_t poses_subscription_ = 0;
};

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// One configuration's measurements over the repeats.
struct Measured {
  std::vector<double> latency_ms;   // every step of every repeat
  std::vector<double> poses_per_s;  // every viewer of every repeat
  std::vector<double> messages_per_s;
  std::vector<double> bytes_per_s;
  std::uint64_t dropped = 0;
  std::vector<double> cpu_per_wall;  // per repeat
};

// One run with `viewers` viewers (nullopt: no panel at all).
void run_once(const run::Scenario& scenario, std::optional<int> viewers, double seconds, Measured& out) {
  std::string error;
  auto lcm = bus::open_lcm("memq://", error);
  if (!lcm) throw std::runtime_error(error);
  bus::LcmRunPublisher::Options po;
  po.in_process = true;
  bus::LcmRunPublisher publisher(*lcm, bus::Channels{}, po);
  std::unique_ptr<gui_web::GuiService> gui;
  asio::io_context io;
  std::vector<std::shared_ptr<Viewer>> clients;
  std::thread viewer_thread;
  if (viewers) {
    gui_web::WebServerConfig config;
    config.port = 0;
    config.token = kToken;
    config.session_id = "bench";
    gui = std::make_unique<gui_web::GuiService>(config, [](const gui_web::ConsoleRequest&) {
      return gui_web::ConsoleAnswer{false, "a benchmark takes no commands"};
    });
    publisher.add_local_subscriber(*gui);
    for (int k = 0; k < *viewers; ++k) {
      clients.push_back(std::make_shared<Viewer>(io));
      clients.back()->start(gui->server().port());
    }
    viewer_thread = std::thread([&io] {
      auto guard = asio::make_work_guard(io);
      io.run();
    });
    // Every viewer has subscribed (the server counts the connections; give the subscribe
    // messages a moment to be read: at worst the first message or two is missed).
    while (gui->server().clients() < static_cast<std::size_t>(*viewers))
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  run::RunOptions o;
  o.seed = 1;
  o.duration_s = seconds;
  o.realtime = true;
  o.rt_factor = 1.0;
  o.observer = &publisher;
  const double cpu0 = process_cpu_s();
  const run::RunResult r = run::run_scenario(scenario, o);
  const double cpu = process_cpu_s() - cpu0;
  out.cpu_per_wall.push_back(cpu / r.run_wall_s);
  out.latency_ms.insert(out.latency_ms.end(), r.loop_latency_ms.begin(), r.loop_latency_ms.end());
  if (gui) gui->flush(std::chrono::seconds(2));
  io.stop();
  if (viewer_thread.joinable()) viewer_thread.join();
  for (auto& c : clients) c->close();  // the viewers' thread has ended
  for (const auto& c : clients) {
    out.poses_per_s.push_back(static_cast<double>(c->poses) / r.run_wall_s);
    out.messages_per_s.push_back(static_cast<double>(c->messages) / r.run_wall_s);
    out.bytes_per_s.push_back(static_cast<double>(c->bytes) / r.run_wall_s);
  }
  if (gui) out.dropped += gui->server().counters().messages_dropped;
}

double min_of(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }
double max_of(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("rilbed web panel benchmark");
  int robots = 100;
  double seconds = 10.0;
  std::string viewer_list = "0,1,10,50";
  int repeat = 3;
  app.add_option("--robots", robots, "Robots in the run")->check(CLI::PositiveNumber);
  app.add_option("--seconds", seconds, "Simulated (= wall) seconds per run")->check(CLI::PositiveNumber);
  app.add_option("--viewers", viewer_list, "Viewer counts to measure, besides the run without a panel");
  app.add_option("--repeat", repeat, "Runs per configuration (taking turns)")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  const auto counts = parse_id_list(viewer_list, 0, 1000);
  if (!counts.ok()) {
    std::fprintf(stderr, "--viewers: %s\n", counts.error.c_str());
    return 2;
  }
  std::vector<std::optional<int>> configs{std::nullopt};
  for (int v : counts.ids) configs.emplace_back(v);

  const run::Scenario scenario = run::wandering_scenario(robots, seconds);
  std::printf("# rilbed web panel benchmark\n\n");
  std::printf("- CPU: %s; `nproc`: %d; load average at start: %s\n", cpu_model().c_str(), bench::usable_cpus(),
              first_line("/proc/loadavg").c_str());
  std::printf("- build type: %s; sources: %s\n",
              env_or("RILBED_BENCH_BUILD_TYPE", "unknown (run through tools/bench.sh)").c_str(),
              env_or("RILBED_BENCH_SOURCE", "unknown (run through tools/bench.sh)").c_str());
  std::printf(
      "- the run: %d wandering Kheperas with 8 IR sensors (sim-bench's scenario, field %.2f x %.2f m), control "
      "period 100 ms, real time at factor 1, %.0f s per run, %d runs per configuration taking turns; published "
      "on memq:// as `rilbed run --gui` publishes, the panel's GuiService a local subscriber of the bytes\n",
      robots, scenario.map.field.width_m, scenario.map.field.height_m, seconds, repeat);
  std::printf(
      "- viewers: Beast WebSocket clients on one thread of this process, over loopback, each subscribed to the "
      "page's %zu topics (world, status, poses, sensors, detections, events, summary, console replies; this run "
      "has no camera), reading as fast as they can\n",
      kPageTopics.size());
  std::printf(
      "- loop latency: how far behind the wall clock each control step finished, its reports handed on "
      "(summary.json's loop_latency_ms); p50 and p99 over every step of every run of the configuration\n\n");
  std::fflush(stdout);

  std::map<int, Measured> measured;  // -1: no panel
  for (int rep = 0; rep < repeat; ++rep) {
    for (const auto& c : configs) {
      run_once(scenario, c, seconds, measured[c.value_or(-1)]);
    }
  }

  std::printf(
      "| viewers | poses msgs/s per viewer (slowest, median) | all msgs/s per viewer (median) | KB/s per viewer "
      "(median) | msgs dropped | loop latency p50 ms | p99 ms | max ms | steps | process CPU s per wall s |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  for (const auto& c : configs) {
    const Measured& m = measured[c.value_or(-1)];
    const std::string name = c ? std::to_string(*c) : std::string("no panel");
    const bool any = !m.poses_per_s.empty();
    char delivered[64] = "—", all[32] = "—", kb[32] = "—";
    if (any) {
      std::snprintf(delivered, sizeof delivered, "%.2f, %.2f", min_of(m.poses_per_s), percentile(m.poses_per_s, 0.5));
      std::snprintf(all, sizeof all, "%.1f", percentile(m.messages_per_s, 0.5));
      std::snprintf(kb, sizeof kb, "%.1f", percentile(m.bytes_per_s, 0.5) / 1000.0);
    }
    std::printf("| %s | %s | %s | %s | %llu | %.3f | %.3f | %.3f | %zu | %.2f |\n", name.c_str(), delivered, all, kb,
                static_cast<unsigned long long>(m.dropped), percentile(m.latency_ms, 0.5),
                percentile(m.latency_ms, 0.99), max_of(m.latency_ms), m.latency_ms.size(),
                percentile(m.cpu_per_wall, 0.5));
  }
  // The goal: 10 viewers cost the run within 5 % of none.
  if (measured.contains(0) && measured.contains(10)) {
    const Measured& none = measured[0];
    const Measured& ten = measured[10];
    const auto change = [](double a, double b) { return a > 0.0 ? 100.0 * (b - a) / a : 0.0; };
    std::printf(
        "\nLoop latency with 10 viewers against none (goal: within 5 %%): p50 %+.1f %% (%.3f -> %.3f ms), "
        "p99 %+.1f %% (%.3f -> %.3f ms).\n",
        change(percentile(none.latency_ms, 0.5), percentile(ten.latency_ms, 0.5)), percentile(none.latency_ms, 0.5),
        percentile(ten.latency_ms, 0.5), change(percentile(none.latency_ms, 0.99), percentile(ten.latency_ms, 0.99)),
        percentile(none.latency_ms, 0.99), percentile(ten.latency_ms, 0.99));
  }
  return 0;
}
