// The event-driven twins against their clock-by-clock references (clockwise_ref.h), bit for bit,
// on random inputs and the edge cases (CTest label unit): run_profile (LINE_PROFILE: ticks of
// every step, J, cruised) and arc::run / arc::Dda (ARC: every event, end clock, moves, position,
// err, late), the closed-form helpers of ramp.h against direct sums, and PinRecorder's merge
// against a plain sort. Fixed seeds; exit status 1 on any difference. Options: --profiles N,
// --arcs N, --seed S.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdlib>
#include <random>
#include <string>

#include "../cosim/arc_stimulus.h"
#include "clockwise_ref.h"
#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/models/ramp.h"
#include "fpgacnc/twins/timing.h"
#include "fpgacnc/twins/tlm_common.h"

namespace {

using namespace fpgacnc::twins;
namespace arc = fpgacnc::models::arc;
namespace ramp = fpgacnc::models::ramp;
using u128 = unsigned __int128;
int failures = 0;

void fail(const std::string& what) {
  if (++failures <= 20) fmt::print("FAIL: {}\n", what);
}

uint64_t pick(std::mt19937_64& g, uint64_t lo, uint64_t hi) {
  return std::uniform_int_distribution<uint64_t>(lo, hi)(g);
}
// log-uniform in [lo, hi]
uint64_t pick_log(std::mt19937_64& g, uint64_t lo, uint64_t hi) {
  const double x =
      std::uniform_real_distribution<double>(std::log(double(lo)), std::log(double(hi) + 1.0))(g);
  return std::clamp<uint64_t>(static_cast<uint64_t>(std::exp(x)), lo, hi);
}

// ---- ramp.h ------------------------------------------------------------------------------------

void ramp_helpers(std::mt19937_64& g) {
  // sum() against the clock-by-clock sum, rising and falling, and saturation.
  for (int n = 0; n < 2000; ++n) {
    const u128 q = pick(g, 0, ~0ull), step = pick_log(g, 1, 1ull << 40);
    const bool falling = pick(g, 0, 1) == 1;
    const uint64_t len = pick(g, 0, 300);
    const u128 r = falling ? step * len + pick(g, 0, 1000) : u128{pick(g, 0, ~0ull)};
    u128 qq = q, rr = r;
    for (uint64_t i = 0; i <= len; ++i) {
      if (ramp::sum(q, r, step, falling, i) != qq) {
        fail(fmt::format("ramp::sum falling={} i={}", falling, i));
        break;
      }
      qq += rr;
      rr = falling ? rr - step : rr + step;
    }
  }
  if (ramp::sum(1, u128{1} << 100, 1, false, 1ull << 40) != ramp::kSat) fail("ramp::sum saturates");
  if (ramp::sat_mul(u128{1} << 70, u128{1} << 70) != ramp::kSat) fail("sat_mul saturates");
  if (ramp::tri_below(1ull << 62) != (u128{1} << 61) * ((u128{1} << 62) - 1))
    fail("tri_below(2^62)");
  // last_true against a linear scan.
  for (int n = 0; n < 5000; ++n) {
    const uint64_t hi = pick(g, 0, 3) == 0 ? pick(g, 0, 70) : pick_log(g, 1, 1ull << 62);
    const uint64_t edge = pick(g, 0, 1) == 0 ? pick(g, 0, std::min<uint64_t>(hi + 3, 70))
                                             : pick_log(g, 1, std::max<uint64_t>(hi, 1) + 5);
    uint64_t calls = 0;
    const uint64_t got = ramp::last_true(hi, [&](uint64_t i) {
      ++calls;
      return i <= edge;
    });
    if (got != std::min(hi, edge)) fail(fmt::format("last_true hi={} edge={}: {}", hi, edge, got));
    if (calls > 130) fail(fmt::format("last_true hi={}: {} calls", hi, calls));
  }
}

// ---- DdaTicks ----------------------------------------------------------------------------------

void dda_ticks(std::mt19937_64& g) {
  // ceil_div's 64-bit path against the 128-bit one
  for (int i = 0; i < 200'000; ++i) {
    const __int128 b = pick_log(g, 1, ~0ull >> 1);
    const __int128 a = pick(g, 0, 2) == 0   ? static_cast<__int128>(pick(g, 0, 3)) * b
                       : pick(g, 0, 9) == 0 ? -static_cast<__int128>(pick_log(g, 1, ~0ull >> 1))
                                            : static_cast<__int128>(pick_log(g, 1, ~0ull >> 1));
    const __int128 q = a / b, r = a % b;
    const __int128 want = q + (r > 0 ? 1 : 0);
    if (ceil_div(a, b) != static_cast<int64_t>(want))
      fail(fmt::format("ceil_div({}, {})", static_cast<int64_t>(a), static_cast<int64_t>(b)));
  }
  for (int i = 0; i < 20'000; ++i) {
    const uint64_t n = pick(g, 0, 3) == 0 ? pick(g, 1, 5) : pick_log(g, 1, 1u << 16);
    const uint64_t total = pick(g, 0, 2) == 0 ? n * pick(g, 1, 100'000) + pick(g, 0, n - 1)
                                              : pick_log(g, 1, ~0ull >> 8);
    DdaTicks t(n, total);
    const uint64_t probe = std::min<uint64_t>(n, 2000);
    for (uint64_t k = 1; k <= n; ++k) {
      const uint64_t got = t.next();
      if (k > probe && k < n - 2) continue;  // check the first 2000 and the last ones
      if (static_cast<int64_t>(got) != dda_tick(k, n, total)) {
        fail(fmt::format("DdaTicks n {} T {}: step {} at {}, dda_tick {}", n, total, k, got,
                         dda_tick(k, n, total)));
        break;
      }
    }
  }
}

// ---- run_profile -------------------------------------------------------------------------------

struct ProfileCase {
  ProfileParams p;
  std::array<uint32_t, kAxes> n{};
};

// A LINE_PROFILE within the decoder's rules, its clocks of acceleration and deceleration kept in
// the tens of thousands (the reference walks them one by one); one in eight breaks the host
// rules the decoder does not check (V_entry above V_cruise, deceleration starting below V_exit).
ProfileCase random_profile(std::mt19937_64& g) {
  ProfileCase c;
  const uint32_t shape = static_cast<uint32_t>(pick(g, 0, 9));
  const uint32_t n_dom = shape == 0   ? 1
                         : shape == 1 ? static_cast<uint32_t>(pick(g, 1, 4))
                                      : static_cast<uint32_t>(pick_log(g, 1, 4000));
  for (int a = 0; a < kAxes; ++a) {
    const uint64_t kind = pick(g, 0, 5);
    c.n[a] = kind == 0 ? 0 : kind == 1 ? n_dom : static_cast<uint32_t>(pick(g, 0, n_dom));
  }
  c.n[pick(g, 0, kAxes - 1)] = n_dom;
  const uint64_t ramp_clocks = pick(g, 0, 3) == 0 ? pick(g, 0, 20) : pick_log(g, 1, 30'000);
  const uint64_t accel = pick(g, 0, 9) == 0   ? 0
                         : pick(g, 0, 9) == 0 ? pick(g, 1, 3)
                         : pick(g, 0, 9) == 0 ? 0xFFFF'FFFFull
                                              : pick_log(g, 1, 0xFFFF'FFFFull);
  const uint64_t vmax = (1ull << 47) - 1;
  c.p.accel = static_cast<uint32_t>(accel);
  c.p.v_cruise = std::clamp<uint64_t>(std::max<uint64_t>(accel, 1) * ramp_clocks, 1, vmax);
  if (pick(g, 0, 7) == 0) c.p.v_cruise = pick_log(g, 1, vmax);
  const uint64_t vc = c.p.v_cruise;
  // the reference skips constant stretches only: every ramp within 200 000 clocks
  if (accel != 0)
    c.p.accel = static_cast<uint32_t>(std::clamp<uint64_t>(vc / 200'000, accel, 0xFFFF'FFFFull));
  const uint64_t e = pick(g, 0, 4);
  c.p.v_entry = e == 0 ? 0 : e == 1 ? vc : pick(g, 0, vc);
  if (accel == 0 && c.p.v_entry == 0) c.p.v_entry = vc;
  const uint64_t x = pick(g, 0, 4);
  c.p.v_exit = x == 0 ? 1 : x == 1 ? vc : pick(g, 1, vc);
  const uint64_t d = pick(g, 0, 5);
  c.p.decel_at = d == 0   ? 0
                 : d == 1 ? n_dom
                 : d == 2 ? n_dom + static_cast<uint32_t>(pick(g, 1, 5))
                          : static_cast<uint32_t>(pick(g, 0, n_dom));
  if (pick(g, 0, 7) == 0) {  // outside the host rules, still within the decoder's
    if (pick(g, 0, 1) == 0 && vc > 1)
      c.p.v_cruise = pick(g, 1, vc - 1);  // V_entry / V_exit above V_cruise
    else
      c.p.v_exit = std::min(vmax, vc + pick(g, 0, vc));
  }
  return c;
}

void compare_profile(const ProfileCase& c, const std::string& name) {
  const ProfileRun got = run_profile(c.p, c.n), want = ref::run_profile(c.p, c.n);
  const std::string what =
      fmt::format("{} (Ve {} Vc {} Vx {} A {} D {} n {} {} {} {})", name, c.p.v_entry, c.p.v_cruise,
                  c.p.v_exit, c.p.accel, c.p.decel_at, c.n[0], c.n[1], c.n[2], c.n[3]);
  if (got.ticks_total != want.ticks_total)
    fail(fmt::format("{}: J {} != {}", what, got.ticks_total, want.ticks_total));
  if (got.cruised != want.cruised) fail(fmt::format("{}: cruised {}", what, got.cruised));
  for (int a = 0; a < kAxes; ++a)
    if (got.ticks[a] != want.ticks[a]) {
      size_t k = 0;
      while (k < got.ticks[a].size() && k < want.ticks[a].size() &&
             got.ticks[a][k] == want.ticks[a][k])
        ++k;
      fail(fmt::format("{}: axis {} step {} differs ({} / {} steps)", what, a, k + 1,
                       got.ticks[a].size(), want.ticks[a].size()));
    }
}

void profiles(std::mt19937_64& g, int count) {
  // Edge cases by hand: A = 0, V_entry = 0, a triangle, D = 0, V_exit = 1, one step, huge and
  // tiny A, four axes with different counts, the docs/protocol.md worked example.
  const std::array<ProfileCase, 10> fixed{{
      {{5'000'000'000, 5'000'000'000, 5'000'000'000, 0, 7}, {7, 3, 0, 1}},
      {{0, 18'014'398'509, 1'000'000'000, 18'014, 288}, {320, 160, 0, 0}},
      {{0, 70'368'744'177'663, 1'000'000'000, 18'014, 3}, {6, 1, 2, 5}},
      {{0, 70'368'744'177'663, 1, 0xFFFF'FFFF, 0}, {1, 0, 0, 0}},
      {{0, 40'000, 1, 1, 1}, {1, 1, 1, 1}},
      {{1'000, 1'000'000'000'000, 1'000, 1'234'567, 0}, {1000, 999, 500, 1}},
      {{0, 1ull << 46, 1ull << 46, 0xFFFF'FFFF, 4}, {4, 3, 2, 1}},
      {{1ull << 46, 1ull << 46, 1, 0xFFFF'FFFF, 2}, {17, 0, 16, 15}},
      {{3, 30'000, 2, 1, 0}, {2, 1, 0, 0}},
      {{0, 100'000, 100'000, 7, 10}, {1, 1, 1, 1}},
  }};
  for (size_t i = 0; i < fixed.size(); ++i) compare_profile(fixed[i], fmt::format("fixed {}", i));
  for (int i = 0; i < count; ++i) compare_profile(random_profile(g), fmt::format("random {}", i));
}

// ---- arc::run ----------------------------------------------------------------------------------

void compare_arc(const arc::Frame& f, uint64_t max_clocks, const std::string& name) {
  const arc::RunResult got = arc::run(f, max_clocks), want = ref::arc::run(f, max_clocks);
  const std::string what = fmt::format(
      "{} (I {} J {} DX {} DY {} DZ {} ccw {} N_RAMP {} C {} Ve {} Vc {} Vx {} A {} D {})", name,
      f.g.i, f.g.j, f.g.dx, f.g.dy, f.dz, f.g.ccw, f.n_ramp, f.c_total, f.v_entry, f.v_cruise,
      f.v_exit, f.a, f.d);
  if (got.events.size() != want.events.size())
    fail(fmt::format("{}: {} events != {}", what, got.events.size(), want.events.size()));
  for (size_t k = 0; k < std::min(got.events.size(), want.events.size()); ++k) {
    const arc::Event &a = got.events[k], &b = want.events[k];
    if (a.clock != b.clock || a.dx != b.dx || a.dy != b.dy || a.dz != b.dz || a.last != b.last) {
      fail(fmt::format("{}: event {} at clock {} ({} {} {}) != clock {} ({} {} {})", what, k,
                       a.clock, a.dx, a.dy, a.dz, b.clock, b.dx, b.dy, b.dz));
      break;
    }
  }
  if (got.end_clock != want.end_clock || got.moves != want.moves || got.x != want.x ||
      got.y != want.y || got.z != want.z || got.err != want.err || got.late != want.late)
    fail(
        fmt::format("{}: end {} / {}, moves {} / {}, xyz {} {} {} / {} {} {}, err {} / {}, "
                    "late {} / {}",
                    what, got.end_clock, want.end_clock, got.moves, want.moves, got.x, got.y, got.z,
                    want.x, want.y, want.z, got.err, want.err, got.late, want.late));
}

// A random ARC frame (arc_stimulus.h's host rules) with its profile fields and Z varied: fast
// arcs whose moves wait for the walk (late), long helices (several Z steps per move), ramps
// that never cruise, D = 0, V_exit = 1, V_entry = 0, A = 0, tiny and huge A.
arc::Frame random_arc(std::mt19937_64& g) {
  ArcStimulus o;
  o.r_log_max = pick(g, 0, 1) == 0 ? 60 : 0;
  o.r_min = 1;
  o.r_span = 40;
  o.cps_lo = static_cast<uint32_t>(pick(g, 0, 1) == 0 ? 1 : 20);
  o.cps_hi = o.cps_lo + 200;
  o.bad_in = 8;
  arc::Frame f = random_arc_frame(g, o);
  const uint64_t vc = f.v_cruise;
  switch (pick(g, 0, 9)) {
    case 0:
      f.a = 0;
      f.v_entry = std::max<uint64_t>(f.v_entry, 1);
      break;
    case 1:
      f.v_entry = 0;
      f.a = std::max<uint64_t>(f.a, vc / 3000 + 1);
      break;
    case 2:
      f.d = 0;
      break;
    case 3:
      f.v_exit = 1;
      f.d = f.c_total / 2;
      break;
    case 4:
      f.a = (1ull << 48) - 1;
      break;
    case 5:
      f.a = std::max<uint64_t>(1, vc / 20'000);
      f.v_entry = vc;
      break;
    case 6:
      f.d = f.c_total / 4;
      f.a = std::max<uint64_t>(1, vc / 50'000);
      f.v_entry = 0;
      break;
    default:
      break;
  }
  if (f.a == 0 && f.v_entry == 0) f.v_entry = 1;
  const uint64_t z = pick(g, 0, 5);
  if (z == 0) f.dz = static_cast<int32_t>(pick(g, 0, 40'000)) - 20'000;  // steeper than 1:1
  if (z == 1) f.dz = pick(g, 0, 1) == 0 ? 1 : -1;
  return f;
}

void arcs(std::mt19937_64& g, int count) {
  // A quarter circle (docs/protocol.md's ARC example), a full circle with a helix, and a ramp.
  arc::Frame q;
  q.g = {-100, 0, -100, 100, true};
  q.n_ramp = 127;
  q.c_total = 15'703;
  q.v_cruise = 1'125'544'154'615;
  q.v_entry = q.v_exit = 281'386'038'653;
  q.a = 1'125'544;
  q.d = 13'828;
  compare_arc(q, 0, "quarter");
  arc::Frame full = q;
  full.g = {0, 25, 0, 0, false};
  const arc::Plan pf = arc::plan(full.g);
  full.n_ramp = pf.n_ramp;
  full.c_total = pf.c_total;
  full.d = pf.c_total * 3 / 4;
  full.dz = -777;
  compare_arc(full, 0, "full circle with Z");
  arc::Frame ramp = q;
  ramp.g = {-30, 0, -32, 32, true};  // R0 30, R1 32
  const arc::Plan pr = arc::plan(ramp.g);
  if (pr.ok) {
    ramp.n_ramp = pr.n_ramp;
    ramp.c_total = pr.c_total;
    ramp.d = pr.c_total / 2;
    ramp.dz = 5;
    compare_arc(ramp, 0, "ramp R0 != R1");
  } else {
    fail("ramp R0 30 -> R1 32: no plan");
  }
  for (int i = 0; i < count; ++i) {
    const arc::Frame f = random_arc(g);
    // the reference walks every clock: slow tails are cut at the same clock by both
    compare_arc(f, pick(g, 0, 3) == 0 ? pick(g, 1, 50'000) : 400'000, fmt::format("random {}", i));
  }
}

// ---- PinRecorder --------------------------------------------------------------------------------

// take_sorted() against a plain sort by (cycle, signal, value) with the laser's same-edge fall and
// rise removed: per-signal streams mostly in time order (as the twins add them), some not, ties
// across signals, chunk boundaries (streams longer than a chunk).
void pin_recorder(std::mt19937_64& g) {
  PinRecorder rec, sum;
  sum.summary_only = true;
  for (int round = 0; round < 60; ++round) {
    rec.record_tx = pick(g, 0, 1) == 1;
    sum.record_tx = rec.record_tx;
    std::vector<Edge> all;
    const size_t n = round < 3 ? pick(g, 300'000, 600'000) : pick(g, 0, 3000);
    std::array<uint64_t, fpgacnc::models::kSignalCount> t{};
    const bool messy = pick(g, 0, 3) == 0;
    for (size_t i = 0; i < n; ++i) {
      const auto s = static_cast<uint8_t>(pick(g, 0, fpgacnc::models::kSignalCount - 1));
      t[s] += pick(g, 0, 3);
      const uint64_t c = messy && pick(g, 0, 9) == 0 ? pick(g, 0, t[s] + 10) : t[s];
      const auto v = static_cast<uint8_t>(pick(g, 0, 1));
      rec.add(static_cast<Cycle>(c), s, v);
      sum.add(static_cast<Cycle>(c), s, v);
      if (s != fpgacnc::models::kTx || rec.record_tx) all.push_back(Edge{c, s, v});
    }
    std::sort(all.begin(), all.end(), [](const Edge& a, const Edge& b) {
      if (a.cycle != b.cycle) return a.cycle < b.cycle;
      if (a.signal != b.signal) return a.signal < b.signal;
      return a.value < b.value;
    });
    std::vector<Edge> want;
    for (size_t i = 0; i < all.size(); ++i) {
      const Edge e = all[i];
      if (e.signal == fpgacnc::models::kLaser && i + 1 < all.size() &&
          all[i + 1].cycle == e.cycle && all[i + 1].signal == e.signal &&
          all[i + 1].value != e.value) {
        ++i;
        continue;
      }
      want.push_back(e);
    }
    const std::vector<Edge> got = rec.take_sorted();
    bool eq = got.size() == want.size();
    for (size_t i = 0; eq && i < got.size(); ++i)
      eq = got[i].cycle == want[i].cycle && got[i].signal == want[i].signal &&
           got[i].value == want[i].value;
    if (!eq) fail(fmt::format("PinRecorder round {} ({} edges, messy {})", round, n, messy));
    if (rec.size() != 0) fail("PinRecorder not empty after take_sorted");
    // take_summary() (STEP falls not stored) against the same list
    const EdgeSummary got_sum = sum.take_summary();
    const auto want_net = fpgacnc::models::net_steps(want);
    const Cycle want_last = want.empty() ? 0 : static_cast<Cycle>(want.back().cycle);
    if (got_sum.net != want_net || got_sum.edges != want.size() || got_sum.last != want_last)
      fail(fmt::format("PinRecorder summary round {}: net {} / {}, edges {} / {}, last {} / {}",
                       round, fmt::join(got_sum.net, " "), fmt::join(want_net, " "), got_sum.edges,
                       want.size(), got_sum.last, want_last));
    if (sum.size() != 0) fail("PinRecorder not empty after take_summary");
  }
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  int n_profiles = 20'000, n_arcs = 3'000;
  uint64_t seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--profiles")
      n_profiles = std::atoi(argv[i + 1]);
    else if (k == "--arcs")
      n_arcs = std::atoi(argv[i + 1]);
    else if (k == "--seed")
      seed = std::strtoull(argv[i + 1], nullptr, 10);
  }
  std::mt19937_64 g(seed);
  ramp_helpers(g);
  dda_ticks(g);
  const int f_ramp = failures;
  profiles(g, n_profiles);
  const int f_prof = failures - f_ramp;
  arcs(g, n_arcs);
  const int f_arcs = failures - f_ramp - f_prof;
  pin_recorder(g);
  fmt::print(
      "twins_events: ramp helpers and DdaTicks {} failures; {} profiles, {} failures; {} arcs, {} "
      "failures; "
      "PinRecorder {} failures\n",
      f_ramp, n_profiles, f_prof, n_arcs, f_arcs, failures - f_ramp - f_prof - f_arcs);
  return failures == 0 ? 0 : 1;
}
