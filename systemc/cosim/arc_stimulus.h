// ARC stimulus shared by the co-simulations (SystemC-free: the RTL sides include it too):
// random_arc_frame, the random ARC frame within the host's rules (cosim's v2 sessions,
// cosim_executor's ARC segments, arc_twin_rtl's arcs), and put_arc_load, segment_prep's m_axis_arc
// / the executor's s_axis_arc (arc_dda's load inputs, LSB first) from a frame and arc::derive.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "fpgacnc/models/arc_walk.h"

namespace fpgacnc::twins {

struct ArcStimulus {
  double r_min = 2, r_span = 28;          // radius r_min .. r_min + r_span steps
  double r_log_max = 0;                   // > 0: radius log-uniform in 1 .. r_log_max instead
  uint32_t cps_lo = 1201, cps_hi = 2400;  // tangential cruise, clocks per step
  uint32_t bad_in = 10;                   // one in bad_in has C_TOTAL + 1 (0: none)
};

// An ARC frame within the host's rules: R = r_min .. r_min + r_span steps (full circles too, both
// directions, a helix of up to L/2 Z steps), N_RAMP and C_TOTAL from arc::plan, tangential cruise
// at cps_lo..cps_hi clocks per step (1/8 step per clock and the STEP timing hold for cps_lo >= the
// minimum period; tiny radii may still reverse X / Y faster than DIR hold + setup: those steps are
// reported violations, as on the device), a trapezoid in cost units (entry / exit from cruise/8,
// A reaching cruise within 1..2 C_TOTAL, D by the stopping rule or random). One in bad_in has
// C_TOTAL + 1 (*bad set): the walk reaches its end point first, `arc error` (faults bit 1).
inline models::arc::Frame random_arc_frame(std::mt19937_64& g, const ArcStimulus& o = {},
                                           bool* bad = nullptr) {
  const auto pick = [&g](uint32_t lo, uint32_t hi) {
    return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
  };
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (;;) {
    const double u = u01(g);
    const double r = o.r_log_max > 0 ? std::exp(u * std::log(o.r_log_max)) : o.r_min + o.r_span * u;
    const double cx = u01(g) - 0.5, cy = u01(g) - 0.5, a0 = u01(g) * 2 * M_PI;
    const bool full = u01(g) < 0.2;
    models::arc::Frame f;
    f.g.ccw = u01(g) < 0.5;
    const int64_t sx = std::llround(cx + r * std::cos(a0)),
                  sy = std::llround(cy + r * std::sin(a0));
    f.g.i = static_cast<int32_t>(std::llround(cx) - sx);
    f.g.j = static_cast<int32_t>(std::llround(cy) - sy);
    if (f.g.i == 0 && f.g.j == 0) continue;
    if (!full) {
      const double a1 = a0 + (f.g.ccw ? 1 : -1) * (0.1 + u01(g) * 6.1);
      f.g.dx = static_cast<int32_t>(std::llround(cx + r * std::cos(a1)) - sx);
      f.g.dy = static_cast<int32_t>(std::llround(cy + r * std::sin(a1)) - sy);
      if ((f.g.dx == 0 && f.g.dy == 0) || (f.g.dx == f.g.i && f.g.dy == f.g.j)) continue;
    }
    const double r0 = std::hypot(double(f.g.i), double(f.g.j));
    const double r1 = std::hypot(double(f.g.dx) - f.g.i, double(f.g.dy) - f.g.j);
    if (std::fabs(r1 - r0) > 2.0) continue;
    const models::arc::Plan pl = models::arc::plan(f.g);
    if (!pl.ok) continue;
    f.n_ramp = pl.n_ramp;
    f.c_total = pl.c_total;
    const double len = models::arc::ideal_length(f.g), k = double(f.c_total) / len;
    const double two48 = std::ldexp(1.0, 48), n = double(f.c_total);
    f.v_cruise = static_cast<uint64_t>(k * two48 / pick(o.cps_lo, o.cps_hi));
    auto from8 = [&] { return f.v_cruise / 8 + pick(0, 7) * (f.v_cruise / 8); };
    f.v_entry = pick(0, 2) == 0 ? f.v_cruise : std::min(f.v_cruise, from8());
    f.v_exit = pick(0, 2) == 0 ? f.v_cruise : std::min(f.v_cruise, from8());
    const double vc = double(f.v_cruise), vx = double(f.v_exit);
    const double l = std::ldexp(n * (0.05 + 2 * u01(g)), 48);
    f.a = std::max<uint64_t>(1, static_cast<uint64_t>(vc * vc / (2 * l)));
    const double stop = (vc * vc - vx * vx) / (2.0 * double(f.a)) / two48;
    f.d = pick(0, 3) == 0 ? static_cast<uint64_t>(n * u01(g))
                          : static_cast<uint64_t>(std::max(0.0, n - std::ceil(stop)));
    if (pick(0, 2) == 0) f.dz = static_cast<int32_t>((u01(g) - 0.5) * len);
    if (bad) *bad = false;
    if (o.bad_in != 0 && pick(0, o.bad_in - 1) == 0) {
      f.c_total += 1;
      if (bad) *bad = true;
    }
    return f;
  }
}

// segment_prep's m_axis_arc (rtl/motion/segment_prep.v: arc_dda's load inputs, LSB first, 945
// bits): put(lsb, value, width) for each field.
template <class Put>
void put_arc_load(const models::arc::Frame& f, Put&& put) {
  const models::arc::Derived d = models::arc::derive(f);
  const auto u = [](int64_t v, int w) {
    return static_cast<unsigned __int128>(static_cast<uint64_t>(v) & ((~0ull) >> (64 - w)));
  };
  put(0, f.g.ccw, 1);
  put(1, u(f.g.i, 24), 24);
  put(25, u(f.g.j, 24), 24);
  put(49, u(f.g.dx, 24), 24);
  put(73, u(f.g.dy, 24), 24);
  put(97, u(f.dz, 32), 32);
  put(129, f.n_ramp, 24);
  put(153, u(d.dt_q, 48), 48);
  put(201, u(d.dt_r, 24), 24);
  put(225, f.c_total, 48);
  put(273, f.v_entry, 64);
  put(337, f.v_cruise, 64);
  put(401, f.v_exit, 64);
  put(465, f.a, 48);
  put(513, f.d, 48);
  put(561, d.vz_entry, 96);
  put(657, d.vz_cruise, 96);
  put(753, d.vz_exit, 96);
  put(849, d.az, 96);
}

}  // namespace fpgacnc::twins
