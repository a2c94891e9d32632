// The line assembler: lines split over reads or merged in one, any line end, noise bytes,
// NUL bytes, over-long lines dropped up to the next line end.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "serial/khepera_protocol.hpp"

using rilbed::serial::LineAssembler;
using Lines = std::vector<std::string>;

TEST(LineAssembler, JoinsALineSplitOverManyReads) {
  LineAssembler assembler;
  EXPECT_EQ(assembler.feed("n,1,2"), Lines{});
  EXPECT_EQ(assembler.partial_bytes(), 5u);
  EXPECT_EQ(assembler.feed(",3"), Lines{});
  EXPECT_EQ(assembler.feed("\r"), Lines{"n,1,2,3"});
  EXPECT_EQ(assembler.feed("\n"), Lines{});  // the LF after CR is no line of its own
  EXPECT_EQ(assembler.partial_bytes(), 0u);
  // One byte at a time.
  Lines lines;
  for (const char c : std::string("h,10,-20\r\n")) assembler.feed(std::string_view(&c, 1), lines);
  EXPECT_EQ(lines, Lines{"h,10,-20"});
  EXPECT_EQ(assembler.counters().lines, 2u);
}

TEST(LineAssembler, SplitsLinesMergedInOneRead) {
  LineAssembler assembler;
  EXPECT_EQ(assembler.feed("d\r\nh,1,2\r\nn,0,0"), (Lines{"d", "h,1,2"}));
  EXPECT_EQ(assembler.feed(",0\r\n"), Lines{"n,0,0,0"});
}

TEST(LineAssembler, AcceptsEveryLineEnd) {
  LineAssembler assembler;
  EXPECT_EQ(assembler.feed("a\r\nb\nc\rd\n\re\r\r\n\n"), (Lines{"a", "b", "c", "d", "e"}));
}

TEST(LineAssembler, DropsNoiseAndNulBytesAroundAndInsideALine) {
  LineAssembler assembler;
  const std::string noisy = std::string("\xff\xfe\x80\x00\x01", 5) + "h,1" + std::string("\x00", 1) + ",2\x7f\r\n";
  EXPECT_EQ(assembler.feed(noisy), Lines{"h,1,2"});
  EXPECT_EQ(assembler.counters().noise_bytes, 7u);
}

TEST(LineAssembler, KeepsPrintableGarbageForTheDecoderToReject) {
  LineAssembler assembler;
  EXPECT_EQ(assembler.feed("xyzh,1,2\r\n"), Lines{"xyzh,1,2"});
  // Garbage with a line end of its own becomes a line of its own, and the reply survives.
  EXPECT_EQ(assembler.feed("#@!\r\nh,1,2\r\n"), (Lines{"#@!", "h,1,2"}));
}

TEST(LineAssembler, DropsAnOverlongLineUpToTheNextLineEnd) {
  LineAssembler assembler(16);
  EXPECT_EQ(assembler.feed(std::string(16, 'x')), Lines{});  // exactly the limit: still a line
  EXPECT_EQ(assembler.feed("\r\n"), Lines{std::string(16, 'x')});
  EXPECT_EQ(assembler.feed(std::string(40, 'y')), Lines{});
  EXPECT_EQ(assembler.counters().overlong_lines, 1u);
  EXPECT_EQ(assembler.feed(std::string(40, 'y')), Lines{});  // still skipping, not a new over-long line
  EXPECT_EQ(assembler.counters().overlong_lines, 1u);
  EXPECT_EQ(assembler.feed("yyy\r\nh,1,2\r\n"), Lines{"h,1,2"});
  EXPECT_EQ(assembler.partial_bytes(), 0u);
}

TEST(LineAssembler, DiscardingAPartialLineResynchronises) {
  LineAssembler assembler;
  assembler.feed("n,1,2,3,");  // a reply cut short by a timeout
  assembler.discard_partial();
  EXPECT_EQ(assembler.partial_bytes(), 0u);
  // Its tail arrives late and becomes a line of its own; the next reply is intact.
  EXPECT_EQ(assembler.feed("4,5,6,7,8\r\nh,1,2\r\n"), (Lines{"4,5,6,7,8", "h,1,2"}));
}
