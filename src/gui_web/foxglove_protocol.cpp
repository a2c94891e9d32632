#include "gui_web/foxglove_protocol.hpp"

#include <limits>

namespace rilbed::gui_web::foxglove {

namespace {

using nlohmann::json;

// Reads a message's fields, turning the first missing or mistyped one into a reason.
class Fields {
 public:
  Fields(const json& object, std::string where) : object_(object), where_(std::move(where)) {}
  const std::optional<std::string>& problem() const { return problem_; }

  const json* array(const char* key) {
    const json* v = find(key);
    if (v && !v->is_array()) return fail(key, "is not an array");
    if (v && v->size() > kMaxItems) return fail(key, "lists more than " + std::to_string(kMaxItems) + " items");
    return v;
  }
  std::uint32_t uint32(const json& v, const std::string& name) {
    if (!v.is_number_integer() || v.get<std::int64_t>() < 0 ||
        v.get<std::int64_t>() > static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max())) {
      fail_named(name, "is not an integer in 0..4294967295");
      return 0;
    }
    return static_cast<std::uint32_t>(v.get<std::int64_t>());
  }
  std::string string(const json& v, const std::string& name) {
    if (!v.is_string()) {
      fail_named(name, "is not a string");
      return {};
    }
    return v.get<std::string>();
  }
  const json& member(const json& item, const char* key, const std::string& name) {
    static const json null;
    if (!item.is_object()) {
      fail_named(name, "is not an object");
      return null;
    }
    const auto it = item.find(key);
    if (it == item.end()) {
      fail_named(name + "." + key, "is missing");
      return null;
    }
    return *it;
  }
  std::optional<std::string> optional_string(const char* key) {
    const auto it = object_.find(key);
    if (it == object_.end() || it->is_null()) return std::nullopt;
    if (!it->is_string()) {
      fail(key, "is not a string");
      return std::nullopt;
    }
    return it->get<std::string>();
  }

 private:
  const json* find(const char* key) {
    const auto it = object_.find(key);
    if (it == object_.end()) return fail(key, "is missing");
    return &*it;
  }
  const json* fail(const char* key, const std::string& what) {
    fail_named(key, what);
    return nullptr;
  }
  void fail_named(const std::string& name, const std::string& what) {
    if (!problem_) problem_ = where_ + ": " + name + " " + what;
  }

  const json& object_;
  std::string where_;
  std::optional<std::string> problem_;
};

std::string item(const char* array, std::size_t i) { return std::string(array) + "[" + std::to_string(i) + "]"; }

template <typename T>
std::variant<ClientText, std::string> done(Fields& f, T value) {
  if (f.problem()) return *f.problem();
  return ClientText{std::move(value)};
}

std::variant<ClientText, std::string> parse_subscribe(Fields& f) {
  Subscribe s;
  if (const json* list = f.array("subscriptions")) {
    for (std::size_t i = 0; i < list->size() && !f.problem(); ++i) {
      const std::string name = item("subscriptions", i);
      const json& e = (*list)[i];
      const std::uint32_t id = f.uint32(f.member(e, "id", name), name + ".id");
      const std::uint32_t channel = f.uint32(f.member(e, "channelId", name), name + ".channelId");
      s.subscriptions.push_back({id, channel});
    }
  }
  return done(f, std::move(s));
}

std::vector<std::uint32_t> ids(Fields& f, const char* key) {
  std::vector<std::uint32_t> out;
  if (const json* list = f.array(key)) {
    for (std::size_t i = 0; i < list->size() && !f.problem(); ++i) out.push_back(f.uint32((*list)[i], item(key, i)));
  }
  return out;
}

std::variant<ClientText, std::string> parse_client_advertise(Fields& f) {
  ClientAdvertise a;
  if (const json* list = f.array("channels")) {
    for (std::size_t i = 0; i < list->size() && !f.problem(); ++i) {
      const std::string name = item("channels", i);
      const json& e = (*list)[i];
      ClientChannel c;
      c.id = f.uint32(f.member(e, "id", name), name + ".id");
      c.topic = f.string(f.member(e, "topic", name), name + ".topic");
      c.encoding = f.string(f.member(e, "encoding", name), name + ".encoding");
      c.schema_name = f.string(f.member(e, "schemaName", name), name + ".schemaName");
      a.channels.push_back(std::move(c));
    }
  }
  return done(f, std::move(a));
}

std::vector<std::string> parameter_names(Fields& f) {
  std::vector<std::string> names;
  if (const json* list = f.array("parameterNames")) {
    for (std::size_t i = 0; i < list->size() && !f.problem(); ++i)
      names.push_back(f.string((*list)[i], item("parameterNames", i)));
  }
  return names;
}

std::variant<ClientText, std::string> parse_get_parameters(Fields& f) {
  GetParameters g;
  g.names = parameter_names(f);
  g.id = f.optional_string("id");
  return done(f, std::move(g));
}

std::variant<ClientText, std::string> parse_set_parameters(Fields& f) {
  SetParameters s;
  if (const json* list = f.array("parameters")) {
    for (std::size_t i = 0; i < list->size() && !f.problem(); ++i) {
      const std::string name = item("parameters", i);
      const json& e = (*list)[i];
      Parameter p;
      p.name = f.string(f.member(e, "name", name), name + ".name");
      if (e.is_object()) {
        if (const auto it = e.find("value"); it != e.end()) p.value = *it;
      }
      s.parameters.push_back(std::move(p));
    }
  }
  s.id = f.optional_string("id");
  return done(f, std::move(s));
}

void put_le(std::uint8_t* out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::string dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

}  // namespace

std::variant<ClientText, std::string> parse_client_text(std::string_view text) {
  const json j = json::parse(text.begin(), text.end(), nullptr, false);
  if (j.is_discarded()) return std::string("not JSON");
  if (!j.is_object()) return std::string("not a JSON object");
  const auto op_it = j.find("op");
  if (op_it == j.end() || !op_it->is_string()) return std::string("no string \"op\"");
  const std::string op = op_it->get<std::string>();
  Fields f(j, op);
  if (op == "subscribe") return parse_subscribe(f);
  if (op == "unsubscribe") {
    Unsubscribe u;
    u.subscription_ids = ids(f, "subscriptionIds");
    return done(f, std::move(u));
  }
  if (op == "advertise") return parse_client_advertise(f);
  if (op == "unadvertise") {
    ClientUnadvertise u;
    u.channel_ids = ids(f, "channelIds");
    return done(f, std::move(u));
  }
  if (op == "getParameters") return parse_get_parameters(f);
  if (op == "setParameters") return parse_set_parameters(f);
  if (op == "subscribeParameterUpdates") return done(f, SubscribeParameterUpdates{parameter_names(f)});
  if (op == "unsubscribeParameterUpdates") return done(f, UnsubscribeParameterUpdates{parameter_names(f)});
  std::string shown = op.substr(0, 64);
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  }
  return "unknown op '" + shown + "'";
}

std::variant<ClientMessage, std::string> parse_client_binary(std::span<const std::uint8_t> frame) {
  if (frame.empty()) return std::string("empty binary message");
  if (frame[0] != 0x01) return "unknown binary opcode " + std::to_string(frame[0]);
  if (frame.size() < 5)
    return "message of " + std::to_string(frame.size()) + " bytes is shorter than its 5-byte header";
  ClientMessage m;
  m.channel_id = static_cast<std::uint32_t>(frame[1]) | (static_cast<std::uint32_t>(frame[2]) << 8) |
                 (static_cast<std::uint32_t>(frame[3]) << 16) | (static_cast<std::uint32_t>(frame[4]) << 24);
  m.payload = frame.subspan(5);
  return m;
}

std::string server_info(const std::string& name, const std::vector<std::string>& capabilities,
                        const std::vector<std::string>& supported_encodings, const std::string& session_id) {
  json j;
  j["op"] = "serverInfo";
  j["name"] = name;
  j["capabilities"] = capabilities;
  j["supportedEncodings"] = supported_encodings;
  j["metadata"] = json::object();
  j["sessionId"] = session_id;
  return dump(j);
}

std::string advertise(std::span<const Channel> channels) {
  json list = json::array();
  for (const Channel& c : channels) {
    json e;
    e["id"] = c.id;
    e["topic"] = c.topic;
    e["encoding"] = c.encoding;
    e["schemaName"] = c.schema_name;
    e["schema"] = c.schema;
    if (!c.schema_encoding.empty()) e["schemaEncoding"] = c.schema_encoding;
    list.push_back(std::move(e));
  }
  return dump(json{{"op", "advertise"}, {"channels", std::move(list)}});
}

std::string unadvertise(std::span<const std::uint32_t> channel_ids) {
  return dump(
      json{{"op", "unadvertise"}, {"channelIds", std::vector<std::uint32_t>(channel_ids.begin(), channel_ids.end())}});
}

std::string status(Level level, const std::string& message, const std::string& id) {
  json j{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}};
  if (!id.empty()) j["id"] = id;
  return dump(j);
}

std::string parameter_values(std::span<const Parameter> parameters, const std::optional<std::string>& id) {
  json list = json::array();
  for (const Parameter& p : parameters) list.push_back(json{{"name", p.name}, {"value", p.value}});
  json j{{"op", "parameterValues"}, {"parameters", std::move(list)}};
  if (id) j["id"] = *id;
  return dump(j);
}

std::array<std::uint8_t, 13> message_data_header(std::uint32_t subscription_id, std::uint64_t t_ns) {
  std::array<std::uint8_t, 13> h{};
  h[0] = 0x01;
  put_le(&h[1], subscription_id, 4);
  put_le(&h[5], t_ns, 8);
  return h;
}

}  // namespace rilbed::gui_web::foxglove
