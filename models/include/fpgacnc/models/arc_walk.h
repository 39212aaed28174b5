// arc_walk: the integer reference of the circular DDA (rtl/motion/arc_dda.v, docs/motion.md "Arcs",
// ARC frame in docs/protocol.md). Header-only, no SystemC: the host packer includes it to compute
// N_RAMP and C_TOTAL, the tests and the twin include it to compute the exact edge list.
//
// Geometry relative to the arc's start (steps, on the lattice): centre (I, J), end (DX, DY), CCW
// or CW, DZ steps of Z over the arc. The walk runs in coordinates relative to the centre: it
// starts at P0 = (-I, -J) and ends at P1 = (DX - I, DY - J); DX = DY = 0 is a full circle.
//
// Walk (one lattice move per step; all integer):
//   F = x^2 + y^2 - T, T the target radius^2 (T = R0^2 + ramp steps so far).
//   t = s * (-y, x) the tangent (s = +1 CCW, -1 CW); a = sign(t_x) or -sign(x) when t_x = 0,
//   b = sign(t_y) or -sign(y) when t_y = 0 (the zero component points inward).
//   Candidates: D = (a, b) always, A = (a, 0) when t_x != 0, B = (0, b) when t_y != 0; each
//   moves strictly forward in angle (cost > 0). F(P + d) = F + 2(x dx + y dy) + dx^2 + dy^2.
//   Take the candidate with the smallest |F(P + d)|, ties in the order D, A, B.
//   Cost of the move: |x dy - y dx| (x, y before the move) = |x| + |y| for D, |y| for A, |x| for B.
//   Target ramp: T steps by q or q + 1 (Bresenham: acc += r; acc >= N takes the +1 and acc -= N),
//   q = floor(dT / N_RAMP), r = dT - q N_RAMP, dT = R1^2 - R0^2, once before each of the first
//   N_RAMP choices (the first step, q, before move 1: F = -q, acc = r), so move k is chosen
//   against T_k and moves N_RAMP, N_RAMP + 1, ... against R1^2 exactly.
//   The walk ends with the move that reaches P1. Guard: it also stops (error) when the cumulative
//   cost reaches C_TOTAL before P1, or reaches P1 with a different total.
// Timing (one clock = one path tick; U, V: UQ48.48 / UQ16.48 cost units, prof's rules):
//   U(0) = 0, V(0) = V_entry; U(c+1) = U(c) + V(c);
//   V(c+1) = U(c+1) >= D*2^48 ? max(V(c) - A, V_exit) : min(V(c) + A, V_cruise).
//   The walk needs WALK_CLOCKS clocks to prepare a move: move k is ready on clock
//   r_1 = WALK_CLOCKS - 1, r_k = c_{k-1} + WALK_CLOCKS, and happens on the first clock c >= r_k
//   with floor(U(c) / 2^48) >= C_k (C_k = cost of moves 1..k). `late` when U(r_k - 1) already
//   reached C_k (the move waited for the walk: tangential speed above the host rule).
//   Z: z(c) = min(|DZ|, floor(U(c) |DZ| / (C_TOTAL 2^48))), one step on every clock where it grows.
//   Output pins (rtl/motion/arc_dda.v) show an event of clock c on clock c + 1.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "fpgacnc/models/ramp.h"

namespace fpgacnc::models::arc {

using u128 = unsigned __int128;
using i128 = __int128;

inline constexpr int WALK_CLOCKS =
    4;                           // clocks between two moves at the fastest (rtl/motion/arc_dda.v)
inline constexpr int FRAC = 48;  // fractional bits of U, V, A

struct Geometry {
  int32_t i = 0, j = 0;    // centre - start
  int32_t dx = 0, dy = 0;  // end - start (0, 0: full circle)
  bool ccw = true;         // G3 (true) or G2
};

struct Move {
  int8_t dx = 0, dy = 0;
  uint32_t cost = 0;
};

struct WalkResult {
  std::vector<Move> moves;
  uint64_t c_total = 0;  // sum of the costs
  bool reached = false;  // the walk reached P1 (within the move limit)
};

inline int sgn(int64_t v) {
  return (v > 0) - (v < 0);
}

// Floor division and remainder (r in [0, n)).
inline void floor_divmod(int64_t num, int64_t n, int64_t& q, int64_t& r) {
  q = num / n;
  r = num % n;
  if (r < 0) {
    r += n;
    q -= 1;
  }
}

inline int64_t delta_t(const Geometry& g) {
  const int64_t x0 = -int64_t{g.i}, y0 = -int64_t{g.j};
  const int64_t x1 = int64_t{g.dx} - g.i, y1 = int64_t{g.dy} - g.j;
  return (x1 * x1 + y1 * y1) - (x0 * x0 + y0 * y0);
}

// The walk state between moves (the RTL holds the same registers).
struct Walker {
  int64_t x = 0, y = 0, f = 0;
  int64_t q = 0, r = 0, n_ramp = 1, acc = 0, m = 0;
  int s = 1;
  int last_a = 0, last_b = 0;  // the tangent signs a, b of the last move returned by next()

  Walker(const Geometry& g, uint32_t nramp) {
    x = -int64_t{g.i};
    y = -int64_t{g.j};
    s = g.ccw ? 1 : -1;
    n_ramp = nramp == 0 ? 1 : nramp;
    floor_divmod(delta_t(g), n_ramp, q, r);
    // the first ramp step (q: r < n_ramp gives no carry) is applied before the first choice
    f = -q;
    acc = r;
    m = 1;
  }

  Move next() {
    const int64_t tx = -s * y, ty = s * x;
    const int a = tx != 0 ? sgn(tx) : -sgn(x);
    const int b = ty != 0 ? sgn(ty) : -sgn(y);
    last_a = a;
    last_b = b;
    const int64_t fa = f + 2 * a * x + 1;
    const int64_t fb = f + 2 * b * y + 1;
    const int64_t fd = f + 2 * a * x + 2 * b * y + 2;
    const auto mag = [](int64_t v) { return v < 0 ? -v : v; };
    const bool va = tx != 0, vb = ty != 0;
    Move mv;
    int64_t fnew;
    if ((!va || mag(fd) <= mag(fa)) && (!vb || mag(fd) <= mag(fb))) {
      mv = {static_cast<int8_t>(a), static_cast<int8_t>(b), static_cast<uint32_t>(mag(x) + mag(y))};
      fnew = fd;
    } else if (va && (!vb || mag(fa) <= mag(fb))) {
      mv = {static_cast<int8_t>(a), 0, static_cast<uint32_t>(mag(y))};
      fnew = fa;
    } else {
      mv = {0, static_cast<int8_t>(b), static_cast<uint32_t>(mag(x))};
      fnew = fb;
    }
    if (m < n_ramp) {
      int64_t step = q;
      acc += r;
      if (acc >= n_ramp) {
        acc -= n_ramp;
        step += 1;
      }
      fnew -= step;
    }
    m += 1;
    f = fnew;
    x += mv.dx;
    y += mv.dy;
    return mv;
  }
};

// The whole walk. Stops at P1, or when the cost reaches c_limit (0: no limit) or after max_moves.
inline WalkResult walk(const Geometry& g, uint32_t n_ramp, uint64_t c_limit = 0,
                       uint64_t max_moves = 0) {
  WalkResult res;
  const int64_t x1 = int64_t{g.dx} - g.i, y1 = int64_t{g.dy} - g.j;
  if (max_moves == 0) {
    const int64_t r = std::llabs(g.i) + std::llabs(g.j) + std::llabs(x1) + std::llabs(y1);
    max_moves = static_cast<uint64_t>(8 * r + 64);
  }
  Walker w(g, n_ramp);
  while (res.moves.size() < max_moves) {
    const Move mv = w.next();
    res.moves.push_back(mv);
    res.c_total += mv.cost;
    if (w.x == x1 && w.y == y1) {
      res.reached = true;
      break;
    }
    if (c_limit != 0 && res.c_total >= c_limit) break;
  }
  return res;
}

// Swept angle from P0 to P1 in the arc's direction, (0, 2 pi]; 2 pi for a full circle (and for an
// end on the start's ray).
inline double sweep(const Geometry& g) {
  const double a0 = std::atan2(-double(g.j), -double(g.i));
  const double a1 = std::atan2(double(g.dy) - g.j, double(g.dx) - g.i);
  double th = g.ccw ? a1 - a0 : a0 - a1;
  const double two_pi = 2.0 * M_PI;
  th = std::fmod(th, two_pi);
  if (th < 0) th += two_pi;
  if (th <= 0.0 || (g.dx == 0 && g.dy == 0)) th = two_pi;
  return th;
}

// True XY length of the ideal arc (radius linear in angle from R0 to R1), steps.
inline double ideal_length(const Geometry& g) {
  const double r0 = std::hypot(double(g.i), double(g.j));
  const double r1 = std::hypot(double(g.dx) - g.i, double(g.dy) - g.j);
  const double th = sweep(g);
  // length of r(phi) = r0 + (r1 - r0) phi / th: integral of sqrt(r^2 + r'^2), Simpson.
  const int n = 256;
  const double dr = (r1 - r0) / th;
  double s = 0;
  for (int k = 0; k <= n; ++k) {
    const double phi = th * k / n;
    const double r = r0 + dr * phi;
    const double w = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
    s += w * std::sqrt(r * r + dr * dr);
  }
  return s * th / (3.0 * n);
}

// Host choice of N_RAMP: 90 % of the expected number of moves (radius times the integral of
// max(|cos|, |sin|) over the swept angles: one move per unit of the major coordinate), at least 1.
inline uint32_t choose_n_ramp(const Geometry& g) {
  const double r0 = std::hypot(double(g.i), double(g.j));
  const double r1 = std::hypot(double(g.dx) - g.i, double(g.dy) - g.j);
  const double th = sweep(g);
  const double a0 = std::atan2(-double(g.j), -double(g.i));
  const int n = 64 + static_cast<int>(th * 64);
  double s = 0;
  for (int k = 0; k < n; ++k) {
    const double p = a0 + (g.ccw ? 1 : -1) * (k + 0.5) * th / n;
    s += std::fmax(std::fabs(std::cos(p)), std::fabs(std::sin(p)));
  }
  const double est = 0.5 * (r0 + r1) * s * th / n;
  const double nr = std::floor(0.9 * est);
  return nr < 1 ? 1u : static_cast<uint32_t>(nr);
}

// What the host packer needs: N_RAMP, C_TOTAL, and whether the walk lands on the end point.
struct Plan {
  uint32_t n_ramp = 1;
  uint64_t c_total = 0;
  uint64_t moves = 0;
  bool ok = false;
};

// Angle (radians) the walk turns about the centre: equals sweep(g) when it lands on the end point
// in the first pass; one turn more when it missed it.
inline double walked_angle(const Geometry& g, const std::vector<Move>& moves) {
  int64_t x = -int64_t{g.i}, y = -int64_t{g.j};
  double phi = 0;
  for (const Move& m : moves) {
    const int64_t nx = x + m.dx, ny = y + m.dy;
    const double cr = double(x) * double(ny) - double(y) * double(nx);
    const double dt = double(x) * double(nx) + double(y) * double(ny);
    phi += (g.ccw ? 1.0 : -1.0) * std::atan2(cr, dt);
    x = nx;
    y = ny;
  }
  return phi;
}

// The host's choice: the estimate first, then halving N_RAMP (the ramp must be done before the
// walk comes near the end point; tiny arcs need a short ramp) until the walk lands on the end
// point in its first pass. ok = false: no N_RAMP works (the host cuts the arc into chords).
inline Plan plan(const Geometry& g) {
  Plan p;
  const double th = sweep(g);
  for (uint32_t n = choose_n_ramp(g);; n /= 2) {
    if (n == 0) n = 1;
    const WalkResult w = walk(g, n);
    if (w.reached && std::fabs(walked_angle(g, w.moves) - th) < 1e-6) {
      p.n_ramp = n;
      p.c_total = w.c_total;
      p.moves = w.moves.size();
      p.ok = true;
      return p;
    }
    if (n == 1) break;
  }
  return p;
}

// Host scaling of the profile: K = C_TOTAL / L cost units per step of arc (L: ideal_length), so
// that a tangential speed of v steps per clock is V = v K 2^48 (likewise A, and D = K x the
// distance in steps at which deceleration starts).
inline double cost_per_step(const Geometry& g, uint64_t c_total) {
  return double(c_total) / ideal_length(g);
}
inline uint64_t to_fixed48(double cost_units) {
  return static_cast<uint64_t>(std::llround(std::ldexp(cost_units, FRAC)));
}

// Everything the block is loaded with (the ARC frame fields and what prep derives from them).
struct Frame {
  Geometry g;
  int32_t dz = 0;
  uint32_t n_ramp = 1;
  uint64_t c_total = 1;
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 1;
  uint64_t a = 0;  // u48
  uint64_t d = 0;  // u48, cost units
};

struct Derived {
  int64_t dt_q = 0;                                       // floor(dT / N_RAMP)
  int64_t dt_r = 0;                                       // dT - q N_RAMP
  u128 vz_entry = 0, vz_cruise = 0, vz_exit = 0, az = 0;  // V * |DZ|, A * |DZ|
};

// The first move's X / Y directions (true: +), prep's m_axis_dir for an ARC segment: the tangent
// signs at the start (-I, -J), a zero component inward (arc_dda's rule).
inline std::array<bool, 2> start_dirs(const Geometry& g) {
  const int64_t x0 = -int64_t{g.i}, y0 = -int64_t{g.j}, sg = g.ccw ? 1 : -1;
  const int64_t tx = -sg * y0, ty = sg * x0;
  return {tx != 0 ? tx > 0 : x0 < 0, ty != 0 ? ty > 0 : y0 < 0};
}

inline Derived derive(const Frame& f) {
  Derived d;
  floor_divmod(delta_t(f.g), f.n_ramp == 0 ? 1 : f.n_ramp, d.dt_q, d.dt_r);
  const u128 nz = static_cast<u128>(f.dz < 0 ? -int64_t{f.dz} : int64_t{f.dz});
  d.vz_entry = u128{f.v_entry} * nz;
  d.vz_cruise = u128{f.v_cruise} * nz;
  d.vz_exit = u128{f.v_exit} * nz;
  d.az = u128{f.a} * nz;
  return d;
}

// One clock's output of the block (an event of clock c; the pins show it on clock c + 1).
struct Event {
  uint64_t clock = 0;
  int8_t dx = 0, dy = 0, dz = 0;  // -1, 0, +1
  bool last = false;
};

struct RunResult {
  std::vector<Event> events;  // clocks with at least one step, in order
  uint64_t end_clock = 0;     // clock of the last move
  uint64_t moves = 0;
  int64_t x = 0, y = 0, z = 0;  // net steps from the start
  bool err = false;             // guard fired (end point or C_TOTAL inconsistent)
  bool late = false;            // some move waited for the walk
};

// The block (rtl/motion/arc_dda.v's registers in exact integers): clock() runs one clock;
// skip_quiet() jumps over the clocks in which nothing happens, in closed form (the cost of a run
// grows with its moves and Z steps, not with its clocks).
class Dda {
 public:
  explicit Dda(const Frame& f)
      : f_(f), dv_(derive(f)), w_(f.g, f.n_ramp), c2_(u128{f.c_total} << FRAC) {
    x1_ = int64_t{f.g.dx} - f.g.i;
    y1_ = int64_t{f.g.dy} - f.g.j;
    px_ = -int64_t{f.g.i};
    py_ = -int64_t{f.g.j};
    nz_ = static_cast<uint64_t>(f.dz < 0 ? -int64_t{f.dz} : int64_t{f.dz});
    zdir_ = f.dz < 0 ? -1 : 1;
    pending_ = w_.next();
    pa_ = w_.last_a;
    pb_ = w_.last_b;
    c_next_ = pending_.cost;
    v_ = f.v_entry;
    vz_ = dv_.vz_entry;
  }

  bool done() const { return done_; }
  bool err() const { return err_; }
  bool late() const { return late_; }
  uint64_t next_clock() const { return c_; }
  // rtl/motion/arc_dda.v's dir_valid, nx_dir, ny_dir in the clock next_clock() (ask before
  // clock()): the walk has chosen the tangent signs of the next move from the second clock of its
  // preparation (W1) on: valid unless the clock is the move's first (W0, clock r_k - 3).
  bool dir_valid() const { return c_ + (WALK_CLOCKS - 1) != ready_; }
  bool next_x_pos() const { return pa_ > 0; }
  bool next_y_pos() const { return pb_ > 0; }

  // Jumps over the next n <= limit clocks and returns n, as n calls of clock() would run them, when
  // none of them has an event: no move, no Z step, no `late`, and dir_valid() true with the same
  // next_x_pos() / next_y_pos() in each (skips only from the move's ready clock on: the clocks of
  // the walk's preparation run one by one). n is the largest such count except that it stops
  // before the clock in which U reaches the move's cost (one clock early at most), so a clock of
  // interest is never skipped.
  uint64_t skip_quiet(uint64_t limit) {
    if (done_ || z_due_ || c_ < ready_ || limit == 0) return 0;
    const u128 cn = u128{c_next_} << FRAC, dd = u128{f_.d} << FRAC;
    const bool decel = u_ >= dd;
    // the ramp from here: V (and VZ = V |DZ|) change by +A, -A or 0 per clock for at most n_max
    // clocks before the update saturates them
    constexpr uint64_t kNoLimit = uint64_t{1} << 62;
    u128 step = f_.a, step_z = dv_.az;
    bool falling = decel;
    uint64_t n_max = 0;
    if (!decel && v_ + f_.a <= f_.v_cruise) {
      n_max = f_.a == 0
                  ? kNoLimit
                  : static_cast<uint64_t>(std::min<u128>(kNoLimit, (f_.v_cruise - v_) / f_.a));
    } else if (decel && v_ >= u128{f_.v_exit} + f_.a) {
      n_max = f_.a == 0 ? kNoLimit
                        : static_cast<uint64_t>(std::min<u128>(kNoLimit, (v_ - f_.v_exit) / f_.a));
    } else if (v_ == (decel ? f_.v_exit : f_.v_cruise)) {
      step = step_z = 0;
      falling = false;
      n_max = kNoLimit;
    }
    const u128 target = decel ? cn : std::min(cn, dd);
    const bool z_live = zc_ < nz_;
    if (n_max == 0 || u_ >= target) return 0;
    uint64_t n = ramp::last_below(u_, v_, step, falling, target, std::min(limit, n_max));
    if (z_live && n != 0) n = ramp::last_below(rz_, vz_, step_z, falling, c2_, n);
    if (n == 0) return 0;
    u_ = ramp::sum(u_, v_, step, falling, n);
    rz_ = ramp::sum(rz_, vz_, step_z, falling, n);  // saturates only once Z is done (unused then)
    v_ = falling ? v_ - step * n : v_ + step * n;
    vz_ = falling ? vz_ - step_z * n : vz_ + step_z * n;
    c_ += n;
    return n;
  }

  // Clock c (0, 1, ... after the load): its event. Call only while !done().
  Event clock() {
    Event ev;
    ev.clock = c_;
    if (z_due_) ev.dz = static_cast<int8_t>(zdir_);
    const uint64_t uint_part = static_cast<uint64_t>(u_ >> FRAC);
    if (c_ + 1 == ready_ && uint_part >= c_next_) late_ = true;
    if (c_ >= ready_ && uint_part >= c_next_) {
      ev.dx = pending_.dx;
      ev.dy = pending_.dy;
      px_ += pending_.dx;
      py_ += pending_.dy;
      const bool at_end = px_ == x1_ && py_ == y1_;
      if (at_end || c_next_ >= f_.c_total) {
        done_ = true;
        ev.last = true;
        if (!at_end || c_next_ != f_.c_total) err_ = true;
        c_ += 1;
        return ev;
      }
      pending_ = w_.next();
      pa_ = w_.last_a;
      pb_ = w_.last_b;
      c_next_ += pending_.cost;
      ready_ = c_ + WALK_CLOCKS;
    }
    // Z for clock c + 1
    const u128 rzn = rz_ + vz_;
    z_due_ = rzn >= c2_ && zc_ < nz_;
    rz_ = z_due_ ? rzn - c2_ : rzn;
    if (z_due_) zc_ += 1;
    // U, V for clock c + 1
    u_ += v_;
    if ((u_ >> FRAC) >= u128{f_.d}) {
      if (v_ >= u128{f_.v_exit} + f_.a) {
        v_ -= f_.a;
        vz_ -= dv_.az;
      } else {
        v_ = f_.v_exit;
        vz_ = dv_.vz_exit;
      }
    } else {
      if (v_ + f_.a <= f_.v_cruise) {
        v_ += f_.a;
        vz_ += dv_.az;
      } else {
        v_ = f_.v_cruise;
        vz_ = dv_.vz_cruise;
      }
    }
    c_ += 1;
    return ev;
  }

 private:
  Frame f_;
  Derived dv_;
  Walker w_;
  u128 c2_;
  int64_t x1_ = 0, y1_ = 0, px_ = 0, py_ = 0;
  uint64_t nz_ = 0, zc_ = 0;
  int zdir_ = 1;
  Move pending_;
  int pa_ = 0, pb_ = 0;  // tangent signs of pending_ (the directions arc_dda announces)
  uint64_t c_next_ = 0, ready_ = WALK_CLOCKS - 1, c_ = 0;
  u128 u_ = 0, v_ = 0, vz_ = 0, rz_ = 0;
  bool z_due_ = false, done_ = false, err_ = false, late_ = false;
};

// Clock-exact run of the block. max_clocks bounds runaway inputs (0: none).
inline RunResult run(const Frame& f, uint64_t max_clocks = 0) {
  RunResult res;
  Dda dda(f);
  while (!dda.done()) {
    const uint64_t c = dda.next_clock();
    if (max_clocks == 0)
      dda.skip_quiet(~uint64_t{0});
    else if (c < max_clocks)
      dda.skip_quiet(max_clocks - c);
    const Event ev = dda.clock();
    if (ev.dx || ev.dy || ev.dz) res.events.push_back(ev);
    if (ev.dx || ev.dy) res.moves += 1;
    res.x += ev.dx;
    res.y += ev.dy;
    res.z += ev.dz;
    res.end_clock = ev.clock;
    if (max_clocks && ev.clock >= max_clocks && !dda.done()) {
      res.err = true;
      return res;
    }
  }
  res.err = dda.err();
  res.late = dda.late();
  return res;
}

}  // namespace fpgacnc::models::arc
