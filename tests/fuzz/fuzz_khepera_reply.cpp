// Fuzz target for the Khepera serial protocol (src/serial/khepera_protocol.hpp): arbitrary
// bytes from a "serial port" go through the line assembler, and every line (and the raw
// input as one line) through decode_reply for every command kind of both robot models,
// looks_like_reply_to, decode_command and printable.
//
// Which lines the parsers accept is theirs to decide (they may grow more tolerant); this
// target checks only what holds whatever those rules are, and leaves crashes, leaks and
// undefined behaviour to ASan/UBSan:
//   - the assembler cuts the same lines however the bytes are split over feed() calls,
//     and a line never holds a line end, is never empty, never exceeds the limit;
//   - a decoded reply encodes to bytes that look like a reply to its kind and decode again,
//     to the same wheel and sensor values, and encode again to the same bytes;
//   - a decoded command encodes to bytes that decode again, to the same command;
//   - a command encode_command accepts decodes to itself (after clamping);
//   - printable() and every failure reason hold no control byte.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "serial/khepera_protocol.hpp"

namespace {

using namespace rilbed::serial;

constexpr CommandKind kKinds[] = {CommandKind::kReadVersions, CommandKind::kSetSpeeds,    CommandKind::kReadSpeeds,
                                  CommandKind::kSetCounters,  CommandKind::kReadCounters, CommandKind::kReadProximity,
                                  CommandKind::kReadAmbient,  CommandKind::kSetLed};
static_assert(sizeof kKinds / sizeof kKinds[0] == kCommandKindCount);

// An invariant broken: say which and on what, then abort so that libFuzzer saves the input.
[[noreturn]] void broken(const char* what, std::string_view detail) {
  std::fprintf(stderr, "\nfuzz_khepera_reply: invariant broken: %s\n  on %s\n", what, printable(detail, 400).c_str());
  std::abort();
}
#define FUZZ_CHECK(condition, detail)               \
  do {                                              \
    if (!(condition)) broken(#condition, (detail)); \
  } while (false)

bool has_control_byte(std::string_view text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return true;
  }
  return false;
}

bool all_printable_ascii(std::string_view text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte > 0x7e) return false;
  }
  return true;
}

void check_printable(std::string_view bytes) {
  for (const std::size_t max_chars : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{80}}) {
    const std::string quoted = printable(bytes, max_chars);
    FUZZ_CHECK(all_printable_ascii(quoted), quoted);
    FUZZ_CHECK(quoted.size() >= 2 && quoted.front() == '"' && quoted.back() == '"', quoted);
    // At most max_chars characters shown, each at most 4 bytes (\xNN), plus quotes and "...".
    FUZZ_CHECK(quoted.size() <= 2 + 4 * max_chars + 3, quoted);
  }
}

void check_reply(const RobotModel& model, CommandKind kind, std::string_view line) {
  const Result<Reply> reply = decode_reply(model, kind, line);
  if (!reply.ok()) {
    FUZZ_CHECK(!has_control_byte(reply.error()), reply.error());
    return;
  }
  FUZZ_CHECK(reply.error().empty(), line);
  FUZZ_CHECK(reply->kind == kind, line);
  // What the emulator would send for this reply is a reply to the same command again.
  const std::string encoded = encode_reply(model, reply.value());
  FUZZ_CHECK(encoded.size() >= 2 && encoded.compare(encoded.size() - 2, 2, "\r\n") == 0, encoded);
  FUZZ_CHECK(looks_like_reply_to(model, kind, encoded), encoded);
  const Result<Reply> again = decode_reply(model, kind, encoded);
  if (!again.ok())
    broken("encode_reply of a decoded reply decodes again",
           std::string(line) + " -> " + encoded + " -> " + again.error());
  FUZZ_CHECK(again->kind == kind, encoded);
  // The values rilbed computes with survive the round trip. (Versions are text kept for
  // display: one that is not a bios,protocol pair may read back differently, e.g. "B" has
  // an empty text and encodes to "b,,", which reads back as ",".)
  if (again->wheels != reply->wheels || again->sensors != reply->sensors) {
    broken("decode_reply(encode_reply(r)) has r's values", std::string(line) + " -> " + encoded);
  }
  // What the emulator sends is stable: encoding what it decodes gives the same bytes.
  FUZZ_CHECK(encode_reply(model, again.value()) == encoded, encoded);
}

void check_command(const RobotModel& model, std::string_view line) {
  const Result<Command> command = decode_command(model, line);
  if (!command.ok()) {
    FUZZ_CHECK(!has_control_byte(command.error()), command.error());
    return;
  }
  // What the link would send for this command is that command again.
  const Result<EncodedCommand> encoded = encode_command(model, command.value());
  if (!encoded.ok())
    broken("encode_command of a decoded command succeeds", std::string(line) + " -> " + encoded.error());
  const Result<Command> again = decode_command(model, encoded->bytes);
  if (!again.ok()) broken("encode_command of a decoded command decodes again", encoded->bytes + " -> " + again.error());
  if (!(again.value() == command.value()))
    broken("decode_command(encode_command(c)) == c", std::string(line) + " -> " + encoded->bytes);
}

void check_line(std::string_view line) {
  check_printable(line);
  for (const RobotModel* model : {&khepera2_model(), &epuck_model()}) {
    for (const CommandKind kind : kKinds) {
      check_reply(*model, kind, line);
      (void)looks_like_reply_to(*model, kind, line);
    }
    check_command(*model, line);
  }
}

// A command built from fuzzed numbers: when encode_command takes it, its bytes decode to it.
void check_encoded_command(FuzzedDataProvider& numbers) {
  const RobotModel& model = numbers.ConsumeBool() ? khepera2_model() : epuck_model();
  Command command;
  command.kind = kKinds[numbers.ConsumeIntegralInRange<std::size_t>(0, kCommandKindCount - 1)];
  command.first = numbers.ConsumeIntegral<std::int64_t>();
  command.second = numbers.ConsumeIntegral<std::int64_t>();
  const Result<EncodedCommand> encoded = encode_command(model, command);
  if (!encoded.ok()) {
    FUZZ_CHECK(!has_control_byte(encoded.error()), encoded.error());
    return;
  }
  const Result<Command> decoded = decode_command(model, encoded->bytes);
  if (!decoded.ok()) broken("an encoded command decodes", encoded->bytes + " -> " + decoded.error());
  FUZZ_CHECK(decoded->kind == command.kind, encoded->bytes);
  const bool has_arguments = command.kind == CommandKind::kSetSpeeds || command.kind == CommandKind::kSetCounters ||
                             command.kind == CommandKind::kSetLed;
  if (!has_arguments) return;
  Command expected = command;
  if (encoded->clamped) {
    FUZZ_CHECK(command.kind == CommandKind::kSetSpeeds, encoded->bytes);
    const std::int64_t limit = model.max_speed_units;
    expected.first = std::clamp(command.first, -limit, limit);
    expected.second = std::clamp(command.second, -limit, limit);
  }
  FUZZ_CHECK(decoded.value() == expected, encoded->bytes);
}

void check_lines(const std::vector<std::string>& lines, std::size_t max_line_bytes) {
  for (const std::string& line : lines) {
    FUZZ_CHECK(!line.empty(), line);
    FUZZ_CHECK(line.size() <= max_line_bytes, line);
    FUZZ_CHECK(line.find_first_of("\r\n") == std::string::npos, line);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);

  // The same bytes whole, and split over feed() calls where the bytes themselves say
  // (a serial port returns whatever has arrived), must give the same lines.
  LineAssembler whole;
  const std::vector<std::string> lines = whole.feed(bytes);
  check_lines(lines, LineAssembler::kDefaultMaxLineBytes);
  FUZZ_CHECK(whole.counters().lines == lines.size(), bytes);
  FUZZ_CHECK(whole.partial_bytes() <= LineAssembler::kDefaultMaxLineBytes, bytes);

  LineAssembler pieces;
  std::vector<std::string> piece_lines;
  for (std::size_t at = 0; at < size;) {
    const std::size_t length = std::min<std::size_t>(1 + data[at] % 13, size - at);
    pieces.feed(bytes.substr(at, length), piece_lines);
    at += length;
  }
  if (piece_lines != lines) broken("the same lines whether fed whole or in pieces", bytes);
  FUZZ_CHECK(pieces.counters().lines == whole.counters().lines, bytes);
  FUZZ_CHECK(pieces.counters().noise_bytes == whole.counters().noise_bytes, bytes);
  FUZZ_CHECK(pieces.counters().overlong_lines == whole.counters().overlong_lines, bytes);
  FUZZ_CHECK(pieces.partial_bytes() == whole.partial_bytes(), bytes);

  // A small limit reaches the over-long path, and discard_partial() between pieces (a
  // timeout) must leave the assembler sound.
  if (size > 0) {
    const std::size_t limit = 1 + data[0] % 24;
    LineAssembler small(limit);
    std::vector<std::string> small_lines;
    for (std::size_t at = 0; at < size;) {
      const std::size_t length = std::min<std::size_t>(1 + data[at] % 29, size - at);
      small.feed(bytes.substr(at, length), small_lines);
      if (data[at] % 5 == 0) {
        small.discard_partial();
        FUZZ_CHECK(small.partial_bytes() == 0, bytes);
      }
      at += length;
    }
    check_lines(small_lines, limit);
  }

  for (const std::string& line : lines) check_line(line);
  // The decoders also get raw bytes: callers may hand them a line with its CR LF, or one
  // that did not come through an assembler.
  check_line(bytes.substr(0, 4 * LineAssembler::kDefaultMaxLineBytes));

  FuzzedDataProvider numbers(data, size);
  check_encoded_command(numbers);
  return 0;
}
