// A Foxglove WebSocket client for end-to-end tests (Beast, synchronous): connects to a
// `rilbed gui` URL, subscribes to the given topics, prints each message it gets as
// "<topic> <json>" and every status as "status <level> <message>", and, once it has had a
// message, publishes one message on a client channel, or sets parameters (printing the
// answer as "parameterValues <json>"). Exits 0 after --count messages (or the first on the
// --until topic; --until parameterValues: the answer to its setParameters), 1 on a timeout
// or error (it says which).
//   ws_probe ws://127.0.0.1:PORT/ws?token=T --topics /rilbed/poses,/rilbed/console_reply
//            --count 5 [--until /rilbed/console_reply] [--send '/rilbed/console={"command":"pause"}']
//            [--set-parameters '[{"name":"vision.threshold","value":30}]' | --get-parameters all] [--timeout 20]
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;
using nlohmann::json;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: ws_probe URL --topics A,B [--count N] [--send TOPIC=JSON] [--timeout S]\n");
    return 2;
  }
  std::string url = argv[1], send, until, set_parameters;
  bool get_parameters = false;
  std::set<std::string> topics;
  int count = 1, timeout_s = 20;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--topics") {
      std::stringstream s(value);
      for (std::string t; std::getline(s, t, ',');) topics.insert(t);
    } else if (key == "--count") {
      count = std::stoi(value);
    } else if (key == "--send") {
      send = value;
    } else if (key == "--set-parameters") {
      set_parameters = value;
    } else if (key == "--get-parameters") {
      get_parameters = true;
    } else if (key == "--until") {
      until = value;
    } else if (key == "--timeout") {
      timeout_s = std::stoi(value);
    }
  }
  // ws://HOST:PORT/PATH
  const std::string rest = url.substr(url.find("//") + 2);
  const std::string hostport = rest.substr(0, rest.find('/'));
  const std::string target = rest.substr(hostport.size());
  const std::string host = hostport.substr(0, hostport.find(':'));
  const std::string port = hostport.substr(hostport.find(':') + 1);
  try {
    boost::asio::io_context io;
    websocket::stream<beast::tcp_stream> ws(io);
    beast::get_lowest_layer(ws).connect(
        tcp::endpoint(boost::asio::ip::make_address(host), static_cast<unsigned short>(std::stoi(port))));
    ws.set_option(websocket::stream_base::decorator([](websocket::request_type& r) {
      r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
    }));
    ws.handshake(hostport, target);
    beast::get_lowest_layer(ws).expires_after(std::chrono::seconds(timeout_s));
    std::map<std::uint32_t, std::string> sub_topic;
    std::uint32_t next_sub = 0;
    int got = 0;
    bool sent = false;
    beast::flat_buffer buffer;
    while (got < count) {
      buffer.consume(buffer.size());
      ws.read(buffer);
      const std::string bytes = beast::buffers_to_string(buffer.data());
      if (ws.got_text()) {
        const json m = json::parse(bytes);
        if (m["op"] == "advertise") {
          json subs = json::array();
          for (const auto& c : m["channels"]) {
            if (!topics.contains(c["topic"].get<std::string>())) continue;
            sub_topic[next_sub] = c["topic"];
            subs.push_back({{"id", next_sub++}, {"channelId", c["id"]}});
          }
          if (!subs.empty()) {
            ws.text(true);
            ws.write(boost::asio::buffer(json{{"op", "subscribe"}, {"subscriptions", subs}}.dump()));
          }
        } else if (m["op"] == "status") {
          std::printf("status %d %s\n", m["level"].get<int>(), m["message"].get<std::string>().c_str());
        } else if (m["op"] == "parameterValues") {
          std::printf("parameterValues %s\n", m.dump().c_str());
          std::fflush(stdout);
          if (until == "parameterValues" && m.value("id", "") == "probe") break;
        }
        continue;
      }
      if (bytes.size() < 13 || bytes[0] != 0x01) continue;
      const std::uint32_t sub = static_cast<unsigned char>(bytes[1]) | static_cast<unsigned char>(bytes[2]) << 8 |
                                static_cast<unsigned char>(bytes[3]) << 16 |
                                static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[4])) << 24;
      std::printf("%s %s\n", sub_topic[sub].c_str(), bytes.substr(13).c_str());
      std::fflush(stdout);
      ++got;
      if (!until.empty() && sub_topic[sub] == until) break;
      if (get_parameters && !sent) {
        sent = true;
        ws.text(true);
        ws.write(boost::asio::buffer(
            json{{"op", "getParameters"}, {"parameterNames", json::array()}, {"id", "probe"}}.dump()));
      }
      if (!set_parameters.empty() && !sent) {
        sent = true;
        ws.text(true);
        ws.write(boost::asio::buffer(
            json{{"op", "setParameters"}, {"parameters", json::parse(set_parameters)}, {"id", "probe"}}.dump()));
      }
      if (!send.empty() && !sent) {
        sent = true;
        const std::string topic = send.substr(0, send.find('='));
        const std::string payload = send.substr(send.find('=') + 1);
        ws.text(true);
        ws.write(boost::asio::buffer(
            json{{"op", "advertise"},
                 {"channels",
                  {{{"id", 1}, {"topic", topic}, {"encoding", "json"}, {"schemaName", "rilbed.console_command"}}}}}
                .dump()));
        ws.binary(true);
        ws.write(boost::asio::buffer(std::string("\x01\x01\x00\x00\x00", 5) + payload));
      }
    }
    // Done: what it waited for came. The server may be gone already (a run that the
    // probe's own `exit` ended closes its connections as it stops), so a failed close
    // handshake does not make the probe fail.
    beast::error_code ignored;
    ws.close(websocket::close_code::normal, ignored);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ws_probe: %s\n", e.what());
    return 1;
  }
}
