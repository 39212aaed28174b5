// The G-code interpreter: Blocks from the reader (reader.h) -> machine Commands in machine
// coordinates (mm; work offsets, G92 and tool length offsets applied), with the meanings of the
// program's dialect (dialect.h). What is accepted and why: docs/gcode.md.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "fpgacnc/gcode/block.h"
#include "fpgacnc/gcode/dialect.h"
#include "fpgacnc/gcode/interpreter_error.h"

namespace fpgacnc::gcode {

using Vec4 = std::array<double, 4>;  // X Y Z E in mm, machine coordinates

enum class Motion : uint8_t { kRapid = 0, kLinear = 1, kArcCw = 2, kArcCcw = 3 };

// Arc planes (G17/G18/G19). An arc's (u, v) are the plane's axes in right-handed order and w
// the third (helix) axis: XY -> (X, Y, Z), ZX -> (Z, X, Y), YZ -> (Y, Z, X).
enum class Plane : uint8_t { kXY = 0, kZX = 1, kYZ = 2 };
struct PlaneAxes {
  int u, v, w;  // indices into Vec4
};
constexpr PlaneAxes plane_axes(Plane p) {
  return p == Plane::kXY   ? PlaneAxes{0, 1, 2}
         : p == Plane::kZX ? PlaneAxes{2, 0, 1}
                           : PlaneAxes{1, 2, 0};
}

struct Move {
  Motion motion = Motion::kRapid;
  Vec4 start{};
  Vec4 end{};
  // Arcs only: the plane, the centre (u, v) in machine mm (plane_axes order), full_circle when
  // the end equals the start in the plane (one turn), extra_turns for LinuxCNC's G2/G3 P (P - 1).
  Plane plane = Plane::kXY;
  std::array<double, 2> center{};
  bool full_circle = false;
  int extra_turns = 0;
  double feed_mm_min = 0.0;         // feed in force (mm/min, after M220); rapids carry it too
  bool spindle_on = false;          // M3/M4 active
  std::optional<double> spindle_s;  // last S word, if any
  // Path control (G61 exact stop / G64 P tolerance): stop at the end of this move; the
  // tolerance (mm) the look-ahead may leave the path by at its end (0 = the machine's).
  bool exact_stop = false;
  double path_tolerance_mm = 0.0;
  int line = 0;
};

struct Dwell {
  double seconds = 0.0;
  int line = 0;
};

// M104/M109/M140/M190 (heaters; fpgacnc/heat).
struct Heater {
  int mcode = 0;
  std::optional<double> s;
  int line = 0;
};

// The job stops at rest until the operator resumes: M0/M1 (M1 only with optional stop on),
// M6 tool changes (with the configured tool_change = "pause"), Marlin's M600 filament change and,
// in the printer dialects, a slicer's T<n> for another filament (this machine has one extruder).
struct Pause {
  enum class Reason : uint8_t { kProgramPause, kOptionalStop, kToolChange, kFilamentChange };
  Reason reason = Reason::kProgramPause;
  int tool = 0;        // kToolChange: the tool to insert; kFilamentChange after T<n>: n
  std::string prompt;  // what the operator is asked to do
  int line = 0;
};

// Machine outputs in step with motion (FIFO entries between segments on protocol v2).
struct Output {
  // kLaserMode: the spindle / laser power mode, value 1 for M4 (dynamic power: scaled with the
  // actual speed), 0 for M3 (constant); emitted at the first M3 / M4 and where one changes it.
  enum class Kind : uint8_t { kFlood, kMist, kFan, kDigital, kLaserMode };
  Kind kind = Kind::kFlood;
  int index = 0;           // kDigital: output number (M62-M65 P); kFan: fan number (0)
  double value = 0.0;      // 0/1 for switches; fan duty 0..1
  bool immediate = false;  // M64/M65 (else M62/M63: with the next motion)
  int line = 0;
};

// Operator messages and progress: M117/M118, (MSG,...), M73 P (percent).
struct Message {
  enum class Kind : uint8_t { kDisplay, kEcho, kProgress, kDebug };
  Kind kind = Kind::kDisplay;
  std::string text;
  double percent = -1.0;  // kProgress
  int line = 0;
};

// Job limits for the rest of the job (M201/M203/M204/M205): 0 = unchanged. The planner never
// lets them exceed the machine's configured limits.
struct Limits {
  std::array<double, 4> accel_mm_s2{};      // M201 per axis
  std::array<double, 4> max_feed_mm_min{};  // M203 per axis (Marlin gives mm/s: converted)
  double path_accel_mm_s2 = 0.0;            // M204 P/S (printing) / T (travel: ignored)
  double junction_deviation_mm = 0.0;       // M205 J
  int line = 0;
};

// G38.2 .. G38.5 (grbl, LinuxCNC; only with Options::probing): a straight move at the feed in
// force toward `move.end` that the board ends at the probe's contact (G38.2 / G38.3) or release
// (G38.4 / G38.5). A front end runs it with link::ProbeCycle; where the machine stops is the
// board's (docs/machine.md "Homing and probing (host)"), so the front end moves the interpreter
// there afterwards.
struct Probe {
  Move move;       // motion kLinear, start and end in machine mm, feed
  int code = 382;  // 382 .. 385: G38.2 .. G38.5
  int line = 0;
  bool toward() const { return code == 382 || code == 383; }  // contact (else release)
  bool error_on_miss() const { return code == 382 || code == 384; }
};

using Command = std::variant<Move, Dwell, Heater, Pause, Output, Message, Limits, Probe>;

struct Options {
  double default_feed_mm_min = 1000.0;
  std::optional<Dialect> dialect;            // override of the detection
  std::string dialect_source = "--dialect";  // where the override came from, for the report
  std::string tool_table;         // LinuxCNC tool table file ("" = none: G43 H needs one)
  bool tool_change_pause = true;  // M6 pauses with a prompt (false: T/M6 only recorded)
  // The fourth axis: 'E' (the extruder; A, B, C words are refused) or 'A' (a rotary axis in
  // degrees: A words move it, E words are refused; Move::end[3] is then A in degrees).
  char fourth_axis = 'E';
  bool optional_stop = false;  // M1 pauses (LinuxCNC's optional stop switch)
  bool block_delete = false;   // lines starting with '/' are skipped
  // Firmware retraction defaults (G10/G11; M207/M208 change them), mm and mm/min.
  double retract_mm = 1.0;
  double retract_feed_mm_min = 2100.0;
  double retract_zlift_mm = 0.0;
  double recover_extra_mm = 0.0;
  double recover_feed_mm_min = 2100.0;
  // Splines (G5, G5.1) run as straight pieces within this distance of the curve (mm): the
  // machine's arc_tolerance_mm.
  double arc_tolerance_mm = 0.01;
  // G38.2 .. G38.5 give Probe commands (a front end that runs the probing cycle: fpgacnc grbl);
  // else they are refused with their line (a streamed job cannot know where a probe stops).
  bool probing = false;
};

// A warning kept in the statistics: once per kind, with its count and first line.
struct Warning {
  std::string what;  // e.g. "M900 (linear advance) ignored"
  int first_line = 0;
  uint64_t count = 0;
};

struct Stats {
  uint64_t lines = 0;  // blocks executed (a loop body counts once per pass)
  uint64_t moves = 0;
  uint64_t commands = 0;  // non-motion commands of any kind (modal changes, M codes, dwell)
  // Lines repeating a modal G2/G3 with axis words but no I/J/R: run as straight lines
  // (cutting, G1 semantics) as CNCjs and the files of its corpus expect.
  uint64_t modal_arc_as_line = 0;
  // I/J arcs whose end radius differs from the start radius by more than 0.005 mm and 0.1%
  // (up to 50%, beyond that an error): planned as a spiral that ends exactly at the end point.
  uint64_t arc_radius_mismatch = 0;
  uint64_t canned_cycles = 0;  // holes drilled by G73/G81..G89
  uint64_t tool_changes = 0;
  uint64_t pauses = 0;
  uint64_t outputs = 0;
  std::string dialect;         // "grbl", "linuxcnc", ...
  std::string dialect_reason;  // why that dialect
  std::string generator;       // the program named in the file's header, if any
  std::vector<Warning> warnings;
};

class Params;

// Executes Blocks one at a time (the parse_* functions below drive it from a Reader; a line
// front end such as a grbl server can drive it directly).
class Interpreter {
 public:
  // `params` is the rs274ngc parameter table the reader evaluates against: the interpreter
  // writes the system parameters (positions, offsets, tool) into it as its state changes.
  Interpreter(std::string file_name, Options options, const DialectChoice& dialect, Params& params);
  ~Interpreter();
  Interpreter(const Interpreter&) = delete;
  Interpreter& operator=(const Interpreter&) = delete;

  // Executes one block; appends the commands it produces to `out`. Returns false when the block
  // ends the program (M2/M30).
  bool execute(const Block& block, std::vector<Command>& out);
  // Call after the last block when the program did not end with M2/M30: appends the moves
  // cutter radius compensation still holds back (each waits for the next move).
  void flush(std::vector<Command>& out);
  // Call after the last block: throws "empty job" when nothing was produced at all.
  void finish();

  const Vec4& position() const;  // machine mm
  const Stats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct Program {
  std::vector<Command> commands;
  Stats stats;
  std::string file_name;
};

// Reads the whole stream / file / string. Throws Error.
Program parse_stream(std::istream& in, const std::string& file_name, Options options = {});
Program parse_file(const std::string& path, Options options = {});
Program parse_string(std::string_view text, const std::string& file_name = "<string>",
                     Options options = {});

// Streaming form: calls `sink` for each command as lines are parsed.
Stats parse_stream(std::istream& in, const std::string& file_name, Options options,
                   const std::function<void(const Command&)>& sink);

}  // namespace fpgacnc::gcode
