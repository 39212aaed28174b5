// LinuxCNC's standalone interpreter `rs274` as a test oracle (docs/oracle.md): run it on a file
// as a child process and turn its canonical machine commands into moves in machine mm.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fpgacnc::oracle {

using Xyz = std::array<double, 3>;

enum class Plane { kXY, kYZ, kXZ };

struct CanonMove {
  enum class Kind { kTraverse, kFeed, kArc, kSpline, kOther };
  Kind kind = Kind::kTraverse;
  std::string name;  // canonical command, e.g. STRAIGHT_TRAVERSE, ARC_FEED, STRAIGHT_PROBE
  Xyz end{};         // machine mm: work offset, G92 offset, XY rotation and tool length applied
  Xyz centre{};      // arcs: centre in machine mm (the axis of the plane holds the start's value)
  Plane plane = Plane::kXY;
  int rotation = 0;  // arcs: > 0 counter-clockwise (G3), < 0 clockwise (G2); |rotation| turns
  int line = 0;      // source line of the block that produced it (1-based)
  std::string text;  // the printed command
  // kSpline (NURBS_FEED as the precision library prints it): the control points in machine mm
  // (Z of the position before) and their weights; the curve is the rational Bezier curve of
  // those points (rs274 gives G5 four points, G5.1 three, with the order equal to the count).
  std::vector<Xyz> control;
  std::vector<double> weights;
};

struct CanonDwell {
  double seconds = 0.0;
  int line = 0;
};

struct OracleRun {
  bool refused = false;
  std::string message;             // rs274's error (its stderr without the "executing" line)
  bool ended_without_end = false;  // "File ended with no percent sign or program end" only
  std::vector<CanonMove> moves;
  std::vector<CanonDwell> dwells;
  std::string out;  // stdout as printed
};

// Parses rs274's stdout as printed through the precision library (rs274_shim.c): each line is
// "<counter> L<line> N<number or .....> NAME(args)". Lengths are converted with the units of the
// last USE_LENGTH_UNITS and offsets are tracked (SET_G5X_OFFSET, SET_G92_OFFSET,
// SET_XY_ROTATION, USE_TOOL_LENGTH_OFFSET). Throws std::runtime_error on a line it cannot read.
void parse_canon(std::string_view out, OracleRun& run);

struct Rs274Setup {
  std::string rs274;            // path of the rs274 executable
  std::string shim;             // path of the precision library (LD_PRELOAD)
  std::string tool_mm;          // LinuxCNC tool table, lengths in mm (converted to rs274's inches)
  double wall_limit_s = 120.0;  // hang guard only (generous; a verdict never depends on it)
};

// Finds rs274: $FPGACNC_RS274, else `rs274` on PATH, else /usr/bin/rs274; nullopt if none.
std::optional<std::string> find_rs274();

// Runs rs274 on `program` in a fresh temporary directory (empty parameter file, the tool table
// in inches) and parses what it printed. Throws std::runtime_error when rs274 cannot be run,
// hangs past the wall limit, dies on a signal, or prints what the parser cannot read.
OracleRun run_rs274(const Rs274Setup& setup, const std::string& program);

}  // namespace fpgacnc::oracle
