#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/plan/planner.h"
#include "gcode_test_util.h"

namespace gc = fpgacnc::gcode;

namespace {

using gc::test::moves_of;

gc::Move last_move(std::string_view text) {
  const auto m = moves_of(gc::parse_string(text));
  EXPECT_FALSE(m.empty());
  return m.back();
}

void expect_refused(std::string_view text, int line, int col, std::string_view msg) {
  gc::test::expect_error(text, line, col, msg, {}, "t.gcode");
}

}  // namespace

// Every file of the CNCjs corpus runs; helical-thread-milling.gcode's G42 D08 reads tool 8's
// diameter from the corpus tool table.
TEST(Interpreter, WholeCorpusIsAccepted) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(FPGACNC_CORPUS_DIR)) {
    if (entry.path().extension() != ".gcode") continue;
    ++files;
    const std::string path = entry.path().string();
    SCOPED_TRACE(path);
    gc::Options o;
    o.tool_table = std::string(FPGACNC_CORPUS_DIR) + "/../tools.tbl";
    const auto p = gc::parse_file(path, o);
    EXPECT_GT(p.stats.moves, 0u);
  }
  EXPECT_GE(files, 12);
}

TEST(Interpreter, UnitsInchIs25_4Mm) {
  EXPECT_DOUBLE_EQ(last_move("G21 G1 X1 Y2 F100").end[0], 1.0);
  const auto m = last_move("G20 G1 X1 Y2 F10");
  EXPECT_DOUBLE_EQ(m.end[0], 25.4);
  EXPECT_DOUBLE_EQ(m.end[1], 50.8);
  EXPECT_DOUBLE_EQ(m.feed_mm_min, 254.0);
}

TEST(Interpreter, AbsoluteAndIncremental) {
  EXPECT_DOUBLE_EQ(last_move("G90 G0 X5\nX7").end[0], 7.0);
  EXPECT_DOUBLE_EQ(last_move("G90 G0 X5\nG91 X7").end[0], 12.0);
  EXPECT_DOUBLE_EQ(last_move("G91 G0 X5\nX7\nG90 X1").end[0], 1.0);
  // M83: E relative even under G90.
  EXPECT_DOUBLE_EQ(last_move("M83 G1 E2 F100\nE3").end[3], 5.0);
  EXPECT_DOUBLE_EQ(last_move("M82 G1 E2 F100\nE3").end[3], 3.0);
}

TEST(Interpreter, ModalMotionLowercaseNoSpacesPercent) {
  const auto p = gc::parse_string("%\ng1x1y2f100\nX3Y4\nG01 X0Y20\nn10 g0 x1 ; c\n%\n");
  const auto m = moves_of(p);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[1].motion, gc::Motion::kLinear);
  EXPECT_DOUBLE_EQ(m[1].end[1], 4.0);
  EXPECT_DOUBLE_EQ(m[2].end[1], 20.0);
  EXPECT_EQ(m[3].motion, gc::Motion::kRapid);
  EXPECT_EQ(m[3].line, 5);
}

TEST(Interpreter, IJArcEndExactAndChordsWithinTolerance) {
  const auto m = last_move("G0 X0 Y20\nG2 X20 Y0 I0 J-20 F200");
  EXPECT_EQ(m.motion, gc::Motion::kArcCw);
  EXPECT_DOUBLE_EQ(m.center[0], 0.0);
  EXPECT_DOUBLE_EQ(m.center[1], 0.0);
  const double tol = 0.01;
  const auto pts = fpgacnc::plan::arc_chord_points(m, tol);
  EXPECT_EQ(pts.back(), m.end);
  gc::Vec4 prev = m.start;
  for (const auto& p : pts) {
    EXPECT_NEAR(std::hypot(p[0], p[1]), 20.0, 1e-9);
    const double mx = (prev[0] + p[0]) / 2, my = (prev[1] + p[1]) / 2;
    EXPECT_LE(20.0 - std::hypot(mx, my), tol + 1e-12);
    // clockwise: the angle decreases
    EXPECT_LT(std::atan2(p[1], p[0]), std::atan2(prev[1], prev[0]) + 1e-12);
    prev = p;
  }
  // Planned in steps: ends exactly at the programmed end.
  fpgacnc::config::MachineConfig cfg;
  const auto plan =
      fpgacnc::plan::plan_program(gc::parse_string("G0 X0 Y20\nG2 X20 Y0 I0 J-20 F200"), cfg, {});
  EXPECT_EQ(plan.final_steps[0], 3200);
  EXPECT_EQ(plan.final_steps[1], 0);
  // and every chord midpoint in steps is within tolerance plus one step of quantization
  fpgacnc::plan::Steps4 prev_s{0, 3200, 0, 0};
  for (const auto& it : plan.items) {
    const auto& s = std::get<fpgacnc::plan::Segment>(it);
    if (s.source_line != 2) {
      prev_s = s.target;
      continue;
    }
    const double mx = (prev_s[0] + s.target[0]) / 2.0 / 160,
                 my = (prev_s[1] + s.target[1]) / 2.0 / 160;
    EXPECT_LE(std::fabs(20.0 - std::hypot(mx, my)), tol + 1.0 / 160);
    prev_s = s.target;
  }
}

TEST(Interpreter, RFormArcs) {
  // CW, short arc: centre right of the chord direction.
  auto m = last_move("G0 X0 Y0\nG2 X10 Y10 R10 F100");
  EXPECT_NEAR(m.center[0], 10.0, 1e-12);
  EXPECT_NEAR(m.center[1], 0.0, 1e-12);
  // Negative R: the long way round, the other centre.
  m = last_move("G0 X0 Y0\nG2 X10 Y10 R-10 F100");
  EXPECT_NEAR(m.center[0], 0.0, 1e-12);
  EXPECT_NEAR(m.center[1], 10.0, 1e-12);
  m = last_move("G0 X0 Y0\nG3 X10 Y10 R10 F100");
  EXPECT_NEAR(m.center[0], 0.0, 1e-12);
  EXPECT_NEAR(m.center[1], 10.0, 1e-12);
  // Half circle exactly (R = half chord) and within the tiny tolerance.
  m = last_move("G0 X0 Y0\nG2 X10 Y0 R5 F100");
  EXPECT_NEAR(m.center[0], 5.0, 1e-9);
  m = last_move("G0 X0 Y0\nG2 X10 Y0 R4.9995 F100");
  EXPECT_NEAR(m.center[0], 5.0, 1e-9);
  const auto pts = fpgacnc::plan::arc_chord_points(m, 0.01);
  EXPECT_EQ(pts.back(), m.end);
  // Helical: Z spread linearly.
  m = last_move("G0 X0 Y0 Z0\nG3 X10 Y10 Z5 R10 F100");
  const auto h = fpgacnc::plan::arc_chord_points(m, 0.01);
  for (size_t i = 0; i < h.size(); ++i) {
    EXPECT_NEAR(h[i][2], 5.0 * static_cast<double>(i + 1) / static_cast<double>(h.size()), 1e-9);
  }
}

TEST(Interpreter, FullCircles) {
  for (const char* text :
       {"G0 X0 Y0\nG2 I5 F100", "G0 X0 Y0\nG2 J5 F100", "G0 X0 Y0\nG3 X0 Y0 I-5 J0 F100"}) {
    SCOPED_TRACE(text);
    const auto m = last_move(text);
    EXPECT_TRUE(m.full_circle);
    const auto pts = fpgacnc::plan::arc_chord_points(m, 0.01);
    EXPECT_GT(pts.size(), 20u);
    EXPECT_EQ(pts.back(), m.start);
    for (const auto& p : pts) {
      EXPECT_NEAR(std::hypot(p[0] - m.center[0], p[1] - m.center[1]), 5.0, 1e-9);
    }
    // Goes all the way round: some chord point is on the far side.
    double far = 0;
    for (const auto& p : pts) far = std::max(far, std::hypot(p[0], p[1]));
    EXPECT_NEAR(far, 10.0, 0.05);
  }
}

TEST(Interpreter, G92SetsCurrentPosition) {
  const auto p = gc::parse_string("G0 X10 Y3\nG92 X0\nG1 X5 F100\nG92 E0\nG1 E2\nG92 E0\nG1 E1");
  const auto m = moves_of(p);
  EXPECT_DOUBLE_EQ(m[1].end[0], 15.0);  // machine X
  EXPECT_DOUBLE_EQ(m[1].end[1], 3.0);
  EXPECT_DOUBLE_EQ(m.back().end[3], 3.0);  // E keeps extruding: 2 + 1
}

TEST(Interpreter, G28GoesHomeViaIntermediatePoint) {
  auto m = moves_of(gc::parse_string("G0 X10 Y10 Z5\nG28"));
  EXPECT_EQ(m.back().end, (gc::Vec4{0, 0, 0, 0}));
  m = moves_of(gc::parse_string("G0 X10 Y10 Z5\nG28 Z20"));
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[1].end, (gc::Vec4{10, 10, 20, 0}));
  EXPECT_EQ(m[2].end, (gc::Vec4{10, 10, 0, 0}));
}

TEST(Interpreter, DwellSpindleHeater) {
  gc::Options grbl;
  grbl.dialect = gc::Dialect::kGrbl;
  const auto p = gc::parse_string("M3 S80\nG4 P0.5\nM104 S200\nM109 S210\nM140 S60\nM190 S60\nM5",
                                  "t.gcode", grbl);
  ASSERT_EQ(p.commands.size(), 6u);
  // M3: the laser / spindle mode (constant power), in step with the motion
  EXPECT_EQ(std::get<gc::Output>(p.commands[0]).kind, gc::Output::Kind::kLaserMode);
  EXPECT_DOUBLE_EQ(std::get<gc::Output>(p.commands[0]).value, 0.0);
  EXPECT_DOUBLE_EQ(std::get<gc::Dwell>(p.commands[1]).seconds, 0.5);
  EXPECT_EQ(std::get<gc::Heater>(p.commands[2]).mcode, 104);
  EXPECT_DOUBLE_EQ(*std::get<gc::Heater>(p.commands[2]).s, 200.0);
  const auto m = last_move("M3 S80\nG1 X1 F100");
  EXPECT_TRUE(m.spindle_on);
  EXPECT_DOUBLE_EQ(*m.spindle_s, 80.0);
}

TEST(Interpreter, Checksums) {
  auto with_sum = [](std::string s) {
    unsigned x = 0;
    for (char c : s) x ^= static_cast<unsigned char>(c);
    return s + "*" + std::to_string(x);
  };
  const auto good = with_sum("N1 G1 X1 F100");
  EXPECT_DOUBLE_EQ(last_move(good).end[0], 1.0);
  std::string bad = good;
  bad.back() = bad.back() == '0' ? '1' : '0';
  expect_refused("G0 X0\n" + bad, 2, 14, "checksum mismatch");
  expect_refused("G0 X0 *", 1, 7, "malformed checksum");
}

TEST(Interpreter, ErrorsHaveLineAndColumn) {
  expect_refused("G1 X1 F100\nG42 D3", 2, 5, "G42: no tool table to read the diameter of tool 3");
  expect_refused("G1 X1 F100\n  M7000", 2, 3, "M7000: not supported in the grbl dialect");
  expect_refused("G0 X0\nG2 X1 Y1 F100", 2, 1, "arc without centre");
  expect_refused("G0 X0 Y0\nG2 X10 Y0 R4 F100", 2, 11, "impossible arc");
  expect_refused("G1 Xnan F1", 1, 4, "expected a number");
  expect_refused("G1 X1 Yinf F1", 1, 7, "expected a number");
  expect_refused("G1 X1.2.3 F1", 1, 8, "garbage in the number of 'X'");
  expect_refused("G1 X1 Y-- F1", 1, 7, "expected a number");
  expect_refused("G1 X2000000 F1", 1, 4, "out of range");
  expect_refused("G20 G1 X50000 F1", 1, 8, "out of range");
  expect_refused("G1 X1 F-5", 1, 7, "negative feed");
  expect_refused("G1 X1 F0", 1, 7, "feed is 0");
  expect_refused("G1 F0\nG1 X1", 2, 1, "feed is 0");
  expect_refused("G1 X1 F100\nG1 X2\x01", 2, 6, "non-printable byte 0x01");
  expect_refused("G1 X1 F100\nG1 X2 \xff\xfe", 2, 7, "non-ASCII");
  expect_refused("G1 X1 X2 F100", 1, 7, "two 'X' words");
  expect_refused("G1 G0 X1", 1, 4, "G1 and G0 on one line are in the same modal group");
  expect_refused("G1.5 X1 F100", 1, 1, "G1.5: not supported");
  expect_refused("G1 X1 F100 D3", 1, 12, "'D' word with nothing on the line that uses it");
  expect_refused("G1 X1 F100 (unclosed", 1, 12, "unterminated comment");
  expect_refused("X1", 1, 1, "no motion mode");
  expect_refused("G4", 1, 1, "G4 needs a P word");
  expect_refused("", 1, 1, "empty job");
  expect_refused("; nothing\n(nothing)\n\n", 3, 1, "empty job");
  expect_refused("G21 G90\n", 1, 1, "empty job");
}

TEST(Interpreter, ModalArcWithoutCentreRunsAsLine) {
  // full-circle-without-xyz.gcode line 55: "X.75" after "G2 I-1.1".
  const auto p = gc::parse_string("G0 X0 Y0\nG2 I1 F30\nX.75");
  const auto m = moves_of(p);
  EXPECT_EQ(m.back().motion, gc::Motion::kLinear);
  EXPECT_EQ(p.stats.modal_arc_as_line, 1u);
}
