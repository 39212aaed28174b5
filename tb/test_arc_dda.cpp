// Bench for arc_dda (circular / helical DDA): the RTL against the integer reference
// walk (models/include/fpgacnc/models/arc_walk.h) edge for edge, and the geometry and speed of
// the walk against the real-valued ideal arc:
//  - every visited lattice point within 1 step of the ideal arc (radius linear in the swept angle
//    from R0 to R1, LinuxCNC's rule for slightly inconsistent arcs), the walk turns exactly the
//    programmed angle (no extra turn) and ends exactly on the end point;
//  - tangential speed (true arc length / time, from the move clocks) within 2 % of the commanded
//    speed over windows of >= 1/16 turn and >= 100 steps, or the whole arc when shorter (the time
//    of a move is quantised to 1 clock and its position to 1 step: the windows keep both below
//    1 %); never above it on profiled arcs;
//  - Z (helix) count exact, and within 1 step of DZ * C_k / C_TOTAL at every XY move.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "common/arc_rtl.h"
#include "common/seed.h"
#include "fpgacnc/models/arc_walk.h"

namespace {

namespace arc = fpgacnc::models::arc;

using fpgacnc::tb::ArcRtl;

// ---------------------------------------------------------------- geometry of the ideal arc
struct Ideal {
  double r0 = 0, r1 = 0, th = 0;
  double r(double phi) const { return r0 + (r1 - r0) * std::min(phi, th) / th; }
  // arc length from 0 to phi (r' term neglected: (r1 - r0)^2 / th^2 << r^2 for the host rule)
  double len(double phi) const { return r0 * phi + (r1 - r0) * phi * phi / (2 * th); }
};

Ideal ideal_of(const arc::Geometry& g) {
  Ideal id;
  id.r0 = std::hypot(double(g.i), double(g.j));
  id.r1 = std::hypot(double(g.dx) - g.i, double(g.dy) - g.j);
  id.th = arc::sweep(g);
  return id;
}

struct GeoCheck {
  bool ok = true;
  std::string why;
  double worst_radial = 0;
  std::vector<double> phi;  // swept angle at each visited point (phi[0] = 0)
};

// Walks the move list from the start: radial error of every point, swept angle, end point.
GeoCheck check_geometry(const arc::Geometry& g, const std::vector<arc::Move>& moves) {
  GeoCheck gc;
  const Ideal id = ideal_of(g);
  int64_t x = -int64_t{g.i}, y = -int64_t{g.j};
  const double s = g.ccw ? 1.0 : -1.0;
  double phi = 0;
  gc.phi.push_back(0);
  for (size_t k = 0; k < moves.size(); ++k) {
    const int64_t nx = x + moves[k].dx, ny = y + moves[k].dy;
    const double cr = double(x) * double(ny) - double(y) * double(nx);
    const double dt = double(x) * double(nx) + double(y) * double(ny);
    const double dphi = s * std::atan2(cr, dt);
    if (dphi <= 0) {
      gc.ok = false;
      gc.why = "move " + std::to_string(k + 1) + " does not advance the angle";
      return gc;
    }
    phi += dphi;
    x = nx;
    y = ny;
    gc.phi.push_back(phi);
    const double err = std::fabs(std::hypot(double(x), double(y)) - id.r(phi));
    gc.worst_radial = std::max(gc.worst_radial, err);
  }
  if (x != int64_t{g.dx} - g.i || y != int64_t{g.dy} - g.j) {
    gc.ok = false;
    gc.why = "walk does not end on the end point";
  } else if (std::fabs(phi - id.th) > 1e-6) {
    gc.ok = false;
    gc.why = "walk turned " + std::to_string(phi) + " rad, programmed " + std::to_string(id.th);
  }
  return gc;
}

// A random arc as the host would send it: real centre and radius, start/centre/end rounded to
// the lattice; rejects what the host would cut into chords (|R1 - R0| > 2 steps).
bool random_geometry(std::mt19937_64& rng, double rmin, double rmax, arc::Geometry& g) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double r = std::exp(std::log(rmin) + u01(rng) * (std::log(rmax) - std::log(rmin)));
  const double cx = u01(rng) - 0.5, cy = u01(rng) - 0.5;
  const double a0 = u01(rng) * 2 * M_PI;
  const double pick = u01(rng);
  double sw;
  bool full = false;
  if (pick < 0.2) {
    full = true;
    sw = 2 * M_PI;
  } else if (pick < 0.35) {
    sw = M_PI / 2;
  } else if (pick < 0.5) {
    sw = M_PI;
  } else {
    sw = 0.02 + u01(rng) * (2 * M_PI - 0.04);
  }
  g.ccw = u01(rng) < 0.5;
  const int64_t sx = std::llround(cx + r * std::cos(a0)), sy = std::llround(cy + r * std::sin(a0));
  const int64_t ccx = std::llround(cx), ccy = std::llround(cy);
  g.i = static_cast<int32_t>(ccx - sx);
  g.j = static_cast<int32_t>(ccy - sy);
  if (g.i == 0 && g.j == 0) return false;
  if (full) {
    g.dx = g.dy = 0;
  } else {
    const double a1 = a0 + (g.ccw ? sw : -sw);
    const int64_t ex = std::llround(cx + r * std::cos(a1)),
                  ey = std::llround(cy + r * std::sin(a1));
    g.dx = static_cast<int32_t>(ex - sx);
    g.dy = static_cast<int32_t>(ey - sy);
    if (g.dx == 0 && g.dy == 0) return false;
    if (g.dx == g.i && g.dy == g.j) return false;
  }
  const Ideal id = ideal_of(g);
  return std::fabs(id.r1 - id.r0) <= 2.0;
}

struct Profile {
  bool constant = true;
  double v = 0;  // commanded tangential cruise, steps per clock
};

// Fills the speed fields of f for geometry with plan p; returns the commanded profile.
Profile random_profile(std::mt19937_64& rng, arc::Frame& f, double length) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double k = double(f.c_total) / length;  // cost units per step of arc
  const double two48 = std::ldexp(1.0, 48);
  Profile pr;
  pr.v = 0.01 + 0.11 * u01(rng);
  pr.v = std::min(pr.v, length / 200.0);  // at least 200 clocks: 1-clock quantisation < 0.5 %
  pr.constant = u01(rng) < 0.7;
  const auto q = [&](double x) { return static_cast<uint64_t>(std::llround(x)); };
  f.v_cruise = std::max<uint64_t>(1, q(pr.v * k * two48));
  if (pr.constant) {
    f.v_entry = f.v_exit = f.v_cruise;
    f.a = 1 + q(u01(rng) * 1000);
    f.d = f.c_total;
  } else {
    f.v_entry = std::max<uint64_t>(1, q(f.v_cruise * (0.05 + 0.9 * u01(rng))));
    f.v_exit = std::max<uint64_t>(1, q(f.v_cruise * (0.05 + 0.9 * u01(rng))));
    const double frac = 0.05 + 0.4 * u01(rng);  // accel distance as a fraction of the arc
    const double a = pr.v * pr.v / (2 * frac * length);
    f.a = std::max<uint64_t>(1, q(a * k * two48));
    const double vc = double(f.v_cruise), vx = double(f.v_exit), aa = double(f.a);
    const double dec = (vc * vc - vx * vx) / (2 * aa) / two48;  // cost units
    const double dd = double(f.c_total) - std::ceil(dec);
    f.d = dd < 0 ? 0 : static_cast<uint64_t>(dd);
  }
  return pr;
}

std::string describe(const arc::Frame& f) {
  char b[400];
  std::snprintf(
      b, sizeof b,
      "I=%d J=%d DX=%d DY=%d %s DZ=%d N_RAMP=%u C_TOTAL=%llu Ve=%llu Vc=%llu Vx=%llu A=%llu "
      "D=%llu",
      f.g.i, f.g.j, f.g.dx, f.g.dy, f.g.ccw ? "CCW" : "CW", f.dz, f.n_ramp,
      static_cast<unsigned long long>(f.c_total), static_cast<unsigned long long>(f.v_entry),
      static_cast<unsigned long long>(f.v_cruise), static_cast<unsigned long long>(f.v_exit),
      static_cast<unsigned long long>(f.a), static_cast<unsigned long long>(f.d));
  return b;
}

// ---------------------------------------------------------------- tests

// The worked ARC frame of docs/protocol.md: N_RAMP 127 gives C_TOTAL 15 703 and lands.
TEST(ArcWalk, ProtocolWorkedFrame) {
  arc::Geometry g{-100, 0, -100, 100, true};
  EXPECT_EQ(arc::choose_n_ramp(g), 127u);
  const arc::WalkResult w = arc::walk(g, 127);
  EXPECT_TRUE(w.reached);
  EXPECT_EQ(w.c_total, 15703u);
  const GeoCheck gc = check_geometry(g, w.moves);
  EXPECT_TRUE(gc.ok) << gc.why;
  EXPECT_LE(gc.worst_radial, 1.0);
}

// Full circles of tiny radii, both directions, all start positions on the circle.
TEST(ArcWalk, TinyFullCircles) {
  double worst = 0;
  for (int r = 1; r <= 6; ++r)
    for (int sx = -r; sx <= r; ++sx)
      for (int sy = -r; sy <= r; ++sy) {
        if (sx * sx + sy * sy != r * r) continue;  // start exactly on the circle
        for (bool ccw : {true, false}) {
          arc::Geometry g{-sx, -sy, 0, 0, ccw};
          const arc::Plan p = arc::plan(g);
          ASSERT_TRUE(p.ok) << "R=" << r << " start (" << sx << "," << sy << ")";
          const arc::WalkResult w = arc::walk(g, p.n_ramp);
          const GeoCheck gc = check_geometry(g, w.moves);
          EXPECT_TRUE(gc.ok) << gc.why << " R=" << r;
          EXPECT_LE(gc.worst_radial, 1.0) << "R=" << r;
          worst = std::max(worst, gc.worst_radial);
        }
      }
  std::printf("[arc] tiny full circles: worst radial error %.4f steps\n", worst);
}

// Reference walk only (fast): many random arcs up to R = 10^5.
TEST(ArcWalk, RandomGeometry) {
  std::mt19937_64 rng(fpgacnc::tb::test_seed(61, "ArcWalk.RandomGeometry"));
  int n = 0, tries = 0;
  double worst = 0;
  std::string worst_arc;
  while (n < 4000 && tries < 100000) {
    ++tries;
    arc::Geometry g;
    const double rmax = (n % 40 == 0) ? 1e5 : 3e3;
    if (!random_geometry(rng, 1.0, rmax, g)) continue;
    ++n;
    const arc::Plan p = arc::plan(g);
    ASSERT_TRUE(p.ok) << "walk misses the end point: I=" << g.i << " J=" << g.j << " DX=" << g.dx
                      << " DY=" << g.dy << (g.ccw ? " CCW" : " CW") << " N_RAMP=" << p.n_ramp;
    const arc::WalkResult w = arc::walk(g, p.n_ramp);
    const GeoCheck gc = check_geometry(g, w.moves);
    ASSERT_TRUE(gc.ok) << gc.why << " I=" << g.i << " J=" << g.j << " DX=" << g.dx
                       << " DY=" << g.dy;
    ASSERT_LE(gc.worst_radial, 1.0) << "I=" << g.i << " J=" << g.j << " DX=" << g.dx
                                    << " DY=" << g.dy << (g.ccw ? " CCW" : " CW");
    if (gc.worst_radial > worst) {
      worst = gc.worst_radial;
      worst_arc = "I=" + std::to_string(g.i) + " J=" + std::to_string(g.j) +
                  " DX=" + std::to_string(g.dx) + " DY=" + std::to_string(g.dy) +
                  (g.ccw ? " CCW" : " CW");
    }
  }
  EXPECT_EQ(n, 4000);
  std::printf("[arc] reference walk, %d random arcs: worst radial error %.4f steps (%s)\n", n,
              worst, worst_arc.c_str());
}

// Compares one RTL run with the reference (same frame): events, end clock, err, late.
void expect_same(const arc::RunResult& ref, const arc::RunResult& got, const std::string& what) {
  ASSERT_EQ(got.err, ref.err) << what;
  ASSERT_EQ(got.late, ref.late) << what;
  const size_t ne = std::min(got.events.size(), ref.events.size());
  for (size_t k = 0; k < ne; ++k) {
    const arc::Event &a = ref.events[k], &b = got.events[k];
    ASSERT_TRUE(a.clock == b.clock && a.dx == b.dx && a.dy == b.dy && a.dz == b.dz &&
                a.last == b.last)
        << what << ": event " << k << " expected clock " << a.clock << " d=(" << int(a.dx) << ","
        << int(a.dy) << "," << int(a.dz) << ") last " << a.last << ", got clock " << b.clock
        << " d=(" << int(b.dx) << "," << int(b.dy) << "," << int(b.dz) << ") last " << b.last;
  }
  ASSERT_EQ(got.events.size(), ref.events.size()) << what;
  ASSERT_EQ(got.end_clock, ref.end_clock) << what;
}

arc::Frame planned(const arc::Geometry& g, double v) {
  arc::Frame f;
  f.g = g;
  const arc::Plan p = arc::plan(g);
  f.n_ramp = p.n_ramp;
  f.c_total = p.c_total;
  const Ideal id = ideal_of(g);
  const double k = double(f.c_total) / id.len(id.th);
  f.v_cruise = f.v_entry = f.v_exit =
      static_cast<uint64_t>(std::llround(v * k * std::ldexp(1.0, 48)));
  f.a = 1;
  f.d = f.c_total;
  return f;
}

// Arcs back to back, each loaded on the edge of the previous one's last move: the next arc's
// clock 0 follows at once (zero gap) and every arc's edges equal the reference's.
TEST(ArcDda, ZeroGapChains) {
  const uint64_t seed = fpgacnc::tb::test_seed(63, "ArcDda.ZeroGapChains");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ArcRtl rtl;
  // a full circle of R = 200 as four quarter arcs, CCW from (200, 0) about the centre
  {
    std::vector<arc::Frame> fs;
    const int pts[5][2] = {{200, 0}, {0, 200}, {-200, 0}, {0, -200}, {200, 0}};
    for (int q = 0; q < 4; ++q) {
      arc::Geometry g{-pts[q][0], -pts[q][1], pts[q + 1][0] - pts[q][0], pts[q + 1][1] - pts[q][1],
                      true};
      fs.push_back(planned(g, 0.05));
    }
    const std::vector<arc::RunResult> got = rtl.run_chain(fs, 1u << 24);
    for (size_t q = 0; q < fs.size(); ++q)
      expect_same(arc::run(fs[q]), got[q], "quarter " + std::to_string(q));
  }
  int chains = 0, arcs = 0;
  while (chains < 40) {
    std::vector<arc::Frame> fs;
    const int len = 2 + static_cast<int>(u01(rng) * 4);
    while (static_cast<int>(fs.size()) < len) {
      arc::Frame f;
      if (!random_geometry(rng, 1.0, 300.0, f.g)) continue;
      const arc::Plan p = arc::plan(f.g);
      ASSERT_TRUE(p.ok);
      f.n_ramp = p.n_ramp;
      f.c_total = p.c_total;
      const Ideal id = ideal_of(f.g);
      random_profile(rng, f, id.len(id.th));
      if (u01(rng) < 0.5)
        f.dz = static_cast<int32_t>((1 + u01(rng) * 20) * (u01(rng) < 0.5 ? -1 : 1));
      fs.push_back(f);
    }
    const std::vector<arc::RunResult> got = rtl.run_chain(fs, 1u << 26);
    for (size_t q = 0; q < fs.size(); ++q) {
      const arc::RunResult ref = arc::run(fs[q]);
      ASSERT_FALSE(ref.err);
      // late is sticky per arc and cleared by the next load: compare it on the chain's last arc
      arc::RunResult g2 = got[q];
      if (q + 1 < fs.size()) g2.late = ref.late;
      expect_same(ref, g2,
                  describe(fs[q]) + " chain " + std::to_string(chains) + " arc " +
                      std::to_string(q) + " seed " + std::to_string(seed));
      ++arcs;
    }
    ++chains;
  }
  std::printf("[arc] %d chains, %d arcs back to back: RTL == reference, zero gap\n", chains, arcs);
}

// Inconsistent frames stop at the guard with err (RTL and reference alike); a tangential speed
// above the host rule makes moves wait for the walk (late), still edge for edge.
TEST(ArcDda, GuardAndLate) {
  ArcRtl rtl;
  const arc::Geometry g{-150, 40, -230, 200, false};
  const arc::Frame good = planned(g, 0.05);
  {
    const arc::RunResult ref = arc::run(good), got = rtl.run(good, ref.end_clock + 16);
    EXPECT_FALSE(ref.err);
    expect_same(ref, got, "consistent");
    EXPECT_EQ(got.x, g.dx);
    EXPECT_EQ(got.y, g.dy);
  }
  for (int64_t delta : {-1, 1, -1000}) {
    arc::Frame f = good;
    f.c_total = static_cast<uint64_t>(int64_t(f.c_total) + delta);
    f.d = f.c_total;
    const arc::RunResult ref = arc::run(f, 1u << 24);
    EXPECT_TRUE(ref.err) << "C_TOTAL " << delta;
    expect_same(ref, rtl.run(f, ref.end_clock + 16), "C_TOTAL off by " + std::to_string(delta));
  }
  {
    arc::Frame f = good;
    f.n_ramp = 1;  // ramp at once: a different walk that misses the planned total
    f.g.dx += 1;   // and an end point off the walk
    const arc::RunResult ref = arc::run(f, 1u << 24);
    EXPECT_TRUE(ref.err);
    expect_same(ref, rtl.run(f, ref.end_clock + 16), "end point off the walk");
  }
  {
    const arc::Frame fast = planned(g, 0.4);  // 0.4 steps per clock: above 1/8
    const arc::RunResult ref = arc::run(fast);
    EXPECT_TRUE(ref.late);
    EXPECT_FALSE(ref.err);
    expect_same(ref, rtl.run(fast, ref.end_clock + 16), "late");
  }
  {
    // an inconsistent arc chained to a good one: its err comes out on end_err with `ending`
    arc::Frame bad = good;
    bad.c_total += 1;
    bad.d = bad.c_total;
    const std::vector<arc::RunResult> got = rtl.run_chain({bad, good}, 1u << 24);
    expect_same(arc::run(bad), got[0], "chained inconsistent arc");
    expect_same(arc::run(good), got[1], "the arc after it");
  }
}

// E-stop: `stop` high in clock c (one clock, or held) and nothing of clock c or later reaches the
// pins, also when c is the clock in which a move fires (its step would be registered on the stop
// edge and show one clock later, after the e-stop). The events before c are the reference's.
TEST(ArcDda, StopInAnyClockEndsTheWalkAtOnce) {
  ArcRtl rtl;
  arc::Frame f = planned(arc::Geometry{-150, 40, -230, 200, false}, 0.05);
  f.dz = 37;  // Z steps as well
  const arc::RunResult ref = arc::run(f);
  ASSERT_FALSE(ref.err);
  ASSERT_GT(ref.events.size(), 40u);
  int checked = 0;
  for (size_t k = 0; k < ref.events.size(); k += 7) {
    const uint64_t fire = ref.events[k].clock;
    for (uint64_t c : {fire - 1, fire, fire + 1}) {
      for (uint64_t len : {uint64_t{1}, uint64_t{5}}) {
        const ArcRtl::Stopped got = rtl.run_stopped(f, c, len, c + 64);
        size_t before = 0;
        while (before < ref.events.size() && ref.events[before].clock < c) ++before;
        const std::string what = "stop in clock " + std::to_string(c) + " for " +
                                 std::to_string(len) + " (move " + std::to_string(k) +
                                 " fires in clock " + std::to_string(fire) + ")";
        ASSERT_FALSE(got.busy_after) << what;
        for (const arc::Event& e : got.events)
          ASSERT_LT(e.clock, c) << what << ": pins show an event of clock " << e.clock;
        ASSERT_EQ(got.events.size(), before) << what;
        for (size_t i = 0; i < before; ++i) {
          const arc::Event &a = ref.events[i], &b = got.events[i];
          ASSERT_TRUE(a.clock == b.clock && a.dx == b.dx && a.dy == b.dy && a.dz == b.dz)
              << what << ": event " << i;
        }
        ++checked;
      }
    }
  }
  std::printf("[arc] %d stops around %zu moves: nothing after the stop clock\n", checked,
              (ref.events.size() + 6) / 7);
}

// The RTL against the reference, edge for edge, with geometry, speed and Z checks.
TEST(ArcDda, RtlVsReferenceRandom) {
  const uint64_t seed = fpgacnc::tb::test_seed(62, "ArcDda.RtlVsReferenceRandom");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  ArcRtl rtl;
  int n = 0, full = 0, helix = 0, late = 0;
  double worst_radial = 0, worst_speed = 0, worst_over = -1;
  uint64_t clocks = 0;
  const int kArcs = 1000;
  while (n < kArcs) {
    arc::Frame f;
    // mostly radii up to 3 000 steps; every 100th up to 10^5 (long runs)
    const double rmax = (n % 100 == 99) ? 1e5 : 3e3;
    if (!random_geometry(rng, 1.0, rmax, f.g)) continue;
    const arc::Plan p = arc::plan(f.g);
    ASSERT_TRUE(p.ok);
    f.n_ramp = p.n_ramp;
    f.c_total = p.c_total;
    const Ideal id = ideal_of(f.g);
    const double length = id.len(id.th);
    const Profile pr = random_profile(rng, f, length);
    if (u01(rng) < 0.4) {
      const int64_t maxz = std::max<int64_t>(1, static_cast<int64_t>(length));
      f.dz = static_cast<int32_t>(1 + static_cast<int64_t>(u01(rng) * double(maxz)));
      if (u01(rng) < 0.5) f.dz = -f.dz;
      ++helix;
    }
    if (f.g.dx == 0 && f.g.dy == 0) ++full;
    const std::string what =
        describe(f) + " (arc " + std::to_string(n) + ", seed " + std::to_string(seed) + ")";

    const arc::RunResult ref = arc::run(f, 1ull << 34);
    const arc::RunResult got = rtl.run(f, ref.end_clock + 16);
    ++n;
    clocks += ref.end_clock;
    ASSERT_FALSE(ref.err) << what;
    ASSERT_EQ(got.err, ref.err) << what;
    ASSERT_EQ(got.late, ref.late) << what;
    late += ref.late;
    // edge for edge
    const size_t ne = std::min(got.events.size(), ref.events.size());
    for (size_t k = 0; k < ne; ++k) {
      const arc::Event &a = ref.events[k], &b = got.events[k];
      ASSERT_TRUE(a.clock == b.clock && a.dx == b.dx && a.dy == b.dy && a.dz == b.dz &&
                  a.last == b.last)
          << what << ": event " << k << " expected clock " << a.clock << " d=(" << int(a.dx) << ","
          << int(a.dy) << "," << int(a.dz) << ") last " << a.last << ", got clock " << b.clock
          << " d=(" << int(b.dx) << "," << int(b.dy) << "," << int(b.dz) << ") last " << b.last;
    }
    ASSERT_EQ(got.events.size(), ref.events.size()) << what;
    // end point and Z count exact
    ASSERT_EQ(got.x, f.g.dx) << what;
    ASSERT_EQ(got.y, f.g.dy) << what;
    ASSERT_EQ(got.z, f.dz) << what;
    ASSERT_EQ(got.moves, p.moves) << what;

    // geometry of the visited points (from the RTL edges)
    std::vector<arc::Move> moves;
    std::vector<uint64_t> t;   // clock of each move
    std::vector<int64_t> zat;  // z after each move
    int64_t z = 0;
    for (const arc::Event& e : got.events) {
      z += e.dz;
      if (e.dx || e.dy) {
        moves.push_back({e.dx, e.dy, 0});
        t.push_back(e.clock);
        zat.push_back(z);
      }
    }
    const GeoCheck gc = check_geometry(f.g, moves);
    ASSERT_TRUE(gc.ok) << gc.why << " " << what;
    ASSERT_LE(gc.worst_radial, 1.0) << what;
    worst_radial = std::max(worst_radial, gc.worst_radial);

    // Z spread linearly over the cost
    if (f.dz != 0) {
      const arc::WalkResult w = arc::walk(f.g, f.n_ramp);
      uint64_t ck = 0;
      for (size_t k = 0; k < moves.size(); ++k) {
        ck += w.moves[k].cost;
        const double ideal = double(f.dz) * double(ck) / double(f.c_total);
        ASSERT_LE(std::fabs(double(zat[k]) - ideal), 1.0 + 1e-9) << what << " move " << k + 1;
      }
    }

    // speed over windows
    const double min_phi = M_PI / 8, min_len = 100;
    size_t i0 = 0;
    double t0 = 0;
    bool any = false;
    for (size_t k = 0; k < moves.size(); ++k) {
      const double phi0 = gc.phi[i0], phi1 = gc.phi[k + 1];
      const double l = id.len(phi1) - id.len(phi0);
      const bool last_one = (k + 1 == moves.size());
      if ((phi1 - phi0 >= min_phi && l >= min_len) || (last_one && !any)) {
        const double dtc = double(t[k]) - t0;
        const double v = l / dtc;
        const double rel = v / pr.v - 1.0;
        if (pr.constant) {
          ASSERT_LE(std::fabs(rel), 0.02)
              << what << ": window of moves " << i0 << ".." << k + 1 << " (" << l << " steps, "
              << dtc << " clocks) speed " << v << " commanded " << pr.v;
          worst_speed = std::max(worst_speed, std::fabs(rel));
        } else {
          ASSERT_LE(rel, 0.02) << what << ": window speed " << v << " above cruise " << pr.v;
          worst_over = std::max(worst_over, rel);
        }
        any = true;
        i0 = k + 1;
        t0 = double(t[k]);
      }
    }
  }
  std::printf(
      "[arc] RTL == reference for %d arcs (%d full circles, %d helices, %d late), %llu clocks; "
      "worst radial error %.4f steps, worst constant-speed error %.3f %%, profiled arcs at most "
      "%.3f %% above cruise\n",
      n, full, helix, late, static_cast<unsigned long long>(clocks), worst_radial,
      100 * worst_speed, 100 * worst_over);
}

}  // namespace
