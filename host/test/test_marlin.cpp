// Marlin's host protocol (fpgacnc/marlin/protocol.h): line numbers, checksums and the answers to
// a bad line, as Marlin's G-code reference and the RepRap wiki's G-code page describe them. The
// checksum example "N3 T0*57" is the RepRap wiki's; the other checksums are computed here byte
// by byte from the rule (XOR of every byte before '*').
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fpgacnc/marlin/protocol.h"

namespace marlin = fpgacnc::marlin;

namespace {

// "N<n> <cmd>*<xor>" as a host (Pronterface, OctoPrint) writes it.
std::string numbered(long n, const std::string& cmd) {
  const std::string body = "N" + std::to_string(n) + " " + cmd;
  unsigned x = 0;
  for (unsigned char c : body) x ^= c;
  return body + "*" + std::to_string(x);
}

}  // namespace

TEST(MarlinProtocol, ChecksumOfThePublishedExample) {
  EXPECT_EQ(marlin::checksum("N3 T0"), 57);
  marlin::LineChecker lc;
  lc.set_last_line(2);
  const auto a = lc.accept("N3 T0*57");
  EXPECT_FALSE(a.refused);
  EXPECT_TRUE(a.answers.empty());
  EXPECT_EQ(a.command, "T0");
  EXPECT_EQ(lc.last_line(), 3);
}

TEST(MarlinProtocol, NumberedLinesInOrderAreTaken) {
  marlin::LineChecker lc;
  for (long n = 1; n <= 5; ++n) {
    const auto a = lc.accept(numbered(n, "G1 X" + std::to_string(n)));
    ASSERT_FALSE(a.refused) << n;
    EXPECT_EQ(a.command, "G1 X" + std::to_string(n));
    EXPECT_EQ(a.line_number, n);
  }
  EXPECT_EQ(lc.last_line(), 5);
}

TEST(MarlinProtocol, CorruptedLineIsResent) {
  marlin::LineChecker lc;
  ASSERT_FALSE(lc.accept(numbered(1, "G28")).refused);
  std::string bad = numbered(2, "G1 X10 Y10");
  bad[6] = 'Z';  // a bit flipped on the line: X -> Z, the checksum no longer matches
  const auto a = lc.accept(bad);
  EXPECT_TRUE(a.refused);
  EXPECT_TRUE(a.command.empty());
  ASSERT_EQ(a.answers.size(), 3u);
  EXPECT_EQ(a.answers[0], "Error:checksum mismatch, Last Line: 1");
  EXPECT_EQ(a.answers[1], "Resend: 2");
  EXPECT_EQ(a.answers[2], "ok");
  EXPECT_EQ(lc.last_line(), 1);
  // The host resends line 2 intact: taken.
  const auto r = lc.accept(numbered(2, "G1 X10 Y10"));
  EXPECT_FALSE(r.refused);
  EXPECT_EQ(r.command, "G1 X10 Y10");
  EXPECT_EQ(lc.last_line(), 2);
}

TEST(MarlinProtocol, LostLineIsResent) {
  marlin::LineChecker lc;
  ASSERT_FALSE(lc.accept(numbered(1, "G28")).refused);
  // Line 2 was lost on the way: line 3 arrives.
  const auto a = lc.accept(numbered(3, "G1 X1"));
  EXPECT_TRUE(a.refused);
  ASSERT_EQ(a.answers.size(), 3u);
  EXPECT_EQ(a.answers[0], "Error:Line Number is not Last Line Number+1, Last Line: 1");
  EXPECT_EQ(a.answers[1], "Resend: 2");
  EXPECT_EQ(a.answers[2], "ok");
  EXPECT_FALSE(lc.accept(numbered(2, "G1 X0.5")).refused);
  EXPECT_FALSE(lc.accept(numbered(3, "G1 X1")).refused);
}

TEST(MarlinProtocol, MissingNumberOrChecksum) {
  marlin::LineChecker lc;
  auto a = lc.accept("N1 G28");
  EXPECT_TRUE(a.refused);
  EXPECT_EQ(a.answers.at(0), "Error:No Checksum with line number, Last Line: 0");
  EXPECT_EQ(a.answers.at(1), "Resend: 1");
  a = lc.accept("G28*77");
  EXPECT_TRUE(a.refused);
  EXPECT_EQ(a.answers.at(0), "Error:No Line Number with checksum, Last Line: 0");
  // Neither: an unnumbered line is taken as it is (comment removed).
  a = lc.accept("  M105 ; temperatures");
  EXPECT_FALSE(a.refused);
  EXPECT_EQ(a.command, "M105");
  EXPECT_EQ(lc.last_line(), 0);
}

TEST(MarlinProtocol, M110SetsTheLineNumber) {
  marlin::LineChecker lc;
  ASSERT_FALSE(lc.accept(numbered(1, "G28")).refused);
  // "N<n> M110" is taken whatever the last line was, and makes n the last line.
  const auto a = lc.accept(numbered(100, "M110"));
  EXPECT_FALSE(a.refused);
  EXPECT_EQ(a.command, "M110");
  EXPECT_EQ(lc.last_line(), 100);
  EXPECT_FALSE(lc.accept(numbered(101, "G1 X1")).refused);
  // "M110 N<n>" without a leading number: the engine sets it.
  lc.set_last_line(0);
  EXPECT_FALSE(lc.accept(numbered(1, "G1 X2")).refused);
}

TEST(MarlinProtocol, TemperatureReportFormat) {
  // Marlin's M105 answer: "T:<temp> /<target> B:<temp> /<target> @:<power> B@:<power>".
  const std::string r =
      marlin::temperature_report({201.35, 202.0, 1.0}, marlin::HeaterReading{117.34, 120.0, 0.0});
  EXPECT_EQ(r, "T:201.35 /202.00 B:117.34 /120.00 @:127 B@:0");
  EXPECT_EQ(marlin::temperature_report({21.0, 0.0, 0.0}, std::nullopt), "T:21.00 /0.00 @:0");
}

TEST(MarlinProtocol, PositionReportFormat) {
  EXPECT_EQ(marlin::position_report({10.0, 0.0, 0.2, 0.0}, {1600, 0, 80}),
            "X:10.00 Y:0.00 Z:0.20 E:0.00 Count X:1600 Y:0 Z:80");
}
