#include "serial/khepera_protocol.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <limits>

namespace rilbed::serial {

namespace {

constexpr std::int64_t kInt32Min = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t kInt32Max = std::numeric_limits<std::int32_t>::max();

constexpr std::size_t index_of(CommandKind kind) { return static_cast<std::size_t>(kind); }

constexpr std::array<CommandKind, kCommandKindCount> kAllKinds = {
    CommandKind::kReadVersions, CommandKind::kSetSpeeds,     CommandKind::kReadSpeeds,  CommandKind::kSetCounters,
    CommandKind::kReadCounters, CommandKind::kReadProximity, CommandKind::kReadAmbient, CommandKind::kSetLed};

RobotModel make_khepera2() {
  RobotModel m;
  m.name = "khepera2";
  m.letters[index_of(CommandKind::kReadVersions)] = 'B';
  m.letters[index_of(CommandKind::kSetSpeeds)] = 'D';
  m.letters[index_of(CommandKind::kReadSpeeds)] = 'E';
  m.letters[index_of(CommandKind::kSetCounters)] = 'G';
  m.letters[index_of(CommandKind::kReadCounters)] = 'H';
  m.letters[index_of(CommandKind::kReadProximity)] = 'N';
  m.letters[index_of(CommandKind::kReadAmbient)] = 'O';
  m.letters[index_of(CommandKind::kSetLed)] = 'L';
  m.bios_protocol_versions = true;
  m.max_speed_units = 127;
  m.max_sensor_value = 1023;
  m.led_count = 2;
  m.speed_unit_mps = 0.008;
  m.counter_pulse_m = 0.08e-3;
  m.wheel_base_m = 0.053;
  m.default_baud = 38400;
  return m;
}

RobotModel make_epuck() {
  RobotModel m = make_khepera2();
  m.name = "epuck";
  m.letters[index_of(CommandKind::kReadVersions)] = 'V';
  m.letters[index_of(CommandKind::kSetCounters)] = 'P';
  m.letters[index_of(CommandKind::kReadCounters)] = 'Q';
  m.bios_protocol_versions = false;
  m.max_speed_units = 1000;
  m.max_sensor_value = 4095;
  m.led_count = 8;
  // 1000 steps per wheel turn, wheel 41 mm across: pi * 41 mm / 1000 per step.
  m.counter_pulse_m = 3.14159265358979323846 * 0.041 / 1000.0;
  m.speed_unit_mps = m.counter_pulse_m;  // speeds are steps per second
  m.wheel_base_m = 0.053;
  m.default_baud = 115200;
  return m;
}

std::string_view strip_terminator(std::string_view line) {
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.remove_suffix(1);
  return line;
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Without line ends, spaces and tabs at either end.
std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank(text.back())) text.remove_suffix(1);
  return text;
}

char lower(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

std::vector<std::string_view> split_fields(std::string_view text) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(text.substr(start));
      return fields;
    }
    fields.push_back(text.substr(start, comma - start));
    start = comma + 1;
  }
}

// Integer syntax: an optional sign, then one or more digits, nothing else (the caller
// trims blanks). from_chars alone would accept a prefix ("12x").
std::optional<std::int64_t> parse_integer(std::string_view field, bool allow_plus) {
  if (allow_plus && field.size() > 1 && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return std::nullopt;
  const std::size_t digits_from = field.front() == '-' ? 1 : 0;
  if (digits_from == field.size()) return std::nullopt;
  for (std::size_t i = digits_from; i < field.size(); ++i) {
    if (field[i] < '0' || field[i] > '9') return std::nullopt;
  }
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (error != std::errc() || end != field.data() + field.size()) return std::nullopt;  // overflow
  return value;
}

// The strict form commands take (the emulator plays K-Team's firmware): exactly
// `expected_count` integers after the letter, no blanks, no sign but '-'.
Result<std::vector<std::int64_t>> parse_command_values(std::string_view after_letter, std::size_t expected_count,
                                                       std::int64_t min, std::int64_t max, const std::string& what) {
  std::vector<std::int64_t> values;
  if (expected_count == 0) {
    if (!after_letter.empty()) return Failure{what + ": expected no values after the letter"};
    return values;
  }
  if (after_letter.empty() || after_letter.front() != ',') {
    return Failure{what + ": expected " + std::to_string(expected_count) + " comma-separated values after the letter"};
  }
  const std::vector<std::string_view> fields = split_fields(after_letter.substr(1));
  if (fields.size() != expected_count) {
    return Failure{what + ": has " + std::to_string(fields.size()) + " values, expected " +
                   std::to_string(expected_count)};
  }
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::optional<std::int64_t> value = parse_integer(fields[i], false);
    if (!value)
      return Failure{what + ": value " + std::to_string(i + 1) + " " + printable(fields[i]) + " is not an integer"};
    if (*value < min || *value > max) {
      return Failure{what + ": value " + std::to_string(i + 1) + " = " + std::to_string(*value) + " is outside " +
                     std::to_string(min) + ".." + std::to_string(max)};
    }
    values.push_back(*value);
  }
  return values;
}

// The name of a reply's computed field `index` (0-based), for messages.
std::string field_name(CommandKind kind, std::size_t index) {
  switch (kind) {
    case CommandKind::kReadSpeeds: return index == 0 ? "left speed" : "right speed";
    case CommandKind::kReadCounters: return index == 0 ? "left counter" : "right counter";
    case CommandKind::kReadProximity: return "proximity sensor " + std::to_string(index);
    case CommandKind::kReadAmbient: return "ambient sensor " + std::to_string(index);
    default: return "value " + std::to_string(index + 1);
  }
}

// The first `expected_count` fields of a reply (after its letter), each trimmed, an
// integer and in range; fields beyond them are ignored. `what` names the line and
// command in the failure.
Result<std::vector<std::int64_t>> parse_reply_values(CommandKind kind, std::string_view after_letter,
                                                     std::size_t expected_count, std::int64_t min, std::int64_t max,
                                                     const std::string& what) {
  std::vector<std::int64_t> values;
  if (expected_count == 0) return values;
  const std::vector<std::string_view> fields =
      after_letter.empty() ? std::vector<std::string_view>{} : split_fields(after_letter.substr(1));
  for (std::size_t i = 0; i < expected_count; ++i) {
    const std::string label = "field " + std::to_string(i + 1) + " (" + field_name(kind, i) + ")";
    if (i >= fields.size()) {
      return Failure{what + ": " + label + " is missing (" + std::to_string(fields.size()) + " of " +
                     std::to_string(expected_count) + " values)"};
    }
    const std::string_view field = trim(fields[i]);
    const std::optional<std::int64_t> value = parse_integer(field, true);
    if (!value) return Failure{what + ": " + label + " " + printable(field) + " is not an integer"};
    if (*value < min || *value > max) {
      return Failure{what + ": " + label + " = " + std::to_string(*value) + " is outside " + std::to_string(min) +
                     ".." + std::to_string(max)};
    }
    values.push_back(*value);
  }
  return values;
}

// What follows a reply's letter without its leading comma, trimmed.
std::string_view after_comma(std::string_view after_letter) {
  after_letter = trim(after_letter);
  if (!after_letter.empty() && after_letter.front() == ',') after_letter.remove_prefix(1);
  return trim(after_letter);
}

// Khepera versions: "b,<bios>,<protocol>" kept as text; whatever the fields hold.
FirmwareVersions bios_protocol_versions(std::string_view after_letter) {
  FirmwareVersions v;
  const std::string_view text = after_comma(after_letter);
  const std::size_t comma = text.find(',');
  v.bios = std::string(trim(text.substr(0, comma)));
  std::string_view more;  // fields beyond the two
  if (comma != std::string_view::npos) {
    const std::string_view after = text.substr(comma + 1);
    const std::size_t next = after.find(',');
    v.protocol = std::string(trim(after.substr(0, next)));
    if (next != std::string_view::npos) more = trim(after.substr(next + 1));
  }
  if (v.bios.empty() || v.protocol.empty()) {
    v.text = std::string(text);
  } else {
    v.text = "bios " + v.bios + ", protocol " + v.protocol;
    if (!more.empty()) v.text += " (" + std::string(more) + ")";
  }
  return v;
}

// How many values a command or its reply carries, and their range, per kind.
struct Shape {
  std::size_t count;
  std::int64_t min;
  std::int64_t max;
};

Shape command_shape(const RobotModel& model, CommandKind kind) {
  switch (kind) {
    case CommandKind::kSetSpeeds: return {2, -model.max_speed_units, model.max_speed_units};
    case CommandKind::kSetCounters: return {2, kInt32Min, kInt32Max};
    case CommandKind::kSetLed: return {2, 0, std::max(model.led_count - 1, 2)};  // n and s checked apart below
    default: return {0, 0, 0};
  }
}

Shape reply_shape(const RobotModel& model, CommandKind kind) {
  switch (kind) {
    case CommandKind::kReadSpeeds: return {2, -model.max_speed_units, model.max_speed_units};
    case CommandKind::kReadCounters: return {2, kInt32Min, kInt32Max};
    case CommandKind::kReadProximity:
    case CommandKind::kReadAmbient: return {environment::kProximityCount, 0, model.max_sensor_value};
    default: return {0, 0, 0};  // acknowledgements
  }
}

}  // namespace

std::string_view command_kind_name(CommandKind kind) {
  switch (kind) {
    case CommandKind::kReadVersions: return "read versions";
    case CommandKind::kSetSpeeds: return "set speeds";
    case CommandKind::kReadSpeeds: return "read speeds";
    case CommandKind::kSetCounters: return "set counters";
    case CommandKind::kReadCounters: return "read counters";
    case CommandKind::kReadProximity: return "read proximity";
    case CommandKind::kReadAmbient: return "read ambient light";
    case CommandKind::kSetLed: return "set LED";
  }
  return "unknown command";
}

char RobotModel::reply_letter(CommandKind kind) const {
  return static_cast<char>(std::tolower(static_cast<unsigned char>(command_letter(kind))));
}

const RobotModel& khepera2_model() {
  static const RobotModel model = make_khepera2();
  return model;
}

const RobotModel& epuck_model() {
  static const RobotModel model = make_epuck();
  return model;
}

const RobotModel* find_robot_model(std::string_view name) {
  if (name == khepera2_model().name) return &khepera2_model();
  if (name == epuck_model().name) return &epuck_model();
  return nullptr;
}

std::string printable(std::string_view bytes, std::size_t max_chars) {
  std::string out = "\"";
  std::size_t shown = 0;
  for (const char c : bytes) {
    if (shown == max_chars) {
      out += "...";
      break;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\r') {
      out += "\\r";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\0') {
      out += "\\0";
    } else if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte > 0x7e) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", byte);
      out += hex;
    } else {
      out += c;
    }
    ++shown;
  }
  return out + "\"";
}

Result<EncodedCommand> encode_command(const RobotModel& model, const Command& command) {
  EncodedCommand encoded;
  encoded.bytes = model.command_letter(command.kind);
  std::int64_t first = command.first, second = command.second;
  switch (command.kind) {
    case CommandKind::kSetSpeeds: {
      const std::int64_t limit = model.max_speed_units;
      first = std::clamp(command.first, -limit, limit);
      second = std::clamp(command.second, -limit, limit);
      encoded.clamped = first != command.first || second != command.second;
      break;
    }
    case CommandKind::kSetCounters:
      if (first < kInt32Min || first > kInt32Max || second < kInt32Min || second > kInt32Max) {
        return Failure{"counters " + std::to_string(first) + ", " + std::to_string(second) +
                       " do not fit the firmware's 32-bit counters"};
      }
      break;
    case CommandKind::kSetLed:
      if (first < 0 || first >= model.led_count) {
        return Failure{"LED " + std::to_string(first) + " does not exist on a " + std::string(model.name) + " (0.." +
                       std::to_string(model.led_count - 1) + ")"};
      }
      if (second < 0 || second > 2)
        return Failure{"LED action " + std::to_string(second) + " is not 0 (off), 1 (on) or 2 (toggle)"};
      break;
    default: encoded.bytes += '\r'; return encoded;
  }
  encoded.bytes += ',' + std::to_string(first) + ',' + std::to_string(second) + '\r';
  return encoded;
}

Result<Command> decode_command(const RobotModel& model, std::string_view line) {
  line = strip_terminator(line);
  if (line.empty()) return Failure{"empty command"};
  const std::string what = "command " + printable(line);
  for (const CommandKind kind : kAllKinds) {
    if (line.front() != model.command_letter(kind)) continue;
    const Shape shape = command_shape(model, kind);
    auto values = parse_command_values(line.substr(1), shape.count, shape.min, shape.max, what);
    if (!values) return Failure{values.error()};
    Command command{kind};
    if (shape.count == 2) {
      command.first = values.value()[0];
      command.second = values.value()[1];
    }
    if (kind == CommandKind::kSetLed && (command.first >= model.led_count || command.second > 2)) {
      return Failure{what + ": no such LED or action"};
    }
    return command;
  }
  return Failure{what + ": unknown command letter"};
}

namespace {

// Whether `line` (trimmed) starts with `letter` in either case, followed by nothing, a
// comma or a blank: the shape of a reply with that letter.
bool starts_with_reply_letter(std::string_view line, char letter) {
  if (line.empty() || lower(line.front()) != letter) return false;
  return line.size() == 1 || line[1] == ',' || is_blank(line[1]);
}

}  // namespace

bool looks_like_reply_to(const RobotModel& model, CommandKind expected, std::string_view line) {
  line = trim(line);
  return starts_with_reply_letter(line, model.reply_letter(expected)) || starts_with_reply_letter(line, 'z');
}

bool is_echo_of(const RobotModel& model, const Command& command, std::string_view line) {
  const Result<EncodedCommand> encoded = encode_command(model, command);
  return encoded.ok() && !trim(line).empty() && trim(line) == trim(encoded->bytes);
}

Result<Reply> decode_reply(const RobotModel& model, CommandKind expected, std::string_view line) {
  line = trim(line);
  const char expected_letter = model.reply_letter(expected);
  const std::string command_text =
      std::string(1, model.command_letter(expected)) + " (" + std::string(command_kind_name(expected)) + ")";
  const std::string what = "reply " + printable(line) + " to " + command_text;
  if (line.empty()) return Failure{"empty reply to " + command_text};
  if (expected_letter != 'z' && starts_with_reply_letter(line, 'z')) {
    return Failure{what + ": the robot reports a protocol error"};
  }
  if (lower(line.front()) != expected_letter) {
    return Failure{what + ": starts with " + printable(line.substr(0, 1)) + ", expected \"" +
                   std::string(1, expected_letter) + "\""};
  }
  if (!starts_with_reply_letter(line, expected_letter)) {
    return Failure{what + ": expected a comma after the letter \"" + std::string(1, expected_letter) + "\""};
  }
  Reply reply;
  reply.kind = expected;
  // What follows the letter: nothing, or a comma and the fields (blanks before it ignored).
  const std::string_view rest = trim(line.substr(1));
  const Shape shape = reply_shape(model, expected);
  if (shape.count > 0 && !rest.empty() && rest.front() != ',') {
    return Failure{what + ": expected a comma before the values"};
  }
  if (expected == CommandKind::kReadVersions) {
    // Shown, never computed with: kept as text, whatever it holds.
    if (model.bios_protocol_versions) {
      reply.versions = bios_protocol_versions(rest);
    } else {
      std::string text(after_comma(rest));
      for (char& c : text) {
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
      }
      reply.versions.text = std::move(text);
    }
    return reply;
  }
  auto values = parse_reply_values(expected, rest, shape.count, shape.min, shape.max, what);
  if (!values) return Failure{values.error()};
  const std::vector<std::int64_t>& v = values.value();
  switch (expected) {
    case CommandKind::kReadSpeeds:
    case CommandKind::kReadCounters: reply.wheels = {v[0], v[1]}; break;
    case CommandKind::kReadProximity:
    case CommandKind::kReadAmbient:
      for (std::size_t i = 0; i < reply.sensors.size(); ++i) reply.sensors[i] = static_cast<int>(v[i]);
      break;
    default: break;  // acknowledgements: whatever follows the letter is ignored
  }
  return reply;
}

std::string encode_reply(const RobotModel& model, const Reply& reply) {
  std::string bytes(1, model.reply_letter(reply.kind));
  switch (reply.kind) {
    case CommandKind::kReadVersions:
      if (model.bios_protocol_versions) {
        bytes += ',' + reply.versions.bios + ',' + reply.versions.protocol;
      } else {
        bytes += ',' + reply.versions.text;
      }
      break;
    case CommandKind::kReadSpeeds:
    case CommandKind::kReadCounters:
      bytes += ',' + std::to_string(reply.wheels.left) + ',' + std::to_string(reply.wheels.right);
      break;
    case CommandKind::kReadProximity:
    case CommandKind::kReadAmbient:
      for (const int value : reply.sensors) bytes += ',' + std::to_string(value);
      break;
    default: break;
  }
  return bytes + "\r\n";
}

LineAssembler::LineAssembler(std::size_t max_line_bytes) : max_line_bytes_(std::max<std::size_t>(max_line_bytes, 1)) {}

void LineAssembler::feed(std::string_view bytes, std::vector<std::string>& lines) {
  for (const char c : bytes) {
    if (c == '\r' || c == '\n') {
      if (skipping_overlong_) {
        skipping_overlong_ = false;  // resynchronised: the next byte starts a fresh line
      } else if (!partial_.empty()) {
        lines.push_back(std::move(partial_));
        ++counters_.lines;
      }
      partial_.clear();
      continue;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte > 0x7e) {
      ++counters_.noise_bytes;
      continue;
    }
    if (skipping_overlong_) continue;
    if (partial_.size() == max_line_bytes_) {
      ++counters_.overlong_lines;
      partial_.clear();
      skipping_overlong_ = true;
      continue;
    }
    partial_ += c;
  }
}

std::vector<std::string> LineAssembler::feed(std::string_view bytes) {
  std::vector<std::string> lines;
  feed(bytes, lines);
  return lines;
}

void LineAssembler::discard_partial() {
  partial_.clear();
  skipping_overlong_ = false;
}

}  // namespace rilbed::serial
