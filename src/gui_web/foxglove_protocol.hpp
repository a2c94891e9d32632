// The Foxglove WebSocket protocol (subprotocol "foxglove.websocket.v1"), as rilbed's web
// server speaks it: the JSON text messages and binary frames of both directions, built and
// parsed here, apart from any socket, so that they are tested (and fuzzed) on their own.
// Foxglove Studio, Lichtblick and @foxglove/ws-protocol's FoxgloveClient are clients of it;
// rilbed's own page is another.
//
// The protocol's rules this follows (its spec, ws-protocol commit 8e2a044^, docs/spec.md):
// every JSON message is one text frame, an object with a string "op"; every binary frame
// starts with a one-byte opcode and holds little-endian integers; a channel's schema is a
// JSON Schema serialized into a string; subscription ids are the client's, 0 included.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

namespace rilbed::gui_web::foxglove {

/// The WebSocket subprotocol a client must offer.
inline constexpr std::string_view kSubprotocol = "foxglove.websocket.v1";

/// A channel the server offers (advertise).
struct Channel {
  std::uint32_t id = 0;
  std::string topic;
  std::string encoding = "json";
  std::string schema_name;  ///< e.g. "rilbed.poses_t", "foxglove.SceneUpdate"
  std::string schema;       ///< the JSON Schema, as text
  std::string schema_encoding = "jsonschema";
};

/// A channel a client offers to publish on (client advertise).
struct ClientChannel {
  std::uint32_t id = 0;
  std::string topic;
  std::string encoding;
  std::string schema_name;
};

/// One subscription: the client's id for it and the server's channel.
struct Subscription {
  std::uint32_t id = 0;
  std::uint32_t channel_id = 0;
};

/// A parameter (getParameters / setParameters / parameterValues). `value` null: unset.
struct Parameter {
  std::string name;
  nlohmann::json value;
};

// What a client's text frame asks.
struct Subscribe {
  std::vector<Subscription> subscriptions;
};
struct Unsubscribe {
  std::vector<std::uint32_t> subscription_ids;
};
struct ClientAdvertise {
  std::vector<ClientChannel> channels;
};
struct ClientUnadvertise {
  std::vector<std::uint32_t> channel_ids;
};
struct GetParameters {
  std::vector<std::string> names;  ///< empty: all
  std::optional<std::string> id;   ///< echoed in the answer
};
struct SetParameters {
  std::vector<Parameter> parameters;
  std::optional<std::string> id;
};
struct SubscribeParameterUpdates {
  std::vector<std::string> names;
};
struct UnsubscribeParameterUpdates {
  std::vector<std::string> names;
};
using ClientText = std::variant<Subscribe, Unsubscribe, ClientAdvertise, ClientUnadvertise, GetParameters,
                                SetParameters, SubscribeParameterUpdates, UnsubscribeParameterUpdates>;

/// A client's binary Client Message Data frame: a message on one of its channels. The
/// payload is a view into the frame.
struct ClientMessage {
  std::uint32_t channel_id = 0;
  std::span<const std::uint8_t> payload;
};

/// The most items (subscriptions, channels, ids, parameters) one client message may list;
/// more is refused, so that a hostile client cannot make the server allocate without bound.
inline constexpr std::size_t kMaxItems = 1024;

/// Parses a client's text frame. Returns the request, or a reason fit for a status
/// message ("not JSON: ...", "unknown op 'x'", "subscribe: subscriptions[2].channelId is
/// not an integer in 0..4294967295"). Never throws.
std::variant<ClientText, std::string> parse_client_text(std::string_view text);

/// Parses a client's binary frame (opcode 0x01, Client Message Data). Returns the message
/// or a reason ("empty binary message", "unknown binary opcode 7", "message of 3 bytes is
/// shorter than its 5-byte header").
std::variant<ClientMessage, std::string> parse_client_binary(std::span<const std::uint8_t> frame);

/// serverInfo: the server's name, what it can do ("clientPublish", "parameters", ...),
/// the encodings it takes from clients, and the session (a new run is a new session).
std::string server_info(const std::string& name, const std::vector<std::string>& capabilities,
                        const std::vector<std::string>& supported_encodings, const std::string& session_id);
/// advertise: the server's channels (every field, the schema as a string).
std::string advertise(std::span<const Channel> channels);
/// unadvertise: channels gone.
std::string unadvertise(std::span<const std::uint32_t> channel_ids);
/// status: 0 info, 1 warning, 2 error; `id` (may be empty) lets a later status replace it.
enum class Level { kInfo = 0, kWarning = 1, kError = 2 };
std::string status(Level level, const std::string& message, const std::string& id = {});
/// parameterValues, with the request's id when it had one.
std::string parameter_values(std::span<const Parameter> parameters, const std::optional<std::string>& id);

/// The 13 bytes that begin a Message Data frame (opcode 0x01, the client's subscription
/// id, the time in nanoseconds); the payload follows in the same WebSocket message.
std::array<std::uint8_t, 13> message_data_header(std::uint32_t subscription_id, std::uint64_t t_ns);

}  // namespace rilbed::gui_web::foxglove
