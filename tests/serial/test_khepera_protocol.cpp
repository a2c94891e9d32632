// The protocol codec: every command encoded, every reply decoded, malformed replies
// rejected with a reason, the e-puck's letters, and the emulator's side (commands decoded,
// replies encoded) agreeing with the link's.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "serial/khepera_protocol.hpp"

using namespace rilbed::serial;

namespace {

std::string encode(const RobotModel& model, const Command& command) {
  const Result<EncodedCommand> encoded = encode_command(model, command);
  EXPECT_TRUE(encoded.ok()) << encoded.error();
  return encoded ? encoded->bytes : std::string();
}

}  // namespace

TEST(KheperaProtocol, EncodesEveryKheperaCommand) {
  const RobotModel& k = khepera2_model();
  EXPECT_EQ(encode(k, Command::read_versions()), "B\r");
  EXPECT_EQ(encode(k, Command::set_speeds(10, -10)), "D,10,-10\r");
  EXPECT_EQ(encode(k, Command::set_speeds(0, 0)), "D,0,0\r");
  EXPECT_EQ(encode(k, Command::read_speeds()), "E\r");
  EXPECT_EQ(encode(k, Command::set_counters(0, -123456)), "G,0,-123456\r");
  EXPECT_EQ(encode(k, Command::read_counters()), "H\r");
  EXPECT_EQ(encode(k, Command::read_proximity()), "N\r");
  EXPECT_EQ(encode(k, Command::read_ambient()), "O\r");
  EXPECT_EQ(encode(k, Command::set_led(1, LedAction::kToggle)), "L,1,2\r");
  EXPECT_EQ(encode(k, Command::set_led(0, LedAction::kOff)), "L,0,0\r");
}

TEST(KheperaProtocol, ClampsSpeedsAndSaysSo) {
  const RobotModel& k = khepera2_model();
  Result<EncodedCommand> e = encode_command(k, Command::set_speeds(127, -127));
  ASSERT_TRUE(e.ok());
  EXPECT_FALSE(e->clamped);
  e = encode_command(k, Command::set_speeds(200, -300));
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(e->bytes, "D,127,-127\r");
  EXPECT_TRUE(e->clamped);
  e = encode_command(k, Command::set_speeds(5, 128));
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(e->bytes, "D,5,127\r");
  EXPECT_TRUE(e->clamped);
  // The e-puck's range is +-1000 steps/s.
  e = encode_command(epuck_model(), Command::set_speeds(800, -1200));
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(e->bytes, "D,800,-1000\r");
  EXPECT_TRUE(e->clamped);
}

TEST(KheperaProtocol, RefusesCommandsTheFirmwareCannotTake) {
  const RobotModel& k = khepera2_model();
  Result<EncodedCommand> e = encode_command(k, Command::set_led(2, LedAction::kOn));
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().find("LED 2 does not exist"), std::string::npos) << e.error();
  e = encode_command(k, Command{CommandKind::kSetLed, 0, 3});
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().find("LED action 3"), std::string::npos) << e.error();
  e = encode_command(k, Command::set_counters(1LL << 31, 0));
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().find("32-bit"), std::string::npos) << e.error();
  EXPECT_TRUE(encode_command(epuck_model(), Command::set_led(7, LedAction::kOn)).ok());
}

TEST(KheperaProtocol, EpuckUsesItsOwnLetters) {
  const RobotModel& e = epuck_model();
  EXPECT_EQ(encode(e, Command::read_versions()), "V\r");
  EXPECT_EQ(encode(e, Command::set_counters(1, 2)), "P,1,2\r");
  EXPECT_EQ(encode(e, Command::read_counters()), "Q\r");
  EXPECT_EQ(encode(e, Command::set_speeds(1, 2)), "D,1,2\r");
  EXPECT_EQ(encode(e, Command::read_proximity()), "N\r");
  EXPECT_EQ(e.reply_letter(CommandKind::kReadCounters), 'q');
  EXPECT_EQ(e.default_baud, 115200u);

  Result<Reply> r = decode_reply(e, CommandKind::kReadVersions, "v,Version 1.2.2 August 2008 GCtronic\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->versions.text, "Version 1.2.2 August 2008 GCtronic");
  r = decode_reply(e, CommandKind::kReadCounters, "q,-1000,2000\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->wheels, (WheelPair{-1000, 2000}));
  EXPECT_TRUE(decode_reply(e, CommandKind::kSetCounters, "p\r\n").ok());
  r = decode_reply(e, CommandKind::kReadProximity, "n,4095,0,0,0,0,0,0,3000\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->sensors[0], 4095);
  // A Khepera's reply to B is not an e-puck's reply to V; an empty version text is still
  // a reply (rilbed only shows it).
  EXPECT_FALSE(decode_reply(e, CommandKind::kReadVersions, "b,5,4\r\n").ok());
  r = decode_reply(e, CommandKind::kReadVersions, "v,\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->versions.text, "");
}

TEST(KheperaProtocol, FindsModelsByName) {
  ASSERT_NE(find_robot_model("khepera2"), nullptr);
  EXPECT_EQ(find_robot_model("khepera2")->command_letter(CommandKind::kReadCounters), 'H');
  ASSERT_NE(find_robot_model("epuck"), nullptr);
  EXPECT_EQ(find_robot_model("epuck")->command_letter(CommandKind::kReadVersions), 'V');
  EXPECT_EQ(find_robot_model("khepera4"), nullptr);
}

TEST(KheperaProtocol, DecodesEveryKheperaReply) {
  const RobotModel& k = khepera2_model();
  Result<Reply> r = decode_reply(k, CommandKind::kReadVersions, "b,5,4\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->versions.bios, "5");
  EXPECT_EQ(r->versions.protocol, "4");
  EXPECT_EQ(r->versions.text, "bios 5, protocol 4");

  for (const CommandKind ack : {CommandKind::kSetSpeeds, CommandKind::kSetCounters, CommandKind::kSetLed}) {
    const std::string line = std::string(1, k.reply_letter(ack)) + "\r\n";
    r = decode_reply(k, ack, line);
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_EQ(r->kind, ack);
  }

  r = decode_reply(k, CommandKind::kReadSpeeds, "e,-127,127\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->wheels, (WheelPair{-127, 127}));

  r = decode_reply(k, CommandKind::kReadCounters, "h,2147483647,-2147483648\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->wheels, (WheelPair{2147483647, -2147483648LL}));

  r = decode_reply(k, CommandKind::kReadProximity, "n,0,1,2,3,1020,1021,1022,1023\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->sensors, (SensorArray{0, 1, 2, 3, 1020, 1021, 1022, 1023}));

  r = decode_reply(k, CommandKind::kReadAmbient, "o,500,501,502,503,504,505,506,507\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->sensors[7], 507);
}

// Firmware differs between robots and BIOS versions, and independent peers answer in
// their own ways: every one of these is a good reply (ARCHITECTURE.md, "tolerant link").
TEST(KheperaProtocol, AcceptsRepliesOfOtherFirmware) {
  const RobotModel& k = khepera2_model();
  struct VersionCase {
    std::string line, bios, protocol, text;
  };
  for (const VersionCase& c :
       std::vector<VersionCase>{{"b,5.02,5.01\r\n", "5.02", "5.01", "bios 5.02, protocol 5.01"},
                                {"B,5.02,5.01\n", "5.02", "5.01", "bios 5.02, protocol 5.01"},
                                {"b, 5 , 4  ", "5", "4", "bios 5, protocol 4"},
                                {"b,K2 BIOS v5", "K2 BIOS v5", "", "K2 BIOS v5"},
                                {"b,,4", "", "4", ",4"},
                                {"b,5,4,2019-03, rev C", "5", "4", "bios 5, protocol 4 (2019-03, rev C)"},
                                {"b", "", "", ""},
                                {"b,-1,x", "-1", "x", "bios -1, protocol x"}}) {
    const Result<Reply> r = decode_reply(k, CommandKind::kReadVersions, c.line);
    ASSERT_TRUE(r.ok()) << printable(c.line) << ": " << r.error();
    EXPECT_EQ(r->versions.bios, c.bios) << printable(c.line);
    EXPECT_EQ(r->versions.protocol, c.protocol) << printable(c.line);
    EXPECT_EQ(r->versions.text, c.text) << printable(c.line);
  }
  const SensorArray eight = {1, 2, 3, 4, 5, 6, 7, 8};
  for (const char* line : {"n,1,2,3,4,5,6,7,8,9,10\r\n", "n,1,2,3,4,5,6,7,8   \r\n", "N,1,2,3,4,5,6,7,8\r\n",
                           "n, 1, 2, 3, 4, 5, 6, 7, 8\n", "  n,1,2,3,4,5,6,7,8 \t\r", "n ,1,2,3,4,5,6,7,8",
                           "n,+1,2,3,4,5,6,7,8,ok", "n,1,2,3,4,5,6,7,8,\r\n"}) {
    const Result<Reply> r = decode_reply(k, CommandKind::kReadProximity, line);
    ASSERT_TRUE(r.ok()) << printable(line) << ": " << r.error();
    EXPECT_EQ(r->sensors, eight) << printable(line);
  }
  for (const char* line : {"d", "D", "d,0", "d,10,-10", "d OK", "d\n", " D \r\n"}) {
    EXPECT_TRUE(decode_reply(k, CommandKind::kSetSpeeds, line).ok()) << printable(line);
  }
  for (const char* line : {"h,1,-2,extra,fields", "H,1,-2", "\th,1,-2\t", "h,  1,-2  ,  "}) {
    const Result<Reply> r = decode_reply(k, CommandKind::kReadCounters, line);
    ASSERT_TRUE(r.ok()) << printable(line) << ": " << r.error();
    EXPECT_EQ(r->wheels, (WheelPair{1, -2})) << printable(line);
  }
  const Result<Reply> speeds = decode_reply(k, CommandKind::kReadSpeeds, "E,+5,-5,0\n");
  ASSERT_TRUE(speeds.ok()) << speeds.error();
  EXPECT_EQ(speeds->wheels, (WheelPair{5, -5}));
}

TEST(KheperaProtocol, TellsAnEchoOfTheCommandFromItsReply) {
  const RobotModel& k = khepera2_model();
  EXPECT_TRUE(is_echo_of(k, Command::set_speeds(10, -10), "D,10,-10"));
  EXPECT_TRUE(is_echo_of(k, Command::set_speeds(10, -10), "D,10,-10\r\n"));
  EXPECT_TRUE(is_echo_of(k, Command::read_proximity(), " N \r"));
  EXPECT_TRUE(is_echo_of(k, Command::read_versions(), "B"));
  EXPECT_FALSE(is_echo_of(k, Command::set_speeds(10, -10), "D,10,-11"));
  EXPECT_FALSE(is_echo_of(k, Command::set_speeds(10, -10), "d"));
  EXPECT_FALSE(is_echo_of(k, Command::read_proximity(), "n"));
  EXPECT_FALSE(is_echo_of(k, Command::read_proximity(), "N,1,2,3,4,5,6,7,8"));
  EXPECT_FALSE(is_echo_of(k, Command::read_proximity(), ""));
  EXPECT_FALSE(is_echo_of(epuck_model(), Command::read_versions(), "B"));
}

TEST(KheperaProtocol, AcceptsAnyLineEnd) {
  const RobotModel& k = khepera2_model();
  for (const char* line : {"h,1,2\r\n", "h,1,2\n", "h,1,2\r", "h,1,2", "h,1,2\n\r"}) {
    const Result<Reply> r = decode_reply(k, CommandKind::kReadCounters, line);
    ASSERT_TRUE(r.ok()) << printable(line) << ": " << r.error();
    EXPECT_EQ(r->wheels, (WheelPair{1, 2}));
  }
}

TEST(KheperaProtocol, RejectsMalformedRepliesWithAReason) {
  struct Case {
    CommandKind expected;
    std::string line;
    std::string reason;  // a piece of the failure's text
  };
  const std::vector<Case> cases = {
      {CommandKind::kReadProximity, "", "empty reply"},
      {CommandKind::kReadProximity, "\r\n", "empty reply"},
      {CommandKind::kReadProximity, " \t \r\n", "empty reply"},
      {CommandKind::kReadProximity, "o,1,2,3,4,5,6,7,8", "expected \"n\""},
      {CommandKind::kReadProximity, "n,1,2,3,4,5,6,7", "field 8 (proximity sensor 7) is missing (7 of 8 values)"},
      {CommandKind::kReadProximity, "n", "field 1 (proximity sensor 0) is missing (0 of 8 values)"},
      {CommandKind::kReadProximity, "n1,2,3,4,5,6,7,8", "expected a comma after the letter"},
      {CommandKind::kReadProximity, "nn,1,2,3,4,5,6,7,8", "expected a comma after the letter"},
      {CommandKind::kReadProximity, "n 1,2,3,4,5,6,7,8", "expected a comma before the values"},
      {CommandKind::kReadProximity, "n,1,2,3,a,5,6,7,8", "field 4 (proximity sensor 3) \"a\" is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,,5,6,7,8", "field 4 (proximity sensor 3) \"\" is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,4 4,5,6,7,8", "field 4 (proximity sensor 3) \"4 4\" is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,4-,5,6,7,8", "is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,-,5,6,7,8", "is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,+,5,6,7,8", "is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,4.5,5,6,7,8", "is not an integer"},
      {CommandKind::kReadProximity, "n,1,2,3,4,5,6,7,1024", "field 8 (proximity sensor 7) = 1024 is outside 0..1023"},
      {CommandKind::kReadProximity, "n,-1,2,3,4,5,6,7,8", "field 1 (proximity sensor 0) = -1 is outside 0..1023"},
      {CommandKind::kReadAmbient, "o,1,2,3,4,5,6,7,99999", "field 8 (ambient sensor 7) = 99999 is outside 0..1023"},
      {CommandKind::kReadSpeeds, "e,128,0", "field 1 (left speed) = 128 is outside -127..127"},
      {CommandKind::kReadSpeeds, "e,0,-128", "field 2 (right speed) = -128 is outside -127..127"},
      {CommandKind::kReadCounters, "h,2147483648,0", "field 1 (left counter) = 2147483648 is outside"},
      {CommandKind::kReadCounters, "h,99999999999999999999999,0", "is not an integer"},
      {CommandKind::kReadCounters, "h", "field 1 (left counter) is missing"},
      {CommandKind::kReadCounters, "h,1", "field 2 (right counter) is missing (1 of 2 values)"},
      {CommandKind::kReadCounters, "h,1,x2", "field 2 (right counter) \"x2\" is not an integer"},
      {CommandKind::kSetSpeeds, "dx", "expected a comma after the letter"},
      {CommandKind::kSetSpeeds, "e", "expected \"d\""},
      {CommandKind::kSetLed, "z,Protocol error", "protocol error"},
      {CommandKind::kReadProximity, "z,Protocol error", "protocol error"},
      {CommandKind::kReadProximity, "Z", "protocol error"},
      {CommandKind::kReadProximity, std::string("\xff\xfe\x01garbage", 10), "expected \"n\""},
      {CommandKind::kReadProximity, std::string("n,1,2\0,3,4,5,6,7,8", 18), "is not an integer"},
  };
  for (const Case& c : cases) {
    const Result<Reply> r = decode_reply(khepera2_model(), c.expected, c.line);
    ASSERT_FALSE(r.ok()) << printable(c.line) << " was accepted";
    EXPECT_NE(r.error().find(c.reason), std::string::npos) << printable(c.line) << ": " << r.error();
    EXPECT_FALSE(r.error().empty());
  }
}

TEST(KheperaProtocol, ReasonsQuoteTheLineWithControlBytesEscaped) {
  const Result<Reply> r = decode_reply(khepera2_model(), CommandKind::kReadCounters, std::string("h,1,\x01\x00", 6));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("\"h,1,\\x01\\0\""), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("to H (read counters)"), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("field 2 (right counter)"), std::string::npos) << r.error();
  EXPECT_EQ(printable("a\r\n\"b\\"), "\"a\\r\\n\\\"b\\\\\"");
  EXPECT_EQ(printable("abcdef", 3), "\"abc...\"");
}

TEST(KheperaProtocol, TellsAReplyShapedLineFromAStrayOne) {
  const RobotModel& k = khepera2_model();
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kReadProximity, "n,1,x"));
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kSetSpeeds, "d"));
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kSetSpeeds, "z,Protocol error"));
  EXPECT_FALSE(looks_like_reply_to(k, CommandKind::kReadProximity, "abcn,1,2"));
  EXPECT_FALSE(looks_like_reply_to(k, CommandKind::kReadProximity, "nx"));
  EXPECT_FALSE(looks_like_reply_to(k, CommandKind::kReadProximity, "h,1,2"));
  EXPECT_FALSE(looks_like_reply_to(k, CommandKind::kReadProximity, ""));
  // Other firmware: either case, blanks around the line.
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kReadProximity, "N,1,2,3,4,5,6,7,8"));
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kReadProximity, "  n ,1"));
  EXPECT_TRUE(looks_like_reply_to(k, CommandKind::kSetSpeeds, "Z,Protocol error"));
  EXPECT_FALSE(looks_like_reply_to(k, CommandKind::kReadProximity, "No such thing"));
}

TEST(KheperaProtocol, RepliesEncodedByTheEmulatorDecodeToThemselves) {
  for (const RobotModel* model : {&khepera2_model(), &epuck_model()}) {
    std::vector<Reply> replies;
    Reply r;
    r.kind = CommandKind::kReadVersions;
    r.versions = model->bios_protocol_versions ? FirmwareVersions{"5.02", "5.01", "bios 5.02, protocol 5.01"}
                                               : FirmwareVersions{"", "", "emulated"};
    replies.push_back(r);
    for (const CommandKind ack : {CommandKind::kSetSpeeds, CommandKind::kSetCounters, CommandKind::kSetLed}) {
      replies.push_back(Reply{ack});
    }
    r = Reply{CommandKind::kReadSpeeds};
    r.wheels = {-model->max_speed_units, 7};
    replies.push_back(r);
    r = Reply{CommandKind::kReadCounters};
    r.wheels = {-5, 123456};
    replies.push_back(r);
    r = Reply{CommandKind::kReadProximity};
    r.sensors = {0, 1, 2, 3, 4, 5, 6, model->max_sensor_value};
    replies.push_back(r);
    r = Reply{CommandKind::kReadAmbient};
    r.sensors = {9, 9, 9, 9, 9, 9, 9, 9};
    replies.push_back(r);
    for (const Reply& reply : replies) {
      const std::string bytes = encode_reply(*model, reply);
      ASSERT_EQ(bytes.substr(bytes.size() - 2), "\r\n");
      const Result<Reply> decoded = decode_reply(*model, reply.kind, bytes);
      ASSERT_TRUE(decoded.ok()) << model->name << ": " << decoded.error();
      EXPECT_EQ(*decoded, reply) << model->name << ": " << printable(bytes);
    }
  }
}

TEST(KheperaProtocol, TheEmulatorDecodesCommandsStrictly) {
  const RobotModel& k = khepera2_model();
  Result<Command> c = decode_command(k, "D,10,-20\r");
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(*c, Command::set_speeds(10, -20));
  c = decode_command(k, "H\n");
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->kind, CommandKind::kReadCounters);
  c = decode_command(k, "L,1,2");
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(*c, Command::set_led(1, LedAction::kToggle));
  // Every encoded command decodes back.
  for (const Command& command : {Command::read_versions(), Command::set_speeds(-3, 4), Command::read_speeds(),
                                 Command::set_counters(7, -8), Command::read_counters(), Command::read_proximity(),
                                 Command::read_ambient(), Command::set_led(0, LedAction::kOn)}) {
    for (const RobotModel* model : {&khepera2_model(), &epuck_model()}) {
      const Result<Command> back = decode_command(*model, encode(*model, command));
      ASSERT_TRUE(back.ok()) << back.error();
      EXPECT_EQ(*back, command);
    }
  }
  for (const char* bad : {"", "X", "D", "D,1", "D,1,2,3", "D,128,0", "D,a,b", "B,1", "L,2,0", "L,0,3", "d,1,2"}) {
    EXPECT_FALSE(decode_command(k, bad).ok()) << bad;
  }
  // The e-puck's `B` is not the Khepera's.
  EXPECT_FALSE(decode_command(epuck_model(), "B").ok());
  EXPECT_TRUE(decode_command(epuck_model(), "D,1000,-1000").ok());
}
