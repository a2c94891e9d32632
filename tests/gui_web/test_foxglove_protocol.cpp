// The Foxglove WebSocket protocol's messages, built and parsed without a socket: what
// @foxglove/ws-protocol's FoxgloveClient sends parses to what it means, every malformed
// message is refused with a reason a status message can carry, and what the server sends
// has the spec's shape (a JSON object per text frame, little-endian binary headers).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "gui_web/foxglove_protocol.hpp"

namespace rilbed::gui_web::foxglove {
namespace {

using nlohmann::json;

template <typename T>
T parsed(const std::string& text) {
  auto r = parse_client_text(text);
  EXPECT_TRUE(std::holds_alternative<ClientText>(r))
      << text << ": " << (std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : "");
  return std::get<T>(std::get<ClientText>(r));
}

std::string refused(const std::string& text) {
  auto r = parse_client_text(text);
  EXPECT_TRUE(std::holds_alternative<std::string>(r)) << text;
  return std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : "";
}

TEST(FoxgloveProtocol, ParsesWhatFoxgloveClientSends) {
  // Exactly as FoxgloveClient writes them (JSON.stringify), subscription ids from 0.
  const auto s = parsed<Subscribe>(
      R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":1},{"id":1,"channelId":4294967295}]})");
  ASSERT_EQ(s.subscriptions.size(), 2u);
  EXPECT_EQ(s.subscriptions[0].id, 0u);
  EXPECT_EQ(s.subscriptions[1].channel_id, 4294967295u);
  EXPECT_EQ(parsed<Unsubscribe>(R"({"op":"unsubscribe","subscriptionIds":[0,7]})").subscription_ids,
            (std::vector<std::uint32_t>{0, 7}));
  const auto a = parsed<ClientAdvertise>(
      R"({"op":"advertise","channels":[{"id":1,"topic":"/rilbed/console","encoding":"json","schemaName":"rilbed.console_command"}]})");
  ASSERT_EQ(a.channels.size(), 1u);
  EXPECT_EQ(a.channels[0].topic, "/rilbed/console");
  EXPECT_EQ(a.channels[0].encoding, "json");
  EXPECT_EQ(parsed<ClientUnadvertise>(R"({"op":"unadvertise","channelIds":[1]})").channel_ids,
            (std::vector<std::uint32_t>{1}));
  const auto g = parsed<GetParameters>(R"({"op":"getParameters","parameterNames":[],"id":"req-1"})");
  EXPECT_TRUE(g.names.empty());
  EXPECT_EQ(g.id, "req-1");
  EXPECT_EQ(parsed<GetParameters>(R"({"op":"getParameters","parameterNames":["a"]})").id, std::nullopt);
  const auto p = parsed<SetParameters>(
      R"({"op":"setParameters","parameters":[{"name":"/vision/min_score","value":0.8},{"name":"/x"}],"id":"abc"})");
  ASSERT_EQ(p.parameters.size(), 2u);
  EXPECT_EQ(p.parameters[0].value, json(0.8));
  EXPECT_TRUE(p.parameters[1].value.is_null());  // unset
  // Fields the protocol may add later are ignored.
  EXPECT_EQ(parsed<Unsubscribe>(R"({"op":"unsubscribe","subscriptionIds":[3],"future":true})").subscription_ids.size(),
            1u);
}

TEST(FoxgloveProtocol, RefusesMalformedMessagesWithAReason) {
  EXPECT_EQ(refused("{"), "not JSON");
  EXPECT_EQ(refused("[1,2]"), "not a JSON object");
  EXPECT_EQ(refused(R"({"subscriptions":[]})"), "no string \"op\"");
  EXPECT_EQ(refused(R"({"op":7})"), "no string \"op\"");
  EXPECT_EQ(refused(R"({"op":"fly"})"), "unknown op 'fly'");
  EXPECT_EQ(refused("{\"op\":\"a\\u0001b\"}"), "unknown op 'a?b'");
  EXPECT_EQ(refused(std::string(R"({"op":")") + std::string(500, 'x') + "\"}"),
            "unknown op '" + std::string(64, 'x') + "'");
  EXPECT_EQ(refused(R"({"op":"subscribe"})"), "subscribe: subscriptions is missing");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":{}})"), "subscribe: subscriptions is not an array");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":1},{"id":1}]})"),
            "subscribe: subscriptions[1].channelId is missing");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})"),
            "subscribe: subscriptions[0].id is not an integer in 0..4294967295");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})"),
            "subscribe: subscriptions[0].id is not an integer in 0..4294967295");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})"),
            "subscribe: subscriptions[0].id is not an integer in 0..4294967295");
  EXPECT_EQ(refused(R"({"op":"subscribe","subscriptions":[3]})"), "subscribe: subscriptions[0] is not an object");
  EXPECT_EQ(refused(R"({"op":"unsubscribe","subscriptionIds":["1"]})"),
            "unsubscribe: subscriptionIds[0] is not an integer in 0..4294967295");
  EXPECT_EQ(refused(R"({"op":"advertise","channels":[{"id":1,"topic":5,"encoding":"json","schemaName":"x"}]})"),
            "advertise: channels[0].topic is not a string");
  EXPECT_EQ(refused(R"({"op":"getParameters","parameterNames":[],"id":5})"), "getParameters: id is not a string");
  EXPECT_EQ(refused(R"({"op":"setParameters","parameters":[{"value":1}]})"),
            "setParameters: parameters[0].name is missing");
  // No list longer than kMaxItems.
  std::string many = R"({"op":"unsubscribe","subscriptionIds":[)";
  for (std::size_t i = 0; i <= kMaxItems; ++i) many += (i ? ",1" : "1");
  EXPECT_EQ(refused(many + "]}"), "unsubscribe: subscriptionIds lists more than 1024 items");
}

TEST(FoxgloveProtocol, BinaryFramesBothWays) {
  // Client Message Data: 01, channel id (LE), payload.
  const std::vector<std::uint8_t> frame = {0x01, 0x02, 0x01, 0x00, 0x00, '{', '}'};
  const auto m = std::get<ClientMessage>(parse_client_binary(frame));
  EXPECT_EQ(m.channel_id, 258u);
  EXPECT_EQ(std::string(m.payload.begin(), m.payload.end()), "{}");
  EXPECT_EQ(std::get<ClientMessage>(parse_client_binary(std::vector<std::uint8_t>{1, 0, 0, 0, 0})).payload.size(), 0u);
  EXPECT_EQ(std::get<std::string>(parse_client_binary({})), "empty binary message");
  EXPECT_EQ(std::get<std::string>(parse_client_binary(std::vector<std::uint8_t>{7, 0, 0, 0, 0})),
            "unknown binary opcode 7");
  EXPECT_EQ(std::get<std::string>(parse_client_binary(std::vector<std::uint8_t>{1, 0, 0})),
            "message of 3 bytes is shorter than its 5-byte header");
  // Message Data header: the spec's example (subscription 7, 1700000000123456789 ns).
  const auto h = message_data_header(7, 1700000000123456789ULL);
  const std::array<std::uint8_t, 13> expected = {0x01, 0x07, 0x00, 0x00, 0x00, 0x15, 0xcd,
                                                 0x85, 0x3d, 0xfe, 0x9c, 0x97, 0x17};
  EXPECT_EQ(h, expected);
}

TEST(FoxgloveProtocol, ServerMessagesHaveTheSpecsShape) {
  const json info = json::parse(server_info("rilbed", {"clientPublish", "parameters"}, {"json"}, "run-1"));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"], json::array({"clientPublish", "parameters"}));
  EXPECT_EQ(info["supportedEncodings"], json::array({"json"}));
  EXPECT_TRUE(info["metadata"].is_object());
  EXPECT_EQ(info["sessionId"], "run-1");
  const std::vector<Channel> channels = {
      {3, "/rilbed/poses", "json", "rilbed.poses", R"({"type":"object"})", "jsonschema"}};
  const json adv = json::parse(advertise(channels));
  ASSERT_EQ(adv["channels"].size(), 1u);
  EXPECT_EQ(adv["channels"][0]["id"], 3);
  EXPECT_TRUE(adv["channels"][0]["schema"].is_string());  // the schema as text, not an object
  EXPECT_EQ(adv["channels"][0]["schemaEncoding"], "jsonschema");
  EXPECT_EQ(json::parse(advertise({}))["channels"], json::array());
  const std::vector<std::uint32_t> gone = {3, 4};
  EXPECT_EQ(json::parse(unadvertise(gone))["channelIds"], json::array({3, 4}));
  const json st = json::parse(status(Level::kError, "bad \"thing\"\n"));
  EXPECT_EQ(st["level"], 2);
  EXPECT_EQ(st["message"], "bad \"thing\"\n");
  EXPECT_FALSE(st.contains("id"));
  EXPECT_EQ(json::parse(status(Level::kWarning, "x", "slow"))["id"], "slow");
  // Invalid UTF-8 in a message (a client's bad topic name echoed back) still gives JSON.
  EXPECT_FALSE(json::parse(status(Level::kError, "topic \xff\xfe"), nullptr, false).is_discarded());
  const std::vector<Parameter> params = {{"/vision/min_score", 0.75}};
  const json pv = json::parse(parameter_values(params, std::string("abc")));
  EXPECT_EQ(pv["parameters"][0]["value"], 0.75);
  EXPECT_EQ(pv["id"], "abc");
  EXPECT_FALSE(json::parse(parameter_values(params, std::nullopt)).contains("id"));
}

}  // namespace
}  // namespace rilbed::gui_web::foxglove
