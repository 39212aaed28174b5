// Planner: interpreter moves -> v1 segments (straight moves in integer steps).
// mm -> steps rounds the ABSOLUTE target (std::llround(mm * steps_per_mm)) so rounding never
// accumulates; arcs are cut into chords whose sagitta is within the arc tolerance; a move longer
// than a v1 packet can carry (|steps| > INT32_MAX) is split into equal parts, never clamped.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include <optional>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/error.h"
#include "fpgacnc/gcode/interpreter.h"

namespace fpgacnc::plan {

using Steps4 = std::array<int64_t, 4>;  // X Y Z E

struct Segment {
  // 0 rapid / laser off, 1 G1, 2 G2 chord, 3 G3 chord. A non-cutting G1/G2/G3 (laser off)
  // is code 0 but keeps its programmed feed.
  uint8_t code = 0;
  // G0. Protocol v2 frames carry the motion code apart from the laser power: a non-cutting
  // G1/G2/G3 goes as code 1 with power 0, so the device runs it at its feed rate, a G0 as code 0
  // at its rapid rate (docs/protocol.md "MOTION").
  bool rapid = false;
  Steps4 steps{};            // relative steps of this segment
  uint16_t feed_v1 = 1;      // dominant axis feed, mm/min, in [1, 65535]
  double length_mm = 0.0;    // XYZ path length of the segment
  double feed_mm_min = 0.0;  // commanded path feed (rapid feed for rapids)
  // Path feed the move is executed at: after the feed override and the axis max feeds (0 for
  // a step-file segment: v1 timing from feed_v1). Protocol v2 derives the segment time from it.
  double exec_feed_mm_min = 0.0;
  double spindle_s = -1.0;  // S word in force (laser power for v2), negative when none given
  int source_line = 0;      // G-code (or step file) line
  Steps4 target{};          // absolute position in steps after the segment
  uint32_t arc_id = 0;      // chord of Plan::arcs[arc_id - 1] (0: not an arc chord)
  // Job limits in force (M201/M204/M205, G61/G64; 0 = the machine's): the look-ahead takes the
  // smaller of these and the machine's limits.
  std::array<double, 4> accel_mm_s2{};  // per axis
  double path_accel_mm_s2 = 0.0;
  double junction_deviation_mm = 0.0;
  bool exact_stop = false;  // G61: stop at the end of this segment
};

struct Dwell {
  double seconds = 0.0;
  int source_line = 0;
};

// M104/M109/M140/M190, carried for a future heater-capable protocol; the v1 packer skips them.
struct HeaterCommand {
  int mcode = 0;
  double s = 0.0;
  bool has_s = false;
  int source_line = 0;
};

// Pauses (M0/M1, M6, M600), outputs (M7-M9, M62-M65, M106/M107) and messages (M117, M118,
// M73, (MSG,...)) keep their place between the segments.
using PlanItem =
    std::variant<Segment, Dwell, HeaterCommand, gcode::Pause, gcode::Output, gcode::Message>;

struct Stats {
  uint64_t segments = 0;
  uint64_t rapid_segments = 0;    // code 0
  uint64_t cutting_segments = 0;  // code 1..3
  uint64_t arc_chords = 0;
  uint64_t dwells = 0;
  uint64_t heater_commands = 0;  // recorded, not sent by v1
  uint64_t pauses = 0;
  uint64_t outputs = 0;
  uint64_t messages = 0;
  uint64_t limits_clamped = 0;  // M201/M203/M204/M205 values above the machine's (lowered)
  uint64_t feed_clamped = 0;    // v1 feed outside [1, 65535] (warning)
  uint64_t feed_limited = 0;    // feed reduced to respect an axis max feed (warning)
  uint64_t split_moves = 0;     // moves split because |steps| > INT32_MAX
  uint64_t ze_only_moves = 0;   // Z/E-only moves not driven by v1 (sent as 0,0 steps)
  double path_length_mm = 0.0;
  double estimated_time_s = 0.0;  // sum of length / feed plus dwells (no acceleration)
};

struct Plan {
  std::vector<PlanItem> items;
  Stats stats;
  std::array<uint32_t, 2> numerator{18'750'000, 18'750'000};  // v1 init packet (X, Y)
  Steps4 final_steps{};
  std::array<double, 4> final_mm{};
  char fourth_axis = 'E';  // the name of axis 4 (the configuration's fourth_axis; A in degrees)
  // G2/G3 moves as programmed (machine mm), for packers that send arcs natively; their chords
  // carry Segment::arc_id = index + 1.
  std::vector<gcode::Move> arcs;
  std::string source;  // input file name
  gcode::Stats input;  // interpreter statistics (empty for a step file)
};

struct PlanOptions {
  double feed_override_pct = 100.0;  // applies to feeds, not to rapids
};

// v1 init numerator for one axis: clk_hz * 60 / steps_per_mm (integer). Throws if it does not fit.
uint32_t v1_numerator(uint64_t clk_hz, double steps_per_mm);

// Points on an arc cut into chords: chord end points in mm (the last is exactly move.end).
std::vector<gcode::Vec4> arc_chord_points(const gcode::Move& move, double tolerance_mm);

// Soft limits (config::Travel): where a move first leaves the travel. What is checked: a straight
// move's end (the travel is a box, so a move that starts inside stays inside up to its end); an
// arc's end and every point where it crosses one of its plane's four axis directions (its extent
// in the plane: first and last crossing of each direction, so a spiral's largest radius is seen),
// and its linear axes at their end. Positions compare in steps (llround(mm * steps_per_mm)), the
// units the device's own check uses, so the host never sends what the device would refuse.
struct TravelViolation {
  int axis = 0;            // config::Axis
  bool above_max = false;  // true: beyond max_mm; false: below min_mm
  bool in_arc = false;     // the point is inside an arc, not its end
  double value_mm = 0.0;   // where the move gets to on that axis
  double limit_mm = 0.0;   // the limit it passes
};
std::optional<TravelViolation> check_travel(const gcode::Move& move,
                                            const config::MachineConfig& cfg);
// The same test for a position in steps (a step file's segment end).
std::optional<TravelViolation> check_travel_steps(const Steps4& position,
                                                  const config::MachineConfig& cfg);
// "X reaches 312.500 mm, 12.500 mm beyond its max 300.000 mm" (the arc's extent said so).
std::string describe(const TravelViolation& v, char fourth_axis = 'E');

// A move that leaves the travel: what() reads "FILE:LINE: error: move leaves the travel: ...".
class TravelError : public SourceError {
 public:
  TravelError(std::string file, int line, TravelViolation v, std::string message)
      : SourceError(std::move(file), line, 0, std::move(message)), violation_(v) {}
  const TravelViolation& violation() const { return violation_; }

 private:
  TravelViolation violation_;
};

class Planner {
 public:
  // `source` names the input in errors (TravelError: "source:line").
  Planner(const config::MachineConfig& cfg, PlanOptions options, std::string source = {});
  void add(const gcode::Command& command);
  Plan finish();  // moves the plan out
  // The items added so far, moved out; the planner goes on from the same position (a line
  // front end such as `fpgacnc grbl` plans as lines arrive).
  std::vector<PlanItem> take_items();
  const Steps4& position() const { return pos_; }  // absolute steps after the last item
  // The feed override for the moves added from now on (PlanOptions::feed_override_pct; a front
  // end's real-time override above 100 %, fpgacnc grbl).
  void set_feed_override(double pct) { opt_.feed_override_pct = pct; }

 private:
  void add_move(const gcode::Move& m);
  void add_straight(const gcode::Vec4& target_mm, uint8_t code, double feed, bool rapid, int line,
                    double spindle_s);
  void add_limits(const gcode::Limits& l);
  config::MachineConfig cfg_;
  PlanOptions opt_;
  std::string source_;
  // Job limits in force (0 = the machine's).
  std::array<double, 4> job_max_feed_{};
  std::array<double, 4> job_accel_{};
  double job_path_accel_ = 0.0;
  double job_jd_ = 0.0;
  const gcode::Move* move_ = nullptr;  // the move being added
  bool last_piece_ = true;             // its last chord (G61 stops there only)
  Plan plan_;
  Steps4 pos_{};         // absolute steps
  uint32_t arc_id_ = 0;  // arc whose chords are being added
};

// The interpreter's options from the machine configuration ([gcode] and default feed).
gcode::Options gcode_options(const config::MachineConfig& cfg);

Plan plan_program(const gcode::Program& program, const config::MachineConfig& cfg,
                  PlanOptions options);
// Parses and plans a G-code file in one streaming pass (no intermediate command list).
Plan plan_gcode_file(const std::string& path, const config::MachineConfig& cfg,
                     PlanOptions options);
// G-code file or step-file CSV (by extension .csv or by a CSV header in the first line).
Plan plan_input_file(const std::string& path, const config::MachineConfig& cfg,
                     PlanOptions options);

}  // namespace fpgacnc::plan
