#include "fpgacnc/gcode/interpreter.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include "cutter_comp.h"
#include "fpgacnc/gcode/reader.h"
#include "fpgacnc/gcode/tool_table.h"

namespace fpgacnc {

SourceError::SourceError(std::string file, int line, int column, std::string message)
    : std::runtime_error(
          line > 0 ? (column > 0 ? fmt::format("{}:{}:{}: error: {}", file, line, column, message)
                                 : fmt::format("{}:{}: error: {}", file, line, message))
                   : fmt::format("{}: error: {}", file, message)),
      file_(std::move(file)),
      line_(line),
      column_(column),
      message_(std::move(message)) {}

}  // namespace fpgacnc

namespace fpgacnc::gcode {
namespace {

constexpr double kMaxValue = 1e6;  // |value| limit for every word (mm, s) but F
// F may ask for more than any machine has (LinuxCNC's 3D_Chips.ngc programs 2 250 000 mm/min to
// mean "as fast as the machine goes"): the planner lowers it to the axes' limits.
constexpr double kMaxFeed = 1e12;
constexpr int kCoordSystems = 9;  // G54 .. G59.3
constexpr double kInch = 25.4;

// G and M codes are compared as ten times their value (G91.1 -> 911).
int code10(const Word& w) {
  return static_cast<int>(std::lround(w.value * 10.0));
}

bool is_code10_exact(const Word& w) {
  return std::fabs(w.value * 10.0 - std::round(w.value * 10.0)) < 1e-6;
}

std::string gname(int c10) {
  return c10 % 10 ? fmt::format("G{}.{}", c10 / 10, c10 % 10) : fmt::format("G{}", c10 / 10);
}

// Motion modes: the four moves and the canned cycles (G-code times ten; 800 = G80, none).
constexpr int kCycleNone = 800;
bool is_cycle(int m) {
  return m == 730 || (m >= 810 && m <= 890);
}

// Modal groups of G codes (rs274ngc table), for "two codes of one group" errors.
int g_group(int c10) {
  switch (c10) {
    case 0:
    case 10:
    case 20:
    case 30:
    case 380:
    case 382:
    case 383:
    case 384:
    case 385:
    case 730:
    case 800:
    case 810:
    case 820:
    case 830:
    case 840:
    case 850:
    case 860:
    case 870:
    case 880:
    case 890:
    case 330:
    case 50:
    case 51:
    case 52:
    case 53:
      return 1;
    case 170:
    case 180:
    case 190:
      return 2;
    case 900:
    case 910:
      return 3;
    case 901:
    case 911:
      return 4;
    case 930:
    case 940:
    case 950:
      return 5;
    case 200:
    case 210:
      return 6;
    case 400:
    case 410:
    case 411:
    case 420:
    case 421:
      return 7;
    case 70:
    case 80:
      return 11;  // lathe diameter / radius mode (LinuxCNC's group 15)
    case 430:
    case 431:
    case 432:
    case 490:
      return 8;
    case 980:
    case 990:
      return 10;
    case 540:
    case 550:
    case 560:
    case 570:
    case 580:
    case 590:
    case 591:
    case 592:
    case 593:
      return 12;
    case 610:
    case 611:
    case 640:
      return 13;
    case 690:
      return 14;  // rotation cancel: nothing is ever rotated here
    case 40:
    case 100:
    case 110:
    case 280:
    case 281:
    case 300:
    case 301:
    case 530:
    case 920:
    case 921:
    case 922:
    case 923:
      return 0;
    default:
      return -1;
  }
}

// Known M codes that change nothing here, per dialect family; each is a warning once.
struct Ignored {
  int code;
  const char* what;
};
constexpr Ignored kPrinterIgnored[] = {
    {17, "M17 (motors on)"},
    {105, "M105 (report temperatures)"},
    {108, "M108 (break and continue)"},
    {110, "M110 (set line number)"},
    {113, "M113 (host keepalive)"},
    {114, "M114 (report position)"},
    {115, "M115 (firmware info)"},
    {119, "M119 (endstop states)"},
    {141, "M141 (chamber temperature: no chamber heater)"},
    {191, "M191 (wait for chamber temperature: no chamber heater)"},
    {155, "M155 (temperature auto-report)"},
    {280, "M280 (servo)"},
    {300, "M300 (beep)"},
    {420, "M420 (bed levelling state)"},
    {486, "M486 (object cancel labels)"},
    {500, "M500 (save settings)"},
    {501, "M501 (restore settings)"},
    {502, "M502 (factory settings)"},
    {503, "M503 (report settings)"},
    {851, "M851 (probe offset)"},
    {900, "M900 (linear advance)"},
    {103, "M103 (extruder off, old RepRap)"},
    {101, "M101 (extruder on, old RepRap)"},
};

const char* printer_ignored(int code) {
  for (const auto& i : kPrinterIgnored)
    if (i.code == code) return i.what;
  return nullptr;
}

// A spline's control points (machine mm, XY): 3 (G5.1, quadratic) or 4 (G5, cubic Bezier).
struct SplinePoints {
  int n = 0;
  std::array<std::array<double, 2>, 4> p{};
};

std::array<double, 2> spline_at(const SplinePoints& c, double t) {
  const double s = 1.0 - t;
  std::array<double, 2> r{};
  for (size_t a = 0; a < 2; ++a)
    r[a] = c.n == 3 ? s * s * c.p[0][a] + 2 * s * t * c.p[1][a] + t * t * c.p[2][a]
                    : s * s * s * c.p[0][a] + 3 * s * s * t * c.p[1][a] +
                          3 * s * t * t * c.p[2][a] + t * t * t * c.p[3][a];
  return r;
}

// The points of straight pieces within `tolerance` of the curve: a chord over a parameter step h
// is within h^2 / 8 * max|C''| of the curve, and |C''| is at most 2 |P0 - 2 P1 + P2| (quadratic)
// or 6 max(|P0 - 2 P1 + P2|, |P1 - 2 P2 + P3|) (cubic). The first point is the start, the last
// exactly the end.
std::vector<std::array<double, 2>> spline_pieces(const SplinePoints& c, double tolerance) {
  auto second = [&](size_t k) {
    return std::hypot(c.p[k][0] - 2 * c.p[k + 1][0] + c.p[k + 2][0],
                      c.p[k][1] - 2 * c.p[k + 1][1] + c.p[k + 2][1]);
  };
  const double curv = c.n == 3 ? 2 * second(0) : 6 * std::max(second(0), second(1));
  const double n_real = std::ceil(std::sqrt(curv / (8.0 * std::max(tolerance, 1e-6))));
  const int n = static_cast<int>(std::clamp(n_real, 1.0, 1e6));
  std::vector<std::array<double, 2>> pts;
  pts.reserve(static_cast<size_t>(n) + 1);
  pts.push_back(c.p[0]);
  for (int k = 1; k < n; ++k) pts.push_back(spline_at(c, static_cast<double>(k) / n));
  pts.push_back(c.p[static_cast<size_t>(c.n - 1)]);
  return pts;
}

}  // namespace

struct Interpreter::Impl {
  std::string file;
  Options opt;
  const DialectRules* rules;
  // The fourth step channel: the extruder E (mm, M82/M83, M221) or a rotary A axis (degrees,
  // G90/G91, work offsets like X Y Z, never scaled by G20).
  bool rotary;
  std::array<char, 4> axis_names;
  int offset_axes;  // axes with work offsets, G28/G30 positions and parameters: 3, or 4 with A
  Params* params;
  Stats stats;
  ToolTable tools;

  Vec4 pos{};           // machine mm (E: the extruder's real position, after M221)
  double e_prog = 0.0;  // E as programmed (machine frame, before M221 flow)
  std::array<Vec4, kCoordSystems> g5x{};
  int cs = 0;  // 0 = G54
  Vec4 g92{};
  Vec4 g92_saved{};  // parameters 5211-5213 (G92.2 clears the offsets, G92.3 restores them)
  Vec4 tlo{};        // tool length offset
  Vec4 pos_tlo{};    // the tool length offset the program position is reckoned with
  Vec4 move_tlo{};   // the tool length offset of the last move
  bool tool_changed = false;  // M6 in this block
  double unit = 1.0;
  bool absolute = true;
  bool arc_absolute = false;  // G90.1
  bool e_absolute = true;     // M82
  int motion = -1;            // G code times ten; -1: none yet
  Plane plane = Plane::kXY;
  bool inverse_time = false;  // G93
  double feed;                // mm/min as programmed
  bool feed_given = false;
  double feed_factor = 1.0;  // M220
  double flow = 1.0;         // M221
  bool spindle_on = false;
  std::optional<bool> laser_m4;  // the last M3 / M4 was M4 (unset before the first one)
  std::optional<double> spindle_s;
  int tool = 0;
  int next_tool = 0;
  int filament = 0;  // printer dialects: the filament (slicer's T) loaded in the one extruder
  bool exact_stop = false;
  double tolerance = 0.0;
  bool retract_to_r = false;  // G99 (else G98)
  double cycle_z = 0.0, cycle_r = 0.0, cycle_p = 0.0, cycle_q = 0.0;
  bool cycle_z_set = false, cycle_r_set = false;
  double cycle_il = 0.0;  // initial level of a series of cycle blocks (G98 returns there)
  bool cycle_il_set = false;
  bool cycle_positioned = false;  // the series' first positioning move is done
  Vec4 g28_home{}, g30_home{};
  double retract_mm, retract_feed, retract_zlift, recover_extra, recover_feed;
  bool retracted = false;
  bool produced = false;
  std::map<std::string, size_t> warning_index;
  bool diameter_mode = false;              // G7: X words are diameters
  bool mist = false, flood = false;        // M7 / M8 (M9 both off)
  std::array<double, 2> spline_last_pq{};  // the last G5's P, Q (mm)
  // M70-M73: the modal state saved at a call depth (call_depth), deepest last. Leaving a
  // depth (a subroutine's return) drops its state, restoring it first when M73 saved it.
  struct ModalState {
    double unit;
    Plane plane;
    bool absolute, arc_absolute, inverse_time, retract_to_r, exact_stop, diameter_mode;
    int cs;
    Vec4 tlo;
    double tolerance, feed;
    std::optional<double> spindle_s;
    bool spindle_on, mist, flood, comp_on;
    CutterComp::Side comp_side;
    double comp_radius;
  };
  struct SavedState {
    int depth;
    bool autorestore;  // M73
    ModalState st;
  };
  std::vector<SavedState> saved;
  int leave_below = -1;  // the depth of saved.back() (-1: none): a return below it leaves it
  int call_depth = 0;    // subroutine calls in progress (BlockKind::kCall / kReturn blocks)
  // Cutter radius compensation: a G40/G41/G42 of the block being executed takes effect from
  // the block's command comp_at on (compensate()).
  CutterComp comp;
  enum class CompEvent : uint8_t { kNone, kOn, kOff };
  CompEvent comp_event = CompEvent::kNone;
  size_t comp_at = 0;
  CutterComp::Side comp_side = CutterComp::Side::kLeft;
  double comp_radius = 0.0;
  Vec4 comp_pos{};
  int move_col = 1;  // column of the block's motion, for compensation errors
  int last_line = 0;
  bool comp_on() const {
    return comp_event == CompEvent::kOn || (comp_event == CompEvent::kNone && comp.on());
  }

  Impl(std::string f, Options o, const DialectChoice& d, Params& p)
      : file(std::move(f)),
        opt(std::move(o)),
        rules(&dialect_rules(d.dialect)),
        rotary(opt.fourth_axis == 'A'),
        axis_names{'X', 'Y', 'Z', rotary ? 'A' : 'E'},
        offset_axes(rotary ? 4 : 3),
        params(&p),
        feed(opt.default_feed_mm_min),
        retract_mm(opt.retract_mm),
        retract_feed(opt.retract_feed_mm_min),
        retract_zlift(opt.retract_zlift_mm),
        recover_extra(opt.recover_extra_mm),
        recover_feed(opt.recover_feed_mm_min) {
    stats.dialect = rules->name;
    stats.dialect_reason = d.reason;
    stats.generator = d.generator;
    if (!opt.tool_table.empty()) tools = load_tool_table(opt.tool_table);
    write_params();
  }

  void warn(const std::string& what, int line) {
    auto [it, fresh] = warning_index.try_emplace(what, stats.warnings.size());
    if (fresh) stats.warnings.push_back(Warning{what, line, 0});
    ++stats.warnings[it->second].count;
  }

  // machine = program + offset(a) on X Y Z.
  double offset(int a) const {
    const auto i = static_cast<size_t>(a);
    return g5x[static_cast<size_t>(cs)][i] + g92[i] + tlo[i];
  }

  // Program units per machine unit of an axis: degrees of A are never scaled by G20.
  double unit_of(int a) const { return rotary && a == 3 ? 1.0 : unit; }

  // rs274ngc system parameters (LinuxCNC numbering) that programs read, in program units.
  void write_params() {
    Params& p = *params;
    for (int a = 0; a < offset_axes; ++a) {
      const auto i = static_cast<size_t>(a);
      p.set(5420 + a, (pos[i] - offset(a)) / unit_of(a));
      p.set(5211 + a, g92_saved[i] / unit_of(a));
      p.set(5161 + a, g28_home[i] / unit_of(a));
      p.set(5181 + a, g30_home[i] / unit_of(a));
    }
    p.set(5210,
          std::any_of(g92.begin(), g92.begin() + offset_axes, [](double v) { return v != 0.0; }));
    p.set(5220, cs + 1);
    for (int s = 0; s < kCoordSystems; ++s)
      for (int a = 0; a < offset_axes; ++a)
        p.set(5221 + 20 * s + a, g5x[static_cast<size_t>(s)][static_cast<size_t>(a)] / unit_of(a));
    p.set(5400, tool);
    p.set(5403, tlo[2] / unit);
    if (rules->syntax.ngc) write_named();
  }
  void write_position() {
    for (int a = 0; a < offset_axes; ++a)
      params->set(5420 + a, (pos[static_cast<size_t>(a)] - offset(a)) / unit_of(a));
  }
  // LinuxCNC's read-only named parameters that programs test (#<_x>, #<_metric>, #<_task>...).
  void write_named() {
    Params& p = *params;
    static constexpr const char* kXyza[4] = {"_x", "_y", "_z", "_a"};
    for (int a = 0; a < offset_axes; ++a)
      p.set_named(kXyza[a], (pos[static_cast<size_t>(a)] - offset(a)) / unit_of(a));
    p.set_named("_metric", unit == 1.0);
    p.set_named("_imperial", unit != 1.0);
    p.set_named("_absolute", absolute);
    p.set_named("_incremental", !absolute);
    p.set_named("_feed", feed / unit);
    p.set_named("_rpm", spindle_s.value_or(0.0));
    p.set_named("_current_tool", tool);
    p.set_named("_selected_tool", next_tool);
    p.set_named("_plane", plane == Plane::kXY ? 170 : plane == Plane::kZX ? 180 : 190);
    p.set_named("_coord_system", cs < 6 ? 540 + 10 * cs : 590 + (cs - 5));
    p.set_named("_motion_mode", motion < 0 ? 800 : motion);
    p.set_named("_task", 1);  // running a job, not a preview
  }

  Error fail(const Block& b, int col, const std::string& msg) const {
    return Error(file, b.line, col, msg);
  }

  Move make_move(Motion m, const Vec4& end, int line, double feed_mm_min) const {
    Move mv;
    mv.motion = m;
    mv.start = pos;
    mv.end = end;
    mv.feed_mm_min = feed_mm_min;
    mv.spindle_on = spindle_on;
    mv.spindle_s = spindle_s;
    mv.exact_stop = exact_stop;
    mv.path_tolerance_mm = tolerance;
    mv.plane = plane;
    mv.line = line;
    return mv;
  }
  void push(std::vector<Command>& out, const Move& mv) {
    pos = mv.end;
    pos_tlo = tlo;
    move_tlo = tlo;
    out.emplace_back(mv);
    ++stats.moves;
    produced = true;
  }
  void line_to(std::vector<Command>& out, Motion m, const Vec4& end, int line,
               double feed_mm_min = -1.0) {
    push(out, make_move(m, end, line, feed_mm_min > 0 ? feed_mm_min : feed * feed_factor));
  }

  ModalState modal_state() const {
    return ModalState{unit,         plane,      absolute,      arc_absolute, inverse_time,
                      retract_to_r, exact_stop, diameter_mode, cs,           tlo,
                      tolerance,    feed,       spindle_s,     spindle_on,   mist,
                      flood,        comp_on(),  comp_side,     comp_radius};
  }
  void restore_state(const ModalState& st, const Block& b, int col, const char* what,
                     std::vector<Command>& out);
  void leave_depths(const Block& b, std::vector<Command>& out);
  [[gnu::cold, gnu::noinline]] void spline_block(const Block& b, const Word& g,
                                                 const Word* const letters[26], bool used[26],
                                                 const Word* polar, std::vector<Command>& out);
  bool execute(const Block& b, std::vector<Command>& out);
  void compensate(const Block& b, std::vector<Command>& out, size_t first, bool go_on);
  void canned_cycle(const Block& b, const Vec4& hole, bool hole_given[3], std::vector<Command>& out,
                    int repeats, const Word* first_col, const Word* polar_r, const Word* polar_a);
};

namespace {

// The words of one block, by letter; G and M codes by modal group.
struct BlockWords {
  const Word* letter[26] = {};
  const Word* g[16] = {};  // index: modal group + 1
  int mcodes[16] = {};
  const Word* mwords[16] = {};
  int mcount = 0;
  const Word* get(char l) const { return letter[l - 'A']; }
  const Word* m(int code) const {
    for (int i = 0; i < mcount; ++i)
      if (mcodes[i] == code) return mwords[i];
    return nullptr;
  }
};

}  // namespace

// M72 / M73's restore: the modes as they were saved; coolant switched as M7/M8/M9 would.
void Interpreter::Impl::restore_state(const ModalState& st, const Block& b, int col,
                                      const char* what, std::vector<Command>& out) {
  if ((st.comp_on || comp_on()) &&
      (st.comp_on != comp_on() || st.comp_side != comp_side || st.comp_radius != comp_radius ||
       st.plane != plane || st.cs != cs || st.tlo != tlo))
    throw fail(b, col,
               fmt::format("{}: the saved modal state differs in cutter radius compensation (or "
                           "in the plane, work offset or tool length offset under it); G40 before "
                           "saving and restoring",
                           what));
  unit = st.unit;
  plane = st.plane;
  absolute = st.absolute;
  arc_absolute = st.arc_absolute;
  inverse_time = st.inverse_time;
  retract_to_r = st.retract_to_r;
  exact_stop = st.exact_stop;
  diameter_mode = st.diameter_mode;
  cs = st.cs;
  if (tlo != st.tlo) {
    tlo = st.tlo;
    pos_tlo = tlo;  // as G43: the machine stays, the program position moves
  }
  tolerance = st.tolerance;
  feed = st.feed;
  spindle_s = st.spindle_s;
  spindle_on = st.spindle_on;
  auto output = [&](Output::Kind kind, double value) {
    out.emplace_back(Output{kind, 0, value, false, b.line});
    ++stats.outputs;
  };
  if (st.mist && !mist) output(Output::Kind::kMist, 1.0);
  if (st.flood && !flood) output(Output::Kind::kFlood, 1.0);
  if (!st.mist && !st.flood && (mist || flood)) {
    output(Output::Kind::kMist, 0.0);
    output(Output::Kind::kFlood, 0.0);
    mist = flood = false;
  }
  mist = mist || st.mist;
  flood = flood || st.flood;
  write_params();
}

// A subroutine returned (b is its endsub or return line): the states saved deeper than the
// caller go, and an M73 state comes back.
void Interpreter::Impl::leave_depths(const Block& b, std::vector<Command>& out) {
  while (!saved.empty() && saved.back().depth > call_depth) {
    const SavedState s = saved.back();
    saved.pop_back();
    leave_below = saved.empty() ? -1 : saved.back().depth;
    if (s.autorestore) restore_state(s.st, b, 1, "M73 (restore on return)", out);
  }
}

// A G5 / G5.1 block, whole, in the motion step (docs/gcode.md, "Splines"): the control points
// in machine mm are P0 the start, P1 = P0 + (I, J); G5: P2 = end + (P, Q); the end. G5 without
// I J continues the last G5's curve smoothly: (I, J) = -(its P, Q). `letters` are the block's
// words by letter; the ones it uses are marked in `used`.
void Interpreter::Impl::spline_block(const Block& b, const Word& g, const Word* const letters[26],
                                     bool used[26], const Word* polar, std::vector<Command>& out) {
  const int code = code10(g);
  const std::string name = gname(code);
  auto get = [&](char l) { return letters[l - 'A']; };
  auto word = [&](char l) {
    used[l - 'A'] = true;
    return letters[l - 'A'];
  };
  if (code == 52 || code == 53)
    throw fail(
        b, g.col,
        fmt::format("{}: NURBS curves are not supported (the G5 and G5.1 splines are)", name));
  if (rules->dialect != Dialect::kLinuxCnc)
    throw fail(b, g.col,
               fmt::format("{}: splines are not supported in the {} dialect (LinuxCNC's G5 and "
                           "G5.1 are)",
                           name, rules->name));
  if (plane != Plane::kXY)
    throw fail(b, g.col, fmt::format("{}: splines need the XY plane (G17)", name));
  if (comp_on())
    throw fail(b, g.col,
               fmt::format("{}: no spline with cutter radius compensation on (G40 first)", name));
  for (char l : {'Z', axis_names[3]})
    if (const Word* aw = get(l))
      throw fail(b, aw->col, fmt::format("{}: a spline moves X and Y only, not {}", name, l));
  if (!get('X') && !get('Y'))
    throw fail(b, g.col, fmt::format("{}: a spline needs X or Y (its end point)", name));
  if (polar)
    throw fail(b, polar->col,
               fmt::format("{}: polar coordinates in a spline are not supported", name));
  const Word* iw = word('I');
  const Word* jw = word('J');
  const Word* pw = code == 50 ? word('P') : nullptr;
  const Word* qw = code == 50 ? word('Q') : nullptr;
  const Word* fw = get('F');
  move_col = g.col;
  if (!iw != !jw || (code == 51 && !iw))
    throw fail(b,
               (iw   ? iw
                : jw ? jw
                     : &g)
                   ->col,
               fmt::format("{} needs both I and J{}", name, code == 50 ? " (or neither)" : ""));
  if (code == 50 && (!pw || !qw))
    throw fail(b, (pw ? pw : qw ? qw : &g)->col, fmt::format("{} needs both P and Q", name));
  if (inverse_time) {
    if (!fw || fw->value <= 0)
      throw fail(b, fw ? fw->col : g.col, "G93 inverse time: each move needs F > 0");
  } else if (rules->feed_required && !feed_given && !fw) {
    throw fail(b, g.col,
               fmt::format("no feed given yet: {} needs F (LinuxCNC starts at F0)", name));
  } else if (feed <= 0.0) {
    throw fail(b, g.col, fmt::format("feed is 0: {} needs F > 0", name));
  }
  auto mm = [&](const Word* wd) {
    const double v = wd->value * unit * (diameter_mode && wd->letter == 'X' ? 0.5 : 1.0);
    if (std::fabs(v) > kMaxValue)
      throw fail(b, wd->col,
                 fmt::format("value of '{}' out of range (|value| > 1e6 mm)", wd->letter));
    return v;
  };
  // The end point as any move's (G90/G91, offsets; a tool length offset changed since the last
  // move shifts every axis).
  Vec4 t = pos;
  for (int a = 0; a < offset_axes; ++a) {
    const auto i = static_cast<size_t>(a);
    const double shift = tlo[i] - pos_tlo[i];
    t[i] = pos[i] + shift;
    if (a > 1) continue;
    if (const Word* aw = word(axis_names[i])) {
      const double v = mm(aw);
      t[i] = absolute ? v + offset(a) : pos[i] + shift + v;
      if (std::fabs(t[i]) > 1e9) throw fail(b, aw->col, "position out of range");
    }
  }
  SplinePoints cp{};
  cp.n = code == 50 ? 4 : 3;
  cp.p[0] = {pos[0], pos[1]};
  const std::array<double, 2> ij =
      iw ? std::array<double, 2>{mm(iw), mm(jw)}
         : std::array<double, 2>{-spline_last_pq[0], -spline_last_pq[1]};
  cp.p[1] = {pos[0] + ij[0], pos[1] + ij[1]};
  cp.p[static_cast<size_t>(cp.n - 1)] = {t[0], t[1]};
  if (code == 50) {
    spline_last_pq = {mm(pw), mm(qw)};
    cp.p[2] = {t[0] + spline_last_pq[0], t[1] + spline_last_pq[1]};
  }
  const std::vector<std::array<double, 2>> pts = spline_pieces(cp, opt.arc_tolerance_mm);
  double f = feed * feed_factor;
  if (inverse_time) {
    double len = 0.0;
    for (size_t k = 1; k < pts.size(); ++k)
      len += std::hypot(pts[k][0] - pts[k - 1][0], pts[k][1] - pts[k - 1][1]);
    f = len * fw->value * feed_factor;
    if (f <= 0) f = feed;
  }
  for (size_t k = 1; k < pts.size(); ++k) {
    Vec4 e = t;
    e[0] = pts[k][0];
    e[1] = pts[k][1];
    line_to(out, Motion::kLinear, e, b.line, f);
  }
  write_position();
}

bool Interpreter::Impl::execute(const Block& b, std::vector<Command>& out) {
  ++stats.lines;
  if (b.block_delete && opt.block_delete) return true;
  if (b.kind != BlockKind::kWords) [[unlikely]] {
    if (b.kind == BlockKind::kCall) {
      ++call_depth;
      return true;
    }
    if (b.kind == BlockKind::kReturn) {
      --call_depth;
      if (call_depth < leave_below) leave_depths(b, out);
      return true;
    }
    if (b.kind == BlockKind::kPercent || b.kind == BlockKind::kQuery) return true;
    if (b.kind == BlockKind::kMacro) {
      std::string name = b.text.substr(0, b.text.find_first_of(" \t"));
      warn(fmt::format("extended command '{}' skipped (a Klipper macro: Klipper runs it from its "
                       "printer.cfg; nothing here moves for it)",
                       name),
           b.line);
      return true;
    }
    if (b.kind == BlockKind::kSystem) {
      const std::string& t = b.text;
      if (t.size() >= 2 && (t[1] == 'H' || t[1] == 'h'))
        throw fail(b, b.text_col,
                   "'$H' homing cycle in a job: home the machine before the job (`fpgacnc home`, "
                   "or '$H' in `fpgacnc grbl`) and remove the line");
      if (t.size() >= 2 && (t[1] == 'J' || t[1] == 'j'))
        throw fail(b, b.text_col, "'$J=' jogging is not a job command");
      warn(fmt::format("grbl system line '{}' ignored", t), b.line);
      return true;
    }
  }

  // Classify.
  BlockWords w;
  const Word* polar_r = nullptr;
  const Word* polar_a = nullptr;
  for (int i = 0; i < b.count; ++i) {
    const Word& wd = b.words[static_cast<size_t>(i)];
    const char l = wd.letter;
    if (l == kPolarRadius || l == kPolarAngle) {
      const Word*& slot = l == kPolarRadius ? polar_r : polar_a;
      if (slot) throw fail(b, wd.col, fmt::format("two '{}' words on one line", l));
      slot = &wd;
      continue;
    }
    if (l == 'G') {
      if (!is_code10_exact(wd) || wd.value < 0 || wd.value >= 1000)
        throw fail(b, wd.col, fmt::format("G{} is not a G code", wd.value));
      const int c = code10(wd);
      const int grp = g_group(c);
      if (grp < 0 && rules->unknown_m_warns && c >= 290 && c <= 299) {
        warn(fmt::format("{} bed levelling skipped: no bed levelling on this machine (the line is "
                         "not run)",
                         gname(c)),
             b.line);
        return true;
      }
      if (grp < 0) {
        std::string why = "not supported";
        if (c == 330 || c == 331 || c == 760 || c == 950)
          why = "needs a spindle encoder, which this machine does not have";
        else if (c == 680)
          why = "coordinate system rotation is not supported";
        else if (c == 520)
          why = "G52 local offsets are not supported (use G92 or G10 L2)";
        else if (c == 290 || c == 291 || c == 292 || c == 293)
          why = "bed levelling is not built on this machine";
        throw fail(b, wd.col, fmt::format("{}: {}", gname(c), why));
      }
      if (w.g[grp + 1])
        throw fail(b, wd.col,
                   fmt::format("{} and {} on one line are in the same modal group",
                               gname(code10(*w.g[grp + 1])), gname(c)));
      w.g[grp + 1] = &wd;
      continue;
    }
    if (l == 'M') {
      if (!wd.integer && !(rules->dialect != Dialect::kLinuxCnc && is_code10_exact(wd)))
        throw fail(b, wd.col, "M codes are integers");
      if (!(wd.value >= 0.0 && wd.value < 10000.0))
        throw fail(b, wd.col, fmt::format("M{} out of range", wd.value));
      const int c = static_cast<int>(std::floor(wd.value));
      auto group = [](int m) {
        return (m == 0 || m == 1 || m == 2 || m == 30 || m == 60) ? 1
               : (m >= 3 && m <= 5)                               ? 2
               : m == 6                                           ? 3
                                                                  : 0;
      };
      for (int k = 0; k < w.mcount; ++k)
        if (group(c) && group(w.mcodes[k]) == group(c))
          throw fail(
              b, wd.col,
              fmt::format("M{} and M{} on one line are in the same modal group", w.mcodes[k], c));
      if (w.mcount == 16) throw fail(b, wd.col, "too many M codes on one line");
      w.mcodes[w.mcount] = c;
      w.mwords[w.mcount++] = &wd;
      continue;
    }
    if (l == 'A' && rules->a_is_extruder) {
      if (w.letter['E' - 'A']) throw fail(b, wd.col, "two extruder words (A/E) on one line");
      w.letter['E' - 'A'] = &wd;
      continue;
    }
    if (l == 'E' && !rules->e_is_axis)
      throw fail(
          b, wd.col,
          fmt::format("'E' is not a word of the {} dialect (no extruder axis)", rules->name));
    if (l == 'E' && rotary && !(rules->unknown_m_warns && w.mcount > 0))
      throw fail(b, wd.col, "no E axis on this machine (its fourth axis is the rotary A)");
    if ((l == 'A' && !rotary) || l == 'B' || l == 'C' || l == 'U' || l == 'V' || l == 'W') {
      // Marlin's M-codes take some of these as parameters; the used-word check catches the rest.
      bool m_param = rules->unknown_m_warns && w.mcount > 0;
      if (rules->g28_homes && w.g[1] && code10(*w.g[1]) == 280) {  // G28 U0: a second carriage
        warn(fmt::format("G28 {}: no {} axis on this machine, ignored", l, l), b.line);
        continue;
      }
      if (!m_param)
        throw fail(
            b, wd.col,
            fmt::format("no {} axis on this machine (its axes are X Y Z {})", l, axis_names[3]));
    }
    if (l == 'N') {
      if (!wd.integer || wd.value < 0) throw fail(b, wd.col, "N must be a non-negative integer");
      continue;
    }
    if (w.letter[l - 'A']) throw fail(b, wd.col, fmt::format("two '{}' words on one line", l));
    if (std::fabs(wd.value) > (l == 'F' ? kMaxFeed : kMaxValue))
      throw fail(b, wd.col, fmt::format("value of '{}' out of range (|value| > 1e6)", l));
    w.letter[l - 'A'] = &wd;
  }
  auto gw = [&](int grp) { return w.g[grp + 1]; };
  // A letter without a number is a parameter of an M code or Marlin's G28 X Y; nothing else.
  if (w.mcount == 0 && !(w.g[1] && code10(*w.g[1]) == 280)) {
    for (int i = 0; i < b.count; ++i) {
      const Word& wd = b.words[static_cast<size_t>(i)];
      if (wd.bare) throw fail(b, wd.col, fmt::format("expected a number after '{}'", wd.letter));
    }
  }
  bool used[26] = {};
  auto word = [&](char l) {
    used[l - 'A'] = true;
    return w.get(l);
  };
  auto to_mm = [&](const Word* wd) {
    const double v = wd->value * unit * (diameter_mode && wd->letter == 'X' ? 0.5 : 1.0);
    if (std::fabs(v) > kMaxValue)
      throw fail(b, wd->col,
                 fmt::format("value of '{}' out of range (|value| > 1e6 mm)", wd->letter));
    return v;
  };
  // An axis word in machine units: mm (scaled by G20), or degrees of a rotary A.
  auto axis_mm = [&](int a, const Word* wd) { return rotary && a == 3 ? wd->value : to_mm(wd); };
  bool did = false;

  // rs274ngc order of execution.
  // 1. Messages.
  if (b.message_kind == MessageKind::kMsg)
    out.emplace_back(Message{Message::Kind::kDisplay, b.text, -1.0, b.line});
  else if (b.message_kind == MessageKind::kDebug || b.message_kind == MessageKind::kPrint)
    out.emplace_back(Message{Message::Kind::kDebug, b.text, -1.0, b.line});
  // 2. Feed mode and units (F and all lengths are read in them).
  if (const Word* g = gw(5)) {
    if (code10(*g) == 950)
      throw fail(
          b, g->col,
          "G95 feed per revolution needs a spindle encoder, which this machine does not have");
    inverse_time = code10(*g) == 930;
  }
  if (const Word* g = gw(6)) unit = code10(*g) == 200 ? kInch : 1.0;
  if (const Word* g = gw(11)) diameter_mode = code10(*g) == 70;  // G7 / G8
  // 3. F.
  const bool s_for_m = w.m(104) || w.m(109) || w.m(140) || w.m(190) || w.m(106) || w.m(220) ||
                       w.m(221) || w.m(207) || w.m(208) || w.m(204) || w.m(205) || w.m(141) ||
                       w.m(191) || w.m(73) ||
                       (rules->dwell_p_ms && gw(0) && code10(*gw(0)) == 40) ||
                       (rules->g10_retract && gw(0) && code10(*gw(0)) == 100);
  const bool f_for_m = w.m(207) || w.m(208);
  if (const Word* f = w.get('F'); f && !f_for_m) {
    word('F');
    if (f->value < 0) throw fail(b, f->col, "negative feed");
    if (!inverse_time) feed = f->value * unit;
    feed_given = true;
  }
  // 4. S.
  if (const Word* s = w.get('S'); s && !s_for_m) {
    word('S');
    if (s->value < 0) throw fail(b, s->col, "negative S value");
    spindle_s = s->value;
  }
  // 5. T (in the printer dialects a T beside an M code is that code's tool parameter).
  const Word* t_word = rules->t_selects_extruder && w.mcount > 0 ? nullptr : w.get('T');
  if (const Word* t = t_word) {
    word('T');
    if (!t->integer || t->value < 0) throw fail(b, t->col, "T must be a non-negative integer");
    if (rules->t_selects_extruder) {
      // One extruder: a slicer's T<n> for another filament is a manual filament change at rest
      // (the prompt names the filament), or only recorded with tool_change = "ignore".
      const int n = static_cast<int>(t->value);
      if (n != filament) {
        ++stats.tool_changes;
        if (opt.tool_change_pause) {
          out.emplace_back(Pause{
              Pause::Reason::kFilamentChange, n,
              fmt::format("load the filament of T{} (this machine has one extruder)", n), b.line});
          ++stats.pauses;
        }
        filament = n;
      }
    } else {
      next_tool = static_cast<int>(t->value);
    }
    did = true;
  }
  // 6. M6.
  if (w.m(6)) {
    if (comp_on())
      throw fail(b, w.m(6)->col,
                 "M6: no tool change with cutter radius compensation on (G40 first)");
    if (!rules->t_selects_extruder) {
      ++stats.tool_changes;
      if (opt.tool_change_pause && next_tool != tool) {
        Pause p;
        p.reason = Pause::Reason::kToolChange;
        p.tool = next_tool;
        const ToolEntry* e = tools.find(next_tool);
        p.prompt = fmt::format("insert tool T{}{}", next_tool,
                               e && !e->comment.empty() ? fmt::format(" ({})", e->comment) : "");
        p.line = b.line;
        out.emplace_back(p);
        ++stats.pauses;
      }
      tool = next_tool;
      tool_changed = true;
    }
    did = true;
  }
  // 7. Spindle.
  for (int k = 0; k < w.mcount; ++k)
    if (w.mcodes[k] >= 3 && w.mcodes[k] <= 5) {
      spindle_on = w.mcodes[k] != 5;
      did = true;
      // M3 constant power, M4 dynamic (scaled with the speed): an output in step with motion
      // (the first one sets it whatever the machine holds from before)
      if (w.mcodes[k] != 5 && (!laser_m4 || (w.mcodes[k] == 4) != *laser_m4)) {
        laser_m4 = w.mcodes[k] == 4;
        out.emplace_back(Output{Output::Kind::kLaserMode, 0, *laser_m4 ? 1.0 : 0.0, false, b.line});
        ++stats.outputs;
      }
    }
  // 7b. Saving and restoring the modal state (LinuxCNC's M70-M73), after F, S and the spindle and
  // before the modes of the line's G codes (units excepted: they are read first here).
  if (w.mcount > 0 && rules->dialect == Dialect::kLinuxCnc)
    for (int k = 0; k < w.mcount; ++k) {
      const int c = w.mcodes[k];
      if (c < 70 || c > 73) continue;
      did = true;
      SavedState* mine =
          !saved.empty() && saved.back().depth == call_depth ? &saved.back() : nullptr;
      if (c == 70 || c == 73) {
        if (!mine) mine = &saved.emplace_back();
        *mine = SavedState{call_depth, c == 73, modal_state()};
        leave_below = call_depth;
      } else if (c == 71) {
        if (mine) saved.pop_back();
        leave_below = saved.empty() ? -1 : saved.back().depth;
      } else {
        if (!mine)
          throw fail(b, w.mwords[k]->col,
                     "M72: no modal state saved at this call level (M70 or M73 first)");
        const ModalState st = mine->st;
        restore_state(st, b, w.mwords[k]->col, "M72", out);
      }
    }
  // 8. The other M codes, in the order written.
  for (int k = 0; k < w.mcount; ++k) {
    const int c = w.mcodes[k];
    const Word& mw = *w.mwords[k];
    auto output = [&](Output::Kind kind, int index, double value, bool immediate) {
      out.emplace_back(Output{kind, index, value, immediate, b.line});
      ++stats.outputs;
      did = true;
    };
    switch (c) {
      case 0:
      case 1:
      case 2:
      case 30:
      case 3:
      case 4:
      case 5:
      case 6:
        break;  // in their own step
      case 60:
        throw fail(b, mw.col, "M60 pallet change: this machine has no pallet changer");
      case 7:
        output(Output::Kind::kMist, 0, 1.0, false);
        mist = true;
        break;
      case 8:
        output(Output::Kind::kFlood, 0, 1.0, false);
        flood = true;
        break;
      case 9:
        output(Output::Kind::kMist, 0, 0.0, false);
        output(Output::Kind::kFlood, 0, 0.0, false);
        mist = flood = false;
        break;
      case 48:
      case 49:
      case 50:
      case 51:
      case 52:
      case 53:
        word('P');
        warn(fmt::format("M{} (override switches) ignored", c), b.line);
        break;
      case 62:
      case 63:
      case 64:
      case 65: {
        const Word* p = word('P');
        if (!p) throw fail(b, mw.col, fmt::format("M{} needs P (output number)", c));
        if (!p->integer || p->value < 0 || p->value > 3)
          throw fail(b, p->col, "digital output number P must be 0..3 (four outputs)");
        output(Output::Kind::kDigital, static_cast<int>(p->value), (c == 62 || c == 64) ? 1.0 : 0.0,
               c >= 64);
        break;
      }
      case 66:
        throw fail(b, mw.col, "M66 wait on input: this machine has no inputs for it");
      case 67:
      case 68:
        throw fail(b, mw.col, fmt::format("M{} analog output: this machine has none", c));
      case 82:
        e_absolute = true;
        did = true;
        break;
      case 83:
        e_absolute = false;
        did = true;
        break;
      case 18:
      case 84:
        for (char l : {'X', 'Y', 'Z', 'E', 'S'}) word(l);
        did = true;
        break;
      case 61: {  // set the loaded tool's number without a change (LinuxCNC)
        if (rules->dialect != Dialect::kLinuxCnc)
          throw fail(b, mw.col, fmt::format("M61: not supported in the {} dialect", rules->name));
        const Word* q = word('Q');
        if (!q || !q->integer || q->value < 0)
          throw fail(b, q ? q->col : mw.col, "M61 needs Q<tool number> (a non-negative integer)");
        tool = next_tool = static_cast<int>(q->value);
        did = true;
        break;
      }
      case 104:
      case 109:
      case 140:
      case 190: {
        Heater h;
        h.mcode = c;
        if (const Word* s = word('S')) h.s = s->value;
        if (const Word* r = word('R'); r && !h.s) h.s = r->value;
        for (char l : {'T', 'B', 'F', 'D', 'I', 'P'}) word(l);
        h.line = b.line;
        out.emplace_back(h);
        did = true;
        produced = true;
        break;
      }
      case 106:
      case 107: {
        double duty = 0.0;
        if (c == 106) {
          const Word* s = word('S');
          duty = s ? std::clamp(s->value / 255.0, 0.0, 1.0) : 1.0;
        }
        if (const Word* p = word('P'); p && p->value != 0) {
          warn(fmt::format("M{} P{}: this machine has one part-cooling fan (P0); other fans "
                           "ignored",
                           c, p->value),
               b.line);
          for (char l : {'S', 'T'}) word(l);
          did = true;
          break;
        }
        for (char l : {'T', 'I'}) word(l);
        output(Output::Kind::kFan, 0, duty, false);
        break;
      }
      case 73: {  // printers: progress; LinuxCNC: save the modal state, restore it on return
        if (rules->dialect == Dialect::kLinuxCnc) break;  // in its own step
        const Word* p = word('P');
        for (char l : {'R', 'Q', 'S', 'C', 'D'}) word(l);
        if (p) out.emplace_back(Message{Message::Kind::kProgress, "", p->value, b.line});
        did = true;
        break;
      }
      case 117:
      case 118:
        for (char l = 'A'; l <= 'Z'; ++l) word(l);
        out.emplace_back(Message{c == 117 ? Message::Kind::kDisplay : Message::Kind::kEcho, b.text,
                                 -1.0, b.line});
        did = true;
        break;
      case 400:
        for (char l = 'A'; l <= 'Z'; ++l) word(l);
        did = true;
        break;  // wait for the moves: a streamed job is in order anyway
      case 201:
      case 203:
      case 204:
      case 205: {
        Limits lim;
        lim.line = b.line;
        for (int a = 0; a < 4; ++a) {
          const Word* aw = word(axis_names[a]);
          if (!aw || aw->value <= 0) continue;
          const auto i = static_cast<size_t>(a);
          if (c == 201) lim.accel_mm_s2[i] = aw->value * unit_of(a);
          // Marlin's M203 is in units per second; RepRapFirmware's in units per minute.
          if (c == 203)
            lim.max_feed_mm_min[i] =
                aw->value * unit_of(a) * (rules->dialect == Dialect::kMarlin ? 60.0 : 1.0);
        }
        if (c == 204) {
          const Word* p = word('P');
          const Word* s = word('S');
          if (!p) p = s;
          if (p && p->value > 0) lim.path_accel_mm_s2 = p->value * unit;
        }
        if (c == 205) {
          if (const Word* j = word('J'); j && j->value > 0)
            lim.junction_deviation_mm = j->value * unit;
        }
        for (char l = 'A'; l <= 'Z'; ++l) word(l);  // the rest: jerk, retract and travel
        out.emplace_back(lim);
        did = true;
        break;
      }
      case 220:
      case 221: {
        const Word* s = word('S');
        for (char l : {'B', 'R', 'T', 'D'}) word(l);
        if (s) {
          if (s->value <= 0 || s->value > 1000) throw fail(b, s->col, "factor must be 1..1000 %");
          (c == 220 ? feed_factor : flow) = s->value / 100.0;
        }
        did = true;
        break;
      }
      case 207:
      case 208: {
        if (const Word* s = word('S')) (c == 207 ? retract_mm : recover_extra) = s->value * unit;
        if (const Word* f = word('F')) (c == 207 ? retract_feed : recover_feed) = f->value * unit;
        if (const Word* z = word('Z'); z && c == 207) retract_zlift = z->value * unit;
        word('R');
        did = true;
        break;
      }
      case 600: {
        for (char l = 'A'; l <= 'Z'; ++l) word(l);
        out.emplace_back(Pause{Pause::Reason::kFilamentChange, 0, "change the filament", b.line});
        ++stats.pauses;
        did = true;
        break;
      }
      default: {
        if (rules->user_m_warns && c >= 100 && c <= 199 && !rules->unknown_m_warns) {
          warn(fmt::format("M{} (a user or vendor M code) ignored: no such output here", c),
               b.line);
          for (char l = 'A'; l <= 'Z'; ++l) word(l);
          break;
        }
        if (rules->dialect == Dialect::kLinuxCnc && c >= 70 && c <= 72) break;  // step 7b
        if (!rules->unknown_m_warns)
          throw fail(b, mw.col,
                     fmt::format("M{}: not supported in the {} dialect", c, rules->name));
        const char* what = printer_ignored(c);
        warn(what ? fmt::format("{} ignored", what)
                  : fmt::format("M{} unknown here, ignored (as {} does)", c, rules->name),
             b.line);
        for (char l = 'A'; l <= 'Z'; ++l) word(l);  // its parameters belong to it
        break;
      }
    }
  }
  // 9. Dwell.
  const Word* nm = gw(0);
  const int nmc = nm ? code10(*nm) : -1;
  if (nmc == 40) {
    const Word* p = word('P');
    const Word* s = rules->dwell_p_ms ? word('S') : nullptr;
    if (!p && !s && !rules->dwell_p_ms) throw fail(b, nm->col, "G4 needs a P word (seconds)");
    // Marlin: G4 alone waits for the moves to finish (a stop, no time).
    double secs = 0.0;
    if (s) secs += s->value;
    if (p) secs += rules->dwell_p_ms ? p->value / 1000.0 : p->value;
    if (secs < 0) throw fail(b, (p ? p : s)->col, "negative dwell time");
    out.emplace_back(Dwell{secs, b.line});
    did = true;
    produced = true;
  }
  // 10. Plane.
  if (const Word* g = gw(2)) {
    const Plane p = code10(*g) == 170 ? Plane::kXY : code10(*g) == 180 ? Plane::kZX : Plane::kYZ;
    if (p != plane && comp_on())
      throw fail(b, g->col,
                 fmt::format("{}: no change of plane with cutter radius compensation on",
                             gname(code10(*g))));
    plane = p;
  }
  // 11. Cutter radius compensation (cutter_comp.h; compensate() applies it).
  if (const Word* g = gw(7)) {
    const int c = code10(*g);
    if (c == 400) {
      comp_event = CompEvent::kOff;
    } else {
      if (comp_on())
        throw fail(
            b, g->col,
            fmt::format("{}: cutter radius compensation is already on (G40 first)", gname(c)));
      if (plane == Plane::kYZ)
        throw fail(b, g->col,
                   fmt::format("{}: cutter radius compensation needs the XY or XZ plane (G17 or "
                               "G18), not G19",
                               gname(c)));
      const Word* d = word('D');
      if (c == 410 || c == 420) {  // D: a tool of the tool table (none: the current tool)
        if (d && (!d->integer || d->value < 0))
          throw fail(b, d->col, fmt::format("{} D must be a tool number", gname(c)));
        const int n = d ? static_cast<int>(d->value) : tool;
        const ToolEntry* e = tools.find(n);
        if (!e && n != 0)
          throw fail(b, d ? d->col : g->col,
                     opt.tool_table.empty()
                         ? fmt::format("{}: no tool table to read the diameter of tool {} from "
                                       "(give one with --tool-table or tool_table in the machine "
                                       "configuration)",
                                       gname(c), n)
                         : fmt::format("{}: tool {} is not in the tool table {}", gname(c), n,
                                       opt.tool_table));
        comp_radius = e ? e->diameter / 2.0 : 0.0;
      } else {  // G41.1/G42.1: D is the diameter; L (a lathe tool's orientation) changes nothing
        if (!d) throw fail(b, g->col, fmt::format("{} needs D (the tool diameter)", gname(c)));
        comp_radius = to_mm(d) / 2.0;
        word('L');
      }
      comp_side = c == 410 || c == 411 ? CutterComp::Side::kLeft : CutterComp::Side::kRight;
      comp_event = CompEvent::kOn;
      comp_pos = pos;
    }
    comp_at = out.size();
  }
  // 12. Tool length offset.
  bool tlo_words = false;
  if (const Word* g = gw(8)) {
    const int c = code10(*g);
    if (comp_on())
      throw fail(b, g->col,
                 fmt::format("{}: no tool length offset change with cutter radius compensation on "
                             "(G40 first)",
                             gname(c)));
    if (c == 490) {
      tlo = {};
    } else if (c == 430 || c == 432) {
      const Word* h = word('H');
      if (h && (!h->integer || h->value < 0)) throw fail(b, h->col, "H must be a tool number");
      const int n = h ? static_cast<int>(h->value) : tool;
      const ToolEntry* e = tools.find(n);
      if (!e && n != 0)
        throw fail(b, h ? h->col : g->col,
                   opt.tool_table.empty()
                       ? fmt::format("{}: no tool table to read tool {} from (give one with "
                                     "--tool-table or tool_table in the machine configuration)",
                                     gname(c), n)
                       : fmt::format("{}: tool {} is not in the tool table {}", gname(c), n,
                                     opt.tool_table));
      Vec4 off{};
      if (e)
        for (size_t a = 0; a < 3; ++a) off[a] = e->offset[a];
      if (c == 430)
        tlo = off;
      else
        for (size_t a = 0; a < 3; ++a) tlo[a] += off[a];
    } else {  // G43.1: the axis words are the offsets
      tlo = {};
      for (int a = 0; a < 3; ++a)
        if (const Word* aw = word(axis_names[a])) tlo[static_cast<size_t>(a)] = to_mm(aw);
      tlo_words = true;
    }
    pos_tlo = tlo;  // the machine stays; the program position moves (until an M6, below)
    did = true;
  }
  // 13. Coordinate system.
  if (const Word* g = gw(12)) {
    const int c = code10(*g);
    if (comp_on())
      throw fail(b, g->col,
                 fmt::format("{}: no change of coordinate system with cutter radius compensation "
                             "on (G40 first)",
                             gname(c)));
    cs = c < 591 ? c / 10 - 54 : 6 + (c - 591);
    did = true;
  }
  // 14. Path control.
  if (const Word* g = gw(13)) {
    const int c = code10(*g);
    exact_stop = c != 640;
    tolerance = 0.0;
    if (c == 640) {
      if (const Word* p = word('P')) tolerance = std::fabs(to_mm(p));
      word('Q');  // the look-ahead does not merge collinear segments: Q has nothing to do
    }
    did = true;
  }
  // 15. Distance modes, retract mode.
  if (const Word* g = gw(3)) absolute = code10(*g) == 900;
  if (const Word* g = gw(4)) arc_absolute = code10(*g) == 901;
  if (const Word* g = gw(10)) retract_to_r = code10(*g) == 990;
  if (gw(2) || gw(3) || gw(4) || gw(5) || gw(6) || gw(7) || gw(10)) did = true;

  bool has_axis = polar_r || polar_a;  // axis words no M code on the line took as its own
  for (char l : axis_names) has_axis = has_axis || (w.get(l) && !used[l - 'A']);
  if (tlo_words) has_axis = false;
  auto no_motion_word = [&](const char* what) {
    if (gw(1))
      throw fail(b, gw(1)->col, fmt::format("{} and a motion G code on the same line", what));
  };
  // Program E -> machine E (G92 E offset; relative under M83 or G91), then M221's flow.
  auto e_target = [&](const Word* ew) {
    const double v = to_mm(ew);
    const double prog = (!e_absolute || !absolute) ? e_prog + v : v + g92[3];
    return prog;
  };
  // Machine target of the axis words in the current modes (G53: machine coordinates).
  // A tool length offset changed since the last move applies to every axis of the next move
  // (LinuxCNC keeps the program position, so the machine moves by the change).
  auto target = [&](bool machine) {
    Vec4 t = pos;
    for (int a = 0; a < offset_axes; ++a) {
      const auto i = static_cast<size_t>(a);
      const double shift = tlo[i] - pos_tlo[i];
      t[i] = pos[i] + shift;
      const Word* aw = word(axis_names[a]);
      if (!aw) continue;
      const double v = axis_mm(a, aw);
      t[i] = machine ? v : absolute ? v + offset(a) : pos[i] + shift + v;
      if (std::fabs(t[i]) > 1e9) throw fail(b, aw->col, "position out of range");
    }
    return t;
  };
  // LinuxCNC's polar coordinates in the XY plane: '@' distance and '^' angle (degrees) from the
  // program origin; in G91 they add to the current point's distance and angle.
  auto apply_polar = [&](Vec4& t) {
    if (!polar_r && !polar_a) return;
    const Word* pw = polar_r ? polar_r : polar_a;
    if (w.get('X') || w.get('Y')) throw fail(b, pw->col, "polar '@'/'^' and X/Y on the same line");
    if (plane != Plane::kXY) throw fail(b, pw->col, "polar coordinates need the XY plane (G17)");
    const double px = pos[0] - offset(0), py = pos[1] - offset(1);
    double r = std::hypot(px, py), a = std::atan2(py, px);
    if (!absolute && r == 0.0)
      throw fail(b, pw->col, "incremental polar move from the origin is indeterminate");
    if (polar_r) r = absolute ? to_mm(polar_r) : r + to_mm(polar_r);
    if (polar_a) {
      const double deg = polar_a->value * M_PI / 180.0;
      a = absolute ? deg : a + deg;
    }
    t[0] = r * std::cos(a) + offset(0);
    t[1] = r * std::sin(a) + offset(1);
  };
  auto apply_e = [&](Vec4& t) {
    if (const Word* ew = word('E')) {
      const double prog = e_target(ew);
      t[3] = pos[3] + (prog - e_prog) * flow;
      e_prog = prog;
    }
  };

  // 16. Non-modal codes.
  if (nmc == 100) {  // G10
    const Word* l = word('L');
    if (!l) {
      if (!rules->g10_retract)
        throw fail(b, nm->col,
                   fmt::format("G10 needs L (L2/L20 work offsets, L1 tool table) in the {} "
                               "dialect",
                               rules->name));
      for (char c : {'P', 'S', 'R'}) word(c);
      if (!retracted) {
        Vec4 t = pos;
        t[3] -= retract_mm;
        e_prog -= retract_mm / flow;
        line_to(out, Motion::kLinear, t, b.line, retract_feed);
        if (retract_zlift > 0) {
          t[2] += retract_zlift;
          line_to(out, Motion::kRapid, t, b.line);
        }
        retracted = true;
      }
      write_position();
      return true;
    }
    const Word* p = word('P');
    const int lv = static_cast<int>(l->value);
    no_motion_word("G10");
    if (lv == 2 || lv == 20) {
      if (const Word* r = word('R'))
        throw fail(b, r->col, "G10 R: coordinate system rotation is not supported");
      const int n = p ? static_cast<int>(p->value) : 0;
      if (p && (!p->integer || n < 0 || n > 9)) throw fail(b, p->col, "G10 P must be 0..9");
      const int s = n == 0 ? cs : n - 1;
      if (s == cs && comp_on())
        throw fail(b, nm->col,
                   fmt::format("G10 L{}: no change of the active coordinate system with cutter "
                               "radius compensation on (G40 first)",
                               lv));
      for (int a = 0; a < offset_axes; ++a) {
        const Word* aw = word(axis_names[a]);
        if (!aw) continue;
        const auto i = static_cast<size_t>(a);
        const double v = axis_mm(a, aw);
        // L20: the current position becomes v in that system.
        g5x[static_cast<size_t>(s)][i] = lv == 2 ? v : pos[i] - g92[i] - tlo[i] - v;
      }
      write_params();
      ++stats.commands;
      return true;
    }
    if (lv == 1) {
      if (!p || !p->integer || p->value < 0) throw fail(b, l->col, "G10 L1 needs P (tool number)");
      ToolEntry e;
      if (const ToolEntry* old = tools.find(static_cast<int>(p->value))) e = *old;
      e.tool = static_cast<int>(p->value);
      for (int a = 0; a < 3; ++a)
        if (const Word* aw = word(axis_names[a])) e.offset[static_cast<size_t>(a)] = to_mm(aw);
      if (const Word* r = word('R')) e.diameter = 2 * to_mm(r);
      for (char c : {'I', 'J', 'Q'}) word(c);
      tools.set(e);
      ++stats.commands;
      return true;
    }
    throw fail(b, l->col, fmt::format("G10 L{} is not supported (L1, L2 and L20 are)", lv));
  }
  if (nmc == 110) {  // G11
    if (!rules->g10_retract)
      throw fail(b, nm->col,
                 fmt::format("G11 (firmware retraction) is not in the {} dialect", rules->name));
    word('S');
    if (retracted) {
      Vec4 t = pos;
      if (retract_zlift > 0) {
        t[2] -= retract_zlift;
        line_to(out, Motion::kRapid, t, b.line);
      }
      t[3] += retract_mm + recover_extra;
      e_prog += (retract_mm + recover_extra) / flow;
      line_to(out, Motion::kLinear, t, b.line, recover_feed);
      retracted = false;
    }
    write_position();
    return true;
  }
  if (nmc >= 920 && nmc <= 923) {
    no_motion_word(gname(nmc).c_str());
    if (nmc == 920) {
      if (!has_axis) throw fail(b, nm->col, "G92 needs at least one axis word");
      if (comp_on()) throw fail(b, nm->col, "G92 with cutter radius compensation on (G40 first)");
      for (int a = 0; a < 4; ++a) {
        const Word* aw = word(axis_names[a]);
        if (!aw) continue;
        const auto i = static_cast<size_t>(a);
        if (a == 3 && !rotary)
          g92[3] = e_prog - to_mm(aw);
        else
          g92[i] = pos[i] - g5x[static_cast<size_t>(cs)][i] - tlo[i] - axis_mm(a, aw);
      }
      g92_saved = g92;
    } else if (nmc == 923) {
      g92 = g92_saved;  // G92.3: the offsets G92.2 put aside (LinuxCNC: parameters 5211-5219)
    } else {
      if (nmc == 921) g92_saved = {};  // G92.1 also zeroes the parameters; G92.2 keeps them
      g92 = {};
    }
    write_params();
    ++stats.commands;
    return true;
  }
  if (nmc == 281 || nmc == 301) {
    (nmc == 281 ? g28_home : g30_home) = pos;
    write_params();
    return true;
  }
  if (nmc == 280 || nmc == 300) {
    no_motion_word(gname(nmc).c_str());
    if (comp_on())
      throw fail(b, nm->col,
                 fmt::format("{} with cutter radius compensation on (G40 first)", gname(nmc)));
    if (rules->g28_homes && nmc == 280) {
      // Marlin's G28 [X] [Y] [Z]: home the named axes (all when none): machine zero.
      Vec4 t = pos;
      bool any = false;
      for (int a = 0; a < 3; ++a)
        if (word(axis_names[a])) {
          t[static_cast<size_t>(a)] = 0.0;
          any = true;
        }
      if (!any) t[0] = t[1] = t[2] = 0.0;
      for (char c : {'O', 'R', 'L'}) word(c);
      line_to(out, Motion::kRapid, t, b.line);
      write_position();
      return true;
    }
    const Vec4& stored = nmc == 280 ? g28_home : g30_home;
    Vec4 home = pos;
    if (has_axis) {
      const Vec4 via = target(false);
      line_to(out, Motion::kRapid, via, b.line);
      for (int a = 0; a < offset_axes; ++a)
        if (w.get(axis_names[a])) home[static_cast<size_t>(a)] = stored[static_cast<size_t>(a)];
    } else {
      for (size_t a = 0; a < static_cast<size_t>(offset_axes); ++a) home[a] = stored[a];
    }
    line_to(out, Motion::kRapid, home, b.line);
    write_position();
    return true;
  }
  const bool g53 = nmc == 530;
  if (g53 && comp_on())
    throw fail(b, nm->col, "G53 with cutter radius compensation on (G40 first)");

  // 17. Motion.
  if (const Word* g = gw(1)) {
    int c = code10(*g);
    if (c >= 380 && c <= 385) {
      if (c < 382 || !rules->probing)
        throw fail(b, g->col,
                   fmt::format("{}: not a probing code in the {} dialect (G38.2 .. G38.5 probe "
                               "in grbl and LinuxCNC programs)",
                               gname(c), rules->name));
      if (!opt.probing)
        throw fail(b, g->col,
                   fmt::format("{}: probing runs in `fpgacnc grbl` or `fpgacnc probe`, not in a "
                               "streamed job (where the probe stops is known only on the "
                               "machine): split the job at the probe",
                               gname(c)));
    }
    if (c == 840 || c == 860 || c == 870 || c == 880)
      throw fail(b, g->col,
                 fmt::format("{}: this cycle needs spindle control (orient, stop or tapping) that "
                             "this machine does not have",
                             gname(c)));
    if (c == 330) throw fail(b, g->col, "G33: spindle-synchronised motion needs a spindle encoder");
    if (c >= 50 && c <= 53) [[unlikely]] {  // G5, G5.1: the whole move here
      spline_block(b, *g, w.letter, used, polar_r ? polar_r : polar_a, out);
      has_axis = false;
      c = kCycleNone;  // no motion mode after a spline (LinuxCNC)
    }
    if (is_cycle(c) && motion != c) cycle_z_set = false;
    if (!is_cycle(c)) cycle_il_set = false;
    motion = c;
    did = true;
  }
  const bool cycle_mode = is_cycle(motion);
  const PlaneAxes pa = plane_axes(plane);
  static constexpr char kOffsetWord[3] = {'I', 'J', 'K'};  // centre offsets of X, Y, Z
  const bool arc_mode = motion == 20 || motion == 30;
  auto unused = [&](char l) { return used[l - 'A'] ? nullptr : w.get(l); };
  const Word* cu = arc_mode ? unused(kOffsetWord[pa.u]) : nullptr;
  const Word* cv = arc_mode ? unused(kOffsetWord[pa.v]) : nullptr;
  const Word* r_word = arc_mode ? unused('R') : nullptr;
  const bool arc_words = cu || cv || r_word;
  if (cycle_mode) {
    for (char l : {'Z', 'R', 'P', 'Q', 'L'}) word(l);
    const PlaneAxes cpa = pa;
    const char wl = axis_names[cpa.w];
    const Word* zw = w.get(wl);
    if (const Word* r = w.get('R')) {
      cycle_r = to_mm(r);
      cycle_r_set = true;
    }
    if (zw) {
      cycle_z = to_mm(zw);
      cycle_z_set = true;
    }
    if (const Word* p = w.get('P')) cycle_p = p->value;
    if (const Word* q = w.get('Q')) {
      if (q->value <= 0) throw fail(b, q->col, "Q (peck depth) must be > 0");
      cycle_q = to_mm(q);
    }
    const bool pos_words = w.get(axis_names[cpa.u]) || w.get(axis_names[cpa.v]) || zw ||
                           w.get('R') || gw(1) || polar_r || polar_a;
    if (pos_words) {
      for (int a = 0; a < 3; ++a) word(axis_names[a]);
      bool given[3] = {w.get('X') != nullptr, w.get('Y') != nullptr, w.get('Z') != nullptr};
      Vec4 hole = pos;
      for (int a = 0; a < 3; ++a)
        if (given[a]) hole[static_cast<size_t>(a)] = to_mm(w.get(axis_names[a]));
      int repeats = 1;
      if (const Word* l = w.get('L')) {
        if (!l->integer || l->value < 1) throw fail(b, l->col, "L (repeats) must be >= 1");
        repeats = static_cast<int>(l->value);
      }
      canned_cycle(b, hole, given, out, repeats, gw(1) ? gw(1) : w.get(axis_names[cpa.u]), polar_r,
                   polar_a);
    }
    if (w.get('E')) throw fail(b, w.get('E')->col, "E in a canned cycle");
  } else if (has_axis && motion >= 382 && motion <= 385) {
    // G38.2 .. G38.5: a straight move at the feed in force that the board ends at the probe.
    const int col = gw(1) ? gw(1)->col : 1;
    move_col = col;
    if (g53)
      throw fail(b, nm->col, "G53 with a probe move: only G0/G1 may use machine coordinates");
    if (comp_on())
      throw fail(b, col,
                 fmt::format("{} with cutter radius compensation on (G40 first)", gname(motion)));
    if (inverse_time)
      throw fail(b, col, fmt::format("{} in inverse time mode (G93): G94 first", gname(motion)));
    Vec4 t = target(false);
    apply_polar(t);
    apply_e(t);
    if (t[3] != pos[3])
      throw fail(b, col, fmt::format("{}: a probe move runs X, Y and Z only", gname(motion)));
    if (rules->feed_required && !feed_given && !w.get('F'))
      throw fail(b, col, fmt::format("no feed given yet: {} needs F", gname(motion)));
    if (feed <= 0.0) {
      const Word* fw = w.get('F');
      throw fail(b, fw ? fw->col : col, fmt::format("feed is 0: {} needs F > 0", gname(motion)));
    }
    if (t[0] == pos[0] && t[1] == pos[1] && t[2] == pos[2])
      throw fail(b, col,
                 fmt::format("{}: the probe target is the current position", gname(motion)));
    Probe pr;
    pr.move = make_move(Motion::kLinear, t, b.line, feed * feed_factor);
    pr.code = motion;
    pr.line = b.line;
    // The front end moves the interpreter to where the board stopped; until then, the target.
    pos = t;
    pos_tlo = tlo;
    move_tlo = tlo;
    out.emplace_back(pr);
    ++stats.moves;
    produced = true;
    write_position();
  } else if (has_axis || (arc_mode && arc_words && (gw(1) || true) && (has_axis || arc_words))) {
    const Word* first_axis = nullptr;
    for (int i = 0; i < b.count && !first_axis; ++i) {
      const char l = b.words[static_cast<size_t>(i)].letter;
      if (l == 'X' || l == 'Y' || l == 'Z' || l == axis_names[3] || l == 'I' || l == 'J' ||
          l == 'K' || l == 'R')
        first_axis = &b.words[static_cast<size_t>(i)];
    }
    const int motion_col = gw(1) ? gw(1)->col : first_axis ? first_axis->col : 1;
    move_col = motion_col;
    if (motion < 0 || motion == kCycleNone)
      throw fail(b, motion_col, "axis words with no motion mode (G0/G1/G2/G3) active");
    Vec4 t = target(g53);
    apply_polar(t);
    if (g53 && (motion == 20 || motion == 30))
      throw fail(b, nm->col, "G53 with an arc: only G0/G1 may use machine coordinates");
    if (g53 && !absolute) throw fail(b, nm->col, "G53 needs G90 (absolute distance mode)");
    apply_e(t);
    Motion mo = static_cast<Motion>(motion / 10);
    double f = feed * feed_factor;
    // A move of the rotary A alone: F is in degrees per minute, whatever G20/G21 (LinuxCNC).
    const bool a_only =
        rotary && t[3] != pos[3] && t[0] == pos[0] && t[1] == pos[1] && t[2] == pos[2];
    if (a_only) f /= unit;
    if (inverse_time && mo != Motion::kRapid) {
      const Word* fw = w.get('F');
      if (!fw || fw->value <= 0)
        throw fail(b, fw ? fw->col : motion_col, "G93 inverse time: each move needs F > 0");
    }
    if (mo != Motion::kRapid && !inverse_time && rules->feed_required && !feed_given && !w.get('F'))
      throw fail(b, motion_col,
                 "no feed given yet: a G1/G2/G3 move needs F (LinuxCNC starts at F0)");
    if (mo != Motion::kRapid && !inverse_time && feed <= 0.0) {
      const Word* fw = w.get('F');
      throw fail(b, fw ? fw->col : motion_col, "feed is 0: a G1/G2/G3 move needs F > 0");
    }
    Move mv = make_move(mo, t, b.line, f);
    if (mo == Motion::kArcCw || mo == Motion::kArcCcw) {
      word(kOffsetWord[pa.u]);
      word(kOffsetWord[pa.v]);
      word('R');
      const Word* pw = word('P');
      if (!arc_words) {
        if (!rules->modal_arc_as_line && !gw(1))
          throw fail(b, motion_col,
                     fmt::format("arc without centre (no {}, {} or R) in the {} dialect",
                                 kOffsetWord[pa.u], kOffsetWord[pa.v], rules->name));
        if (gw(1))
          throw fail(b, gw(1)->col,
                     fmt::format("arc without centre (no {}, {} or R)", kOffsetWord[pa.u],
                                 kOffsetWord[pa.v]));
        // A modal G2/G3 repeated with axis words only: a straight cutting line, as CNCjs does.
        mv.motion = Motion::kLinear;
        ++stats.modal_arc_as_line;
      } else {
        const auto u = static_cast<size_t>(pa.u), v = static_cast<size_t>(pa.v);
        const double su = pos[u], sv = pos[v], eu = t[u], ev = t[v];
        if (pw) {
          if (!pw->integer || pw->value < 1)
            throw fail(b, pw->col, "arc P (turns) must be an integer >= 1");
          mv.extra_turns = static_cast<int>(pw->value) - 1;
        }
        if (r_word) {
          if (cu || cv) throw fail(b, r_word->col, "R and I/J/K on the same arc");
          const double r = to_mm(r_word);
          const double x = eu - su, y = ev - sv;
          const double d = std::hypot(x, y);
          if (d < 1e-9)
            throw fail(b, r_word->col, "R-form arc with end point equal to start point");
          double disc = 4.0 * r * r - x * x - y * y;
          if (disc < 0.0) {
            constexpr double kRTolerance = 1e-3;  // mm: rounding in the file's decimals
            if (d / 2.0 - std::fabs(r) > kRTolerance)
              throw fail(b, r_word->col,
                         fmt::format("impossible arc: radius {:.6g} mm is smaller than half the "
                                     "chord ({:.6g} mm)",
                                     std::fabs(r), d / 2.0));
            disc = 0.0;
          }
          double h = -std::sqrt(disc) / d;
          if (mo == Motion::kArcCcw) h = -h;
          if (r < 0) h = -h;
          mv.center = {su + 0.5 * (x - y * h), sv + 0.5 * (y + x * h)};
        } else {
          auto centre = [&](const Word* cw, size_t axis, double start) {
            if (!cw) return arc_absolute ? offset(static_cast<int>(axis)) : start;
            const double c = to_mm(cw);
            return arc_absolute ? c + offset(static_cast<int>(axis)) : start + c;
          };
          mv.center = {centre(cu, u, su), centre(cv, v, sv)};
          const double r0 = std::hypot(su - mv.center[0], sv - mv.center[1]);
          const double r1 = std::hypot(eu - mv.center[0], ev - mv.center[1]);
          if (r0 < 1e-6) throw fail(b, (cu ? cu : cv)->col, "arc with zero radius");
          if (std::fabs(r1 - r0) > 0.005 && std::fabs(r1 - r0) > 0.001 * r0) {
            if (std::fabs(r1 - r0) > 0.5 * r0)
              throw fail(b, motion_col,
                         fmt::format("arc end point is not on the circle (start radius {:.6g} mm, "
                                     "end radius {:.6g} mm)",
                                     r0, r1));
            ++stats.arc_radius_mismatch;
          }
          mv.full_circle = std::hypot(eu - su, ev - sv) < 1e-9;
        }
      }
    } else if (arc_words || w.get('I') || w.get('J') || w.get('K')) {
      const Word* a = w.get('R')   ? w.get('R')
                      : w.get('I') ? w.get('I')
                      : w.get('J') ? w.get('J')
                                   : w.get('K');
      throw fail(b, a->col, "I/J/K/R words on a G0/G1 move");
    }
    if (inverse_time && mo != Motion::kRapid) {
      double len = 0;
      for (size_t a = 0; a < 3; ++a) len += (t[a] - pos[a]) * (t[a] - pos[a]);
      len = a_only ? std::fabs(t[3] - pos[3]) : std::sqrt(len);
      if (mv.motion == Motion::kArcCw || mv.motion == Motion::kArcCcw) {
        const auto u = static_cast<size_t>(pa.u), v = static_cast<size_t>(pa.v);
        const double r = std::hypot(pos[u] - mv.center[0], pos[v] - mv.center[1]);
        double a0 = std::atan2(pos[v] - mv.center[1], pos[u] - mv.center[0]);
        double a1 = std::atan2(t[v] - mv.center[1], t[u] - mv.center[0]);
        double sweep = a1 - a0;
        const bool cw = mv.motion == Motion::kArcCw;
        if (cw && sweep >= 0) sweep -= 2 * M_PI;
        if (!cw && sweep <= 0) sweep += 2 * M_PI;
        sweep = std::fabs(sweep) + 2 * M_PI * mv.extra_turns;
        const double wlen = t[static_cast<size_t>(pa.w)] - pos[static_cast<size_t>(pa.w)];
        len = std::hypot(r * sweep, wlen);
      }
      mv.feed_mm_min = len * w.get('F')->value * feed_factor;
      if (mv.feed_mm_min <= 0) mv.feed_mm_min = feed;
    }
    push(out, mv);
    write_position();
  } else if (arc_words || (!used['I' - 'A'] && w.get('I')) || (!used['J' - 'A'] && w.get('J')) ||
             (!used['K' - 'A'] && w.get('K')) || (!arc_mode && !used['R' - 'A'] && w.get('R'))) {
    const Word* a = w.get('R')   ? w.get('R')
                    : w.get('I') ? w.get('I')
                    : w.get('J') ? w.get('J')
                                 : w.get('K');
    throw fail(b, a->col, "I/J/K/R words without an arc (G2/G3)");
  }
  if (g53 && !has_axis) throw fail(b, nm->col, "G53 needs axis words on the same line");

  // Every word must have been used by something on the line.
  for (int i = 0; i < b.count; ++i) {
    const Word& wd = b.words[static_cast<size_t>(i)];
    const char l = wd.letter;
    if (l == 'G' || l == 'M' || l == 'N' || l == kPolarRadius || l == kPolarAngle) continue;
    const char as = (l == 'A' && rules->a_is_extruder) ? 'E' : l;
    if (!used[as - 'A'])
      throw fail(b, wd.col, fmt::format("'{}' word with nothing on the line that uses it", l));
  }
  if (did && !has_axis) ++stats.commands;

  // 18. Stops.
  for (int k = 0; k < w.mcount; ++k) {
    const int c = w.mcodes[k];
    if (c == 0 || (c == 1 && rules->dialect != Dialect::kLinuxCnc && rules->unknown_m_warns)) {
      out.emplace_back(Pause{Pause::Reason::kProgramPause, 0,
                             b.message_kind == MessageKind::kText && !b.text.empty()
                                 ? b.text
                                 : "program paused (M0): resume to go on",
                             b.line});
      ++stats.pauses;
      produced = true;
    } else if (c == 1) {
      if (opt.optional_stop) {
        out.emplace_back(
            Pause{Pause::Reason::kOptionalStop, 0, "optional stop (M1): resume to go on", b.line});
        ++stats.pauses;
      }
      produced = true;
    } else if (c == 2 || c == 30) {
      produced = true;
      return false;
    }
  }
  return true;
}

// Canned cycles G73, G81, G82, G83, G85, G89 as LinuxCNC runs them (docs/gcode.md, "Canned
// cycles"): in the active plane, w the drilling axis. Preliminary move: if w is below R, up to R;
// per hole: rapid to the hole at the current level, down to R, the cycle's moves, back to the
// clear level (G98: the level before the cycle or R, whichever is higher; G99: R).
void Interpreter::Impl::canned_cycle(const Block& b, const Vec4& given_pos, bool given[3],
                                     std::vector<Command>& out, int repeats, const Word* first_col,
                                     const Word* polar_r, const Word* polar_a) {
  const PlaneAxes pa = plane_axes(plane);
  const auto u = static_cast<size_t>(pa.u), v = static_cast<size_t>(pa.v),
             wa = static_cast<size_t>(pa.w);
  const int col = first_col ? first_col->col : 1;
  if (comp_on())
    throw fail(b, col,
               fmt::format("{}: no canned cycle with cutter radius compensation on (G40 first)",
                           gname(motion)));
  if (!cycle_z_set)
    throw fail(b, col,
               fmt::format("{}: the cycle needs {} (the bottom)", gname(motion), axis_names[wa]));
  if (!cycle_r_set)
    throw fail(b, col, fmt::format("{}: the cycle needs R (the retract level)", gname(motion)));
  if ((motion == 730 || motion == 830) && cycle_q <= 0)
    throw fail(b, col, fmt::format("{}: the cycle needs Q (the peck depth) > 0", gname(motion)));
  if (feed <= 0 && !inverse_time) throw fail(b, col, "feed is 0: a canned cycle needs F > 0");
  // LinuxCNC's levels: the initial level of the series (kept from its first block), the level at
  // the start of this block, R and the bottom.
  if (!cycle_il_set) {
    cycle_il = pos[wa];
    cycle_il_set = true;
    cycle_positioned = false;
  }
  double old_w = cycle_il;
  double current_w = pos[wa];
  double r, bottom;
  if (absolute) {
    r = cycle_r + offset(pa.w);
    bottom = cycle_z + offset(pa.w);
  } else {
    r = old_w + cycle_r;
    bottom = r + cycle_z;
  }
  if (bottom > r + 1e-9)
    throw fail(b, col,
               fmt::format("{}: the bottom ({}) is above R", gname(motion), axis_names[wa]));
  const double f = feed * feed_factor;
  const double rapid_delta = 0.010 * kInch;  // LinuxCNC's G73/G83 back-off (0.010 inch)
  auto at = [&](double cu, double cv, double cw) {
    Vec4 t = pos;
    t[u] = cu;
    t[v] = cv;
    t[wa] = cw;
    return t;
  };
  if (old_w < r) {  // below R: straight up to R first
    line_to(out, Motion::kRapid, at(pos[u], pos[v], r), b.line);
    old_w = r;
    current_w = r;
  }
  const double clear = retract_to_r ? r : old_w;
  double hu = pos[u], hv = pos[v];
  const bool polar = polar_r || polar_a;
  if (polar && plane != Plane::kXY)
    throw fail(b, (polar_r ? polar_r : polar_a)->col, "polar coordinates need the XY plane (G17)");
  // Polar: distance and angle about the program origin (G91: added per repeat).
  const double d_r = polar_r ? polar_r->value * unit : 0.0;
  const double d_a = polar_a ? polar_a->value * M_PI / 180.0 : 0.0;
  if (absolute) {
    if (given[u]) hu = given_pos[u] + offset(pa.u);
    if (given[v]) hv = given_pos[v] + offset(pa.v);
    if (polar) {
      const double px = hu - offset(0), py = hv - offset(1);
      const double rr = polar_r ? d_r : std::hypot(px, py);
      const double aa = polar_a ? d_a : std::atan2(py, px);
      hu = rr * std::cos(aa) + offset(0);
      hv = rr * std::sin(aa) + offset(1);
    }
  }
  for (int k = 0; k < repeats; ++k) {
    if (!absolute) {
      if (given[u]) hu += given_pos[u];
      if (given[v]) hv += given_pos[v];
      if (polar) {
        const double px = hu - offset(0), py = hv - offset(1);
        if (px == 0.0 && py == 0.0)
          throw fail(b, (polar_r ? polar_r : polar_a)->col,
                     "incremental polar move from the origin is indeterminate");
        const double rr = std::hypot(px, py) + d_r;
        const double aa = std::atan2(py, px) + d_a;
        hu = rr * std::cos(aa) + offset(0);
        hv = rr * std::sin(aa) + offset(1);
      }
    }
    // The first positioning move of a series runs at the current level, every later one at the
    // clear level (LinuxCNC's CYCLE_MACRO).
    line_to(out, Motion::kRapid, at(hu, hv, cycle_positioned ? clear : current_w), b.line);
    cycle_positioned = true;
    if (old_w != r) line_to(out, Motion::kRapid, at(hu, hv, r), b.line);
    switch (motion) {
      case 810:
        line_to(out, Motion::kLinear, at(hu, hv, bottom), b.line, f);
        line_to(out, Motion::kRapid, at(hu, hv, clear), b.line);
        break;
      case 820:
      case 890:
        line_to(out, Motion::kLinear, at(hu, hv, bottom), b.line, f);
        out.emplace_back(Dwell{cycle_p, b.line});
        if (motion == 820)
          line_to(out, Motion::kRapid, at(hu, hv, clear), b.line);
        else
          line_to(out, Motion::kLinear, at(hu, hv, clear), b.line, f);
        break;
      case 830:
      case 730: {
        for (double depth = r - cycle_q; depth > bottom; depth -= cycle_q) {
          line_to(out, Motion::kLinear, at(hu, hv, depth), b.line, f);
          if (motion == 830) line_to(out, Motion::kRapid, at(hu, hv, r), b.line);
          line_to(out, Motion::kRapid, at(hu, hv, depth + rapid_delta), b.line);
        }
        line_to(out, Motion::kLinear, at(hu, hv, bottom), b.line, f);
        line_to(out, Motion::kRapid, at(hu, hv, clear), b.line);
        break;
      }
      case 850:
        line_to(out, Motion::kLinear, at(hu, hv, bottom), b.line, f);
        line_to(out, Motion::kLinear, at(hu, hv, r), b.line, f);
        line_to(out, Motion::kRapid, at(hu, hv, clear), b.line);
        break;
      default:
        throw fail(b, col, fmt::format("{}: not supported", gname(motion)));
    }
    ++stats.canned_cycles;
  }
}

Interpreter::Interpreter(std::string file_name, Options options, const DialectChoice& dialect,
                         Params& params)
    : impl_(std::make_unique<Impl>(std::move(file_name), std::move(options), dialect, params)) {}
Interpreter::~Interpreter() = default;

// Cutter radius compensation takes the block's commands (moves as programmed) and puts back
// what the machine runs; a block with no compensation in force skips it.
void Interpreter::Impl::compensate(const Block& b, std::vector<Command>& out, size_t first,
                                   bool go_on) {
  std::vector<Command> cmds(std::make_move_iterator(out.begin() + static_cast<long>(first)),
                            std::make_move_iterator(out.end()));
  out.erase(out.begin() + static_cast<long>(first), out.end());
  const size_t at =
      comp_event == CompEvent::kNone ? cmds.size() : std::min(comp_at - first, cmds.size());
  std::vector<Command> after(std::make_move_iterator(cmds.begin() + static_cast<long>(at)),
                             std::make_move_iterator(cmds.end()));
  cmds.resize(at);
  try {
    comp.process(cmds, out, b.line);
    if (comp_event == CompEvent::kOn)
      comp.start(comp_side, comp_radius, plane, comp_pos);
    else if (comp_event == CompEvent::kOff)
      comp.stop(out, b.line);
    comp.process(after, out, b.line);
    if (!go_on) comp.flush(out, b.line);
  } catch (const CutterComp::Error& e) {
    throw fail(b, move_col, e.what());
  }
}

bool Interpreter::execute(const Block& block, std::vector<Command>& out) {
  Impl& m = *impl_;
  const size_t first = out.size();
  const bool engaged = m.comp.engaged();
  m.comp_event = Impl::CompEvent::kNone;
  m.move_col = 1;
  const bool go_on = m.execute(block, out);
  m.last_line = block.line;
  // LinuxCNC reads the position back after a tool change: the program position from before any
  // tool length offset change since the last move, so the next move goes there with the new
  // offset (the machine moves by the change).
  if (m.tool_changed) {
    m.pos_tlo = m.move_tlo;
    m.tool_changed = false;
  }
  if (engaged || m.comp_event != Impl::CompEvent::kNone) {
    m.compensate(block, out, first, go_on);
    m.comp_event = Impl::CompEvent::kNone;
  }
  if (m.rules->syntax.ngc) m.write_named();  // what the next line may read
  return go_on;
}

void Interpreter::flush(std::vector<Command>& out) {
  impl_->comp.flush(out, impl_->last_line);
}

void Interpreter::finish() {
  if (!impl_->produced)
    throw Error(impl_->file, static_cast<int>(std::max<uint64_t>(impl_->stats.lines, 1)), 1,
                "empty job (no motion and no commands)");
}

const Vec4& Interpreter::position() const {
  return impl_->pos;
}
const Stats& Interpreter::stats() const {
  return impl_->stats;
}

namespace {

Stats run(std::string text, const std::string& file_name, const Options& options,
          const std::function<void(const Command&)>& sink) {
  bool reader_block_delete = false;
  const DialectChoice choice = detect_dialect(text, options.dialect, options.dialect_source);
  Params params;
  Interpreter interp(file_name, options, choice, params);
  Syntax syntax = dialect_rules(choice.dialect).syntax;
  reader_block_delete = options.block_delete;
  if (choice.nested_comments) syntax.paren_in_comment = true;
  syntax.dialect_name = dialect_rules(choice.dialect).name;
  Reader reader(file_name, std::move(text), syntax, params);
  reader.set_block_delete(reader_block_delete);
  Block block;
  std::vector<Command> out;
  int last_line = 0;
  while (reader.next(block)) {
    last_line = block.line;
    out.clear();
    const bool go_on = interp.execute(block, out);
    for (const auto& c : out) sink(c);
    if (!go_on) {
      reader.end_program();
      break;
    }
  }
  (void)last_line;
  out.clear();
  interp.flush(out);
  for (const auto& c : out) sink(c);
  interp.finish();
  return interp.stats();
}

std::string slurp(std::istream& in, const std::string& file_name) {
  std::ostringstream s;
  if (in.peek() != std::char_traits<char>::eof()) s << in.rdbuf();
  if (in.bad()) throw Error(file_name, 0, 0, "read error");
  return std::move(s).str();
}

}  // namespace

Stats parse_stream(std::istream& in, const std::string& file_name, Options options,
                   const std::function<void(const Command&)>& sink) {
  return run(slurp(in, file_name), file_name, options, sink);
}

Program parse_stream(std::istream& in, const std::string& file_name, Options options) {
  Program p;
  p.file_name = file_name;
  p.stats = run(slurp(in, file_name), file_name, options,
                [&](const Command& c) { p.commands.push_back(c); });
  return p;
}

Program parse_file(const std::string& path, Options options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, 0, 0, "cannot open file");
  return parse_stream(f, path, std::move(options));
}

Program parse_string(std::string_view text, const std::string& file_name, Options options) {
  Program p;
  p.file_name = file_name;
  p.stats = run(std::string(text), file_name, options,
                [&](const Command& c) { p.commands.push_back(c); });
  return p;
}

}  // namespace fpgacnc::gcode
