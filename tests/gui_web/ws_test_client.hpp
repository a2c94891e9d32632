// Test clients of the web server: an HTTP GET, a raw WebSocket upgrade (to see a refusal's
// status), and a synchronous Foxglove WebSocket client, all Beast on loopback.
#pragma once

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>

#include <nlohmann/json.hpp>

#include "gui_web/web_server.hpp"

namespace rilbed::gui_web::testing {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using nlohmann::json;

inline const std::string kToken = "0123456789abcdef0123456789abcdef";

inline WebServerConfig config() {
  WebServerConfig c;
  c.port = 0;
  c.token = kToken;
  c.session_id = "test";
  return c;
}

// An HTTP GET (with a Cookie header when given); returns the status code and body.
inline std::pair<int, std::string> get(std::uint16_t port, const std::string& target, const std::string& cookie = "") {
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, "127.0.0.1");
  if (!cookie.empty()) req.set(http::field::cookie, cookie);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(stream, buffer, res);
  return {static_cast<int>(res.result_int()), res.body()};
}

// The status of a WebSocket upgrade request (101 when accepted), as a browser would send
// it. (Beast 1.74's client does not keep the response of a declined handshake.)
inline int upgrade_status(std::uint16_t port, const std::string& target,
                          const std::string& subprotocol = "foxglove.websocket.v1", const std::string& origin = "",
                          const std::string& host = "") {
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, host.empty() ? "127.0.0.1:" + std::to_string(port) : host);
  req.set(http::field::upgrade, "websocket");
  req.set(http::field::connection, "upgrade");
  req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  req.set(http::field::sec_websocket_version, "13");
  if (!subprotocol.empty()) req.set(http::field::sec_websocket_protocol, subprotocol);
  if (!origin.empty()) req.set(http::field::origin, origin);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response_parser<http::empty_body> res;
  res.skip(true);  // a 101 has no body
  beast::error_code ec;
  http::read_header(stream, buffer, res, ec);
  return ec ? -1 : static_cast<int>(res.get().result_int());
}

// A Foxglove client: connects, reads the greeting.
struct Client {
  asio::io_context io;
  websocket::stream<beast::tcp_stream> ws{io};
  beast::flat_buffer buffer;

  // Returns the HTTP status of a refused handshake, or 101.
  int connect(std::uint16_t port, const std::string& target, const std::string& subprotocol = "foxglove.websocket.v1",
              const std::string& origin = "") {
    beast::get_lowest_layer(ws).connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
    ws.set_option(websocket::stream_base::decorator([subprotocol, origin](websocket::request_type& r) {
      if (!subprotocol.empty()) r.set(http::field::sec_websocket_protocol, subprotocol);
      if (!origin.empty()) r.set(http::field::origin, origin);
    }));
    websocket::response_type res;
    beast::error_code ec;
    ws.handshake(res, "127.0.0.1:" + std::to_string(port), target, ec);
    if (!ec) {
      EXPECT_EQ(res[http::field::sec_websocket_protocol], "foxglove.websocket.v1");
    }
    return static_cast<int>(res.result_int());
  }
  // The next message: text as JSON, binary as raw bytes.
  std::variant<json, std::string> next() {
    buffer.consume(buffer.size());
    ws.read(buffer);
    std::string bytes = beast::buffers_to_string(buffer.data());
    if (ws.got_text()) return json::parse(bytes);
    return bytes;
  }
  json next_json() {
    auto m = next();
    EXPECT_TRUE(std::holds_alternative<json>(m));
    return std::holds_alternative<json>(m) ? std::get<json>(m) : json();
  }
  void send_text(const json& j) {
    ws.text(true);
    ws.write(asio::buffer(j.dump()));
  }
  void send_binary(const std::string& bytes) {
    ws.binary(true);
    ws.write(asio::buffer(bytes));
  }
};

}  // namespace rilbed::gui_web::testing
