// rilbed's web server: HTTP for the page and a WebSocket (/ws) speaking the Foxglove
// WebSocket protocol, on a Boost.Asio io_context with one thread of its own (as each serial
// link and the LCM console server have). It knows nothing of runs: whoever owns it adds
// channels and publishes on them (any thread, never blocking), and hears what clients
// publish on theirs. The GUI bridge (LCM in, console commands out) is one such owner.
//
// Safety of the door: every request, page or WebSocket, needs the token (`?token=`,
// compared in constant time; 401 otherwise); a browser's WebSocket must come from the
// server's own page (its Origin, when it sends one, must be this server or one allowed);
// the server binds to 127.0.0.1 unless told otherwise.
//
// Slow viewers: each client has a bounded send queue. When a client does not keep up, the
// oldest queued data messages are dropped (newest state wins) and it is told once per
// second in a status message; it never slows the publisher or the other clients.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gui_web/foxglove_protocol.hpp"

namespace rilbed::gui_web {

/// A document the server keeps in memory and serves at its path beside the page's files
/// (the controllers' JSON, which the page's editor builds its lists from).
struct ServedDocument {
  std::string content_type;  ///< e.g. "application/json"
  std::string body;
};

/// How the server listens and what it allows; each knob says what it costs.
struct WebServerConfig {
  std::string bind_address = "127.0.0.1";    ///< anything else opens the run to the network
  std::uint16_t port = 8080;                 ///< 0: any free port (tests; port() tells which)
  std::string token;                         ///< required on every request; must not be empty
  std::string name = "rilbed";               ///< serverInfo's name
  std::string session_id;                    ///< serverInfo's sessionId (a run)
  std::filesystem::path web_root;            ///< the page's files; empty: no page, only /ws
  std::size_t max_queued_bytes = 8u << 20;   ///< per client; more memory lets a slow client lag longer
  std::size_t max_message_bytes = 1u << 20;  ///< largest message a client may send; larger closes its socket (1009)
  std::vector<std::string>
      allowed_origins;  ///< Origins allowed besides the server's own, e.g. "https://app.foxglove.dev"
  /// Documents served at their paths ("/controllers.json"), under the same token as the
  /// page's files, even without a web root; their memory is held while the server runs.
  std::map<std::string, ServedDocument> documents;
};

/// What the server counted (all clients together).
struct WebServerCounters {
  std::uint64_t connections = 0;          ///< WebSocket clients accepted
  std::uint64_t refused = 0;              ///< requests refused: token, Origin, subprotocol, method
  std::uint64_t messages_sent = 0;        ///< data messages queued to clients
  std::uint64_t messages_dropped = 0;     ///< data messages dropped for clients that did not keep up
  std::uint64_t bad_client_messages = 0;  ///< client messages answered with an error status
};

/// The web server. Thread-safe; runs until destroyed.
class WebServer {
 public:
  /// What clients do that the owner hears, on the server's thread (quick, never blocking).
  struct Handlers {
    /// A client published `payload` on its channel `topic` (advertised with `encoding`).
    /// Returns an error for the client (a status message), or nullopt.
    std::function<std::optional<std::string>(const std::string& client, const std::string& topic,
                                             const std::string& encoding, std::string_view payload)>
        on_client_message;
    /// A client's socket closed (for a dead man's switch).
    std::function<void(const std::string& client)> on_client_gone;
    /// A client asks to set parameters (setParameters, with its request id if any). The
    /// owner tries them and answers with answer_parameters(), and set_parameters() for
    /// what changed. Null: the server has no parameters ("parameters" and
    /// "parametersSubscribe" are not among its capabilities).
    std::function<void(const std::string& client, const std::vector<foxglove::Parameter>& parameters,
                       const std::optional<std::string>& id)>
        on_set_parameters;
  };

  /// Binds and starts serving. Throws std::invalid_argument for an empty token and
  /// std::runtime_error naming the address when it cannot listen.
  WebServer(WebServerConfig config, Handlers handlers);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// The port it listens on.
  std::uint16_t port() const;
  /// Offers a channel to every client, present and future; returns its id (from 1). A
  /// `latched` channel's last message is sent to each client as it subscribes (the run's
  /// world and status, for a viewer joining a paused run); costs one message's memory.
  std::uint32_t add_channel(foxglove::Channel channel, bool latched = false);
  /// The latest message of a latched channel, built when asked (on the server's thread):
  /// its time in ns and payload, or null when the last one published is still the latest.
  using LatchSource = std::function<std::shared_ptr<const std::string>(std::uint64_t& t_ns)>;
  /// For a latched channel whose owner publishes only while someone subscribes (see
  /// subscribed()): asked for the latest message as each client subscribes. Must be
  /// thread-safe against the owner; set before clients come.
  void set_latch_source(std::uint32_t channel, LatchSource source);
  /// Whether any client subscribes to `channel` now (any thread; a mutex, tens of ns):
  /// lets the owner skip building messages nobody gets.
  bool subscribed(std::uint32_t channel) const;
  /// Sends `payload` on `channel` to every client subscribed to it, stamped `t_ns`. Never
  /// blocks: the message is queued on the server's thread.
  void publish(std::uint32_t channel, std::uint64_t t_ns, std::shared_ptr<const std::string> payload);
  /// Waits until everything published so far has been written to every client (or
  /// dropped for one that did not keep up), at most `timeout`; returns whether it was.
  bool flush(std::chrono::milliseconds timeout);
  /// The parameters' current values, replacing those of the same names (a null value
  /// removes one); each client subscribed to one that changed gets a parameterValues.
  /// getParameters is answered from these. Never blocks.
  void set_parameters(std::vector<foxglove::Parameter> values);
  /// Sends one client (by the name Handlers get) the current values of `names` (every
  /// parameter when empty; unknown names left out) with its request's `id`: the answer
  /// to a setParameters, after any set_parameters() made before this call.
  void answer_parameters(const std::string& client, std::vector<std::string> names, std::optional<std::string> id);
  /// Sends a status message to one client (by the name Handlers get), if still there.
  void tell(const std::string& client, foxglove::Level level, const std::string& message);
  /// Clients connected now.
  std::size_t clients() const;
  WebServerCounters counters() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

/// The nice value of the threads that serve viewers (the web server's, the channels'):
/// on a busy machine the run's control loop gets the CPU first, and a viewer gets what is
/// left (loop latency p99 with 50 viewers of a 100-robot run on 2 cores: see bench_gui).
inline constexpr int kViewerThreadNice = 10;

/// Lowers the calling thread to kViewerThreadNice (Linux: this thread alone).
void yield_to_control_loop();

/// Whether `a` equals `b`, in a time that depends only on their lengths.
bool same_secret(std::string_view a, std::string_view b);

}  // namespace rilbed::gui_web
