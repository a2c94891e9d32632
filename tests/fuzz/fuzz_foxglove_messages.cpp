// Fuzz target for the Foxglove WebSocket protocol's client messages
// (src/gui_web/foxglove_protocol.hpp), as any browser or program that reaches the web
// server may send them: the first byte says whether the rest is a text frame or a binary
// frame. Whatever the bytes, parsing never throws, and:
//   - a text frame is accepted only when it is a JSON object whose "op" is one the server
//     takes, and then every list it parsed holds at most kMaxItems items;
//   - a refusal is a reason of bounded length (it goes back in a status message);
//   - a binary frame is accepted exactly when it is at least 5 bytes and starts with 0x01,
//     and then its channel id is the next four bytes, little-endian, and its payload the rest.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <variant>

#include "gui_web/foxglove_protocol.hpp"

namespace {

using namespace rilbed::gui_web::foxglove;

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "\nfuzz_foxglove_messages: invariant broken: %s\n", what);
  std::abort();
}
#define FUZZ_CHECK(condition)             \
  do {                                    \
    if (!(condition)) broken(#condition); \
  } while (false)

std::size_t items(const ClientText& t) {
  return std::visit(
      [](const auto& m) -> std::size_t {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, Subscribe>) return m.subscriptions.size();
        if constexpr (std::is_same_v<T, Unsubscribe>) return m.subscription_ids.size();
        if constexpr (std::is_same_v<T, ClientAdvertise>) return m.channels.size();
        if constexpr (std::is_same_v<T, ClientUnadvertise>) return m.channel_ids.size();
        if constexpr (std::is_same_v<T, GetParameters>) return m.names.size();
        if constexpr (std::is_same_v<T, SetParameters>) return m.parameters.size();
        return 0;
      },
      t);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::span<const std::uint8_t> frame(data + 1, size - 1);
  if (data[0] % 2 == 0) {
    const std::string text(frame.begin(), frame.end());
    const auto r = parse_client_text(text);
    if (const auto* why = std::get_if<std::string>(&r)) {
      FUZZ_CHECK(!why->empty() && why->size() < 200);
    } else {
      FUZZ_CHECK(items(std::get<ClientText>(r)) <= kMaxItems);
      FUZZ_CHECK(text.find("\"op\"") != std::string::npos || text.find("\\u") != std::string::npos);
    }
    return 0;
  }
  const auto r = parse_client_binary(frame);
  const bool whole = frame.size() >= 5 && frame[0] == 0x01;
  FUZZ_CHECK(std::holds_alternative<ClientMessage>(r) == whole);
  if (whole) {
    const ClientMessage& m = std::get<ClientMessage>(r);
    const std::uint32_t id = std::uint32_t{frame[1]} | std::uint32_t{frame[2]} << 8 | std::uint32_t{frame[3]} << 16 |
                             std::uint32_t{frame[4]} << 24;
    FUZZ_CHECK(m.channel_id == id && m.payload.data() == frame.data() + 5 && m.payload.size() == frame.size() - 5);
  }
  return 0;
}
