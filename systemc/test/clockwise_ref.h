// Test-only references: the clock-by-clock forms of run_profile (timing.h) and arc::Dda / arc::run
// (arc_walk.h), which the event-driven implementations must match bit for bit. Each runs the
// documented recurrences one clock at a time (run_profile skipping only constant-velocity
// stretches), so their cost grows with the clocks; the tests keep the inputs small enough.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins::ref {

inline ProfileRun run_profile(const ProfileParams& p,
                              const std::array<uint32_t, kAxes>& abs_steps) {
  ProfileRun r;
  uint32_t n_dom = 0;
  for (uint32_t n : abs_steps) n_dom = std::max(n_dom, n);
  if (n_dom == 0) return r;
  using u128 = unsigned __int128;
  const u128 m = static_cast<u128>(n_dom) << 48;
  const u128 d = static_cast<u128>(p.decel_at) << 48;
  // Next step threshold of each axis: the k-th step when U*n_a >= k*M, i.e. U >= ceil(k*M/n_a).
  std::array<u128, kAxes> next{};
  std::array<uint32_t, kAxes> k{};
  for (int a = 0; a < kAxes; ++a) {
    r.ticks[a].reserve(abs_steps[a]);
    if (abs_steps[a] != 0) next[a] = (m + abs_steps[a] - 1) / abs_steps[a];
  }
  u128 u = 0;
  uint64_t v = p.v_entry;
  r.cruised = v == p.v_cruise;
  uint64_t j = 0;
  while (u < m) {
    // Constant velocity (cruise, V_exit reached, A = 0): the ticks before the next event (a step,
    // the start of deceleration, the end) change nothing but U; skip them in one go.
    uint64_t vs = v;
    profile_update(p, u >= d, vs);
    if (vs == v && v != 0) {
      u128 target = m;
      if (u < d) target = std::min(target, d);
      for (int a = 0; a < kAxes; ++a)
        if (k[a] < abs_steps[a]) target = std::min(target, next[a]);
      if (target > u + v) {
        const u128 s = (target - u - 1) / v;  // u + s*v < target
        u += s * v;
        j += static_cast<uint64_t>(s);
      }
    }
    ++j;
    u += v;
    profile_update(p, u >= d, v);
    r.cruised = r.cruised || v == p.v_cruise;
    for (int a = 0; a < kAxes; ++a) {
      if (k[a] < abs_steps[a] && u >= next[a]) {
        r.ticks[a].push_back(j);
        ++k[a];
        next[a] = (m * (k[a] + 1) + abs_steps[a] - 1) / abs_steps[a];
      }
    }
  }
  r.ticks_total = j;
  return r;
}

namespace arc {

using models::arc::derive;
using models::arc::Derived;
using models::arc::Event;
using models::arc::FRAC;
using models::arc::Frame;
using models::arc::Move;
using models::arc::RunResult;
using models::arc::u128;
using models::arc::WALK_CLOCKS;
using models::arc::Walker;

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

}  // namespace arc
}  // namespace fpgacnc::twins::ref
