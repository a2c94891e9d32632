#include "gui_web/web_server.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <array>
#include <chrono>
#include <deque>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace rilbed::gui_web {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

void yield_to_control_loop() {
  // setpriority on a thread's id changes that thread alone (Linux); raising one's own nice
  // value needs no privilege. Failing leaves it as it was: nothing else depends on it.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), kViewerThreadNice);
}

bool same_secret(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max<std::size_t>(b.size(), 1);
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ (b.empty() ? 0 : b[i % n]));
  return diff == 0 && !b.empty();
}

namespace {

// How long a stopping server waits for its clients to answer its close frame.
constexpr std::chrono::milliseconds kCloseWait{500};

std::string_view sv(beast::string_view v) { return {v.data(), v.size()}; }

// "/ws?token=abc&x=1" -> path "/ws", the token's value.
struct Target {
  std::string path;
  std::string token;
};

Target parse_target(std::string_view target) {
  Target t;
  const std::size_t q = target.find('?');
  t.path = std::string(target.substr(0, q));
  if (q == std::string_view::npos) return t;
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const std::size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    if (pair.rfind("token=", 0) == 0) t.token = std::string(pair.substr(6));
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return t;
}

// The value of cookie `name` in a Cookie header ("a=1; b=2"), or "".
std::string cookie_value(std::string_view header, const std::string& name) {
  while (!header.empty()) {
    const std::size_t semi = header.find(';');
    std::string_view item = header.substr(0, semi);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    if (item.size() > name.size() && item.substr(0, name.size()) == name && item[name.size()] == '=') {
      return std::string(item.substr(name.size() + 1));
    }
    if (semi == std::string_view::npos) break;
    header.remove_prefix(semi + 1);
  }
  return {};
}

std::string content_type(const std::filesystem::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  return "application/octet-stream";
}

// The client offered the Foxglove subprotocol (the header is a comma-separated list).
bool offers_subprotocol(std::string_view header) {
  while (!header.empty()) {
    const std::size_t comma = header.find(',');
    std::string_view item = header.substr(0, comma);
    while (!item.empty() && (item.front() == ' ' || item.front() == '\t')) item.remove_prefix(1);
    while (!item.empty() && (item.back() == ' ' || item.back() == '\t')) item.remove_suffix(1);
    if (item == foxglove::kSubprotocol) return true;
    if (comma == std::string_view::npos) break;
    header.remove_prefix(comma + 1);
  }
  return false;
}

}  // namespace

class WsSession;

struct WebServer::Impl {
  WebServerConfig config;
  Handlers handlers;
  asio::io_context io;
  tcp::acceptor acceptor{io};
  std::thread thread;
  std::uint16_t port = 0;
  mutable std::mutex mutex;                 // guards channels and counters
  std::vector<foxglove::Channel> channels;  // every channel offered, in id order
  WebServerCounters counts;
  std::set<std::shared_ptr<WsSession>> sessions;                  // the server's thread only
  std::set<std::uint32_t> latched;                                // guarded by mutex
  std::map<std::uint32_t, int> subscribers;                       // clients subscribed, by channel; guarded by mutex
  std::map<std::uint32_t, WebServer::LatchSource> latch_sources;  // set before clients come
  // The last message of each latched channel (the server's thread only).
  std::map<std::uint32_t, std::pair<std::uint64_t, std::shared_ptr<const std::string>>> latest;
  std::atomic<std::size_t> client_count{0};
  // Shutting down: the clients were sent a close frame; the timer ends the wait for them.
  bool stopping = false;  // the server's thread only
  asio::steady_timer stop_timer{io};
  // The parameters' current values, by name (the server's thread only).
  std::map<std::string, nlohmann::json> parameters;

  std::vector<std::string> capabilities() const {
    std::vector<std::string> c{"clientPublish"};
    if (handlers.on_set_parameters) {
      c.push_back("parameters");
      c.push_back("parametersSubscribe");
    }
    return c;
  }
  // The current values of `names` (every parameter when empty; unknown names left out).
  std::vector<foxglove::Parameter> parameter_values(const std::vector<std::string>& names) const {
    std::vector<foxglove::Parameter> out;
    if (names.empty()) {
      for (const auto& [name, value] : parameters) out.push_back({name, value});
    }
    for (const std::string& name : names) {
      if (const auto it = parameters.find(name); it != parameters.end()) out.push_back({name, it->second});
    }
    return out;
  }

  void count(std::uint64_t WebServerCounters::*field, std::uint64_t n = 1) {
    std::lock_guard lock(mutex);
    counts.*field += n;
  }
  std::vector<foxglove::Channel> channels_now() const {
    std::lock_guard lock(mutex);
    return channels;
  }
  bool has_channel(std::uint32_t id) const {
    std::lock_guard lock(mutex);
    return id >= 1 && id <= channels.size();
  }
  // The Origin a browser sends with the WebSocket: this server's own page (the Origin is
  // the host the browser asked for, on this port), or one allowed.
  bool origin_allowed(std::string_view origin, std::string_view host) const {
    if (origin.empty()) return true;  // not a browser (a program: FoxgloveClient in Node, a test)
    if (!host.empty() && origin == "http://" + std::string(host)) return true;
    for (const std::string& allowed : config.allowed_origins) {
      if (origin == allowed) return true;
    }
    const std::string p = ":" + std::to_string(port);
    for (const std::string& host :
         {std::string("127.0.0.1"), std::string("localhost"), std::string("[::1]"), config.bind_address}) {
      if (origin == "http://" + host + p) return true;
    }
    return false;
  }
  void accept();
  void remove(const std::shared_ptr<WsSession>& s);
  void count_subscriber(std::uint32_t channel, int change) {
    std::lock_guard lock(mutex);
    if ((subscribers[channel] += change) <= 0) subscribers.erase(channel);
  }
};

// One WebSocket client: its subscriptions, its channels, its send queue.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, WebServer::Impl& server) : ws_(std::move(socket)), server_(server) {
    beast::error_code ec;
    const auto remote = beast::get_lowest_layer(ws_).socket().remote_endpoint(ec);
    name_ = ec ? std::string("client") : remote.address().to_string() + ":" + std::to_string(remote.port());
  }
  const std::string& name() const { return name_; }
  // The channels it subscribes to, for the server's counts when it goes.
  std::vector<std::uint32_t> subscribed_channels() const {
    std::vector<std::uint32_t> out;
    for (const auto& [channel, sub] : channel_to_sub_) out.push_back(channel);
    return out;
  }
  // Nothing queued or being written.
  bool idle() const { return queue_.empty() && !writing_; }
  // A status message for this client alone.
  void tell(foxglove::Level level, const std::string& message) { send_text(foxglove::status(level, message)); }

  void start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& r) {
      r.set(http::field::sec_websocket_protocol, std::string(foxglove::kSubprotocol));
      r.set(http::field::server, "rilbed");
    }));
    ws_.read_message_max(server_.config.max_message_bytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return self->close();
      self->accepted_ = true;
      if (self->going_away_) return self->send_close();  // the server began to stop meanwhile
      self->send_text(foxglove::server_info(self->server_.config.name, self->server_.capabilities(), {"json"},
                                            self->server_.config.session_id));
      const auto channels = self->server_.channels_now();
      self->send_text(foxglove::advertise(channels));
      self->read();
    });
  }

  void advertise(const foxglove::Channel& c) { send_text(foxglove::advertise(std::span(&c, 1))); }

  // A data message on `channel`, if this client subscribed to it.
  void offer(std::uint32_t channel, std::uint64_t t_ns, const std::shared_ptr<const std::string>& payload) {
    const auto it = channel_to_sub_.find(channel);
    if (it == channel_to_sub_.end()) return;
    Out o;
    o.binary = true;
    o.header = foxglove::message_data_header(it->second, t_ns);
    o.payload = payload;
    o.bytes = 13 + payload->size();
    make_room(o.bytes);
    queued_bytes_ += o.bytes;
    queue_.push_back(std::move(o));
    server_.count(&WebServerCounters::messages_sent);
    write();
  }

  // The server stops: what is queued is dropped (the run flushed its end before), and
  // once the message being written, if any, is out, the client gets a close frame (1001,
  // going away) and the connection closes when the client answers it. So a client sees a
  // clean close, not a lost connection. One still in its handshake gets the close frame
  // when the handshake is done.
  void go_away() {
    if (closed_ || going_away_) return;
    going_away_ = true;
    if (!accepted_) return;
    while (queue_.size() > (writing_ ? 1u : 0u)) {
      queued_bytes_ -= queue_.back().bytes;
      queue_.pop_back();
    }
    if (!writing_) send_close();
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
    server_.remove(shared_from_this());
  }

 private:
  struct Out {
    bool binary = false;
    std::shared_ptr<const std::string> text;
    std::array<std::uint8_t, 13> header{};
    std::shared_ptr<const std::string> payload;
    std::size_t bytes = 0;
  };

  void send_text(std::string text) {
    Out o;
    o.bytes = text.size();
    o.text = std::make_shared<const std::string>(std::move(text));
    queued_bytes_ += o.bytes;
    queue_.push_back(std::move(o));  // never dropped: control messages are small and few
    write();
  }

  // Drops the oldest data messages (not the one being written) until `bytes` more fit:
  // a client that does not keep up sees the newest state, late.
  void make_room(std::size_t bytes) {
    std::size_t dropped = 0;
    for (auto it = queue_.begin() + (writing_ ? 1 : 0);
         it != queue_.end() && queued_bytes_ + bytes > server_.config.max_queued_bytes;) {
      if (!it->binary) {
        ++it;
        continue;
      }
      queued_bytes_ -= it->bytes;
      it = queue_.erase(it);
      ++dropped;
    }
    if (dropped == 0) return;
    server_.count(&WebServerCounters::messages_dropped, dropped);
    const auto now = std::chrono::steady_clock::now();
    if (now - last_drop_status_ >= std::chrono::seconds(1)) {
      last_drop_status_ = now;
      send_text(foxglove::status(foxglove::Level::kWarning,
                                 "Send buffer limit reached: this client does not keep up, "
                                 "older messages were dropped",
                                 "slow"));
    }
  }

  void send_close() {
    ws_.async_close(websocket::close_reason(websocket::close_code::going_away, "the server stops"),
                    [self = shared_from_this()](beast::error_code) { self->close(); });
  }

  void write() {
    if (writing_ || queue_.empty() || closed_ || going_away_) return;
    writing_ = true;
    Out& o = queue_.front();
    auto done = [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (ec) return self->close();
      self->queued_bytes_ -= self->queue_.front().bytes;
      self->queue_.pop_front();
      if (self->going_away_) return self->send_close();  // (a close is a write: after this one)
      self->write();
    };
    if (o.binary) {
      ws_.binary(true);
      const std::array<asio::const_buffer, 2> buffers = {asio::buffer(o.header), asio::buffer(*o.payload)};
      ws_.async_write(buffers, std::move(done));
    } else {
      ws_.text(true);
      ws_.async_write(asio::buffer(*o.text), std::move(done));
    }
  }

  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();  // closed, or a message over max_message_bytes (closed with 1009)
      const auto data = self->buffer_.cdata();
      const std::span<const std::uint8_t> bytes(static_cast<const std::uint8_t*>(data.data()), data.size());
      if (self->ws_.got_text()) {
        self->on_text(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
      } else {
        self->on_binary(bytes);
      }
      self->buffer_.consume(self->buffer_.size());
      self->read();
    });
  }

  void refuse(foxglove::Level level, const std::string& why) {
    server_.count(&WebServerCounters::bad_client_messages);
    send_text(foxglove::status(level, why));
  }

  void on_text(std::string_view text) {
    auto parsed = foxglove::parse_client_text(text);
    if (auto* why = std::get_if<std::string>(&parsed)) return refuse(foxglove::Level::kError, *why);
    std::visit([this](const auto& m) { handle(m); }, std::get<foxglove::ClientText>(parsed));
  }

  void handle(const foxglove::Subscribe& m) {
    for (const auto& s : m.subscriptions) {
      if (!server_.has_channel(s.channel_id)) {
        refuse(foxglove::Level::kWarning,
               "Channel " + std::to_string(s.channel_id) + " is not available; ignoring subscription");
      } else if (sub_to_channel_.contains(s.id)) {
        refuse(foxglove::Level::kError,
               "Client subscription id " + std::to_string(s.id) + " was already used; ignoring subscription");
      } else if (channel_to_sub_.contains(s.channel_id)) {
        refuse(foxglove::Level::kWarning,
               "Client already subscribed to channel " + std::to_string(s.channel_id) + "; ignoring subscription");
      } else {
        sub_to_channel_[s.id] = s.channel_id;
        channel_to_sub_[s.channel_id] = s.id;
        server_.count_subscriber(s.channel_id, +1);
        if (const auto source = server_.latch_sources.find(s.channel_id); source != server_.latch_sources.end()) {
          std::uint64_t t_ns = 0;
          if (auto latest = source->second(t_ns)) server_.latest[s.channel_id] = {t_ns, std::move(latest)};
        }
        if (const auto it = server_.latest.find(s.channel_id); it != server_.latest.end()) {
          offer(s.channel_id, it->second.first, it->second.second);
        }
      }
    }
  }
  void handle(const foxglove::Unsubscribe& m) {
    for (const std::uint32_t id : m.subscription_ids) {
      const auto it = sub_to_channel_.find(id);
      if (it == sub_to_channel_.end()) {
        refuse(foxglove::Level::kWarning,
               "Client subscription id " + std::to_string(id) + " did not exist; ignoring unsubscription");
        continue;
      }
      channel_to_sub_.erase(it->second);
      server_.count_subscriber(it->second, -1);
      sub_to_channel_.erase(it);
    }
  }
  void handle(const foxglove::ClientAdvertise& m) {
    for (const auto& c : m.channels) {
      if (client_channels_.contains(c.id)) {
        refuse(foxglove::Level::kError, "Channel " + std::to_string(c.id) + " was already advertised");
      } else if (c.encoding != "json") {
        refuse(foxglove::Level::kError,
               "Channel " + std::to_string(c.id) + ": encoding '" + c.encoding + "' is not supported (json is)");
      } else if (client_channels_.size() >= foxglove::kMaxItems) {
        refuse(foxglove::Level::kError, "Too many client channels");
      } else {
        client_channels_[c.id] = c;
      }
    }
  }
  void handle(const foxglove::ClientUnadvertise& m) {
    for (const std::uint32_t id : m.channel_ids) client_channels_.erase(id);
  }
  void handle(const foxglove::GetParameters& m) {
    if (!server_.handlers.on_set_parameters) {
      return refuse(foxglove::Level::kError,
                    "Operation 'getParameters' not supported as server capability 'parameters' is missing");
    }
    answer_parameters(m.names, m.id);
  }
  void handle(const foxglove::SetParameters& m) {
    if (!server_.handlers.on_set_parameters) {
      return refuse(foxglove::Level::kError,
                    "Operation 'setParameters' not supported as server capability 'parameters' is missing");
    }
    // The owner answers (answer_parameters) once it has tried them.
    server_.handlers.on_set_parameters(name_, m.parameters, m.id);
  }
  void handle(const foxglove::SubscribeParameterUpdates& m) {
    if (!server_.handlers.on_set_parameters) {
      return refuse(
          foxglove::Level::kError,
          "Operation 'subscribeParameterUpdates' not supported as server capability 'parametersSubscribe' is missing");
    }
    for (const std::string& name : m.names) {
      if (parameter_subscriptions_.size() >= foxglove::kMaxItems)
        return refuse(foxglove::Level::kError, "Too many parameter subscriptions");
      parameter_subscriptions_.insert(name);
    }
  }
  void handle(const foxglove::UnsubscribeParameterUpdates& m) {
    for (const std::string& name : m.names) parameter_subscriptions_.erase(name);
  }

 public:
  // parameterValues of `names` (all when empty) to this client, with the request's id.
  void answer_parameters(const std::vector<std::string>& names, const std::optional<std::string>& id) {
    send_text(foxglove::parameter_values(server_.parameter_values(names), id));
  }
  // parameterValues of those of `changed` this client subscribed to, if any.
  void parameters_changed(const std::vector<foxglove::Parameter>& changed) {
    std::vector<foxglove::Parameter> mine;
    for (const foxglove::Parameter& p : changed) {
      if (parameter_subscriptions_.contains(p.name)) mine.push_back(p);
    }
    if (!mine.empty()) send_text(foxglove::parameter_values(mine, std::nullopt));
  }

 private:
  void on_binary(std::span<const std::uint8_t> bytes) {
    auto parsed = foxglove::parse_client_binary(bytes);
    if (auto* why = std::get_if<std::string>(&parsed)) return refuse(foxglove::Level::kError, *why);
    const foxglove::ClientMessage& m = std::get<foxglove::ClientMessage>(parsed);
    const auto it = client_channels_.find(m.channel_id);
    if (it == client_channels_.end()) {
      return refuse(foxglove::Level::kError, "Channel " + std::to_string(m.channel_id) + " is not advertised");
    }
    if (!server_.handlers.on_client_message) return refuse(foxglove::Level::kError, "this server takes no messages");
    const std::string_view payload(reinterpret_cast<const char*>(m.payload.data()), m.payload.size());
    if (auto why = server_.handlers.on_client_message(name_, it->second.topic, it->second.encoding, payload)) {
      refuse(foxglove::Level::kError, *why);
    }
  }

  websocket::stream<beast::tcp_stream> ws_;
  WebServer::Impl& server_;
  std::string name_;
  beast::flat_buffer buffer_;
  std::map<std::uint32_t, std::uint32_t> sub_to_channel_, channel_to_sub_;
  std::map<std::uint32_t, foxglove::ClientChannel> client_channels_;
  std::set<std::string> parameter_subscriptions_;
  std::deque<Out> queue_;
  std::size_t queued_bytes_ = 0;
  bool writing_ = false;
  bool closed_ = false;
  bool accepted_ = false;    // the WebSocket handshake is done
  bool going_away_ = false;  // the server stops (go_away)
  std::chrono::steady_clock::time_point last_drop_status_{};
};

// One HTTP request: the page's files, or the upgrade to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, WebServer::Impl& server) : stream_(std::move(socket)), server_(server) {}

  void start() {
    parser_.body_limit(64 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (!ec) self->on_request(self->parser_.release());
    });
  }

 private:
  void on_request(http::request<http::string_body> req) {
    const Target target = parse_target(sv(req.target()));
    const bool by_query = same_secret(target.token, server_.config.token);
    // The page's own files (its script, its style sheet) are fetched without the query:
    // the page's load sets a cookie with the token (this port's own name: cookies do not
    // tell ports apart). The WebSocket needs the query, as Foxglove's clients send it.
    const bool by_cookie = !by_query && !websocket::is_upgrade(req) &&
                           same_secret(cookie_value(sv(req[http::field::cookie]), cookie_name()), server_.config.token);
    if (!by_query && !by_cookie) return refuse(req, http::status::unauthorized, "a valid ?token= is needed\n");
    set_cookie_ = by_query;
    if (websocket::is_upgrade(req)) {
      if (target.path != "/ws") return refuse(req, http::status::not_found, "the WebSocket is at /ws\n");
      if (!server_.origin_allowed(sv(req[http::field::origin]), sv(req[http::field::host])))
        return refuse(req, http::status::forbidden, "Origin not allowed\n");
      if (!offers_subprotocol(sv(req[http::field::sec_websocket_protocol]))) {
        return refuse(req, http::status::bad_request,
                      "Missing expected sec-websocket-protocol header (foxglove.websocket.v1)\n");
      }
      stream_.expires_never();
      auto session = std::make_shared<WsSession>(stream_.release_socket(), server_);
      server_.sessions.insert(session);
      server_.client_count = server_.sessions.size();
      server_.count(&WebServerCounters::connections);
      session->start(std::move(req));
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      return refuse(req, http::status::method_not_allowed, "GET only\n");
    }
    serve_file(req, target.path);
  }

  std::string cookie_name() const { return "rilbed_token_" + std::to_string(server_.port); }

  void serve_file(const http::request<http::string_body>& req, const std::string& path) {
    if (const auto doc = server_.config.documents.find(path); doc != server_.config.documents.end()) {
      return respond(req, http::status::ok, doc->second.content_type, doc->second.body);
    }
    if (server_.config.web_root.empty() || path.find("..") != std::string::npos || path.empty() || path[0] != '/') {
      return respond(req, http::status::not_found, "text/plain", "not found\n");
    }
    const std::filesystem::path file =
        server_.config.web_root / (path == "/" ? std::string("index.html") : path.substr(1));
    std::ifstream in(file, std::ios::binary);
    if (!in) return respond(req, http::status::not_found, "text/plain", "not found\n");
    std::ostringstream body;
    body << in.rdbuf();
    respond(req, http::status::ok, content_type(file), body.str());
  }

  void refuse(const http::request<http::string_body>& req, http::status status, const std::string& why) {
    server_.count(&WebServerCounters::refused);
    respond(req, status, "text/plain", why);
  }

  void respond(const http::request<http::string_body>& req, http::status status, const std::string& type,
               std::string body) {
    auto res = std::make_shared<http::response<http::string_body>>(status, req.version());
    res->set(http::field::server, "rilbed");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    if (set_cookie_ && status == http::status::ok) {
      res->set(http::field::set_cookie,
               cookie_name() + "=" + server_.config.token + "; Path=/; HttpOnly; SameSite=Strict");
    }
    res->keep_alive(false);
    res->body() = req.method() == http::verb::head ? std::string() : std::move(body);
    res->prepare_payload();
    http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code, std::size_t) {
      beast::error_code ignored;
      self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    });
  }

  beast::tcp_stream stream_;
  WebServer::Impl& server_;
  bool set_cookie_ = false;  // this request came with the token in its query
  beast::flat_buffer buffer_;
  http::request_parser<http::string_body> parser_;
};

void WebServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor.is_open()) return;
    if (!ec) std::make_shared<HttpSession>(std::move(socket), *this)->start();
    accept();
  });
}

void WebServer::Impl::remove(const std::shared_ptr<WsSession>& s) {
  if (sessions.erase(s) == 0) return;
  client_count = sessions.size();
  for (const std::uint32_t channel : s->subscribed_channels()) count_subscriber(channel, -1);
  if (handlers.on_client_gone) handlers.on_client_gone(s->name());
  if (stopping && sessions.empty()) stop_timer.cancel();  // every client answered the close
}

WebServer::WebServer(WebServerConfig config, Handlers handlers) : impl_(std::make_shared<Impl>()) {
  if (config.token.empty()) throw std::invalid_argument("web server: the token must not be empty");
  Impl& m = *impl_;
  m.config = std::move(config);
  m.handlers = std::move(handlers);
  beast::error_code ec;
  const auto address = asio::ip::make_address(m.config.bind_address, ec);
  if (ec) throw std::runtime_error("web server: '" + m.config.bind_address + "' is not an IP address");
  const tcp::endpoint endpoint(address, m.config.port);
  m.acceptor.open(endpoint.protocol(), ec);
  if (!ec) m.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) m.acceptor.bind(endpoint, ec);
  if (!ec) m.acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("web server: cannot listen on " + m.config.bind_address + ":" +
                             std::to_string(m.config.port) + ": " + ec.message());
  }
  m.port = m.acceptor.local_endpoint().port();
  m.accept();
  m.thread = std::thread([&m] {
    yield_to_control_loop();
    m.io.run();
  });
}

WebServer::~WebServer() {
  Impl& m = *impl_;
  asio::post(m.io, [&m] {
    beast::error_code ignored;
    m.acceptor.close(ignored);
    m.stopping = true;
    for (const auto& s : std::vector<std::shared_ptr<WsSession>>(m.sessions.begin(), m.sessions.end())) s->go_away();
    if (m.sessions.empty()) return m.io.stop();
    // Clients that do not answer the close frame (one that never reads) are cut off.
    m.stop_timer.expires_after(kCloseWait);
    m.stop_timer.async_wait([&m](beast::error_code) {
      for (const auto& s : std::vector<std::shared_ptr<WsSession>>(m.sessions.begin(), m.sessions.end())) s->close();
      m.io.stop();
    });
  });
  if (m.thread.joinable()) m.thread.join();
  m.sessions.clear();
}

std::uint16_t WebServer::port() const { return impl_->port; }

std::uint32_t WebServer::add_channel(foxglove::Channel channel, bool latched) {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.mutex);
    channel.id = static_cast<std::uint32_t>(m.channels.size() + 1);
    m.channels.push_back(channel);
    if (latched) m.latched.insert(channel.id);
  }
  asio::post(m.io, [&m, channel] {
    for (const auto& s : m.sessions) s->advertise(channel);
  });
  return channel.id;
}

void WebServer::set_latch_source(std::uint32_t channel, LatchSource source) {
  Impl& m = *impl_;
  // Read on the server's thread only, after this post.
  asio::post(m.io, [&m, channel, source = std::move(source)] { m.latch_sources[channel] = source; });
}

bool WebServer::subscribed(std::uint32_t channel) const {
  std::lock_guard lock(impl_->mutex);
  return impl_->subscribers.contains(channel);
}

void WebServer::publish(std::uint32_t channel, std::uint64_t t_ns, std::shared_ptr<const std::string> payload) {
  Impl& m = *impl_;
  bool latched = false;
  {
    std::lock_guard lock(m.mutex);
    latched = m.latched.contains(channel);
  }
  asio::post(m.io, [&m, channel, t_ns, latched, payload = std::move(payload)] {
    if (latched) m.latest[channel] = {t_ns, payload};
    for (const auto& s : m.sessions) s->offer(channel, t_ns, payload);
  });
}

std::size_t WebServer::clients() const { return impl_->client_count.load(); }

void WebServer::tell(const std::string& client, foxglove::Level level, const std::string& message) {
  Impl& m = *impl_;
  asio::post(m.io, [&m, client, level, message] {
    for (const auto& s : m.sessions) {
      if (s->name() == client) s->tell(level, message);
    }
  });
}

void WebServer::set_parameters(std::vector<foxglove::Parameter> values) {
  Impl& m = *impl_;
  asio::post(m.io, [&m, values = std::move(values)] {
    std::vector<foxglove::Parameter> changed;
    for (const foxglove::Parameter& p : values) {
      const auto it = m.parameters.find(p.name);
      if (p.value.is_null()) {
        if (it == m.parameters.end()) continue;
        m.parameters.erase(it);
      } else if (it != m.parameters.end() && it->second == p.value) {
        continue;
      } else {
        m.parameters[p.name] = p.value;
      }
      changed.push_back(p);
    }
    if (changed.empty()) return;
    for (const auto& s : m.sessions) s->parameters_changed(changed);
  });
}

void WebServer::answer_parameters(const std::string& client, std::vector<std::string> names,
                                  std::optional<std::string> id) {
  Impl& m = *impl_;
  asio::post(m.io, [&m, client, names = std::move(names), id = std::move(id)] {
    for (const auto& s : m.sessions) {
      if (s->name() == client) s->answer_parameters(names, id);
    }
  });
}

bool WebServer::flush(std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    // Asked on the server's thread, after everything published before this call.
    auto idle = std::make_shared<std::promise<bool>>();
    std::future<bool> answer = idle->get_future();
    asio::post(m.io, [&m, idle] {
      bool all = true;
      for (const auto& s : m.sessions) all = all && s->idle();
      idle->set_value(all);
    });
    if (answer.wait_until(deadline) != std::future_status::ready) return false;
    if (answer.get()) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

WebServerCounters WebServer::counters() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->counts;
}

}  // namespace rilbed::gui_web
