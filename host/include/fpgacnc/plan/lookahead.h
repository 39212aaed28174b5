// Look-ahead planner (grbl-like) and the conversion of planned trapezoids to the integer
// LINE_PROFILE fields of protocol v2 (docs/motion.md, docs/protocol.md "LINE_PROFILE").
//
// Input: the straight segments of a plan::Plan (steps per axis, executed feed). Each becomes one
// or more blocks (a block = one LINE_PROFILE frame; moves with n_dom >= 2^24 are split into
// equal parts). Per block: path length L (XYZ, or |E| for an E-only move), cruise speed
// vc = min(executed feed, per-axis max feeds incl. E, STEP min-period rate), path acceleration
// a = min over moving axes of a_axis * L / |d_axis|, taken from the integer A actually sent
// (A = floor(a * n_dom / L / clk^2 * 2^48)), so the plan and the hardware use the same value.
// Junctions: grbl's junction deviation v^2 = a_j * delta * s / (1 - s), s = sin(theta/2),
// a_j = the acceleration limit along the junction vector, capped by both cruise speeds.
// Window: a block's profile is final (emitted) only when the next W blocks are known or the
// program ends; the reverse pass always starts from a stop at the end of the window, so every
// prefix of the emitted + tentative plan ends at its stop speed.
// Forced stops: G4 dwells, M109/M190 (heat and wait) and the program end. M3/M5 and S changes
// do not stop (the laser power travels per segment in the frame, like grbl's laser mode);
// M104/M140 do not stop.
//
// Hardware recurrence (docs/motion.md): per clock U += V; the segment ends on the first clock with
// U >= n_dom * 2^48; else V = U >= D * 2^48 ? max(V - A, V_exit) : min(V + A, V_cruise).
// simulate_profile() evaluates it exactly in closed form per phase (same integers).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <variant>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::plan {

inline constexpr int kFracBits = 48;  // V and A: 2^-48 dominant steps (per clock)
inline constexpr int64_t kMaxProfileSteps = protocol::v2::kProfileNDomMax;  // n_dom < 2^24
inline constexpr uint64_t kMaxVCruise = protocol::v2::kProfileVMax - 1;     // V_cruise < 2^47
inline constexpr uint64_t kMaxA = 0xFFFFFFFFull;                            // A is u32

// The integer fields of one LINE_PROFILE frame (besides code, power and steps).
struct ProfileFields {
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;  // u48, 2^-48 dominant steps per clock
  uint32_t a = 0;                                  // 2^-48 dominant steps per clock^2
  uint32_t d = 0;                                  // dominant step at which deceleration starts
  uint32_t n_dom = 0;
};

// The recurrence in general form: n_end path units (n_dom dominant steps for a line, C_TOTAL
// cost units for an arc), rates in 2^-48 units per clock, A in 2^-48 units per clock^2, D units.
struct Recurrence {
  uint64_t n_end = 0;
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;  // < 2^63
  uint64_t a = 0;                                  // < 2^48
  uint64_t d = 0;
};

// ARC frame geometry (docs/protocol.md "ARC"): steps relative to the arc's start.
struct ArcFields {
  uint8_t code = 2;  // 2 = G2 (CW), 3 = G3 (CCW)
  // Plane (flags bits 3:2): 0 XY (G17), 1 ZX (G18), 2 YZ (G19); i/dx along the plane's u axis,
  // j/dy along v, dz along the helix axis w (gcode::plane_axes).
  uint8_t plane = 0;
  int32_t i = 0, j = 0, dx = 0, dy = 0, dz = 0;
  uint32_t n_ramp = 0;
  uint64_t c_total = 0;
};
inline constexpr uint64_t kMaxArcV = (uint64_t{1} << 63) - 1;
inline constexpr uint64_t kMaxArcA = (uint64_t{1} << 48) - 1;
inline constexpr uint64_t kMaxArcCost = protocol::v2::kArcCTotalLimit - 1;

// Exact result of the hardware recurrence for one profiled segment.
struct ProfileRun {
  uint64_t clocks = 0;  // clocks from the segment's first clock to its end (U >= n_dom * 2^48)
  uint64_t v_last = 0;  // V used on the last clock (the exit rate the next segment meets)
  uint64_t v_peak = 0;  // largest V used
  // Speed breakpoints (clock from segment start, V used from that clock on): the piecewise
  // linear speed, recorded only when asked.
  std::vector<std::pair<uint64_t, uint64_t>> knots;
};

// Throws std::invalid_argument when the fields break the device's limits (docs/protocol.md,
// LINE_PROFILE) or the segment would never end. Cost: O(phases * log) (binary searches over 128-bit
// quadratics).
ProfileRun simulate_profile(const ProfileFields& f, bool record_knots = false);
ProfileRun simulate_recurrence(const Recurrence& r, bool record_knots = false);
// Same by stepping every clock (reference for tests; only for short segments).
ProfileRun simulate_profile_naive(const ProfileFields& f);
// Why the device would NAK these fields (BAD_FIELD), or nullptr when acceptable.
const char* profile_field_error(const ProfileFields& f);

struct MotionLimits {
  std::array<double, 4> v_max{};  // mm/s per axis
  std::array<double, 4> a_max{};  // mm/s^2 per axis
  std::array<double, 4> steps_per_mm{};
  double junction_deviation = 0.01;  // mm
  size_t window = 64;
  uint64_t clk_hz = 50'000'000;
  uint32_t min_period = 200;  // STEP high + low, clocks: caps the dominant step rate
  // Native arcs (ARC frames): the reference walk of the arc helper (N_RAMP and C_TOTAL for
  // the geometry in `f`, code/i/j/dx/dy set; nullopt when the walk cannot close the arc).
  // Empty: arcs stay chords.
  std::function<std::optional<std::pair<uint32_t, uint64_t>>(const ArcFields& f)> arc_walk;
};
MotionLimits motion_limits(const config::MachineConfig& cfg);

// One planned block: geometry, plan in mm/s and the integer fields.
struct Profile {
  size_t segment_index = 0;  // index of the plan segment it comes from
  int source_line = 0;
  uint8_t code = 0;
  bool rapid = false;  // Segment::rapid
  double spindle_s = -1.0;
  Steps4 steps{};
  bool split = false;  // part of a move split because n_dom >= 2^24
  double length_mm = 0.0;
  double v_entry = 0.0, v_cruise = 0.0, v_exit = 0.0, accel = 0.0;  // planned, mm/s, mm/s^2
  double v_stop = 0.0;      // stop speed of this block, mm/s (V_stop converted)
  double lsb_mm_s = 0.0;    // mm/s of one V LSB in this block (1 / scale)
  bool stop_after = false;  // planned to stop at its end (exit = V_stop)
  ProfileFields fields;     // LINE_PROFILE (lines)
  bool arc = false;         // an ARC frame: arc_fields + rec, `fields` unused
  ArcFields arc_fields;
  Recurrence rec;       // the recurrence actually sent (lines: the same values as `fields`)
  uint64_t clocks = 0;  // simulate_profile(fields).clocks
  uint64_t v_last = 0;  // simulate_profile(fields).v_last
};

struct ProfileStats {
  uint64_t blocks = 0;
  uint64_t split_moves = 0;
  uint64_t forced_stops = 0;    // dwells, M109/M190
  uint64_t a_clamped = 0;       // A below 1 LSB raised to 1 (limit too small for the resolution)
  uint64_t d_adjusted = 0;      // D lowered after the exact check (exit rate was above V_exit)
  uint64_t exit_overshoot = 0;  // could not bring the exit down to V_exit even with D = 0
  uint64_t total_clocks = 0;    // sum of block clocks + dwell clocks
  uint64_t arcs = 0;            // ARC blocks
  uint64_t arcs_as_chords = 0;  // arcs that could not be sent natively (chords instead)
};

// Pauses, outputs and messages come out in their place between the profiles: before the first
// profile of the segment that followed them in the plan.
using ProfileItem =
    std::variant<Profile, Dwell, HeaterCommand, gcode::Pause, gcode::Output, gcode::Message>;

struct ProfilePlan {
  std::vector<ProfileItem> items;
  ProfileStats stats;
};

// Streaming look-ahead over blocks. push() may emit finished profiles; stop() plans the window
// to a stop and emits it all (dwell, M109/M190, end of program).
class Lookahead {
 public:
  explicit Lookahead(const MotionLimits& lim);
  // Adds one plan segment (split into blocks if needed); emitted profiles go to out().
  void push(const Segment& s, size_t segment_index);
  // Adds one G2/G3 move as an ARC block from its chord segments (consecutive, all with the
  // move's arc_id; first_index = the first chord's segment index). Returns false (nothing
  // added) when the arc cannot be sent natively: the caller pushes the chords instead.
  bool push_arc(const gcode::Move& m, const std::vector<Segment>& chords, size_t first_index);
  void stop();
  // Profiles final so far (moved out).
  std::vector<Profile> take();
  // The whole current plan as if the program ended now: emitted-so-far (not taken) profiles
  // are not included; returns the tentative profiles of the window, planned to stop (tests).
  std::vector<Profile> preview() const;
  const ProfileStats& stats() const { return stats_; }
  size_t window_size() const { return buf_.size(); }

 private:
  struct Block {
    Profile p;
    double scale_v = 0.0;             // LSB per mm/s
    double l_eff = 0.0;               // length used for speed changes, mm (L minus a safety margin)
    double v_junction_max = 0.0;      // entry junction limit, mm/s
    double junction_deviation = 0.0;  // mm at its entry junction (0: the machine's)
    bool exact_stop = false;          // G61: plan a stop at its end
    std::array<double, 4> unit{};     // path direction at the start (XYZ, or E alone)
    std::array<double, 4> unit_out{};  // at the end (= unit for a line)
    uint64_t v_cap = 0;                // largest V field (LSB)
    uint64_t v_stop = 0;               // stop rate (LSB)
  };
  // Fills scale, A, stop rate, margin of a block of n_units path units and length p.length_mm.
  void set_block_rates(Block& b, double n_units, double vc, double acc, uint64_t v_cap,
                       uint64_t a_max);
  void add_block(Block b);
  // Plans buf_[0..] from entry prev_exit_ to a stop at the end; returns exit speeds.
  std::vector<double> plan_exits(const std::deque<Block>& buf) const;
  Profile finalize(const Block& b, double v_entry, double v_exit, bool stop_after,
                   ProfileStats& st) const;
  MotionLimits lim_;
  std::deque<Block> buf_;
  std::optional<std::array<double, 4>> last_unit_;  // end direction of the last emitted block
  double last_vc_ = 0.0;
  bool last_exact_ = false;
  double prev_exit_ = 0.0;  // planned exit speed of the last emitted block (mm/s path)
  std::vector<Profile> out_;
  ProfileStats stats_;
};

// Plans every segment of `plan` (dwells and M109/M190 force stops; heater commands pass
// through). Throws std::invalid_argument for a segment that cannot be converted.
ProfilePlan plan_profiles(const Plan& plan, const config::MachineConfig& cfg);
// Same with explicit limits; with lim.arc_walk set, G2/G3 chords (Segment::arc_id) are sent as
// ARC blocks where push_arc accepts them (counted in stats.arcs; else chords, arcs_as_chords).
ProfilePlan plan_profiles(const Plan& plan, const MotionLimits& lim);

// The integer reference walk of the circular DDA (fpgacnc/models/arc_walk.h, arc::plan) as an
// arc_walk.
decltype(MotionLimits::arc_walk) reference_arc_walk();

// Junction speed limit (mm/s) between two unit directions under junction deviation delta and
// per-axis accelerations (grbl): 0 for a reversal, +inf for a straight continuation.
double junction_speed(const std::array<double, 4>& u_prev, const std::array<double, 4>& u_next,
                      double delta, const std::array<double, 4>& a_max);

}  // namespace fpgacnc::plan
