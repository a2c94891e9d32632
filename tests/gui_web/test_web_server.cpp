// The web server with real clients (Beast's, synchronous, on loopback): the token on every
// request, the Origin and the subprotocol of a WebSocket, the Foxglove protocol's greeting,
// subscriptions and their data, a client's messages, bad messages answered with a status
// and the socket kept, an oversized one closing only its socket, many clients, and a client
// that never reads, which must not hold up the others.
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "agents/builtin_controllers.hpp"
#include "gui_web/web_server.hpp"
#include "support/eventually.hpp"
#include "ws_test_client.hpp"

namespace rilbed::gui_web {
namespace {

using namespace rilbed::gui_web::testing;
using nlohmann::json;
using rilbed::testing::eventually;
namespace asio = boost::asio;

foxglove::Channel poses_channel() {
  return {0, "/rilbed/poses", "json", "rilbed.poses", R"({"type":"object"})", "jsonschema"};
}

TEST(WebServer, TheTokenOpensEverythingAndNothingOpensWithoutIt) {
  const auto root = std::filesystem::temp_directory_path() / ("rilbed_web_" + std::to_string(::getpid()));
  std::filesystem::create_directories(root);
  std::ofstream(root / "index.html") << "<!doctype html><title>rilbed</title>";
  WebServerConfig c = config();
  c.web_root = root;
  WebServer server(c, {});
  EXPECT_EQ(get(server.port(), "/?token=" + kToken),
            (std::pair<int, std::string>{200, "<!doctype html><title>rilbed</title>"}));
  EXPECT_EQ(get(server.port(), "/").first, 401);
  EXPECT_EQ(get(server.port(), "/?token=" + kToken.substr(1)).first, 401);
  EXPECT_EQ(get(server.port(), "/?token=" + kToken + "0").first, 401);
  EXPECT_EQ(get(server.port(), "/nothing.js?token=" + kToken).first, 404);
  EXPECT_EQ(get(server.port(), "/../../etc/passwd?token=" + kToken).first, 404);
  // The WebSocket: the token, the subprotocol, and a browser's Origin.
  EXPECT_EQ(upgrade_status(server.port(), "/ws"), 401);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=nope"), 401);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, ""), 400);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, "foxglove.websocket.v1", "http://evil.example"), 403);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, "foxglove.websocket.v1",
                           "http://127.0.0.1:" + std::to_string(server.port())),
            101);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, "other, foxglove.websocket.v1"), 101);
  // A page loaded from this server under another name (the lab machine's, on the LAN) is its own.
  const std::string lan = "rilbed-lab.local:" + std::to_string(server.port());
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, "foxglove.websocket.v1", "http://" + lan, lan), 101);
  EXPECT_EQ(upgrade_status(server.port(), "/ws?token=" + kToken, "foxglove.websocket.v1", "http://evil.example", lan),
            403);
  EXPECT_EQ(Client().connect(server.port(), "/ws?token=" + kToken), 101);
  EXPECT_EQ(server.counters().refused, 8u);  // 3 pages, 5 WebSockets
  std::filesystem::remove_all(root);
  EXPECT_THROW(WebServer(WebServerConfig{}, {}), std::invalid_argument);  // no token
  WebServerConfig taken = config();
  taken.port = server.port();
  taken.bind_address = "127.0.0.2";  // another address, same port: fine; the same address is not
  taken.bind_address = "127.0.0.1";
  EXPECT_THROW(WebServer(taken, {}), std::runtime_error);
}

TEST(WebServer, ServesTheDocumentsItIsGivenUnderTheToken) {
  // The controllers' JSON of a registry that has one controller more than rilbed's own:
  // what the page's editor reads is the registry the server was given.
  agents::ControllerRegistry registry = agents::builtin_controllers();
  agents::ControllerEntry extra;
  extra.name = "lab_spinner";
  extra.summary = "a lab's own";
  extra.params = {{"turn_radps", "rad/s", 1.0, false, 0.0, 5.0, false, "how fast it turns"}};
  extra.make = [](const agents::ControllerContext&) { return std::unique_ptr<agents::Controller>(); };
  registry.add(extra);
  WebServerConfig c = config();
  c.documents["/controllers.json"] = {"application/json", agents::controllers_json(registry).dump()};
  WebServer server(c, {});  // no web root: the documents alone
  const auto [status, body] = get(server.port(), "/controllers.json?token=" + kToken);
  ASSERT_EQ(status, 200);
  const json served = json::parse(body);
  ASSERT_EQ(served.size(), registry.entries().size());
  EXPECT_EQ(served.back()["name"], "lab_spinner");
  EXPECT_EQ(served.back()["params"][0]["unit"], "rad/s");
  EXPECT_EQ(served.back()["params"][0]["max"], 5.0);
  EXPECT_EQ(get(server.port(), "/controllers.json").first, 401);
  EXPECT_EQ(get(server.port(), "/index.html?token=" + kToken).first, 404);
}

TEST(WebServer, ThePagesLoadSetsACookieThatOpensItsFilesButNotTheWebSocket) {
  const auto root = std::filesystem::temp_directory_path() / ("rilbed_web_cookie_" + std::to_string(::getpid()));
  std::filesystem::create_directories(root);
  std::ofstream(root / "index.html") << "<script src=app.js></script>";
  std::ofstream(root / "app.js") << "console.log(1)";
  WebServerConfig c = config();
  c.web_root = root;
  WebServer server(c, {});
  // The raw response, to see its Set-Cookie.
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), server.port()));
  http::request<http::empty_body> req(http::verb::get, "/?token=" + kToken, 11);
  req.set(http::field::host, "127.0.0.1");
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(stream, buffer, res);
  const std::string cookie(res[http::field::set_cookie]);
  const std::string name = "rilbed_token_" + std::to_string(server.port());
  ASSERT_EQ(cookie.rfind(name + "=" + kToken + ";", 0), 0u) << cookie;
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos);
  EXPECT_NE(cookie.find("SameSite=Strict"), std::string::npos);
  EXPECT_EQ(get(server.port(), "/app.js", "other=1; " + name + "=" + kToken).first, 200);
  EXPECT_EQ(get(server.port(), "/app.js").first, 401);
  EXPECT_EQ(get(server.port(), "/app.js", name + "=" + kToken.substr(1)).first, 401);
  EXPECT_EQ(get(server.port(), "/app.js", "rilbed_token_1=" + kToken).first, 401);  // another port's name
  std::filesystem::remove_all(root);
}

TEST(WebServer, ALatchedChannelsLastMessageGreetsEachNewSubscriber) {
  WebServer server(config(), {});
  const std::uint32_t latched = server.add_channel(poses_channel(), /*latched=*/true);
  const std::uint32_t plain = server.add_channel({0, "/rilbed/events", "json", "rilbed.event", "{}", "jsonschema"});
  server.publish(latched, 5, std::make_shared<const std::string>("{\"n\":1}"));
  server.publish(latched, 7, std::make_shared<const std::string>("{\"n\":2}"));
  server.publish(plain, 7, std::make_shared<const std::string>("{\"e\":1}"));
  ASSERT_TRUE(server.flush(std::chrono::seconds(5)));
  Client client;
  ASSERT_EQ(client.connect(server.port(), "/ws?token=" + kToken), 101);
  client.next_json();
  client.next_json();
  client.send_text({{"op", "subscribe"},
                    {"subscriptions", {{{"id", 1}, {"channelId", plain}}, {{"id", 2}, {"channelId", latched}}}}});
  const auto m = client.next();
  ASSERT_TRUE(std::holds_alternative<std::string>(m));
  const std::string& bytes = std::get<std::string>(m);
  ASSERT_EQ(bytes.size(), 13u + 7u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 2u);  // subscription 2: the latched channel
  EXPECT_EQ(bytes.substr(13), "{\"n\":2}");             // its last message, not the first
  // Nothing from the plain channel's past: the next message is a new one.
  server.publish(plain, 9, std::make_shared<const std::string>("{\"e\":2}"));
  const auto next = client.next();
  ASSERT_TRUE(std::holds_alternative<std::string>(next));
  EXPECT_EQ(std::get<std::string>(next).substr(13), "{\"e\":2}");
}

TEST(WebServer, GreetsSubscribesAndSendsData) {
  WebServer server(config(), {});
  const std::uint32_t poses = server.add_channel(poses_channel());
  EXPECT_EQ(poses, 1u);
  Client client;
  ASSERT_EQ(client.connect(server.port(), "/ws?token=" + kToken), 101);
  const json info = client.next_json();
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["sessionId"], "test");
  const json adv = client.next_json();
  ASSERT_EQ(adv["op"], "advertise");
  ASSERT_EQ(adv["channels"].size(), 1u);
  EXPECT_EQ(adv["channels"][0]["topic"], "/rilbed/poses");
  // Subscription id 0 is the client's first.
  client.send_text({{"op", "subscribe"}, {"subscriptions", {{{"id", 0}, {"channelId", poses}}}}});
  ASSERT_TRUE(eventually([&] { return server.subscribed(poses); }));
  server.publish(poses, 1'000'000'000ULL, std::make_shared<const std::string>(R"({"n":0})"));
  const auto data = std::get<std::string>(client.next());
  ASSERT_GE(data.size(), 13u);
  EXPECT_EQ(static_cast<unsigned char>(data[0]), 0x01);
  EXPECT_EQ(data.substr(1, 4), std::string("\0\0\0\0", 4));  // subscription 0
  EXPECT_EQ(data.substr(13, 5), R"({"n":)");
  // A channel added later is advertised to the client.
  const std::uint32_t world =
      server.add_channel({0, "/rilbed/world", "json", "rilbed.world", R"({"type":"object"})", "jsonschema"});
  for (;;) {
    auto m = client.next();
    if (std::holds_alternative<json>(m) && std::get<json>(m)["op"] == "advertise") {
      EXPECT_EQ(std::get<json>(m)["channels"][0]["id"], world);
      break;
    }
  }
}

TEST(WebServer, AStoppingServerSaysGoingAwayToItsClients) {
  // A client connected when the server goes (a run that ended) gets a close frame with
  // 1001, going away, not a connection cut mid-stream; one that never reads is cut off
  // after a short wait, and holds up nobody.
  auto server = std::make_unique<WebServer>(config(), WebServer::Handlers{});
  Client client, silent;
  ASSERT_EQ(client.connect(server->port(), "/ws?token=" + kToken), 101);
  ASSERT_EQ(silent.connect(server->port(), "/ws?token=" + kToken), 101);
  EXPECT_EQ(client.next_json()["op"], "serverInfo");
  EXPECT_EQ(client.next_json()["op"], "advertise");
  std::thread reader([&] {
    beast::error_code ec;
    for (;;) {
      client.buffer.consume(client.buffer.size());
      client.ws.read(client.buffer, ec);
      if (ec) break;
    }
    EXPECT_EQ(ec, websocket::error::closed) << ec.message();
    EXPECT_EQ(client.ws.reason().code, websocket::close_code::going_away);
  });
  server.reset();
  reader.join();
  // The silent one was sent the close frame too, behind what it had not read (its answer
  // to it then finds the connection cut: the server waited for it no longer). (Its
  // greeting may not have been sent: the server may have stopped before its handshake's
  // end was handled.)
  beast::error_code ec;
  for (int i = 0; i < 10 && !ec; ++i) {
    silent.buffer.consume(silent.buffer.size());
    silent.ws.read(silent.buffer, ec);
  }
  EXPECT_TRUE(ec);
  EXPECT_EQ(silent.ws.reason().code, websocket::close_code::going_away) << ec.message();
}

TEST(WebServer, ClientMessagesReachTheOwnerAndBadOnesGetAStatus) {
  std::mutex mutex;
  std::vector<std::string> heard;
  WebServer::Handlers h;
  h.on_client_message = [&](const std::string&, const std::string& topic, const std::string&,
                            std::string_view payload) -> std::optional<std::string> {
    std::lock_guard lock(mutex);
    heard.push_back(topic + " " + std::string(payload));
    if (payload == "refuse") return std::string("not a command");
    return std::nullopt;
  };
  WebServer server(config(), h);
  Client client;
  ASSERT_EQ(client.connect(server.port(), "/ws?token=" + kToken), 101);
  client.next_json();
  client.next_json();
  auto expect_status = [&](int level, const std::string& text) {
    const json st = client.next_json();
    EXPECT_EQ(st["op"], "status");
    EXPECT_EQ(st["level"], level);
    EXPECT_NE(st["message"].get<std::string>().find(text), std::string::npos) << st.dump();
  };
  client.send_text(
      {{"op", "advertise"},
       {"channels", {{{"id", 1}, {"topic", "/rilbed/console"}, {"encoding", "json"}, {"schemaName", "c"}}}}});
  client.send_binary(std::string("\x01\x01\x00\x00\x00", 5) + R"({"command":"pause"})");
  client.send_binary(std::string("\x01\x01\x00\x00\x00", 5) + "refuse");
  expect_status(2, "not a command");
  client.send_text({{"op", "fly"}});
  expect_status(2, "unknown op 'fly'");
  client.ws.text(true);
  client.ws.write(asio::buffer(std::string("{not json")));
  expect_status(2, "not JSON");
  client.send_binary(std::string("\x01\x09\x00\x00\x00{}", 7));
  expect_status(2, "Channel 9 is not advertised");
  client.send_binary(std::string("\x07", 1));
  expect_status(2, "unknown binary opcode 7");
  client.send_text({{"op", "subscribe"}, {"subscriptions", {{{"id", 0}, {"channelId", 42}}}}});
  expect_status(1, "Channel 42 is not available");
  client.send_text(
      {{"op", "advertise"}, {"channels", {{{"id", 2}, {"topic", "/x"}, {"encoding", "cdr"}, {"schemaName", "c"}}}}});
  expect_status(2, "encoding 'cdr' is not supported");
  {
    std::lock_guard lock(mutex);
    EXPECT_EQ(heard, (std::vector<std::string>{R"(/rilbed/console {"command":"pause"})", "/rilbed/console refuse"}));
  }
  EXPECT_EQ(server.counters().bad_client_messages, 7u);
  // Oversized: only that socket closes (1009); the server serves the next client.
  WebServerConfig small = config();
  small.max_message_bytes = 1024;
  WebServer strict(small, {});
  Client big;
  ASSERT_EQ(big.connect(strict.port(), "/ws?token=" + kToken), 101);
  big.next_json();
  big.next_json();
  beast::error_code ec;
  big.ws.text(true);
  // The server may close before the whole message is written (then the write fails).
  big.ws.write(
      asio::buffer(
          json{{"op", "unsubscribe"}, {"subscriptionIds", json::array()}, {"pad", std::string(4096, 'x')}}.dump()),
      ec);
  if (!ec) {
    big.buffer.consume(big.buffer.size());
    big.ws.read(big.buffer, ec);
    EXPECT_TRUE(ec) << "the oversized message's socket stayed open";
    // The close frame (1009), or, when the server's close met the rest of our unread
    // bytes, a reset before it arrived: either way that socket is gone.
    if (ec == websocket::error::closed) {
      EXPECT_EQ(big.ws.reason().code, websocket::close_code::too_big);
    }
  }
  EXPECT_TRUE(eventually([&] { return strict.clients() == 0; }));  // its socket closed
  Client after;
  EXPECT_EQ(after.connect(strict.port(), "/ws?token=" + kToken), 101);
}

TEST(WebServer, FiftyClientsAndOneThatNeverReadsHoldsUpNobody) {
  WebServerConfig c = config();
  c.max_queued_bytes = 256 * 1024;
  WebServer server(c, {});
  const std::uint32_t channel = server.add_channel(poses_channel());
  std::vector<std::unique_ptr<Client>> clients;
  for (int i = 0; i < 50; ++i) {
    clients.push_back(std::make_unique<Client>());
    ASSERT_EQ(clients.back()->connect(server.port(), "/ws?token=" + kToken), 101);
    clients.back()->next_json();
    clients.back()->next_json();
    clients.back()->send_text({{"op", "subscribe"}, {"subscriptions", {{{"id", 5}, {"channelId", channel}}}}});
  }
  ASSERT_TRUE(eventually([&] { return server.clients() == 50u; }));
  // Client 0 never reads again; the others read as they go. 2,000 messages of 16 kB: 32 MB
  // for each client, far beyond what the stalled one's socket and queue hold.
  const std::string blob(16 * 1024, 'x');
  std::atomic<bool> stop{false};
  std::vector<std::thread> readers;
  std::vector<std::atomic<int>> got(50);
  for (int k = 1; k < 50; ++k) {
    readers.emplace_back([&, k] {
      while (!stop.load()) {
        beast::error_code ec;
        clients[k]->buffer.consume(clients[k]->buffer.size());
        clients[k]->ws.read(clients[k]->buffer, ec);
        if (ec) return;
        if (!clients[k]->ws.got_text()) ++got[k];
      }
    });
  }
  // Wait until every subscription is in (a message reaches each reader).
  ASSERT_TRUE(eventually([&] {
    server.publish(channel, 1, std::make_shared<const std::string>("{}"));
    bool all = true;
    for (int k = 1; k < 50; ++k) all = all && got[k] > 0;
    return all;
  }));
  const auto payload = std::make_shared<const std::string>(blob);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 2000; ++i) server.publish(channel, 2, payload);
  const auto queued_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The last message reaches every reading client: wait for a marker after the blobs.
  const auto last = std::make_shared<const std::string>("{\"last\":true}");
  std::vector<int> before(50);
  for (int k = 1; k < 50; ++k) before[k] = got[k];
  eventually([&] {
    server.publish(channel, 3, last);
    bool all = true;
    for (int k = 1; k < 50; ++k) all = all && got[k] > before[k];
    return all;
  });
  for (int k = 1; k < 50; ++k) EXPECT_GT(got[k].load(), before[k]) << "client " << k;
  stop = true;
  for (int k = 1; k < 50; ++k) {
    beast::error_code ignored;
    beast::get_lowest_layer(clients[k]->ws).socket().shutdown(tcp::socket::shutdown_both, ignored);
  }
  for (auto& t : readers) t.join();
  // The stalled client lost messages; publishing never waited for it.
  EXPECT_GT(server.counters().messages_dropped, 0u);
  std::printf(
      "[ web      ] 2,000 x 16 kB to 50 clients (one stalled): queued in %.3f s, %llu dropped for slow clients\n",
      queued_s, static_cast<unsigned long long>(server.counters().messages_dropped));
}

}  // namespace
}  // namespace rilbed::gui_web
