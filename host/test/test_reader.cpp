// The reader (text -> Blocks): lexing, checksums, '%'/'$'/'?' lines, text M-codes, and rs274ngc
// parameters, expressions and O-word control flow. Expected values come from LinuxCNC's documents
// (docs/src/gcode/overview.adoc and o-code.adoc: operator precedence, FIX/FUP, parameter rules)
// and, where the documents leave room, from LinuxCNC 2.9's own interpreter (the Debian
// linuxcnc-uspace `rs274` command) run on the same lines; each such case says so.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "fpgacnc/gcode/reader.h"

namespace {

using fpgacnc::gcode::Block;
using fpgacnc::gcode::BlockKind;
using fpgacnc::gcode::Error;
using fpgacnc::gcode::MessageKind;
using fpgacnc::gcode::Params;
using fpgacnc::gcode::Reader;
using fpgacnc::gcode::Syntax;
using fpgacnc::gcode::Word;

Syntax plain() {
  Syntax s;
  s.dialect_name = "grbl";
  return s;
}

Syntax ngc() {
  Syntax s;
  s.ngc = true;
  s.checksums = false;
  s.paren_in_comment = false;
  s.dialect_name = "linuxcnc";
  return s;
}

// Reads a whole program like the interpreter does (M2/M30 end it).
std::vector<Block> read_all(const std::string& text, const Syntax& syntax, Params& params,
                            bool block_delete = false, uint64_t loop_limit = 0) {
  Reader r("t.ngc", text, syntax, params);
  r.set_block_delete(block_delete);
  if (loop_limit) r.set_loop_limit(loop_limit);
  std::vector<Block> out;
  Block b;
  while (r.next(b)) {
    out.push_back(b);
    for (int i = 0; i < b.count; ++i) {
      const Word& w = b.words[static_cast<size_t>(i)];
      if (w.letter == 'M' && (w.value == 2 || w.value == 30)) r.end_program();
    }
  }
  return out;
}

std::vector<Block> read_all(const std::string& text, const Syntax& syntax = ngc()) {
  Params p;
  return read_all(text, syntax, p);
}

std::string read_error_of(const std::string& text, const Syntax& syntax = ngc(),
                          uint64_t loop_limit = 0) {
  Params p;
  try {
    read_all(text, syntax, p, false, loop_limit);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// "G1 X1.5" from a block's words (values with up to 6 decimals, trailing zeros dropped).
std::string words(const Block& b) {
  std::string s;
  for (int i = 0; i < b.count; ++i) {
    const Word& w = b.words[static_cast<size_t>(i)];
    if (!s.empty()) s += ' ';
    s += w.letter;
    if (w.bare) continue;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f", w.value);
    std::string v = buf;
    while (v.back() == '0') v.pop_back();
    if (v.back() == '.') v.pop_back();
    if (v == "-0") v = "0";
    s += v;
  }
  return s;
}

// All blocks' words, one string per block that has words or a message.
std::vector<std::string> trace(const std::string& text, const Syntax& syntax = ngc()) {
  std::vector<std::string> out;
  for (const auto& b : read_all(text, syntax)) {
    if (b.count > 0) out.push_back(words(b));
    if (b.message_kind != MessageKind::kNone) out.push_back("msg:" + b.text);
  }
  return out;
}

// The value of an rs274ngc expression.
double eval(const std::string& expr) {
  Params p;
  read_all("#100=[" + expr + "]\n", ngc(), p);
  return p.get(100);
}

using V = std::vector<std::string>;

}  // namespace

// ---- lexing ------------------------------------------------------------------------------------

TEST(ReaderLex, WordsColumnsIntegerFlagAndCase) {
  const auto bs = read_all("g1 x-1.5 Y.5 z 3 F+100\nM3\n", plain());
  ASSERT_EQ(bs.size(), 2u);
  const Block& b = bs[0];
  EXPECT_EQ(b.line, 1);
  ASSERT_EQ(b.count, 5);
  EXPECT_EQ(b.words[0].letter, 'G');
  EXPECT_EQ(b.words[0].col, 1);
  EXPECT_TRUE(b.words[0].integer);
  EXPECT_EQ(b.words[1].letter, 'X');
  EXPECT_DOUBLE_EQ(b.words[1].value, -1.5);
  EXPECT_FALSE(b.words[1].integer);
  EXPECT_EQ(b.words[1].col, 4);
  EXPECT_DOUBLE_EQ(b.words[2].value, 0.5);
  EXPECT_EQ(b.words[3].col, 14);
  EXPECT_DOUBLE_EQ(b.words[3].value, 3.0);
  EXPECT_DOUBLE_EQ(b.words[4].value, 100.0);
  EXPECT_FALSE(b.words[4].from_expr);
  EXPECT_EQ(bs[1].line, 2);
  EXPECT_EQ(words(bs[1]), "M3");
  // "1." has a '.': not an integer (G1. is not G1 for the integer rule of G codes).
  EXPECT_FALSE(read_all("G1.", plain())[0].words[0].integer);
}

TEST(ReaderLex, EveryLineIsABlockBlankAndCommentLinesHaveNoWords) {
  const auto bs = read_all("G0 X1\n\n(comment)\n; semi\nG0 X2", plain());
  ASSERT_EQ(bs.size(), 5u);
  EXPECT_EQ(bs[1].count, 0);
  EXPECT_EQ(bs[2].count, 0);
  EXPECT_EQ(bs[3].count, 0);
  EXPECT_EQ(bs[4].line, 5);
  EXPECT_EQ(words(bs[4]), "G0 X2");
  // CR LF line ends.
  EXPECT_EQ(trace("G0 X1\r\nG0 X2\r\n", plain()), (V{"G0 X1", "G0 X2"}));
}

TEST(ReaderLex, BlanksInsideNumbersOnlyInRs274ngc) {
  // LinuxCNC's overview: "G0X +0. 12 34Y 7" is equivalent to "G0 x+0.1234 Y7".
  EXPECT_EQ(trace("G0X +0. 12 34Y 7"), (V{"G0 X0.1234 Y7"}));
  EXPECT_EQ(read_error_of("G0 X1 2", plain()), "t.ngc:1:7: error: unexpected character '2'");
}

TEST(ReaderLex, Comments) {
  // A '(' inside a comment nests; unbalanced, the comment ends at the line's last ')'.
  EXPECT_EQ(trace("G0 (rapid (to) start) X1 ; end (x", plain()), (V{"G0 X1"}));
  EXPECT_EQ(trace("G0 (a ( b) X1", plain()), (V{"G0 X1"}));
  EXPECT_EQ(read_error_of("G0 (rapid (to) start) X1"), "t.ngc:1:11: error: '(' inside a comment");
  EXPECT_EQ(read_error_of("G0 X1 (open", plain()), "t.ngc:1:7: error: unterminated comment '('");
  Syntax s = plain();
  s.semicolon_comments = false;
  EXPECT_EQ(read_error_of("G0 X1 ; no", s),
            "t.ngc:1:7: error: unexpected character ';' (';' comments are not enabled for this "
            "file)");
  // Non-ASCII text is fine inside comments, not outside.
  EXPECT_EQ(trace("G0 X1 (Fr\xc3\xa4se)", plain()), (V{"G0 X1"}));
  EXPECT_EQ(trace("G0 X1 ; Fr\xc3\xa4se", ngc()), (V{"G0 X1"}));
  EXPECT_EQ(read_error_of("G0 X1 \xc3\xa4", plain()), "t.ngc:1:7: error: non-ASCII byte 0xC3");
  EXPECT_EQ(read_error_of("G0 X1\nG0 X\x01", plain()), "t.ngc:2:5: error: non-printable byte 0x01");
  EXPECT_EQ(read_error_of("G0 X1 (a\x02)", ngc()), "t.ngc:1:9: error: non-printable byte 0x02");
  EXPECT_EQ(read_error_of("G0 X1 ; a\x7f", plain()), "t.ngc:1:10: error: non-printable byte 0x7F");
}

TEST(ReaderLex, NumberErrors) {
  EXPECT_EQ(read_error_of("G1 X1.2.3", plain()), "t.ngc:1:8: error: garbage in the number of 'X'");
  EXPECT_EQ(read_error_of("G1 Xnan", plain()), "t.ngc:1:4: error: expected a number after 'X'");
  EXPECT_EQ(read_error_of("G1 X1 Y-- F1", plain()),
            "t.ngc:1:7: error: expected a number after 'Y'");
  EXPECT_EQ(read_error_of("G1 X1 R", plain()), "t.ngc:1:7: error: expected a number after 'R'");
  EXPECT_EQ(read_error_of("G1 X1 & Y2", plain()), "t.ngc:1:7: error: unexpected character '&'");
  std::string many;
  for (int i = 0; i < 65; ++i) many += "X1 ";
  EXPECT_EQ(read_error_of(many, plain()), "t.ngc:1:193: error: too many words on one line");
}

TEST(ReaderLex, BareLetters) {
  Syntax s = plain();
  s.bare_letters = true;
  const auto bs = read_all("G28 X Y\nG2 X1 R (radius)", s);
  ASSERT_EQ(bs.size(), 2u);
  EXPECT_TRUE(bs[0].words[1].bare);
  EXPECT_EQ(bs[0].words[1].col, 5);
  EXPECT_TRUE(bs[0].words[2].bare);
  EXPECT_EQ(words(bs[0]), "G28 X Y");
  EXPECT_EQ(words(bs[1]), "G2 X1 R");
  EXPECT_DOUBLE_EQ(bs[1].words[2].value, 0.0);
}

TEST(ReaderLex, BareLettersSignWithoutDigitsIsStillAnError) {
  Syntax s = plain();
  s.bare_letters = true;
  EXPECT_EQ(read_error_of("G1 X-", s), "t.ngc:1:4: error: expected a number after 'X'");
}

TEST(ReaderLex, Checksums) {
  auto with_sum = [](const std::string& s) {
    unsigned x = 0;
    for (char c : s) x ^= static_cast<unsigned char>(c);
    return s + "*" + std::to_string(x);
  };
  const std::string good = with_sum("N12 G1 X1 F100");
  EXPECT_EQ(trace(good, plain()), (V{"N12 G1 X1 F100"}));
  EXPECT_EQ(trace(good + " ; comment", plain()), (V{"N12 G1 X1 F100"}));
  std::string bad = good;
  bad.back() = bad.back() == '0' ? '1' : '0';
  EXPECT_EQ(read_error_of("G0 X0\n" + bad, plain()).substr(0, 37),
            "t.ngc:2:15: error: checksum mismatch:");
  EXPECT_EQ(read_error_of("G0 X0 *", plain()),
            "t.ngc:1:7: error: malformed checksum (expected *0..255 at the end of the line)");
  EXPECT_EQ(read_error_of("G0 X0 *12 G1", plain()),
            "t.ngc:1:7: error: malformed checksum (expected *0..255 at the end of the line)");
  EXPECT_EQ(read_error_of("G0 X0 *256", plain()),
            "t.ngc:1:7: error: malformed checksum (expected *0..255 at the end of the line)");
  Syntax s = plain();
  s.checksums = false;
  EXPECT_EQ(read_error_of(good, s),
            "t.ngc:1:15: error: unexpected character '*' (checksums are not enabled for this "
            "file)");
  // In an rs274ngc expression '*' multiplies (the message was "malformed checksum").
  EXPECT_EQ(trace("G0 X[2*3]"), (V{"G0 X6"}));
}

TEST(ReaderLex, PercentLines) {
  const auto bs = read_all("%\nG0 X1\n  % O1000 (end of tape)  \n", plain());
  ASSERT_EQ(bs.size(), 3u);
  EXPECT_EQ(bs[0].kind, BlockKind::kPercent);
  EXPECT_EQ(bs[0].text, "");
  EXPECT_EQ(bs[1].kind, BlockKind::kWords);
  EXPECT_EQ(bs[2].kind, BlockKind::kPercent);
  EXPECT_EQ(bs[2].text, "O1000 (end of tape)");
  EXPECT_EQ(bs[2].text_col, 5);
  EXPECT_EQ(bs[2].count, 0);
  // rs274ngc too: '%' lines are not O-words or words.
  EXPECT_EQ(read_all("% hello #1\n")[0].kind, BlockKind::kPercent);
  EXPECT_EQ(read_error_of("G0 X1 %", plain()), "t.ngc:1:7: error: unexpected character '%'");
}

TEST(ReaderLex, DollarAndQuestionLines) {
  Syntax s = plain();
  s.dollar_lines = true;
  const auto bs = read_all("$H\n ?\n$J=G91 X10 F100 \nG0 X1", s);
  ASSERT_EQ(bs.size(), 4u);
  EXPECT_EQ(bs[0].kind, BlockKind::kSystem);
  EXPECT_EQ(bs[0].text, "$H");
  EXPECT_EQ(bs[1].kind, BlockKind::kQuery);
  EXPECT_EQ(bs[1].text, "?");
  EXPECT_EQ(bs[1].text_col, 2);
  EXPECT_EQ(bs[2].text, "$J=G91 X10 F100");
  EXPECT_EQ(bs[2].count, 0);
  Syntax m;
  m.dialect_name = "marlin";
  EXPECT_EQ(read_error_of("G0 X1\n$H", m),
            "t.ngc:2:1: error: '$' lines are grbl system commands; this file's dialect is marlin");
  EXPECT_EQ(read_error_of("?", m),
            "t.ngc:1:1: error: '?' lines are grbl status queries; this file's dialect is marlin");
}

TEST(ReaderLex, TextMCodes) {
  Syntax s = plain();
  s.text_mcodes = true;
  s.dialect_name = "marlin";
  auto bs =
      read_all("M117 Hello world\nM118 E1 (50%) done ; note\nM23 part(1).gco\nM117\nM30\n", s);
  ASSERT_EQ(bs.size(), 5u);
  EXPECT_EQ(words(bs[0]), "M117");
  EXPECT_EQ(bs[0].message_kind, MessageKind::kText);
  EXPECT_EQ(bs[0].text, "Hello world");
  EXPECT_EQ(bs[0].text_col, 6);
  EXPECT_EQ(words(bs[1]), "M118");
  EXPECT_EQ(bs[1].text, "E1 (50%) done");
  EXPECT_EQ(bs[2].text, "part(1).gco");
  EXPECT_EQ(bs[3].message_kind, MessageKind::kText);  // M117 alone clears the display
  EXPECT_EQ(bs[3].text, "");
  EXPECT_EQ(bs[4].message_kind, MessageKind::kNone);  // M30 alone: program end, no text
  EXPECT_EQ(words(bs[4]), "M30");
  EXPECT_EQ(read_all("M30 old.gco", s)[0].text, "old.gco");
  // With a line number and a checksum (the XOR of everything before '*').
  std::string line = "N7 M117 Layer 2";
  unsigned x = 0;
  for (char c : line) x ^= static_cast<unsigned char>(c);
  bs = read_all(line + "*" + std::to_string(x), s);
  EXPECT_EQ(words(bs[0]), "N7 M117");
  EXPECT_EQ(bs[0].text, "Layer 2");
  EXPECT_EQ(read_error_of(line + "*" + std::to_string(x ^ 1), s).substr(0, 36),
            "t.ngc:1:16: error: checksum mismatch");
  // Without text_mcodes the text is words (and 'H' 'e'... are refused by the interpreter).
  EXPECT_EQ(read_error_of("M117 Hello", plain()), "t.ngc:1:6: error: expected a number after 'H'");
}

TEST(ReaderLex, BlockDelete) {
  Params p;
  auto bs = read_all("/G0 X1\n / #1=5\nG0 X2", ngc(), p);
  ASSERT_EQ(bs.size(), 3u);
  EXPECT_TRUE(bs[0].block_delete);
  EXPECT_EQ(words(bs[0]), "G0 X1");
  EXPECT_TRUE(bs[1].block_delete);
  EXPECT_FALSE(bs[2].block_delete);
  EXPECT_DOUBLE_EQ(p.get(1), 5.0);
  // Switch on: '/' lines are skipped whole, assignments included.
  Params q;
  bs = read_all("/G0 X1\n/#1=5\nG0 X2", ngc(), q, true);
  ASSERT_EQ(bs.size(), 1u);
  EXPECT_EQ(words(bs[0]), "G0 X2");
  EXPECT_DOUBLE_EQ(q.get(1), 0.0);
}

TEST(ReaderLex, Rs274ngcSyntaxRefusedInOtherDialects) {
  EXPECT_EQ(read_error_of("G0 X#1", plain()),
            "t.ngc:1:5: error: '#' parameters are rs274ngc (LinuxCNC) syntax; this file's dialect "
            "is grbl");
  EXPECT_EQ(read_error_of("G0 X[1]", plain()),
            "t.ngc:1:5: error: '[' expressions are rs274ngc (LinuxCNC) syntax; this file's "
            "dialect is grbl");
  EXPECT_EQ(read_error_of("#1=2", plain()),
            "t.ngc:1:1: error: '#' parameters are rs274ngc (LinuxCNC) syntax; this file's dialect "
            "is grbl");
  EXPECT_EQ(read_error_of("G0 [1]", plain()),
            "t.ngc:1:4: error: '[' expressions are rs274ngc (LinuxCNC) syntax; this file's "
            "dialect is grbl");
  EXPECT_EQ(read_error_of("o100 sub", plain()),
            "t.ngc:1:1: error: O-words are rs274ngc (LinuxCNC) syntax; this file's dialect is "
            "grbl");
  EXPECT_EQ(read_error_of("#1=2", Syntax{}),
            "t.ngc:1:1: error: '#' parameters are rs274ngc (LinuxCNC) syntax, not enabled for "
            "this file's dialect");
}

// ---- expressions ---------------------------------------------------------------------------

TEST(ReaderExpr, PrecedenceAndAssociativity) {
  EXPECT_DOUBLE_EQ(eval("2 + 3 * 4"), 14.0);
  EXPECT_DOUBLE_EQ(eval("2 ** 3"), 8.0);
  // LinuxCNC's documented example: [2.0 / 3 * 1.5 - 5.5 / 11.0] = [[[2.0/3]*1.5]-[5.5/11.0]].
  EXPECT_NEAR(eval("2.0 / 3 * 1.5 - 5.5 / 11.0"), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(eval("10 - 2 - 3"), 5.0);  // left to right within a group
  EXPECT_DOUBLE_EQ(eval("16 / 4 / 2"), 2.0);
  // Same group, left first: LinuxCNC's rs274 gives 64 for 2 ** 3 ** 2 and 0 for 1 OR 0 AND 0.
  EXPECT_DOUBLE_EQ(eval("2 ** 3 ** 2"), 64.0);
  EXPECT_DOUBLE_EQ(eval("1 OR 0 AND 0"), 0.0);
  EXPECT_DOUBLE_EQ(eval("0 AND 0 OR 1"), 1.0);
  // Relational below arithmetic, logical below relational.
  EXPECT_DOUBLE_EQ(eval("1 + 2 EQ 3 AND 1"), 1.0);
  EXPECT_DOUBLE_EQ(eval("2 * 3 GT 5"), 1.0);
  EXPECT_DOUBLE_EQ(eval("[2 + 3] * 4"), 20.0);
  // MOD is in the * / group.
  EXPECT_DOUBLE_EQ(eval("1 + 7 MOD 4 * 2"), 7.0);
  // LinuxCNC's own example [1 + acos[0] - [#3 ** [4.0/2]]] with #3 = 0.
  EXPECT_DOUBLE_EQ(eval("1 + acos[0] - [#3 ** [4.0/2]]"), 91.0);
}

TEST(ReaderExpr, UnaryMinusBindsTighterThanPower) {
  // A unary minus belongs to the value: LinuxCNC's rs274 gives 4 for [-2 ** 2].
  EXPECT_DOUBLE_EQ(eval("-2 ** 2"), 4.0);
  EXPECT_DOUBLE_EQ(eval("-[1 + 2]"), -3.0);
  EXPECT_DOUBLE_EQ(eval("--3"), 3.0);
  EXPECT_DOUBLE_EQ(eval("+3"), 3.0);
  EXPECT_DOUBLE_EQ(eval("2 ** -1"), 0.5);
  EXPECT_DOUBLE_EQ(eval("3 - -2"), 5.0);
}

TEST(ReaderExpr, ModAlwaysNonNegative) {
  // LinuxCNC's rs274: -7 MOD 3 = 2, 7 MOD -3 = 1, -7 MOD -3 = 2, -7.5 MOD 2 = 0.5.
  EXPECT_DOUBLE_EQ(eval("7 MOD 3"), 1.0);
  EXPECT_DOUBLE_EQ(eval("-7 MOD 3"), 2.0);
  EXPECT_DOUBLE_EQ(eval("7 MOD -3"), 1.0);
  EXPECT_DOUBLE_EQ(eval("-7 MOD -3"), 2.0);
  EXPECT_DOUBLE_EQ(eval("7.5 MOD 2"), 1.5);
  EXPECT_DOUBLE_EQ(eval("-7.5 MOD 2"), 0.5);
  EXPECT_DOUBLE_EQ(eval("-0.5 MOD 2"), 1.5);
  // No negative zero (LinuxCNC's rs274 prints [-3 MOD 1.5] and [-0] as 0.000000).
  EXPECT_FALSE(std::signbit(eval("-3 MOD 1.5")));
  EXPECT_FALSE(std::signbit(eval("-0")));
}

TEST(ReaderExpr, RoundingFunctions) {
  // Documented: FIX[2.8] = 2, FIX[-2.8] = -3, FUP[2.8] = 3, FUP[-2.8] = -2.
  EXPECT_DOUBLE_EQ(eval("FIX[2.8]"), 2.0);
  EXPECT_DOUBLE_EQ(eval("FIX[-2.8]"), -3.0);
  EXPECT_DOUBLE_EQ(eval("FUP[2.8]"), 3.0);
  EXPECT_DOUBLE_EQ(eval("FUP[-2.8]"), -2.0);
  // Halves away from zero (LinuxCNC's rs274: ROUND[2.5] = 3, ROUND[-2.5] = -3).
  EXPECT_DOUBLE_EQ(eval("ROUND[2.5]"), 3.0);
  EXPECT_DOUBLE_EQ(eval("ROUND[-2.5]"), -3.0);
  EXPECT_DOUBLE_EQ(eval("ROUND[-2.4]"), -2.0);
  EXPECT_DOUBLE_EQ(eval("ROUND[0.5]"), 1.0);
}

TEST(ReaderExpr, TrigInDegrees) {
  EXPECT_NEAR(eval("SIN[30]"), 0.5, 1e-12);
  EXPECT_NEAR(eval("COS[60]"), 0.5, 1e-12);
  EXPECT_NEAR(eval("TAN[45]"), 1.0, 1e-12);
  EXPECT_NEAR(eval("ASIN[0.5]"), 30.0, 1e-12);
  EXPECT_NEAR(eval("ACOS[0.5]"), 60.0, 1e-12);
  EXPECT_NEAR(eval("COS[180]"), -1.0, 1e-12);
  // Four-quadrant ATAN[y]/[x] in degrees.
  EXPECT_NEAR(eval("ATAN[1]/[1]"), 45.0, 1e-12);
  EXPECT_NEAR(eval("ATAN[1]/[-1]"), 135.0, 1e-12);
  EXPECT_NEAR(eval("ATAN[-1]/[-1]"), -135.0, 1e-12);
  EXPECT_NEAR(eval("ATAN[0]/[-1]"), 180.0, 1e-12);
  EXPECT_NEAR(eval("ATAN[-1]/[0]"), -90.0, 1e-12);
  EXPECT_NEAR(eval("2 * ATAN[1]/[1] + 1"), 91.0, 1e-12);  // '/' belongs to ATAN
}

TEST(ReaderExpr, OtherFunctions) {
  EXPECT_DOUBLE_EQ(eval("ABS[-3]"), 3.0);
  EXPECT_DOUBLE_EQ(eval("ABS[3]"), 3.0);
  EXPECT_NEAR(eval("EXP[1]"), 2.718281828459045, 1e-15);
  EXPECT_NEAR(eval("LN[EXP[2]]"), 2.0, 1e-15);
  EXPECT_DOUBLE_EQ(eval("SQRT[16]"), 4.0);
  // Case-insensitive, blanks anywhere (LinuxCNC removes them before reading).
  EXPECT_NEAR(eval("s i n[30] + abs[-1]"), 1.5, 1e-12);
  EXPECT_DOUBLE_EQ(eval("1 2 + 3"), 15.0);
  EXPECT_DOUBLE_EQ(eval("1 a n d 1"), 1.0);
}

TEST(ReaderExpr, LogicalAndRelational) {
  EXPECT_DOUBLE_EQ(eval("1 AND 0"), 0.0);
  EXPECT_DOUBLE_EQ(eval("2 AND 3"), 1.0);  // any non-zero is true; the result is 1
  EXPECT_DOUBLE_EQ(eval("0 OR 0"), 0.0);
  EXPECT_DOUBLE_EQ(eval("0 OR -1"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 XOR 1"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 XOR 0"), 1.0);
  EXPECT_DOUBLE_EQ(eval("0.5 XOR 0"), 1.0);
  EXPECT_DOUBLE_EQ(eval("2 GT 1"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 GT 1"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 GE 1"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 LT 1"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 LT 2"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 LE 1"), 1.0);
  EXPECT_DOUBLE_EQ(eval("2 LE 1"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 NE 1"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 NE 2"), 1.0);
  // EQ/NE: equal within 1e-6 (the documented TOLERANCE_EQUAL); GT..LE are exact.
  EXPECT_DOUBLE_EQ(eval("1 EQ 1.0000001"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 EQ 1.00001"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 NE 1.0000001"), 0.0);
  EXPECT_DOUBLE_EQ(eval("0.1 * 3 EQ 0.3"), 1.0);
  EXPECT_DOUBLE_EQ(eval("1 GE 1.0000001"), 0.0);
  EXPECT_DOUBLE_EQ(eval("1 GT 0.9999999"), 1.0);
}

TEST(ReaderExpr, WordValuesFromExpressions) {
  const auto bs = read_all("#1=2\nG[1+2] X[0.1*3] Y#1 Z-#1 A SIN[30] M[0.1*30] B-[1]");
  const Block& b = bs[1];
  EXPECT_EQ(words(b), "G3 X0.3 Y2 Z-2 A0.5 M3 B-1");
  EXPECT_TRUE(b.words[0].integer);  // G[1+2] is G3
  EXPECT_TRUE(b.words[0].from_expr);
  EXPECT_FALSE(b.words[1].integer);
  EXPECT_TRUE(b.words[2].from_expr);
  EXPECT_TRUE(b.words[2].integer);
  EXPECT_TRUE(b.words[5].integer);  // 0.1*30 = 3.0000000000000004: within 1e-6 of 3
  EXPECT_EQ(b.words[4].col, 26);
  EXPECT_FALSE(read_all("G[1.01]")[0].words[0].integer);
}

TEST(ReaderExpr, Errors) {
  EXPECT_EQ(read_error_of("G0 X[1 + FOO[2]]"), "t.ngc:1:10: error: unknown function 'FOO'");
  EXPECT_EQ(read_error_of("G0 X FOO[2]"), "t.ngc:1:6: error: unknown function 'FOO'");
  EXPECT_EQ(read_error_of("G0 X[1 + 2"), "t.ngc:1:5: error: unclosed '[' (no matching ']')");
  EXPECT_EQ(read_error_of("G0 X[1 + 2]]"), "t.ngc:1:12: error: unbalanced ']'");
  EXPECT_EQ(read_error_of("G0 X[1 + ]"), "t.ngc:1:10: error: expected a value before ']'");
  EXPECT_EQ(read_error_of("G0 X[1 2 3 #1]"),
            "t.ngc:1:12: error: expected an operator or ']', found '#'");
  EXPECT_EQ(read_error_of("G0 X[1 FOO 2]"), "t.ngc:1:8: error: unknown operator 'FOO'");
  EXPECT_EQ(read_error_of("G0 X[4 / [2 - 2]]"), "t.ngc:1:8: error: division by zero");
  EXPECT_EQ(read_error_of("G0 X[4 MOD 0]"), "t.ngc:1:8: error: MOD by zero");
  EXPECT_EQ(read_error_of("G0 X[SQRT[-4]]"), "t.ngc:1:6: error: SQRT of a negative number (-4)");
  EXPECT_EQ(read_error_of("G0 X[LN[0]]"), "t.ngc:1:6: error: LN of 0 (needs a positive number)");
  EXPECT_EQ(read_error_of("G0 X[ACOS[2]]"), "t.ngc:1:6: error: ACOS argument 2 is outside [-1, 1]");
  EXPECT_EQ(read_error_of("G0 X[ASIN[-1.5]]"),
            "t.ngc:1:6: error: ASIN argument -1.5 is outside [-1, 1]");
  EXPECT_EQ(read_error_of("G0 X[-8 ** 0.5]"),
            "t.ngc:1:9: error: negative number raised to a non-integer power");
  EXPECT_EQ(read_error_of("G0 X[0 ** -1]"), "t.ngc:1:8: error: the result is not a finite number");
  EXPECT_EQ(read_error_of("G0 X[EXP[1000]]"),
            "t.ngc:1:6: error: EXP result is not a finite number");
  EXPECT_EQ(read_error_of("G0 X[ATAN[1]]"),
            "t.ngc:1:6: error: ATAN needs two arguments: ATAN[y]/[x]");
  EXPECT_EQ(read_error_of("G0 X[EXISTS[#1]]"),
            "t.ngc:1:6: error: EXISTS takes one named parameter: EXISTS[#<name>]");
  EXPECT_EQ(read_error_of("G0 X[SIN 30]"),
            "t.ngc:1:6: error: unexpected 'SIN' in an expression (a function needs its argument "
            "in brackets, e.g. SIN[30])");
  EXPECT_EQ(read_error_of("G0 [1]"),
            "t.ngc:1:4: error: an expression '[...]' needs a word letter before it");
  EXPECT_EQ(read_error_of("G0 X[1] + 2"), "t.ngc:1:9: error: unexpected character '+'");
  EXPECT_EQ(read_error_of("G0 X[1 (c) + 2]"),
            "t.ngc:1:8: error: expected an operator or ']', found '('");
  // Columns are those of the source line, blanks included.
  EXPECT_EQ(read_error_of("G0   X [ 4 /   0 ]"), "t.ngc:1:12: error: division by zero");
}

// ---- parameters ----------------------------------------------------------------------------

TEST(ReaderParams, NumberedNamedAndIndirect) {
  Params p;
  const auto bs = read_all(
      "#1 = 5\n#2=[#1 * 2]\n#4=2\n##4=7\n#[1+2]=3\n# 5 = - 1\n#<Foo Bar> = 3\n#<_g>=#<foobar>\n"
      "G0 X#1 Y##4 Z#<foobar> A#[2+1] B#5\n",
      ngc(), p);
  EXPECT_DOUBLE_EQ(p.get(1), 5.0);
  EXPECT_DOUBLE_EQ(p.get(2), 7.0);  // ##4=7 wrote #2
  EXPECT_DOUBLE_EQ(p.get(3), 3.0);
  EXPECT_DOUBLE_EQ(p.get(5), -1.0);
  EXPECT_EQ(p.named("foobar"), 3.0);  // names: lower case, blanks removed
  EXPECT_EQ(p.named("_g"), 3.0);
  EXPECT_EQ(words(bs[8]), "G0 X5 Y7 Z3 A3 B-1");
}

TEST(ReaderParams, HashBindsTighterThanPlus) {
  // Documented: #1+2 is the value of #1 plus 2, not parameter 3.
  Params p;
  read_all("#1=10\n#3=100\n#4=[#1+2]\n", ngc(), p);
  EXPECT_DOUBLE_EQ(p.get(4), 12.0);
  EXPECT_EQ(read_error_of("#1=5\n#6=#1+2\n"), "t.ngc:2:6: error: unexpected character '+'");
}

TEST(ReaderParams, AssignmentsTakeEffectAfterTheWholeLineIsRead) {
  // LinuxCNC's overview: with #3 = 15, "#3=6 G1 X#3" moves to X15 and leaves #3 = 6.
  Params p;
  auto bs = read_all("#3=15\n#3=6 G1 X#3\n", ngc(), p);
  EXPECT_EQ(words(bs[1]), "G1 X15");
  EXPECT_DOUBLE_EQ(p.get(3), 6.0);
  // Repeated settings: the last one wins; reads see the old value (rs274: #3=#2 reads 0).
  Params q;
  read_all("#3=15 #3=6\n#2=1 #3=#2\n", ngc(), q);
  EXPECT_DOUBLE_EQ(q.get(3), 0.0);
  EXPECT_DOUBLE_EQ(q.get(2), 1.0);
  Params r;
  read_all("#3=6 #3=15\n", ngc(), r);
  EXPECT_DOUBLE_EQ(r.get(3), 15.0);
  // A named parameter read on the line of its first assignment is not set yet.
  EXPECT_EQ(read_error_of("#<a>=1 #<b>=#<a>"), "t.ngc:1:13: error: parameter #<a> is not set");
}

TEST(ReaderParams, Errors) {
  EXPECT_EQ(read_error_of("G0 X#<depth>"), "t.ngc:1:5: error: parameter #<depth> is not set");
  EXPECT_EQ(read_error_of("G0 X#0"),
            "t.ngc:1:5: error: parameter number 0 is out of range (1..5602)");
  EXPECT_EQ(read_error_of("#5603=1"),
            "t.ngc:1:1: error: parameter number 5603 is out of range (1..5602)");
  EXPECT_EQ(read_error_of("G0 X#1.5"), "t.ngc:1:5: error: parameter number 1.5 is not an integer");
  EXPECT_EQ(read_error_of("#1"),
            "t.ngc:1:1: error: a parameter outside an expression must be assigned ('#1 = "
            "value')");
  EXPECT_EQ(read_error_of("#<a"), "t.ngc:1:2: error: unterminated parameter name '<' (no '>')");
  EXPECT_EQ(read_error_of("#1="), "t.ngc:1:4: error: expected a value at the end of the line");
  // Unset numbered parameters read as 0.
  EXPECT_EQ(trace("G0 X#4000"), (V{"G0 X0"}));
  EXPECT_DOUBLE_EQ(eval("#5602"), 0.0);
}

TEST(ReaderParams, Exists) {
  Params p;
  read_all("#<a>=1\n#<_b>=2\n#1=EXISTS[#<a>]\n#2=EXISTS[#<_b>]\n#3=EXISTS[#<c>]\n#4=exists[#< A >]",
           ngc(), p);
  EXPECT_DOUBLE_EQ(p.get(1), 1.0);
  EXPECT_DOUBLE_EQ(p.get(2), 1.0);
  EXPECT_DOUBLE_EQ(p.get(3), 0.0);
  EXPECT_DOUBLE_EQ(p.get(4), 1.0);
}

TEST(ReaderParams, ParamsFrames) {
  Params p;
  p.set(1, 11.0);
  p.set(31, 31.0);
  p.set_named("loc", 1.0);
  p.set_named("_glob", 2.0);
  p.push_frame();
  EXPECT_DOUBLE_EQ(p.get(1), 0.0);  // arguments start at 0 in a call
  EXPECT_DOUBLE_EQ(p.get(31), 31.0);
  EXPECT_FALSE(p.named("loc").has_value());
  EXPECT_EQ(p.named("_glob"), 2.0);
  p.set(1, 5.0);
  p.set_named("loc", 9.0);
  p.set_named("_glob", 3.0);
  p.pop_frame();
  EXPECT_DOUBLE_EQ(p.get(1), 11.0);
  EXPECT_EQ(p.named("loc"), 1.0);
  EXPECT_EQ(p.named("_glob"), 3.0);
  EXPECT_EQ(p.named("_value"), 0.0);  // exists from the start
}

// ---- messages ------------------------------------------------------------------------------

TEST(ReaderMessages, MsgDebugPrint) {
  // Behaviour checked with LinuxCNC's rs274 on the same lines.
  auto bs = read_all(
      "#1=2.5\n#<a>=3.14159\n(MSG,hello #1 world)\n( msg,lead space)\n(msg , not a message)\n"
      "(DEBUG,v=%d#1 w=%f#<a> x=%.2f#1 y=#1 z=%lf#1)\n(debug,bad #<nope> and #< A >)\n"
      "(PRINT,print #1 #1.5 ##1 #[1])\n(DEBUG,first)(plain)\n(plain)(DEBUG,second)\n"
      "#1=7 (DEBUG,#1)\nG0 X1 ; (MSG,semicolon comments are not active)\n");
  ASSERT_EQ(bs.size(), 12u);
  EXPECT_EQ(bs[2].message_kind, MessageKind::kMsg);
  EXPECT_EQ(bs[2].text, "hello #1 world");  // MSG: no substitution
  EXPECT_EQ(bs[2].text_col, 6);
  EXPECT_EQ(bs[3].message_kind, MessageKind::kMsg);
  EXPECT_EQ(bs[3].text, "lead space");
  EXPECT_EQ(bs[4].message_kind, MessageKind::kNone);
  EXPECT_EQ(bs[5].message_kind, MessageKind::kDebug);
  EXPECT_EQ(bs[5].text, "v=2 w=3.1416 x=2.50 y=2.50 z=2.500000");
  EXPECT_EQ(bs[6].text, "bad ###### and 3.141590");
  EXPECT_EQ(bs[7].message_kind, MessageKind::kPrint);
  EXPECT_EQ(bs[7].text, "print 2.500000 2.500000.5 #2.500000 #[1]");
  EXPECT_EQ(bs[8].message_kind, MessageKind::kNone);  // only the line's last comment counts
  EXPECT_EQ(bs[9].message_kind, MessageKind::kDebug);
  EXPECT_EQ(bs[9].text, "second");
  EXPECT_EQ(bs[10].text, "7.000000");  // after the line's assignments
  EXPECT_EQ(bs[11].message_kind, MessageKind::kNone);
  // Not in other dialects: plain comments there.
  EXPECT_EQ(read_all("(MSG,hi)", plain())[0].message_kind, MessageKind::kNone);
}

// ---- O-words -------------------------------------------------------------------------------

TEST(ReaderO, SubroutineCallArgumentsAndLocals) {
  Params p;
  const auto t = read_all(
      "#1=100\n#5=7\n#31=1\n"
      "o100 sub\n"
      "  G0 X#1 Y#2 Z#3 A#5\n"  // #3 and #5: not passed, 0 in the call
      "  #1=99 #31=2 #<loc>=4\n"
      "o100 endsub\n"
      "o100 call [1] [2 * 3]\n"
      "G0 X#1 Y#31 Z[EXISTS[#<loc>]]\n",
      ngc(), p);
  std::vector<std::string> w;
  for (const auto& b : t)
    if (b.count) w.push_back(words(b) + "@" + std::to_string(b.line));
  EXPECT_EQ(w, (V{"G0 X1 Y6 Z0 A0@5", "G0 X100 Y2 Z0@9"}));
  EXPECT_DOUBLE_EQ(p.get(5), 7.0);  // #1..#30 restored after the call
}

TEST(ReaderO, ForwardCallsNamedSubsAndReturnValues) {
  // A subroutine defined after its call runs (LinuxCNC 2.9's rs274 does the same).
  EXPECT_EQ(trace("o<square> call [3]\nG0 X#<_value> Y#<_value_returned>\nM2\n"
                  "o<square> sub\n  o<square> return [#1 * #1]\n  G0 X999\no<square> endsub\n"),
            (V{"G0 X9 Y1", "M2"}));
  // endsub with a value, endsub without one (value 0, not returned).
  EXPECT_EQ(trace("o1 sub\no1 endsub [3 * 4]\no2 sub\no2 endsub\no1 call\nG0 X#<_value>\n"
                  "o2 call\nG0 X#<_value> Y#<_value_returned>\n"),
            (V{"G0 X12", "G0 X0 Y0"}));
  // Labels: o0100 is o100; names are case-insensitive.
  EXPECT_EQ(trace("o0100 sub\nG0 X1\no100 endsub\nO<Ab> sub\nG0 X2\no<aB> endsub\no100 call\n"
                  "o<AB> call\n"),
            (V{"G0 X1", "G0 X2"}));
  // A computed label.
  EXPECT_EQ(trace("o102 sub\nG0 X2\no102 endsub\n#101=100\no[#101+2] call\n"), (V{"G0 X2"}));
}

TEST(ReaderO, RecursionWithLocals) {
  // Factorial with a local per call: LinuxCNC's rs274 prints n=2,3,4,5 and 5! = 120.
  const std::string prog =
      "o<fact> sub\n"
      "  o1 if [#1 LE 1]\n"
      "    o<fact> return [1]\n"
      "  o1 endif\n"
      "  #<n> = #1\n"
      "  o<fact> call [#1 - 1]\n"
      "  (DEBUG,n=%d#<n> sub=#<_value>)\n"
      "o<fact> endsub [#<n> * #<_value>]\n"
      "o<fact> call [5]\n"
      "(DEBUG,%d#<_value>)\n";
  EXPECT_EQ(trace(prog),
            (V{"msg:n=2 sub=1", "msg:n=3 sub=2", "msg:n=4 sub=6", "msg:n=5 sub=24", "msg:120"}));
}

TEST(ReaderO, CallDepthLimit) {
  // LinuxCNC: 10 levels with the main program: 9 nested calls run, the 10th is refused.
  const std::string prog =
      "#<_d>=0\no<deep> sub\n  #<_d> = [#<_d> + 1]\n  o<deep> call\no<deep> endsub\n"
      "o<deep> call\n";
  Params p;
  try {
    read_all(prog, ngc(), p);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "t.ngc:4:3: error: o<deep> call: too many nested subroutine calls (at most 10 "
                 "levels, the main program included)");
  }
  EXPECT_EQ(p.named("_d"), 9.0);
}

TEST(ReaderO, M2InsideASubroutineEndsTheProgram) {
  EXPECT_EQ(trace("o1 sub\nG0 X1\nM2\no1 endsub\no1 call\nG0 X2\n"), (V{"G0 X1", "M2"}));
}

TEST(ReaderO, IfElseifElse) {
  const std::string prog =
      "o102 if [#2 GT 5]\n  G0 X100\no102 elseif [#2 LT 2]\n  G0 X200\no102 elseif [#2 EQ 3]\n"
      "  G0 X300\no102 else\n  G0 X150\no102 endif\nG0 Y1\n";
  for (const auto& [v, x] : std::vector<std::pair<int, std::string>>{
           {6, "G0 X100"}, {1, "G0 X200"}, {3, "G0 X300"}, {4, "G0 X150"}}) {
    EXPECT_EQ(trace("#2=" + std::to_string(v) + "\n" + prog), (V{x, "G0 Y1"})) << v;
  }
  // Without else, false: nothing.
  EXPECT_EQ(trace("o1 if [0]\nG0 X1\no1 endif\nG0 X2"), (V{"G0 X2"}));
  // Nested ifs.
  EXPECT_EQ(trace("o1 if [1]\no2 if [0]\nG0 X1\no2 else\nG0 X2\no2 endif\no1 endif\n"),
            (V{"G0 X2"}));
}

TEST(ReaderO, WhileDoRepeatBreakContinue) {
  // While (LinuxCNC's sawtooth example, shortened).
  EXPECT_EQ(trace("#1=0\no101 while [#1 LT 3]\nG1 X#1\n#1=[#1+1]\no101 endwhile\nG0 X9"),
            (V{"G1 X0", "G1 X1", "G1 X2", "G0 X9"}));
  // A false while runs nothing; a do runs once before its test.
  EXPECT_EQ(trace("o1 while [0]\nG0 X1\no1 endwhile\no2 do\nG0 X2\no2 while [0]\n"), (V{"G0 X2"}));
  // LinuxCNC's do/continue example: continue skips to the while test.
  EXPECT_EQ(trace("#1=0\no100 do\n  #1=[#1+1]\n  o110 if [#1 EQ 2]\n    o100 continue\n"
                  "  o110 endif\n  G0 X#1\no100 while [#1 LT 4]\nG0 Y1"),
            (V{"G0 X1", "G0 X3", "G0 X4", "G0 Y1"}));
  // break and continue in a while.
  EXPECT_EQ(trace("#2=0\no300 while [#2 LT 10]\n  #2=[#2+1]\n  o310 if [#2 EQ 2]\n"
                  "    o300 continue\n  o310 endif\n  o320 if [#2 EQ 4]\n    o300 break\n"
                  "  o320 endif\n  G0 X#2\no300 endwhile\nG0 Y#2"),
            (V{"G0 X1", "G0 X3", "G0 Y4"}));
  // Repeat: the count is rounded (rs274: [2.6] runs 3 times, [2.4] twice); 0 or less: never.
  EXPECT_EQ(trace("o1 repeat [3]\nG0 X1\no1 endrepeat\no2 repeat [0]\nG0 X2\no2 endrepeat\n"
                  "o3 repeat [-1]\nG0 X3\no3 endrepeat\no4 repeat [2.6]\nG0 X4\no4 endrepeat\n"
                  "o5 repeat [2.4]\nG0 X5\no5 endrepeat"),
            (V{"G0 X1", "G0 X1", "G0 X1", "G0 X4", "G0 X4", "G0 X4", "G0 X5", "G0 X5"}));
}

TEST(ReaderO, SkippedLinesHaveNoEffect) {
  // A break in the body of a loop that never runs does not touch other loops: the do loop runs
  // 3 passes both times. (LinuxCNC 2.9's rs274 runs it once the second time: a quirk of its
  // skipping, not its documented semantics; likewise after a do loop's continue, its repeats
  // can run too often.)
  EXPECT_EQ(trace("o2 repeat [2]\n#116=0\no16 do\n#116=[#116+1]\nG0 X#116\n"
                  "o16 while [#116 LT 3]\no17 while [0]\no17 break\no17 endwhile\no2 endrepeat\n"),
            (V{"G0 X1", "G0 X2", "G0 X3", "G0 X1", "G0 X2", "G0 X3"}));
  // A skipped if body with a repeat inside, then a repeat entered twice from a do/continue.
  EXPECT_EQ(trace("#1=0\no1 do\n#1=[#1+1]\no3 if [#1 EQ 1]\no1 continue\no3 endif\n"
                  "o4 repeat [2]\nG0 X#1\no4 endrepeat\no1 while [#1 LT 3]\n"),
            (V{"G0 X2", "G0 X2", "G0 X3", "G0 X3"}));
}

TEST(ReaderO, NestedLoopsAndLoopsInSubroutines) {
  // 3 x 2 nested whiles; a repeat inside a subroutine called twice.
  const auto t = trace(
      "#1=0\no1 while [#1 LT 3]\n  #2=0\n  o2 while [#2 LT 2]\n    G0 X#1 Y#2\n    #2=[#2+1]\n"
      "  o2 endwhile\n  #1=[#1+1]\no1 endwhile\n"
      "o9 sub\n  o10 repeat [#1]\n    G1 Z#1\n  o10 endrepeat\no9 endsub\no9 call [2]\no9 call "
      "[1]\n");
  EXPECT_EQ(t, (V{"G0 X0 Y0", "G0 X0 Y1", "G0 X1 Y0", "G0 X1 Y1", "G0 X2 Y0", "G0 X2 Y1", "G1 Z2",
                  "G1 Z2", "G1 Z1"}));
}

// A call and an endsub or return give a block of their own kind (no words), in execution order:
// the interpreter counts the call depth from them (M73 restores on the return).
TEST(ReaderO, CallAndReturnBlocks) {
  const auto bs = read_all(
      "o1 sub\nG0 X1\no2 if [#1 GT 0]\no1 return\no2 endif\no1 endsub\no1 call [1]\n"
      "o1 call [0]\nG0 X2\n");
  std::vector<std::pair<int, BlockKind>> seq;
  for (const auto& b : bs) seq.emplace_back(b.line, b.kind);
  const std::vector<std::pair<int, BlockKind>> want = {
      {7, BlockKind::kCall}, {2, BlockKind::kWords}, {4, BlockKind::kReturn},
      {8, BlockKind::kCall}, {2, BlockKind::kWords}, {6, BlockKind::kReturn},
      {9, BlockKind::kWords}};
  EXPECT_EQ(seq, want);
  for (const auto& b : bs) {
    if (b.kind != BlockKind::kWords) {
      EXPECT_EQ(b.count, 0);
    }
  }
}

TEST(ReaderO, BlockLineNumbersFollowExecution) {
  const auto bs = read_all("o1 repeat [2]\nG0 X1\no1 endrepeat\nG0 X2\n");
  std::vector<int> lines;
  for (const auto& b : bs) lines.push_back(b.line);
  EXPECT_EQ(lines, (std::vector<int>{2, 2, 4}));  // O-word lines give no block
}

TEST(ReaderO, ProgramNumberCommentsAndLineNumbers) {
  // "O1000 (title)" (Fanuc style program number) is accepted and ignored; N may come first;
  // comments may follow an O-word.
  EXPECT_EQ(trace("O1000 (PART)\nN10 o400 if [1] (comment)\nG0 X1\nN20 o400 endif\n"),
            (V{"G0 X1"}));
}

TEST(ReaderO, LoopGuardIsAnErrorNamingTheLoop) {
  EXPECT_EQ(read_error_of("G0 X1\no7 while [1]\no7 endwhile\n", ngc(), 1000),
            "t.ngc:2:1: error: o7 while: more than 1000 iterations (an endless loop?)");
  EXPECT_EQ(read_error_of("o8 do\no8 while [1]\n", ngc(), 50),
            "t.ngc:1:1: error: o8 do: more than 50 iterations (an endless loop?)");
  // A loop entered again starts counting again: 3 x 40 iterations under a limit of 50.
  EXPECT_EQ(read_error_of("#1=0\no1 while [#1 LT 3]\n#1=[#1+1]\n#2=0\no2 while [#2 LT 40]\n"
                          "#2=[#2+1]\no2 endwhile\no1 endwhile\n",
                          ngc(), 50),
            "no error");
}

TEST(ReaderO, StructureErrors) {
  EXPECT_EQ(read_error_of("#1=0\no101 endwhile\n"),
            "t.ngc:2:1: error: o101 endwhile without while");
  EXPECT_EQ(read_error_of("G0 X1\no100 sub\nG0 X2\n"), "t.ngc:2:1: error: o100 sub without endsub");
  EXPECT_EQ(read_error_of("o100 call\no100 sub\nG0 X2\n"),
            "t.ngc:2:1: error: o100 sub without endsub");
  EXPECT_EQ(read_error_of("o1 if [0]\nG0 X1\n"), "t.ngc:1:1: error: o1 if without endif");
  EXPECT_EQ(read_error_of("o1 if [1]\nG0 X1\n"), "t.ngc:1:1: error: o1 if without endif");
  EXPECT_EQ(read_error_of("o1 else\n"), "t.ngc:1:1: error: o1 else without if");
  EXPECT_EQ(read_error_of("o1 elseif [1]\n"), "t.ngc:1:1: error: o1 elseif without if");
  EXPECT_EQ(read_error_of("o1 endif\n"), "t.ngc:1:1: error: o1 endif without if");
  EXPECT_EQ(read_error_of("o1 while [1]\n"), "t.ngc:1:1: error: o1 while without endwhile");
  EXPECT_EQ(read_error_of("o1 do\n"), "t.ngc:1:1: error: o1 do without a closing while");
  EXPECT_EQ(read_error_of("o1 repeat [2]\n"), "t.ngc:1:1: error: o1 repeat without endrepeat");
  EXPECT_EQ(read_error_of("o1 endrepeat\n"), "t.ngc:1:1: error: o1 endrepeat without repeat");
  EXPECT_EQ(read_error_of("o1 break\n"),
            "t.ngc:1:1: error: o1 break outside a while or do loop of that number");
  EXPECT_EQ(read_error_of("o1 repeat [2]\no1 break\no1 endrepeat\n"),
            "t.ngc:2:1: error: o1 break outside a while or do loop of that number");
  EXPECT_EQ(read_error_of("o100 return\n"),
            "t.ngc:1:1: error: o100 return outside a subroutine call");
  // A return may carry another label (rs274 returns from o1 here too); endsub may not.
  EXPECT_EQ(trace("o1 sub\nG0 X1\no2 return\nG0 X5\no1 endsub\no1 call\nG0 Y2\n"),
            (V{"G0 X1", "G0 Y2"}));
  EXPECT_EQ(read_error_of("o1 sub\no2 endsub\no1 call\n"),
            "t.ngc:1:1: error: o1 sub without endsub");
  EXPECT_EQ(read_error_of("o1 sub\no1 endsub\no1 sub\no1 endsub\n"),
            "t.ngc:3:1: error: o1 sub is defined twice (first at line 1)");
  EXPECT_EQ(read_error_of("o<lib> call [1]\n"),
            "t.ngc:1:1: error: subroutine o<lib> is not defined in this file (subroutines in "
            "other files are not supported)");
}

TEST(ReaderO, LineErrors) {
  EXPECT_EQ(read_error_of("o100 sub G0\n"),
            "t.ngc:1:10: error: unexpected 'G' after o100 sub: an O-word line has no other words");
  EXPECT_EQ(read_error_of("G0 o100 sub\n"),
            "t.ngc:1:4: error: an O-word must be the first word on its line (only N may come "
            "before it)");
  EXPECT_EQ(read_error_of("#1=1 o100 sub\n"),
            "t.ngc:1:6: error: an O-word line cannot have parameter assignments");
  EXPECT_EQ(read_error_of("o100 foo\n"),
            "t.ngc:1:6: error: unknown O-word keyword 'FOO' (sub, endsub, return, call, do, "
            "while, endwhile, if, elseif, else, endif, break, continue, repeat, endrepeat)");
  EXPECT_EQ(read_error_of("o1 sub\no1 endsub\no1 call 5\n"),
            "t.ngc:3:9: error: o1 call: arguments must be in brackets, e.g. [1.5]");
  EXPECT_EQ(read_error_of("o1 if\no1 endif\n"),
            "t.ngc:1:4: error: o1 if needs one condition in brackets, e.g. [#1 LT 10]");
  EXPECT_EQ(read_error_of("o1 if [1\n"), "t.ngc:1:7: error: unclosed '['");
  EXPECT_EQ(read_error_of("o1.5 sub\n"), "t.ngc:1:3: error: an O-word number must be an integer");
  EXPECT_EQ(read_error_of("o sub\n"),
            "t.ngc:1:1: error: expected a number, <name> or [expression] after 'O'");
  EXPECT_EQ(read_error_of("o1 repeat [1e20]\no1 endrepeat\n"),
            "t.ngc:1:13: error: unknown operator 'E'");
  EXPECT_EQ(read_error_of("o1 repeat [10 ** 20]\no1 endrepeat\n"),
            "t.ngc:1:4: error: o1 repeat: count 1e+20 out of range");
  EXPECT_EQ(read_error_of("o[-1] call\n"),
            "t.ngc:1:1: error: computed O-word number -1 is not a non-negative integer");
  EXPECT_EQ(read_error_of("o[1] if [1]\n"),
            "t.ngc:1:1: error: a computed O-word number ('o[...]') is only supported with call");
  // The condition's own errors name its column.
  EXPECT_EQ(read_error_of("o1 if [#<x> GT 1]\no1 endif\n"),
            "t.ngc:1:8: error: parameter #<x> is not set");
  EXPECT_EQ(read_error_of("o1 if [0]\no1 elseif [1/0]\no1 endif\n"),
            "t.ngc:2:13: error: division by zero");
}

TEST(ReaderO, LinesAfterProgramEndAreNotRead) {
  // After M2 nothing is lexed, so garbage there is no error (LinuxCNC does not read it).
  EXPECT_EQ(trace("G0 X1\nM2\n\x01\x02 garbage [[[\n"), (V{"G0 X1", "M2"}));
}

// ---- header comments -----------------------------------------------------------------------

TEST(ReaderHeader, CommentsOfTheFirstLines) {
  const auto h = fpgacnc::gcode::header_comments(
      "%\n(Generated by Fusion 360 (post: grbl))\n; generated by PrusaSlicer 2.6.0\n"
      "G1 X1 ( move ) ; tail\n(unclosed\n(late)\n",
      5);
  ASSERT_EQ(h.size(), 5u);
  EXPECT_EQ(h[0].line, 2);
  EXPECT_EQ(h[0].text, "Generated by Fusion 360 (post: grbl)");
  EXPECT_EQ(h[1].line, 3);
  EXPECT_EQ(h[1].text, "generated by PrusaSlicer 2.6.0");
  EXPECT_EQ(h[2].text, "move");
  EXPECT_EQ(h[3].text, "tail");
  EXPECT_EQ(h[3].line, 4);
  EXPECT_EQ(h[4].text, "unclosed");
}

// Numbers in words are read exactly as std::from_chars reads them (the reader has a fast path for
// up to 15-16 digits and falls back to from_chars beyond): random numbers of 1 to 24 digits with
// the point anywhere, signs and leading zeros.
TEST(ReaderNumbers, SameDoubleAsFromChars) {
  std::mt19937_64 rng(7);
  std::string text;
  std::vector<double> want;
  for (int k = 0; k < 20000; ++k) {
    const int digits = 1 + static_cast<int>(rng() % 24);
    std::string num;
    for (int d = 0; d < digits; ++d) num += static_cast<char>('0' + rng() % 10);
    const size_t dot = rng() % (num.size() + 2);
    if (dot <= num.size()) num.insert(dot, ".");
    double v = 0;
    std::from_chars(num.data(), num.data() + num.size(), v);
    const bool neg = rng() % 2;
    want.push_back(neg ? -v : v);
    text += std::string("G0 X") + (neg ? "-" : "") + num + "\n";
  }
  Syntax s;
  const auto blocks = read_all(text, s);
  ASSERT_EQ(blocks.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) {
    const Word& x = blocks[k].words[1];
    ASSERT_EQ(x.value, want[k]) << "line " << k + 1;
    ASSERT_EQ(std::signbit(x.value), std::signbit(want[k])) << "line " << k + 1;
  }
}
