// LinuxCNC's M70-M73 (save, invalidate, restore the modal state) and the G5/G5.1 splines.
// Expected values are worked out by hand from the codes' definitions (docs/gcode.md).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "fpgacnc/gcode/interpreter.h"
#include "gcode_test_util.h"

namespace gc = fpgacnc::gcode;

namespace {

gc::Options cnc() {
  gc::Options o;
  o.dialect = gc::Dialect::kLinuxCnc;
  return o;
}

gc::Program run_cnc(std::string_view text, gc::Options o = cnc()) {
  return gc::parse_string(text, "t.ngc", o);
}

using gc::test::moves_of;

void expect_refused_cnc(std::string_view text, int line, int col, std::string_view msg) {
  gc::test::expect_error(text, line, col, msg, cnc());
}

}  // namespace

// G5.1 from (0,0) to (10,0) with I5 J5: control point (5,5), so x = 10 t and y = 10 t (1 - t):
// the parabola y = x (10 - x) / 10, peak (5, 2.5). A chord spanning dx in x leaves it by at most
// dx^2 / 40 (y'' = -1/5): within 0.01 mm needs dx <= 0.632, so 16 equal pieces.
TEST(Splines, QuadraticOnTheParabolaWithinTolerance) {
  const auto m = moves_of(run_cnc("G21 G90 F100\nG5.1 X10 Y0 I5 J5\nM2\n"));
  ASSERT_EQ(m.size(), 16u);
  double peak = 0.0, worst = 0.0;
  for (const auto& mv : m) {
    EXPECT_EQ(mv.motion, gc::Motion::kLinear);
    EXPECT_EQ(mv.line, 2);
    EXPECT_DOUBLE_EQ(mv.feed_mm_min, 100.0);
    const double x = mv.end[0], y = mv.end[1];
    EXPECT_NEAR(y, x * (10 - x) / 10, 1e-9);
    peak = std::max(peak, y);
    const double mx = 0.5 * (mv.start[0] + x), my = 0.5 * (mv.start[1] + y);
    worst = std::max(worst, mx * (10 - mx) / 10 - my);
  }
  EXPECT_NEAR(peak, 2.5, 1e-12);  // t = 1/2 is a piece's end
  EXPECT_LE(worst, 0.01);
  EXPECT_GT(worst, 0.0025);  // not more pieces than the tolerance needs
  EXPECT_EQ(m.back().end[0], 10.0);
  EXPECT_EQ(m.back().end[1], 0.0);
  // A finer tolerance: 0.001 mm needs dx <= 0.2, 50 pieces.
  gc::Options fine = cnc();
  fine.arc_tolerance_mm = 0.001;
  EXPECT_EQ(moves_of(run_cnc("G21 G90 F100\nG5.1 X10 Y0 I5 J5\nM2\n", fine)).size(), 50u);
}

// G5 from (0,0) to (10,0), I0 J3 P0 Q3: control points (0,0) (0,3) (10,3) (10,0). It leaves
// the start along +Y, arrives at the end along -Y, and passes (5, 2.25) at t = 1/2 (1/8 P0 +
// 3/8 P1 + 3/8 P2 + 1/8 P3). A second G5 without I J continues smoothly: I J = -(P Q) of the
// first, so (10,0) (10,-3) (20,-3) (20,0), through (15, -2.25).
TEST(Splines, CubicEndsTangentsAndContinuation) {
  const auto m = moves_of(run_cnc("G21 G90 F100\nG5 X10 Y0 I0 J3 P0 Q3\nG5 X20 Y0 P0 Q-3\nM2\n"));
  std::vector<gc::Move> first, second;
  for (const auto& mv : m) (mv.line == 2 ? first : second).push_back(mv);
  ASSERT_GT(first.size(), 4u);
  ASSERT_EQ(first.size(), second.size());
  const auto& a = first.front();
  EXPECT_LT(std::fabs(a.end[0] - a.start[0]), 0.5 * (a.end[1] - a.start[1]));  // ~ +Y
  const auto& z = first.back();
  EXPECT_EQ(z.end[0], 10.0);
  EXPECT_EQ(z.end[1], 0.0);
  EXPECT_LT(std::fabs(z.end[0] - z.start[0]), 0.5 * (z.start[1] - z.end[1]));  // ~ -Y
  auto near_point = [](const std::vector<gc::Move>& v, double x, double y) {
    double best = 1e9;
    for (const auto& mv : v) best = std::min(best, std::hypot(mv.end[0] - x, mv.end[1] - y));
    return best;
  };
  EXPECT_LT(near_point(first, 5, 2.25), 1e-9);
  EXPECT_LT(near_point(second, 15, -2.25), 1e-9);
  const auto& b = second.front();
  EXPECT_LT(std::fabs(b.end[0] - b.start[0]), 0.5 * (b.start[1] - b.end[1]));  // ~ -Y
  EXPECT_EQ(second.back().end[0], 20.0);
}

// G20 G91: X1 I0.5 J0.5 is 25.4 mm to the right with the control point 12.7 mm above the start:
// the peak is 6.35 mm at x = 12.7 mm. Z stays.
TEST(Splines, InchesAndIncremental) {
  const auto m = moves_of(run_cnc("G21 G90 F100\nG0 Z2\nG20 G91\nG5.1 X1 Y0 I0.5 J0.5\nM2\n"));
  double peak = 0.0;
  for (const auto& mv : m) {
    if (mv.line != 4) continue;
    peak = std::max(peak, mv.end[1]);
    EXPECT_EQ(mv.end[2], 2.0);
  }
  EXPECT_NEAR(peak, 6.35, 1e-9);
  EXPECT_NEAR(m.back().end[0], 25.4, 1e-12);
}

TEST(Splines, Errors) {
  expect_refused_cnc("G21 F100\nG18 G5.1 X10 Y5 I1 J1\n", 2, 5, "splines need the XY plane");
  expect_refused_cnc("G21 F100\nG5 X10 Y5 I1 J1\n", 2, 1, "G5 needs both P and Q");
  expect_refused_cnc("G21 F100\nG5.1 X10 Y5 I1\n", 2, 13, "G5.1 needs both I and J");
  expect_refused_cnc("G21 F100\nG5 X10 Z1 I1 J1 P1 Q1\n", 2, 8, "a spline moves X and Y only");
  expect_refused_cnc("G21 F100\nG5.2 X0 Y0 P1 L3\n", 2, 1, "G5.2: NURBS curves are not supported");
  expect_refused_cnc("G21 F100\nG41.1 D2 G5.1 X10 Y5 I1 J1\n", 2, 10,
                     "no spline with cutter radius compensation on");
  // No motion mode after a spline (LinuxCNC): a bare X line has nothing to move with.
  expect_refused_cnc("G21 F100\nG5.1 X10 Y5 I1 J1\nX20\n", 3, 1, "no motion mode");
}

// M70 saves units, distance mode, feed, spindle and coolant; M72 puts them back (coolant as M8
// would: flood on again) and may be used again; M71 invalidates.
TEST(ModalState, SaveAndRestore) {
  const auto p = run_cnc(
      "G21 G90 F200 S1000 M3 M8\nM70\nG20 G91 F5 S300 M5 M9\nM72\nG1 X10\nG20 G91\nM72\nG1 "
      "X20\nM71\nM2\n");
  const auto m = moves_of(p);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].end[0], 10.0);  // mm, absolute
  EXPECT_EQ(m[0].feed_mm_min, 200.0);
  EXPECT_TRUE(m[0].spindle_on);
  EXPECT_EQ(m[0].spindle_s, 1000.0);
  EXPECT_EQ(m[1].end[0], 20.0);
  int flood_on_line4 = 0;
  for (const auto& c : p.commands)
    if (const auto* o = std::get_if<gc::Output>(&c))
      if (o->line == 4 && o->kind == gc::Output::Kind::kFlood && o->value == 1.0) ++flood_on_line4;
  EXPECT_EQ(flood_on_line4, 1);
  expect_refused_cnc("G21 F100\nM70\nM71\nM72\n", 4, 1, "M72: no modal state saved");
  expect_refused_cnc("G21 F100\nM72\n", 2, 1, "M72: no modal state saved");
}

// On one line F and the units come before the restore, the distance mode after (as rs274).
TEST(ModalState, OrderOnTheLine) {
  const auto m = moves_of(run_cnc("G21 G90 F100\nM70\nG91 M72\nG1 X1\nG1 X1\nM2\n"));
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[1].end[0], 2.0);  // G91 stays
  const auto f = moves_of(run_cnc("G21 G90 F100\nM70\nF50 M72\nG1 X1\nM2\n"));
  EXPECT_EQ(f[0].feed_mm_min, 100.0);
}

// M73 in a subroutine: its state comes back when the subroutine ends (endsub or return).
// Calls run G20 G91 X1 (+25.4 mm); the main program's G90 X5 lines are in mm.
TEST(ModalState, M73RestoresOnReturn) {
  const auto m = moves_of(run_cnc(
      "o100 sub\nM73\nG20 G91 F5\nG1 X1\no100 if [#1 GT 0]\no100 return\no100 endif\nG1 X1\n"
      "o100 endsub\nG21 G90 F100\no100 call [0]\nG1 X5\no100 call [1]\nG1 X5\nM2\n"));
  std::vector<double> xs;
  for (const auto& mv : m) xs.push_back(mv.end[0]);
  ASSERT_EQ(xs.size(), 5u);
  EXPECT_NEAR(xs[0], 25.4, 1e-12);
  EXPECT_NEAR(xs[1], 50.8, 1e-12);
  EXPECT_EQ(xs[2], 5.0);
  EXPECT_NEAR(xs[3], 30.4, 1e-12);
  EXPECT_EQ(xs[4], 5.0);
  EXPECT_EQ(m[4].feed_mm_min, 100.0);
  // The same subroutine called twice in a row: the second call starts from the restored state.
  const auto twice =
      moves_of(run_cnc("o1 sub\nM73\nG20 G91\nG1 X1\no1 endsub\nG21 G90 F100\no1 call\no1 call\n"
                       "G1 X5\nM2\n"));
  ASSERT_EQ(twice.size(), 3u);
  EXPECT_NEAR(twice[1].end[0], 50.8, 1e-12);
  EXPECT_EQ(twice[2].end[0], 5.0);
}

// A state belongs to its call level: M70 in a subroutine cannot be restored in the caller, and
// M73 in the main program is never restored.
TEST(ModalState, PerCallLevel) {
  expect_refused_cnc("o1 sub\nM70\no1 endsub\nG21 F100\no1 call\nM72\n", 6, 1,
                     "M72: no modal state saved at this call level");
  const auto m = moves_of(run_cnc("G21 G90 F100\nM73\nG91\nG1 X1\nG1 X1\nM2\n"));
  EXPECT_EQ(m.back().end[0], 2.0);
}

// rs274 restores cutter compensation too (switching it off without an exit move): refused
// here when the saved state differs from the current one in compensation.
TEST(ModalState, RestoreAcrossCutterCompensationIsRefused) {
  expect_refused_cnc("G21 G90 F100\nM70\nG41.1 D2\nG1 X10\nM72\n", 5, 1,
                     "M72: the saved modal state differs in cutter radius compensation");
  // Compensation on at both ends, nothing else under it changed: allowed.
  const auto m =
      moves_of(run_cnc("G21 G90 F100\nG41.1 D2\nG1 X10\nM70\nG1 X20 Y5\nM72\nG1 X30\nG40 "
                       "X40\nM2\n"));
  EXPECT_EQ(m.back().end[0], 40.0);
}

// The printer dialects' M73 is still a progress report.
TEST(ModalState, PrinterM73IsProgress) {
  gc::Options o;
  o.dialect = gc::Dialect::kMarlin;
  const auto p = gc::parse_string("M73 P50\nG1 X1 F100\n", "t.gcode", o);
  bool progress = false;
  for (const auto& c : p.commands)
    if (const auto* msg = std::get_if<gc::Message>(&c))
      progress = progress || (msg->kind == gc::Message::Kind::kProgress && msg->percent == 50.0);
  EXPECT_TRUE(progress);
}

// M70-M72 are LinuxCNC's: grbl refuses them, Marlin skips unknown M codes with a warning.
TEST(ModalState, OtherDialects) {
  gc::Options grbl;
  grbl.dialect = gc::Dialect::kGrbl;
  try {
    gc::parse_string("M70\nG1 X1 F100\n", "t.gcode", grbl);
    ADD_FAILURE() << "no error";
  } catch (const gc::Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.gcode:1:1: error: M70: not supported in the grbl"),
              std::string::npos)
        << e.what();
  }
  gc::Options marlin;
  marlin.dialect = gc::Dialect::kMarlin;
  const auto p = gc::parse_string("M72\nG1 X1 F100\n", "t.gcode", marlin);
  ASSERT_EQ(p.stats.warnings.size(), 1u);
  EXPECT_NE(p.stats.warnings[0].what.find("M72"), std::string::npos);
}

// The restore happens at the endsub itself: the next line's parameters read the caller's state
// (#<_imperial> is 0 again, so X10, in mm).
TEST(ModalState, M73RestoresBeforeTheNextLineIsRead) {
  const auto m = moves_of(
      run_cnc("o1 sub\nM73\nG20\no1 endsub\nG21 G90 F100\no1 call\nG1 X[10 + #<_imperial>]\n"
              "M2\n"));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].end[0], 10.0);
}
