// ARC frames (TYPE 0x13) through cnc_core's pins: UART -> frame_decoder -> FIFO -> segment_prep
// (R0^2, R1^2, floor(dT / N_RAMP), V*|DZ|) -> segment_executor (arc_dda) -> step_pulse pins.
// Arcs in the three planes (XY, ZX, YZ: the walk's u / v and helix steps on their axes). Every
// arc's STEP edges (time and DIR level at the rise) equal the integer reference walk
// (models/include/fpgacnc/models/arc_walk.h) at a fixed latency of 2 clocks from the arc's first
// clock (seg_start); zero gap where the directions continue (LINE -> ARC, ARC -> ARC, ARC ->
// LINE_PROFILE, ARC -> LINE at the minimum STEP period), an arc segment lasting c_last + 2 clocks
// (its last STEP on its last edge); end positions exact; no STEP/DIR timing violation; BAD_FIELD /
// BAD_LENGTH NAKs and the arc error fault (an inconsistent C_TOTAL) latched in STATUS faults bit 1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "Vcnc_core_heat.h"
#include "common/core_pins.h"
#include "common/pin_harness.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v2_exchange.h"
#include "common/v2_frames.h"
#include "fpgacnc/models/arc_walk.h"

namespace {

namespace arc = fpgacnc::models::arc;
namespace v2 = fpgacnc::tb::v2;

constexpr int kAxes = 4;
constexpr uint64_t kLatency = 2;  // arc clock c -> STEP rise seen at seg_start cycle + c + 2
const fpgacnc::tb::AxisTiming kTiming{2, 2, 4, 4};

class CoreBench : public fpgacnc::tb::PinHarness<Vcnc_core_heat> {
 public:
  CoreBench() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_heat>(), true, 3'000'000.0) {
    fpgacnc::tb::reset_core(*this);
  }
  std::vector<uint64_t> starts;
  std::vector<v2::DeviceMsg> msgs;

  // Sends a frame and runs until an answer other than DONE comes; returns it.
  v2::DeviceMsg exchange(const std::vector<uint8_t>& f) {
    return v2::exchange(*this, msgs, f, 60000);
  }

 protected:
  void observe() override {
    if (tx_bytes().size() != tx_seen_) {
      tx_seen_ = tx_bytes().size();
      if (auto m = parser_.push(tx_bytes().back().value, tx_bytes().back().start_cycle))
        msgs.push_back(*m);
    }
    if (dut().seg_start) starts.push_back(cycle());
  }

 private:
  size_t tx_seen_ = 0;
  v2::DeviceParser parser_;
};

void put(std::vector<uint8_t>& b, uint64_t v, int bytes) {
  for (int k = bytes - 1; k >= 0; --k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
}

// The ARC payload of docs/protocol.md (63 bytes).
// plane (flags bits 3:2): 0 XY, 1 ZX, 2 YZ
std::vector<uint8_t> arc_payload(const arc::Frame& f, uint8_t power, uint8_t plane = 0) {
  std::vector<uint8_t> b{static_cast<uint8_t>((f.g.ccw ? 3 : 2) | plane << 2), power};
  for (int32_t c : {f.g.i, f.g.j, f.g.dx, f.g.dy}) put(b, static_cast<uint32_t>(c) & 0xFFFFFFu, 3);
  put(b, static_cast<uint32_t>(f.dz), 4);
  put(b, f.n_ramp, 3);
  put(b, f.c_total, 6);
  put(b, f.v_entry, 8);
  put(b, f.v_cruise, 8);
  put(b, f.v_exit, 8);
  put(b, f.a, 6);
  put(b, f.d, 6);
  return b;
}

// An arc planned with arc::plan at a tangential speed v (steps per clock); ramp > 0 gives a
// trapezoid from v/4 over about `ramp` of the arc's cost at both ends.
arc::Frame planned(const arc::Geometry& g, int32_t dz, double v, double ramp) {
  arc::Frame f;
  f.g = g;
  f.dz = dz;
  const arc::Plan p = arc::plan(g);
  EXPECT_TRUE(p.ok) << "plan of I " << g.i << " J " << g.j << " DX " << g.dx << " DY " << g.dy;
  f.n_ramp = p.n_ramp;
  f.c_total = p.c_total;
  const double k = arc::cost_per_step(g, f.c_total);  // cost units per step of arc length
  f.v_cruise = arc::to_fixed48(v * k);
  if (ramp <= 0) {
    f.v_entry = f.v_exit = f.v_cruise;
    f.a = 1;
    f.d = f.c_total;
  } else {
    f.v_entry = f.v_exit = f.v_cruise / 4;
    const double cost = ramp * double(f.c_total);  // cost covered while ramping
    const double vc = double(f.v_cruise), ve = double(f.v_entry);
    // cost = (vc^2 - ve^2) / (2 A) in units of 2^-48 per clock: A = (vc^2 - ve^2) / (2 cost 2^48)
    f.a = static_cast<uint64_t>(std::max(1.0, (vc * vc - ve * ve) / (2.0 * cost * 0x1p48)));
    f.d = static_cast<uint64_t>(double(f.c_total) * (1.0 - ramp));
  }
  return f;
}

// The physical axes of an arc plane's u, v and helix (docs/protocol.md "ARC").
struct PlaneAxes {
  int u, v, h;
};
PlaneAxes plane_axes(uint8_t plane) {
  return plane == 1 ? PlaneAxes{2, 0, 1} : plane == 2 ? PlaneAxes{1, 2, 0} : PlaneAxes{0, 1, 2};
}

struct Seg {
  enum Kind { kLine, kProf, kArc, kDwell } kind = kLine;
  arc::Frame f;
  uint8_t plane = 0;   // arcs: 0 XY, 1 ZX, 2 YZ
  arc::RunResult ref;  // arcs
  int64_t steps[kAxes] = {0, 0, 0, 0};
  bool zero_gap_after = false;  // the next segment must start right after this one's last clock
  uint64_t ticks = 0;           // LINE: T
};

// A chain of arcs about one centre, starting 45 degrees from +X (CCW): the tangent signs stay
// (-, +), (-, -), (+, -), (+, +) at the joins away from the axes, so consecutive arcs need no DIR
// change at the join.
std::vector<Seg> chain(int32_t a, bool helix) {
  std::vector<Seg> out;
  const int pts[5][2] = {{a, a}, {-a, a}, {-a, -a}, {a, -a}, {a, a}};
  for (int q = 0; q < 4; ++q) {
    Seg s;
    s.kind = Seg::kArc;
    arc::Geometry g{-pts[q][0], -pts[q][1], pts[q + 1][0] - pts[q][0], pts[q + 1][1] - pts[q][1],
                    true};
    s.f = planned(g, helix ? 25 + 5 * q : 0, 0.06, q == 1 ? 0.2 : 0.0);
    out.push_back(s);
  }
  Seg full;  // one full turn from the same point (DX = DY = 0)
  full.kind = Seg::kArc;
  full.f = planned(arc::Geometry{-a, -a, 0, 0, true}, helix ? 60 : 0, 0.05, 0.1);
  out.push_back(full);
  return out;
}

TEST(ArcCore, ArcFramesThroughThePins) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261121, "ArcCore");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  CoreBench b;
  b.send(v2::hello());
  for (int i = 0; i < 30000 && b.msgs.empty(); ++i) b.tick();
  ASSERT_FALSE(b.msgs.empty()) << "no IDENT";
  uint8_t seq = 0;
  for (uint8_t ax = 0; ax < kAxes; ++ax) {  // min_period is the largest of all axes
    const auto m = b.exchange(v2::config_axis(
        seq++, ax, static_cast<uint16_t>(kTiming.high), static_cast<uint16_t>(kTiming.low),
        static_cast<uint16_t>(kTiming.setup), static_cast<uint16_t>(kTiming.hold)));
    ASSERT_EQ(m.type, v2::kAck) << "CONFIG_AXIS " << int(ax);
  }

  // The job: a dwell (so that every frame is queued before motion starts), a LINE into a chain of
  // quarter arcs (helix) and a full circle, a LINE_PROFILE, then random arcs (both directions,
  // radii 6..400 steps, full circles, helices) and a second chain, flat.
  std::vector<Seg> segs;
  {
    Seg d;
    d.kind = Seg::kDwell;
    segs.push_back(d);
    Seg l;  // X -, Y +, Z + (the chain's first tangent, its helix): no DIR change at the join
    l.kind = Seg::kLine;
    l.steps[0] = -40;
    l.steps[1] = 30;
    l.steps[2] = 1;
    l.ticks = 40 * 20;
    l.zero_gap_after = true;
    segs.push_back(l);
  }
  for (auto& s : chain(70, true)) {
    s.zero_gap_after = true;
    segs.push_back(s);
  }
  {
    Seg p;  // LINE_PROFILE X -20, Y +35 from the chain's last tangent (-, +)
    p.kind = Seg::kProf;
    p.steps[0] = -20;
    p.steps[1] = 35;
    segs.push_back(p);
  }
  int full_circles = 1, helices = 5;
  for (int n = 0; n < 10; ++n) {
    const double r = n == 0 ? 6.0 : 6.0 + u01(rng) * 394.0;
    const double a0 = u01(rng) * 2 * M_PI;
    const bool full = (n % 4 == 1);
    const double sweep = full ? 0.0 : (0.1 + u01(rng) * 1.8) * M_PI;
    const bool ccw = u01(rng) < 0.5;
    const double a1 = a0 + (ccw ? sweep : -sweep);
    const int64_t x0 = std::llround(r * std::cos(a0)), y0 = std::llround(r * std::sin(a0));
    const int64_t x1 = full ? x0 : std::llround(r * std::cos(a1));
    const int64_t y1 = full ? y0 : std::llround(r * std::sin(a1));
    if (x0 == 0 && y0 == 0) continue;
    if (!full && x1 == x0 && y1 == y0) continue;
    arc::Geometry g{static_cast<int32_t>(-x0), static_cast<int32_t>(-y0),
                    static_cast<int32_t>(x1 - x0), static_cast<int32_t>(y1 - y0), ccw};
    const arc::Plan p = arc::plan(g);
    if (!p.ok) continue;
    const int32_t dz = (n % 3 == 2) ? static_cast<int32_t>(u01(rng) * 80) - 40 : 0;
    Seg s;
    s.kind = Seg::kArc;
    s.f = planned(g, dz, 0.02 + u01(rng) * 0.08, n % 2 ? 0.15 : 0.0);
    s.plane = static_cast<uint8_t>(n % 3);  // G17, G18, G19 in turn
    full_circles += full;
    helices += dz != 0;
    segs.push_back(s);
  }
  for (auto& s : chain(150, false)) {
    s.zero_gap_after = true;
    segs.push_back(s);
  }
  {
    // A LINE queued behind the last arc (zero gap, the arc's end tangent (-, +)) with X and Y at
    // the minimum period (STEP high + low = 4): its first steps come 4 clocks after its start, so
    // the arc's last STEP must rise by the arc segment's last edge (one edge later would be a STEP
    // timing violation).
    Seg l;
    l.kind = Seg::kLine;
    l.steps[0] = -8;
    l.steps[1] = 8;
    l.ticks = 8 * (kTiming.high + kTiming.low);
    segs.push_back(l);
  }

  // reference walks, and the frames
  std::vector<std::vector<uint8_t>> frames;
  const uint8_t dwell_seq = seq++;
  uint64_t motion_clocks = 0;
  for (auto& s : segs) {
    switch (s.kind) {
      case Seg::kDwell:
        break;
      case Seg::kLine:
        frames.push_back(
            v2::line(seq++, 1, 200, static_cast<uint32_t>(s.ticks),
                     {static_cast<int32_t>(s.steps[0]), static_cast<int32_t>(s.steps[1]),
                      static_cast<int32_t>(s.steps[2]), 0},
                     true));
        motion_clocks += s.ticks;
        break;
      case Seg::kProf: {
        std::vector<uint8_t> p{0x81, 255};
        const uint64_t vc = (uint64_t{1} << 48) / 20;  // 1/20 step per clock
        put(p, vc / 4, 6);
        put(p, vc, 6);
        put(p, vc / 4, 6);
        put(p, 2'000'000, 4);
        put(p, 20, 4);
        for (int a = 0; a < kAxes; ++a) put(p, static_cast<uint16_t>(s.steps[a]), 2);
        frames.push_back(v2::frame(0x12, seq++, p));
        motion_clocks += 35 * 40;
        break;
      }
      case Seg::kArc: {
        s.ref = arc::run(s.f);
        ASSERT_FALSE(s.ref.err) << "reference walk inconsistent, arc " << frames.size();
        const PlaneAxes ax = plane_axes(s.plane);
        s.steps[ax.u] = s.ref.x;
        s.steps[ax.v] = s.ref.y;
        s.steps[ax.h] = s.ref.z;
        frames.push_back(v2::frame(0x13, seq++, arc_payload(s.f, 255, s.plane)));
        motion_clocks += s.ref.end_clock + 2;  // the segment: c_last + 2 ticks
        break;
      }
    }
  }
  // the dwell lasts until every frame has arrived (10 bits of 16.7 clocks per byte)
  uint64_t bytes = 0;
  for (const auto& f : frames) bytes += f.size();
  const uint32_t dwell = static_cast<uint32_t>(bytes * 10 * 17 + 50'000);
  ASSERT_EQ(b.exchange(v2::dwell(dwell_seq, dwell)).type, v2::kAck);
  for (const auto& f : frames) b.queue(f);
  const uint32_t n_fifo = static_cast<uint32_t>(frames.size()) + 1;
  uint64_t guard = 0;
  while ((b.dut().segments_done < n_fifo || !b.rx_idle()) &&
         ++guard < dwell + 4 * motion_clocks + 1'000'000)
    b.tick();
  ASSERT_EQ(b.dut().segments_done, n_fifo) << "by cycle " << b.cycle() << ", seed " << seed;
  for (int i = 0; i < 200; ++i) b.tick();
  for (const auto& m : b.msgs)
    EXPECT_NE(m.type, v2::kNak) << "a NAK for seq " << int(m.u8(0)) << " reason " << int(m.u8(1));
  ASSERT_EQ(b.starts.size(), segs.size()) << "seg_start count";
  EXPECT_EQ(b.dut().violations, 0) << "STEP/DIR timing violations";
  EXPECT_EQ(b.dut().faults, 0) << "faults";
  for (int a = 0; a < 3; ++a)
    for (auto& v : b.mon().check_pulses(a, kTiming)) ADD_FAILURE() << v;

  // every arc's edges: rises in [start, start + end_clock + latency] equal the reference's
  int arcs = 0, zero_gaps = 0;
  uint64_t events = 0;
  for (size_t i = 0; i < segs.size(); ++i) {
    const Seg& s = segs[i];
    const uint64_t st = b.starts[i];
    if (s.kind == Seg::kArc) {
      arcs += 1;
      for (int a = 0; a < 3; ++a) {
        std::vector<std::pair<uint64_t, int>> want, got;
        const PlaneAxes ax = plane_axes(s.plane);
        for (const auto& e : s.ref.events) {
          const int d = a == ax.u ? e.dx : a == ax.v ? e.dy : e.dz;
          if (d) want.emplace_back(st + e.clock + kLatency, d > 0 ? 1 : 0);
        }
        const auto& tr = b.mon().axis(a);
        for (size_t k = 0; k < tr.rises.size(); ++k)
          if (tr.rises[k] >= st + kLatency && tr.rises[k] <= st + s.ref.end_clock + kLatency)
            got.emplace_back(tr.rises[k], tr.rise_dir[k]);
        for (size_t k = 0; k < std::min(want.size(), got.size()); ++k) {
          ASSERT_EQ(got[k].first, want[k].first) << "arc segment " << i << " axis " << a << " step "
                                                 << k << " (rise cycle), seed " << seed;
          ASSERT_EQ(got[k].second, want[k].second)
              << "arc segment " << i << " axis " << a << " step " << k << " (DIR), seed " << seed;
        }
        ASSERT_EQ(got.size(), want.size())
            << "arc segment " << i << " axis " << a << ", seed " << seed;
        events += want.size();
      }
    }
    if (i + 1 < segs.size()) {
      // an arc segment lasts c_last + 2 ticks: its last STEP rises on its last edge
      const uint64_t len = s.kind == Seg::kArc ? s.ref.end_clock + 2 : s.ticks;
      if (s.zero_gap_after) {
        EXPECT_EQ(b.starts[i + 1] - st, len) << "zero gap after segment " << i;
        zero_gaps += 1;
      } else if (s.kind == Seg::kArc) {
        EXPECT_GE(b.starts[i + 1] - st, len) << "segment " << i + 1 << " starts inside arc " << i;
      }
    }
  }
  // end positions: the sum of all segments, from the pins and from the core's position
  int64_t want_pos[kAxes] = {0, 0, 0, 0};
  for (const auto& s : segs)
    for (int a = 0; a < kAxes; ++a) want_pos[a] += s.steps[a];
  for (int a = 0; a < kAxes; ++a) {
    int64_t net = 0;
    for (int d : b.mon().axis(a).rise_dir) net += d ? 1 : -1;
    EXPECT_EQ(net, want_pos[a]) << "axis " << a << " net steps at the pins";
    const auto pos = static_cast<int32_t>(b.dut().position[a]);
    EXPECT_EQ(pos, want_pos[a]) << "axis " << a << " position";
  }
  std::printf(
      "ArcCore: seed %llu, %d arcs (%d full circles, %d helices), %llu arc step edges equal "
      "to the reference, %d zero-gap joins, %llu cycles\n",
      static_cast<unsigned long long>(seed), arcs, full_circles + 1, helices,
      static_cast<unsigned long long>(events), zero_gaps,
      static_cast<unsigned long long>(b.cycle()));
}

// Feed hold and rates inside arcs (docs/timing.md "Feed hold and overrides"): a chain of quarter
// arcs (X or Y reverses inside each one) and a full helical turn, run plainly and then with a feed
// rate of 37 %, a hold that comes to rest inside an arc, a resume and 100 % again, each at a
// seeded clock. The held run shows the same STEP events (axes, DIR at the rise) in the same order
// with the same coincidences, never two closer together than in the plain run, no STEP/DIR
// timing violation (the in-arc DIR changes only get more room), no STEP while at rest, and the
// same end positions.
struct ArcEvent {
  uint64_t clock;
  unsigned axes, dirs;
};
std::vector<ArcEvent> arc_events(CoreBench& b) {
  std::vector<ArcEvent> ev;
  for (int a = 0; a < 3; ++a) {
    const auto& tr = b.mon().axis(a);
    for (size_t k = 0; k < tr.rises.size(); ++k)
      ev.push_back({tr.rises[k], 1u << a, tr.rise_dir[k] ? 1u << a : 0u});
  }
  std::sort(ev.begin(), ev.end(),
            [](const ArcEvent& x, const ArcEvent& y) { return x.clock < y.clock; });
  std::vector<ArcEvent> merged;
  for (const ArcEvent& e : ev) {
    if (!merged.empty() && merged.back().clock == e.clock) {
      merged.back().axes |= e.axes;
      merged.back().dirs |= e.dirs;
    } else {
      merged.push_back(e);
    }
  }
  return merged;
}

std::vector<uint8_t> motion_frame(uint8_t flags, uint16_t feed, uint32_t ramp) {
  std::vector<uint8_t> p{flags};
  v2::be16(p, feed);
  v2::be16(p, 0x8000);
  v2::be32(p, ramp);
  return v2::frame(0x08, 0, p);
}

TEST(ArcCore, HoldAndRatesInsideArcsKeepThePath) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261127, "ArcCoreHold");
  std::mt19937_64 rng(seed);
  std::vector<std::vector<uint8_t>> frames;
  uint8_t seq = 4;  // after the four CONFIG_AXIS frames and the dwell
  for (auto& s : chain(90, true))
    frames.push_back(v2::frame(0x13, ++seq, arc_payload(s.f, 255, 0)));
  uint64_t bytes = 0;
  for (const auto& f : frames) bytes += f.size();
  const uint32_t dwell = static_cast<uint32_t>(bytes * 10 * 17 + 20'000);

  auto start = [&](CoreBench& b) {
    b.exchange(v2::hello());
    for (uint8_t ax = 0; ax < kAxes; ++ax)
      ASSERT_EQ(b.exchange(v2::config_axis(ax, ax, static_cast<uint16_t>(kTiming.high),
                                           static_cast<uint16_t>(kTiming.low),
                                           static_cast<uint16_t>(kTiming.setup),
                                           static_cast<uint16_t>(kTiming.hold)))
                    .type,
                v2::kAck);
    ASSERT_EQ(b.exchange(v2::dwell(4, dwell)).type, v2::kAck);
    for (const auto& f : frames) b.queue(f);
    while (!b.rx_idle()) b.tick();
  };
  auto finish = [&](CoreBench& b) {
    const uint32_t n = static_cast<uint32_t>(frames.size()) + 1;
    for (uint64_t g = 0; g < 50'000'000 && b.dut().segments_done < n; ++g) b.tick();
    ASSERT_EQ(b.dut().segments_done, n) << "by cycle " << b.cycle() << ", seed " << seed;
    b.idle(200);
  };
  CoreBench plain;
  start(plain);
  finish(plain);

  CoreBench held;
  start(held);
  while (held.starts.size() < 2) held.tick();  // the dwell is over: the first arc runs
  auto wait = [&](uint64_t lo, uint64_t hi) {
    held.idle(std::uniform_int_distribution<uint64_t>(lo, hi)(rng));
  };
  wait(100, 3'000);
  EXPECT_EQ(held.exchange(motion_frame(0, 0x8000 * 37 / 100, 1u << 28)).type, v2::kStatus);
  wait(1'000, 20'000);
  const uint32_t ramp = (1u << 31) / 40;  // 37 % to 0 in about 30 periods
  EXPECT_EQ(held.exchange(motion_frame(1, 0x8000 * 37 / 100, ramp)).type, v2::kStatus);
  held.idle(60 * 256);
  size_t at_rest = 0;
  for (int a = 0; a < 3; ++a) at_rest += held.mon().axis(a).rises.size();
  const uint32_t done_at_rest = held.dut().segments_done;
  held.idle(50'000);
  size_t later = 0;
  for (int a = 0; a < 3; ++a) later += held.mon().axis(a).rises.size();
  EXPECT_EQ(later, at_rest) << "a STEP while at rest";
  EXPECT_LT(done_at_rest, frames.size() + 1) << "the hold came after the last arc, seed " << seed;
  EXPECT_EQ(held.exchange(motion_frame(2, 0x8000 * 37 / 100, ramp)).type, v2::kStatus);
  wait(1'000, 30'000);
  EXPECT_EQ(held.exchange(motion_frame(0, 0x8000, 1u << 26)).type, v2::kStatus);
  finish(held);

  EXPECT_EQ(held.dut().violations, 0) << "STEP/DIR timing violations, seed " << seed;
  EXPECT_EQ(held.dut().faults, 0) << "faults, seed " << seed;
  for (int a = 0; a < 3; ++a)
    for (auto& v : held.mon().check_pulses(a, kTiming)) ADD_FAILURE() << v;
  const auto p = arc_events(plain), h = arc_events(held);
  ASSERT_EQ(p.size(), h.size()) << "step events, seed " << seed;
  for (size_t k = 0; k < p.size(); ++k) {
    ASSERT_EQ(p[k].axes, h[k].axes) << "event " << k << ", seed " << seed;
    ASSERT_EQ(p[k].dirs, h[k].dirs) << "event " << k << " DIR, seed " << seed;
    if (k > 0) {
      ASSERT_GE(h[k].clock - h[k - 1].clock, p[k].clock - p[k - 1].clock)
          << "event " << k << " faster than planned, seed " << seed;
    }
  }
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(held.dut().position[a], plain.dut().position[a]) << "axis " << a;
  std::printf("ArcCoreHold: seed %llu, %zu step events; plain run %llu cycles, held %llu\n",
              static_cast<unsigned long long>(seed), p.size(),
              static_cast<unsigned long long>(plain.cycle()),
              static_cast<unsigned long long>(held.cycle()));
}

// Rule breakers are NAKed (BAD_FIELD 7, BAD_LENGTH 2) with nothing queued; the first good frame
// after them takes the same seq. An arc whose C_TOTAL is one more than its walk's ends at its end
// point and latches `arc error` (faults bit 1) until FAULT_CLEAR.
TEST(ArcCore, BadFieldsAndArcError) {
  CoreBench b;
  b.send(v2::hello());
  for (int i = 0; i < 30000 && b.msgs.empty(); ++i) b.tick();
  ASSERT_FALSE(b.msgs.empty()) << "no IDENT";
  const arc::Frame ok = planned(arc::Geometry{-20, 0, -20, 20, true}, 0, 0.002, 0.0);
  struct Bad {
    const char* what;
    std::vector<uint8_t> payload;
    uint8_t reason;
  };
  std::vector<Bad> bad;
  auto with = [&](auto f) {
    arc::Frame x = ok;
    f(x);
    return arc_payload(x, 255);
  };
  auto flags = [&](uint8_t fl) {
    auto p = arc_payload(ok, 255);
    p[0] = fl;
    return p;
  };
  bad.push_back({"motion code 1", flags(0x01), 7});
  bad.push_back({"motion code 0", flags(0x00), 7});
  bad.push_back({"flag bit 4", flags(0x13), 7});
  bad.push_back({"plane 3", flags(0x0F), 7});
  bad.push_back({"flag bit 7", flags(0x83), 7});
  bad.push_back({"start at the centre", with([](arc::Frame& f) { f.g.i = f.g.j = 0; }), 7});
  bad.push_back({"end at the centre", with([](arc::Frame& f) {
                   f.g.dx = -20;
                   f.g.dy = 0;
                 }),
                 7});
  bad.push_back({"|I| = 2^22", with([](arc::Frame& f) { f.g.i = -(1 << 22); }), 7});
  bad.push_back({"|DX - I| = 2^22", with([](arc::Frame& f) {
                   f.g.dx = (1 << 22) + f.g.i;
                   f.g.dy = f.g.j;
                 }),
                 7});
  bad.push_back({"DZ = -2^31", with([](arc::Frame& f) { f.dz = INT32_MIN; }), 7});
  bad.push_back({"N_RAMP = 0", with([](arc::Frame& f) { f.n_ramp = 0; }), 7});
  bad.push_back({"C_TOTAL = 0", with([](arc::Frame& f) { f.c_total = 0; }), 7});
  bad.push_back({"C_TOTAL = 2^46", with([](arc::Frame& f) { f.c_total = uint64_t{1} << 46; }), 7});
  bad.push_back(
      {"V_cruise = 2^63", with([](arc::Frame& f) { f.v_cruise = uint64_t{1} << 63; }), 7});
  bad.push_back({"V_entry > V_cruise", with([](arc::Frame& f) { f.v_entry = f.v_cruise + 1; }), 7});
  bad.push_back({"V_exit > V_cruise", with([](arc::Frame& f) { f.v_exit = f.v_cruise + 1; }), 7});
  bad.push_back({"V_exit = 0", with([](arc::Frame& f) { f.v_exit = 0; }), 7});
  bad.push_back({"A = 0, V_entry = 0", with([](arc::Frame& f) {
                   f.a = 0;
                   f.v_entry = 0;
                 }),
                 7});
  {
    auto p = arc_payload(ok, 255);
    p.pop_back();
    bad.push_back({"62 bytes", p, 2});
    p.push_back(0);
    p.push_back(0);
    bad.push_back({"64 bytes", p, 2});
  }
  uint8_t seq = 0;
  for (const auto& x : bad) {
    const auto m = b.exchange(v2::frame(0x13, seq, x.payload));
    EXPECT_EQ(m.type, v2::kNak) << x.what;
    if (m.type == v2::kNak) {
      EXPECT_EQ(m.u8(0), seq) << x.what;
      EXPECT_EQ(m.u8(1), x.reason) << x.what;
    }
  }
  EXPECT_EQ(b.dut().fifo_level, 0) << "a NAKed frame reached the FIFO";
  // the good one, then the inconsistent one (C_TOTAL + 1)
  ASSERT_EQ(b.exchange(v2::frame(0x13, seq++, arc_payload(ok, 255))).type, v2::kAck);
  arc::Frame off = ok;
  off.c_total += 1;
  const arc::RunResult ref_off = arc::run(off);
  EXPECT_TRUE(ref_off.err) << "the reference does not see C_TOTAL + 1";
  ASSERT_EQ(b.exchange(v2::frame(0x13, seq++, arc_payload(off, 255))).type, v2::kAck);
  uint64_t guard = 0;
  while (b.dut().segments_done < 2 && ++guard < 4'000'000) b.tick();
  ASSERT_EQ(b.dut().segments_done, 2u) << "by cycle " << b.cycle();
  for (int i = 0; i < 100; ++i) b.tick();
  EXPECT_EQ(b.dut().faults, 2) << "arc error latched in faults bit 1";
  EXPECT_EQ(static_cast<int32_t>(b.dut().position[0]), -40) << "X after two quarter arcs";
  EXPECT_EQ(static_cast<int32_t>(b.dut().position[1]), 40) << "Y after two quarter arcs";
  ASSERT_EQ(b.exchange(v2::fault_clear(seq++)).type, v2::kAck);
  for (int i = 0; i < 100; ++i) b.tick();
  EXPECT_EQ(b.dut().faults, 0) << "after FAULT_CLEAR";
}

}  // namespace
