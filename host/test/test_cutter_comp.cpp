// Cutter radius compensation (G40/G41/G42/G41.1/G42.1) and lathe diameter mode (G7/G8). The
// expected points are worked out by hand from the geometry in the comments: the tool's centre
// runs at the tool radius beside the programmed path (left for G41, right for G42).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fpgacnc/gcode/interpreter.h"
#include "gcode_test_util.h"

namespace gc = fpgacnc::gcode;

namespace {

using gc::test::expect_error;

std::vector<gc::Move> moves_of(std::string_view text, gc::Options o = {}) {
  return gc::test::moves_of(gc::parse_string(text, "t.ngc", o));
}

void expect_at(const gc::Move& m, double x, double y, double z) {
  EXPECT_NEAR(m.end[0], x, 1e-9) << "line " << m.line;
  EXPECT_NEAR(m.end[1], y, 1e-9) << "line " << m.line;
  EXPECT_NEAR(m.end[2], z, 1e-9) << "line " << m.line;
}

}  // namespace

// Left of a square's corner turning left: the inside. Tool radius 2 (G41.1 D4).
TEST(CutterComp, EntryInsideCornerPlungeExit) {
  const auto m = moves_of(
      "G21 G90 G0 X0 Y0 Z5\n"  // 1
      "F100\n"                 // 2
      "G41.1 D4\n"             // 3
      "G1 X10 Y0\n"            // 4 entry: ends 2 mm left of +X, above (10, 0)
      "G1 X20 Y0\n"            // 5 along y = 2 ...
      "G1 Z-1\n"               // 6 ... plunge where the tool is
      "G1 X20 Y10\n"           // 7 up x = 18: the corner is where y = 2 meets x = 18
      "G40\n"                  // 8
      "G1 X30 Y10\n"           // 9 exit: from the offset point to the programmed one
      "M2\n");
  ASSERT_EQ(m.size(), 6u);
  expect_at(m[0], 0, 0, 5);
  expect_at(m[1], 10, 2, 5);
  expect_at(m[2], 18, 2, 5);  // moved back from (20, 2) to the crossing
  expect_at(m[3], 18, 2, -1);
  expect_at(m[4], 18, 10, -1);
  expect_at(m[5], 30, 10, -1);
  EXPECT_NEAR(m[5].start[0], 18, 1e-9);
  EXPECT_NEAR(m[5].start[1], 10, 1e-9);
  // A move leaves when the next move in the plane is known, with that block's line.
  EXPECT_EQ(m[1].line, 5);
  EXPECT_EQ(m[2].line, 7);
  EXPECT_EQ(m[3].line, 7);
  EXPECT_EQ(m[4].line, 8);
  EXPECT_EQ(m[5].line, 9);
  for (size_t i = 1; i < m.size(); ++i)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(m[i].start[a], m[i - 1].end[a], 1e-12) << i;
}

// The same path with the tool on the right: the corner at (20, 0) is outside, and an arc about
// the programmed corner joins the two offset lines.
TEST(CutterComp, OutsideCornerGetsAnArc) {
  const auto m =
      moves_of("G21 G90 G0 X0 Y0\nF100\nG42.1 D4\nG1 X10\nG1 X20\nG1 Y10\nG40\nG1 X30 Y10\nM2\n");
  ASSERT_EQ(m.size(), 6u);
  expect_at(m[1], 10, -2, 0);
  expect_at(m[2], 20, -2, 0);
  EXPECT_EQ(m[3].motion, gc::Motion::kArcCcw);  // tool on the right, path turning left
  expect_at(m[3], 22, 0, 0);
  EXPECT_NEAR(m[3].center[0], 20, 1e-12);
  EXPECT_NEAR(m[3].center[1], 0, 1e-12);
  expect_at(m[4], 22, 10, 0);
  expect_at(m[5], 30, 10, 0);
}

// G0 through an outside corner: a straight rapid replaces the arc.
TEST(CutterComp, RapidOutsideCornerIsStraight) {
  const auto m = moves_of("G21 G90 G0 X0 Y0\nG42.1 D4\nG0 X10\nG0 X20\nG0 Y10\nG40\nG0 X30\nM2\n");
  ASSERT_EQ(m.size(), 6u);
  EXPECT_EQ(m[3].motion, gc::Motion::kRapid);
  expect_at(m[3], 22, 0, 0);
}

// A counter-clockwise arc with the tool on its left runs on the inside: radius 5 - 1 = 4 about
// the same centre.
TEST(CutterComp, ArcInside) {
  const auto m =
      moves_of("G21 G90 G0 X0 Y0\nF100\nG41.1 D2\nG1 X10\nG3 X10 Y10 I0 J5\nG40\nG1 X0 Y10\nM2\n");
  ASSERT_EQ(m.size(), 4u);
  expect_at(m[1], 10, 1, 0);
  EXPECT_EQ(m[2].motion, gc::Motion::kArcCcw);
  expect_at(m[2], 10, 9, 0);
  EXPECT_NEAR(m[2].center[0], 10, 1e-12);
  EXPECT_NEAR(m[2].center[1], 5, 1e-12);
  expect_at(m[3], 0, 10, 0);
}

// The same arc on the right (outside): radius 6.
TEST(CutterComp, ArcOutside) {
  const auto m =
      moves_of("G21 G90 G0 X0 Y0\nF100\nG42.1 D2\nG1 X10\nG3 X10 Y10 I0 J5\nG40\nG1 X0 Y10\nM2\n");
  ASSERT_EQ(m.size(), 4u);
  expect_at(m[1], 10, -1, 0);
  expect_at(m[2], 10, 11, 0);
}

// D of G41/G42 is a tool of the tool table; its diameter / 2 is the radius. A negative
// G41.1/G42.1 diameter puts the tool on the other side.
TEST(CutterComp, ToolTableAndNegativeDiameter) {
  const auto dir = std::filesystem::temp_directory_path() / "fpgacnc_cutter_comp_test";
  std::filesystem::create_directories(dir);
  const auto tbl = dir / "tools.tbl";
  std::ofstream(tbl) << "T1 P1 Z10 D6 ;6 mm end mill\n";
  gc::Options o;
  o.tool_table = tbl.string();
  auto m = moves_of("G21 G90 G0 X0 Y0\nF100\nG41 D1\nG1 X10\nG40 G1 X20\nM2\n", o);
  ASSERT_EQ(m.size(), 3u);
  expect_at(m[1], 10, 3, 0);
  m = moves_of("G21 G90 G0 X0 Y0\nF100\nT1 M6\nG41\nG1 X10\nG40 G1 X20\nM2\n", o);
  expect_at(m[1], 10, 3, 0);  // D omitted: the current tool
  m = moves_of("G21 G90 G0 X0 Y0\nF100\nG42.1 D-4\nG1 X10\nG40 G1 X20\nM2\n");
  expect_at(m[1], 10, 2, 0);
  m = moves_of("G20 G90 G0 X0 Y0\nF10\nG41.1 D0.5\nG1 X1\nG40 G1 X2\nM2\n");
  expect_at(m[1], 25.4, 6.35, 0);  // D in inches under G20
  std::filesystem::remove_all(dir);
}

// Directions within 0.05 rad of each other get no corner: the next move starts where the last
// one ended and runs to its own offset end.
TEST(CutterComp, NearlyStraightCorner) {
  const auto m = moves_of("G21 G90 G0 X0 Y0\nF100\nG41.1 D4\nG1 X10\nG1 X20 Y-0.1\nM2\n");
  ASSERT_EQ(m.size(), 3u);
  const double len = std::hypot(10.0, 0.1);
  EXPECT_NEAR(m[2].start[0], 10, 1e-12);
  EXPECT_NEAR(m[2].start[1], 2, 1e-12);
  expect_at(m[2], 20 + 2 * 0.1 / len, -0.1 + 2 * 10 / len, 0);
}

TEST(CutterComp, Errors) {
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X1 F100", 3, 1, "longer in the plane than the tool radius");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 Z-1 F100", 3, 1, "longer in the plane");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG3 X10 Y2 I0 J1\nM2", 4, 1,
               "arc radius not larger than the tool radius");
  // (10, 10) -> (9, 10) is 1 mm long; the tool (radius 2) cannot turn into the next corner.
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG1 X10 Y10\nG1 X9 Y10\nG1 X9 Y0\nM2", 6, 1,
               "concave corner");
  expect_error("G19 G41.1 D4", 1, 5, "needs the XY or XZ plane");
  expect_error("G41.1 D4\nG42.1 D4", 2, 1, "already on");
  expect_error("G41.1", 1, 1, "G41.1 needs D");
  expect_error("G41.1 D4\nG18", 2, 1, "no change of plane");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nT1 M6", 4, 4, "no tool change");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG28", 4, 1, "G28 with cutter radius");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG53 G0 X0", 4, 1, "G53 with cutter radius");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG81 X5 Y5 Z-1 R1", 4, 1, "no canned cycle");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG40\nG2 X20 Y0 I5 J0", 5, 1,
               "must be a straight line");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG92 X0", 4, 1, "G92 with cutter radius");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG55", 4, 1, "no change of coordinate system");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG10 L2 P0 X1", 4, 1,
               "no change of the active coordinate system");
  expect_error("G0 X0 Y0\nG41.1 D4\nG1 X10 F100\nG43.1 Z1", 4, 1, "no tool length offset change");
}

// G7: X words are diameters (halved), in every distance mode and in G92; I, K and R are not.
TEST(LatheMode, DiameterAndRadius) {
  const auto m = moves_of(
      "G21 G18 G90\n"
      "G7 G0 X20 Z5\n"            // X 10
      "G1 X10 Z0 F100\n"          // X 5
      "G2 X20 Z-5 I5 K0\n"        // centre X 5 + 5 = 10 (I is a radius offset), Z 0
      "G91 G1 X4\nG90\n"          // X 10 + 2
      "G92 X10\nG1 X30\nG92.1\n"  // X 12 is 5 now; X 15 + 7
      "G8 G1 X30\n"               // a radius again
      "M2\n");
  ASSERT_EQ(m.size(), 6u);
  EXPECT_NEAR(m[0].end[0], 10, 1e-12);
  EXPECT_NEAR(m[1].end[0], 5, 1e-12);
  EXPECT_NEAR(m[2].end[0], 10, 1e-12);
  EXPECT_NEAR(m[2].center[0], 0, 1e-12);   // Z (the ZX plane's first axis)
  EXPECT_NEAR(m[2].center[1], 10, 1e-12);  // X
  EXPECT_NEAR(m[3].end[0], 12, 1e-12);
  EXPECT_NEAR(m[4].end[0], 22, 1e-12);
  EXPECT_NEAR(m[5].end[0], 30, 1e-12);
}

// G43 keeps the machine where it is (the program position moves by the offset); an M6 after it
// (on its line or later, before the next move) reads the position back as it was before the
// change, so the next move goes there with the new offset (LinuxCNC's rs274 does both).
TEST(ToolLengthOffset, MachineStaysUnlessAToolChangeFollows) {
  const auto dir = std::filesystem::temp_directory_path() / "fpgacnc_tlo_test";
  std::filesystem::create_directories(dir);
  const auto tbl = dir / "tools.tbl";
  std::ofstream(tbl) << "T3 P3 Z31.75 D10 ;10 mm end mill\n";
  gc::Options o;
  o.tool_table = tbl.string();
  o.tool_change_pause = false;
  auto m = moves_of("G21 G90 G0 X1 Z1\nG43 H3\nG0 X50\nM2\n", o);
  ASSERT_EQ(m.size(), 2u);
  expect_at(m[1], 50, 0, 1);
  m = moves_of("G21 G90 G0 X1 Z1\nT3 M6 G43 H3\nG0 X50\nM2\n", o);
  expect_at(m[1], 50, 0, 1 + 31.75);
  m = moves_of("G21 G90 G0 X1 Z1\nG43 H3\nT3 M6\nG0 X50\nM2\n", o);
  expect_at(m[1], 50, 0, 1 + 31.75);
  m = moves_of("G21 G90 G0 X1 Z1\nG43 H3\nG0 Z0\nM2\n", o);
  expect_at(m[1], 1, 0, 31.75);  // program Z0 with the offset
  std::filesystem::remove_all(dir);
}
