// Streaming G-code interpreter for the RS274/NGC subset fpgacnc accepts (see docs/system.md,
// "Host"). Input is read line by line; each line yields zero or more Commands in machine
// coordinates (mm, G92 offsets already applied).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "fpgacnc/gcode/interpreter_error.h"

namespace fpgacnc::gcode {

using Vec4 = std::array<double, 4>;  // X Y Z E in mm, machine coordinates

enum class Motion : uint8_t { kRapid = 0, kLinear = 1, kArcCw = 2, kArcCcw = 3 };

struct Move {
  Motion motion = Motion::kRapid;
  Vec4 start{};
  Vec4 end{};
  // Arcs only: centre (X, Y) in machine mm; start radius and end radius (equal for a true
  // circle; the planner blends them linearly otherwise); full_circle when end == start.
  std::array<double, 2> center{};
  bool full_circle = false;
  double feed_mm_min = 0.0;         // modal F (mm/min) in force; rapids carry it too
  bool spindle_on = false;          // M3/M4 active
  std::optional<double> spindle_s;  // last S word, if any
  int line = 0;
};

struct Dwell {
  double seconds = 0.0;
  int line = 0;
};

// M104/M109/M140/M190: recorded, not executed yet (heater support comes later).
struct Heater {
  int mcode = 0;
  std::optional<double> s;
  int line = 0;
};

using Command = std::variant<Move, Dwell, Heater>;

struct Options {
  double default_feed_mm_min = 1000.0;
};

struct Stats {
  uint64_t lines = 0;
  uint64_t moves = 0;
  uint64_t commands = 0;  // non-motion commands of any kind (modal changes, M codes, dwell)
  // Lines repeating a modal G2/G3 with axis words but no I/J/R: run as straight lines
  // (cutting, G1 semantics) as CNCjs and the files of its corpus expect.
  uint64_t modal_arc_as_line = 0;
  // I/J arcs whose end radius differs from the start radius by more than 0.005 mm and 0.1%
  // (up to 50%, beyond that an error): planned as a spiral that ends exactly at the end point.
  uint64_t arc_radius_mismatch = 0;
};

class Interpreter {
 public:
  explicit Interpreter(std::string file_name, Options options = {});

  // Parses one line (without the newline); appends produced commands to `out`.
  void parse_line(std::string_view text, int line_number, std::vector<Command>& out);
  // Call after the last line: throws "empty job" when nothing was produced at all.
  void finish();

  const Vec4& position() const { return pos_; }  // machine mm
  const Stats& stats() const { return stats_; }
  const std::string& file_name() const { return file_; }

 private:
  std::string file_;
  Options opt_;
  Stats stats_;
  Vec4 pos_{};              // machine mm
  Vec4 offset_{};           // G92 offset: machine = program + offset
  double unit_ = 1.0;       // 25.4 under G20
  bool absolute_ = true;    // G90
  bool e_absolute_ = true;  // M82
  std::optional<Motion> motion_;
  double feed_;  // mm/min
  bool spindle_on_ = false;
  std::optional<double> spindle_s_;
  bool produced_ = false;
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
