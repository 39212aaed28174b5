// Cutter radius compensation (G41/G42, G41.1/G42.1, G40) as LinuxCNC defines it: the tool's
// centre runs at the tool radius beside the programmed path, in the active plane (XY or XZ).
// Moves arrive programmed (the interpreter's Move, machine mm); the offset path leaves, one
// move late: a move's end depends on the next move (an inside corner moves it to where the
// two offset paths cross; an outside corner adds an arc around the programmed corner).
// What is accepted and refused: docs/gcode.md, "Cutter radius compensation".
#pragma once

#include <stdexcept>
#include <vector>

#include "fpgacnc/gcode/interpreter.h"

namespace fpgacnc::gcode {

class CutterComp {
 public:
  enum class Side { kLeft, kRight };
  // A program the compensation cannot run; the interpreter adds file:line:column.
  struct Error : std::runtime_error {
    using std::runtime_error::runtime_error;
  };

  // True while anything is held back or the exit move is still to come: the interpreter sends
  // every command through process() then, and skips this class otherwise.
  bool engaged() const { return on_ || exiting_ || !queue_.empty(); }
  bool on() const { return on_; }

  // G41/G42 at the tool position `pos` (machine mm). A negative radius swaps the side.
  void start(Side side, double radius, Plane plane, const Vec4& pos);
  // G40: emits what is held back; the next move runs from the offset point to its programmed
  // end (a straight line).
  void stop(std::vector<Command>& out, int line);
  // The commands of one block, in order, with moves as programmed; appends what the machine
  // runs to `out` (moves may wait for the next move that leaves the plane's current point).
  void process(std::vector<Command>& cmds, std::vector<Command>& out, int line);
  // Emits everything held back (end of program).
  void flush(std::vector<Command>& out, int line);

 private:
  struct P2 {
    double x = 0, y = 0;
  };
  // A move's path in the plane as programmed: a line a->b, or an arc about c (dir +1 CCW, -1 CW).
  struct Seg {
    bool arc = false;
    P2 a, b, c;
    double radius = 0;      // arcs: programmed radius at the start
    double radius_end = 0;  // and at the end (they differ by the file's rounding)
    double sweep = 0;       // the angle it turns through, (0, 2 pi]
    int dir = 1;
    bool tool_path = false;  // c and radius are the tool's path already (an entry arc)
  };
  void move(Move mv, std::vector<Command>& out, int line);
  P2 uv(const Vec4& p) const;
  void set_uv(Vec4& p, P2 q) const;
  P2 tangent(const Seg& s, P2 at) const;
  // Arcs: the radius of the offset path, reckoned from the start's or the end's radius.
  double offset_radius(const Seg& s, bool at_end = false) const;
  P2 offset_point(const Seg& s, P2 at) const;
  bool intersect(const Seg& s0, const Seg& s1, P2& hit) const;
  void move_pending_end(P2 hit);
  static double sweep_of(P2 c, P2 a, P2 b, int dir);

  bool on_ = false;
  bool exiting_ = false;
  bool entry_ = false;  // the next move in the plane is the entry move
  int sign_ = 1;        // +1 left of the path, -1 right
  double r_ = 0;
  Plane plane_ = Plane::kXY;
  int u_ = 0, v_ = 1;           // the plane's axes (plane_axes)
  Vec4 cur_{};                  // where the tool is after everything in queue_
  std::vector<Command> queue_;  // [0]: the move in the plane whose end is not known yet
  Seg pending_;                 // its programmed path
  bool pending_entry_ = false;  // it is the entry move (its end may move anywhere)
};

}  // namespace fpgacnc::gcode
