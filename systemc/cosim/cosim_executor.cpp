// Block-level co-simulation of segment_executor (with its dda_linear and step_pulse) against
// SegmentExecutorTwin + DdaLinearTwin + StepPulseTwin (CTest label cosim).
//
// The block is driven directly, on all four axes, with random QUEUED segment streams (see
// random_job: back-to-back offers taken on the running segment's last tick, reversals with and
// without dir_fast, dwells, zero-length entries, laser power 0..255) and random 1..600-clock
// step timing per job. The RTL is the Verilated C++ model `vexec` (tb/core.cmake), clocked by the
// harness; the twins run in SystemC. Each job compares STEP/DIR/LASER edges, seg_start,
// seg_done, seg_done_v2 and positions; the first difference is printed with its cycle.
// Aborts (e-stop, `--abort-pct` of the jobs, `--aborts` each): the bench runs the twins first and
// aims each abort, in turn, at a random clock of a chosen phase of a segment that the twins
// (with the earlier aborts) show: the run of a LINE, a LINE_PROFILE, a dwell, the HOLD and SETUP
// waits before a run, a zero-length entry in ZERO, or anywhere; 1..N clocks long (N random per
// abort: 1, 8 or 300), the offer waiting during it held. Later segments run after it.
// The motion rate (`--rate-pct` of the jobs): the block's `adv` input comes from a clock-by-clock
// model of feed_rate (cosim_executor_rtl.cpp) fed with the block's rapid_seg, the twins use
// FeedRate; before the aborts are aimed, 1..4 events at random clocks of the job's run at full
// rate: a HOLD and its RESUME 1..3 000 or 3 000..40 000 clocks later, or new feed / rapid rates
// (1 % .. 100 %; below 20 % back to at least 20 % within 20 000 clocks); ramps 2^20 .. 2^32 - 1.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <systemc>

#include "arc_stimulus.h"
#include "cosim_args.h"

#include "executor_job.h"
#include "fpgacnc/twins/compare.h"
#include "fpgacnc/twins/segment_executor.h"

using namespace fpgacnc::twins;
namespace arc = fpgacnc::models::arc;

namespace {

// STEP high or low of 0 is treated as 1 clock by step_pulse, but cnc_core's minimum period adds
// the raw values, so a 0 makes the period one clock too short for the pulse generator: steps
// then come late (violations) and DIR can change on the edge of a late STEP rise. Reported to
// the RTL owner; the twins follow the specification there, not the one-deep pending register.
// Off by default (0 becomes 1, same random sequence); `--zero-pulse 1` turns it back on.
bool g_zero_pulse = false;
uint32_t pulse(uint32_t v) {
  return g_zero_pulse ? v : std::max<uint32_t>(v, 1);
}

using Job = ExecJob;

// Share of the segments that are profiled (LINE_PROFILE as segment_prep prepares them), percent.
uint64_t g_profile_pct = 40;
uint64_t g_max_ticks = 40'000;  // J bound: max(this, 6 * n_dom * cruise period) (RTL run time)
bool g_arc_dwell = false;       // a dwell of 1..8 ticks after each arc (see random_job)
uint64_t g_arc_pct = 5;         // share of the moving segments that are ARCs, percent
uint64_t g_abort_pct = 50;      // share of the jobs with aborts, percent
uint64_t g_aborts = 4;          // aborts per such job
uint64_t g_rate_pct = 50;       // share of the jobs with motion-rate requests, percent

// What an abort hit (the twin's trace of the final run), for the summary.
enum AbortHit {
  kHitLine,
  kHitProfile,
  kHitDwell,
  kHitHold,
  kHitSetup,
  kHitZero,
  kHitFastDir,
  kHitArc,
  kHitIdle,
  kHits
};
constexpr std::array<const char*, kHits> kHitNames{
    "LINE", "LINE_PROFILE",           "dwell", "HOLD", "SETUP",
    "ZERO", "fast DIR write pending", "ARC",   "idle"};
AbortHit classify(const std::vector<SegmentExecutorTwin::SegTrace>& tr, Cycle x) {
  for (const auto& t : tr) {
    if (!(t.accept < x && x <= t.end) && t.cut != x) continue;
    if (t.kind == 'Z') return kHitZero;
    if (t.dir_edge >= 0 && x <= t.dir_edge) return kHitHold;
    if (x <= t.run) return kHitSetup;
    if (x <= t.fast_dir) return kHitFastDir;
    return t.kind == 'P'   ? kHitProfile
           : t.kind == 'D' ? kHitDwell
           : t.kind == 'A' ? kHitArc
                           : kHitLine;
  }
  return kHitIdle;
}

uint32_t pick(std::mt19937_64& g, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
}

// An upper bound of a profile's J in clocks: the speed never drops below min(V_exit, V_entry + A
// t).
double profile_ticks_bound(const ProfileParams& p, uint32_t n_dom) {
  const double l = std::ldexp(static_cast<double>(n_dom), 48);
  const double ve = static_cast<double>(p.v_entry), vx = static_cast<double>(p.v_exit),
               a = static_cast<double>(p.accel);
  if (ve >= vx) return l / vx + 2;
  const double t1 = (vx - ve) / a, d1 = (ve + vx) / 2 * t1;
  if (d1 >= l) return (-ve + std::sqrt(ve * ve + 2 * a * l)) / a + 2;
  return t1 + (l - d1) / vx + 2;
}

// A random profile for |steps| with dominant count n_dom: cruise at minp..3*minp+2 clocks per
// step (V_cruise = floor(2^48 / cps): every step interval is >= floor(2^48 / V_cruise) >= cps, so
// the STEP timing holds, as the host plans it; a backlog of late pulses is outside the twins'
// contract, see --zero-pulse), entry and exit rates
// anywhere up to cruise (entry 0 sometimes, exit down to 1), A from 1 (tiny) up to reaching cruise
// within one step, D from the stopping rule (triangles when accel and decel overlap) or random.
// Retried until J fits g_max_ticks; the last resort is a flat profile.
ProfileParams random_profile(std::mt19937_64& g, uint32_t n_dom, uint32_t minp) {
  const double two48 = std::ldexp(1.0, 48);
  for (int tries = 0; tries < 40; ++tries) {
    ProfileParams p;
    const uint32_t cps = pick(g, 0, 3) == 0 ? minp : pick(g, minp, 3 * minp + 2);
    p.v_cruise = std::min<uint64_t>(static_cast<uint64_t>(two48 / cps), (1ull << 47) - 1);
    auto frac = [&](uint64_t v) {
      switch (pick(g, 0, 4)) {
        case 0:
          return v;
        case 1:
          return uint64_t{0};
        default:
          return static_cast<uint64_t>(static_cast<double>(v) *
                                       std::uniform_real_distribution<double>(0, 1)(g));
      }
    };
    p.v_entry = frac(p.v_cruise);
    p.v_exit = std::max<uint64_t>(1, frac(p.v_cruise));
    const double vc = static_cast<double>(p.v_cruise);
    if (pick(g, 0, 5) == 0) {
      p.accel = pick(g, 1, 2000);  // tiny A
    } else {                       // reach cruise over 1..2*n_dom steps
      const double l = std::ldexp(static_cast<double>(pick(g, 1, 2 * n_dom)), 48);
      p.accel = static_cast<uint32_t>(std::clamp(vc * vc / (2 * l), 1.0, 4.0e9));
    }
    if (p.v_entry == 0 && p.accel == 0) p.accel = 1;
    const double vx = static_cast<double>(p.v_exit);
    const double stop = (vc * vc - vx * vx) / (2.0 * p.accel) / two48;
    switch (pick(g, 0, 3)) {
      case 0:
        p.decel_at = pick(g, 0, n_dom + 2);
        break;
      default:
        p.decel_at = static_cast<uint32_t>(std::max(0.0, n_dom - std::ceil(stop)));
    }
    // Slow ends (tiny A from a low entry, a tiny exit rate) are kept within a few cruise times.
    const double budget = std::max(static_cast<double>(g_max_ticks), 6.0 * n_dom * (3 * minp + 2));
    if (profile_ticks_bound(p, n_dom) <= budget) return p;
  }
  ProfileParams p;  // flat at the STEP rate
  p.v_entry = p.v_cruise = p.v_exit = static_cast<uint64_t>(two48 / minp);
  p.accel = 1;
  p.decel_at = n_dom;
  return p;
}

// A queued stream as segment_prep produces it: v1-like segments (T = P * n), v2 segments with any
// T >= n_dom * min_period, dwells, LINEs without steps, zero-length entries; random codes and
// laser power (0 included); dir_fast computed as segment_prep does (from the DIR each axis will
// have), periods sometimes long enough for fast reversals. Offers mostly back to back (valid
// 0..2 edges after the previous accept: queued on the running segment's last tick), some right
// around the previous segment's end, some late.
Job random_job(uint64_t seed, size_t segments) {
  std::mt19937_64 g(seed);
  Job j;
  const uint32_t r = std::array<uint32_t, 4>{3, 20, 150, 600}[pick(g, 0, 3)];
  for (auto& t : j.timing) {
    auto v = [&](uint32_t lo) { return pick(g, 0, 15) == 0 ? 0u : pick(g, lo, r); };
    t = AxisTiming{pulse(v(1)), pulse(v(1)), v(0), v(0)};
  }
  CoreParams p;
  p.timing = j.timing;
  const uint32_t minp = p.min_period();
  uint32_t fast_p = 0;  // a period that makes every reversal fast
  for (const auto& t : j.timing)
    fast_p = std::max(fast_p, std::max(t.hold, 1u) + std::max(t.setup, 1u));
  std::array<bool, kAxes> track{};    // DIR at the start of the next segment (reset: low)
  std::array<bool, kAxes> unknown{};  // DIR unknown after an arc: no dir_fast (prep's unk_reg)
  std::mt19937_64 ga(seed * 0x2545F4914F6CDD1Dull + 0xA4C);  // the arcs' own stream
  uint64_t prev_t = 0;
  for (size_t i = 0; i < segments; ++i) {
    ExecSegment s{};
    s.code = static_cast<uint8_t>(pick(g, 0, 3));
    s.power = pick(g, 0, 5) == 0 ? 0 : static_cast<uint8_t>(pick(g, 1, 255));
    s.v2 = pick(g, 0, 3) != 0;
    const uint32_t kind = pick(g, 0, 19);
    const uint32_t big = pick(g, 0, 20) == 0 ? 2000 : 40;
    uint32_t n = 0;
    for (int a = 0; a < kAxes; ++a) {
      s.steps[a] = pick(g, 0, 2) == 0 ? 0 : pick(g, 0, big);
      s.dir[a] = pick(g, 0, 1) == 1;
      n = std::max(n, s.steps[a]);
    }
    if (kind <= 2) {  // zero-length, dwell, LINE without steps
      s.steps = {0, 0, 0, 0};
      n = 0;
    }
    if (kind > 2 && pick(ga, 0, 99) < g_arc_pct) {  // ARC, as segment_prep prepares it
      ArcStimulus o;
      // cruise at 2..3 minimum periods per step and at least 200 clocks: the walk's moves are
      // not evenly spaced and take a few clocks each (a faster X or Y step is a STEP low-time
      // violation, outside the twins' contract: see docs/systemc.md Findings)
      o.r_span = 8;
      o.cps_lo = std::max<uint32_t>(2 * minp, 200);
      o.cps_hi = std::max<uint32_t>(3 * minp, 300);
      s.arc = true;
      s.arc_frame = random_arc_frame(ga, o);
      s.code = s.arc_frame.g.ccw ? 3 : 2;
      s.v2 = true;
      s.steps = {1, 1, 0, 0};
      s.dir = {};
      const std::array<bool, 2> d0 = arc::start_dirs(s.arc_frame.g);
      s.dir[0] = d0[0];
      s.dir[1] = d0[1];
      const int32_t dz = s.arc_frame.dz;
      s.steps[2] = dz < 0 ? 0u - static_cast<uint32_t>(dz) : static_cast<uint32_t>(dz);
      s.dir[2] = dz >= 0;
      s.total = 0;
      s.period = 0;
      s.tmn = {0, 0, 0, 0};
      track[0] = d0[0];
      track[1] = d0[1];
      if (dz != 0) track[2] = dz >= 0;
      unknown[0] = unknown[1] = true;
      s.dir_fast = false;
      j.offers.push_back(ExecOffer{s, pick(g, 0, 9) == 0 ? pick(g, 0, 400) : pick(g, 0, 2)});
      // --arc-dwell 1: a dwell of 1..8 ticks after each arc (the workaround from when the arc's
      // last STEP rose one clock after its segment's last edge; fixed, docs/systemc.md Findings).
      if (!g_arc_dwell) {
        prev_t = 0;
        continue;
      }
      ExecSegment d{};
      d.v2 = true;
      d.dir = {true, true, true, true};
      d.total = pick(ga, 1, 8);
      d.tmn = {d.total, d.total, d.total, d.total};
      d.dir_fast = true;
      j.offers.push_back(ExecOffer{d, 0});
      prev_t = d.total;
      continue;
    }
    if (kind > 2 && pick(g, 0, 99) < g_profile_pct) {  // profiled: n_a on 1..4 axes, n_a = 1 too
      const uint32_t pbig = pick(g, 0, 15) == 0 ? 3000 : pick(g, 0, 3) == 0 ? 3 : 60;
      const uint32_t axes = pick(g, 1, kAxes);
      s.steps = {0, 0, 0, 0};
      n = 0;
      for (uint32_t k = 0; k < axes; ++k) {
        const uint32_t a = pick(g, 0, kAxes - 1);
        s.steps[a] = pick(g, 0, 5) == 0 ? 1 : pick(g, 1, pbig);
        n = std::max(n, s.steps[a]);
      }
      s.prof = true;
      s.v2 = true;
      s.profile = random_profile(g, n, minp);
      s.total = 0;
      s.period = 0;
      s.tmn = {0, 0, 0, 0};
      for (int a = 0; a < kAxes; ++a)
        if (s.steps[a] != 0) track[a] = s.dir[a], unknown[a] = false;
      s.dir_fast = false;  // a reversing axis takes HOLD/SETUP
      const uint32_t when = pick(g, 0, 9);
      int64_t gap = pick(g, 0, 2);
      if (when == 0) gap = pick(g, 0, 400);
      j.offers.push_back(ExecOffer{s, gap});
      prev_t = static_cast<uint64_t>(profile_ticks_bound(s.profile, n) / 2);
      continue;
    }
    s.period = std::max(minp, pick(g, 0, 2) == 0 ? fast_p : 0u) +
               (pick(g, 0, 1) ? 0 : pick(g, 0, 3 * minp));
    if (kind == 0) {
      s.total = 0;
      s.period = 0;
    } else if (n == 0) {  // dwell or a LINE without steps: T ticks
      s.total = pick(g, 1, 3000);
      s.period = 0;
      if (kind == 1) s.code = s.power = 0;
    } else {
      s.total = static_cast<uint64_t>(s.period) * n;
      if (s.v2 && pick(g, 0, 1)) s.total += pick(g, 0, n - 1);  // T not a multiple of n
    }
    for (int a = 0; a < kAxes; ++a) s.tmn[a] = s.total - s.steps[a];
    std::array<bool, kAxes> rev{};
    bool unk = false;
    for (int a = 0; a < kAxes; ++a) {
      if (s.steps[a] == 0) continue;
      rev[a] = track[a] != s.dir[a];
      track[a] = s.dir[a];
      unk = unk || unknown[a];
      unknown[a] = false;
    }
    s.dir_fast = n == 0 || (!unk && dir_fast(rev, j.timing, s.total / n));
    const uint32_t when = pick(g, 0, 9);
    int64_t gap = pick(g, 0, 2);
    if (when == 0) gap = pick(g, 0, 400);
    if (when == 1) gap = std::max<int64_t>(0, static_cast<int64_t>(prev_t) - 2 + pick(g, 0, 4));
    j.offers.push_back(ExecOffer{s, gap});
    prev_t = s.total;
  }
  return j;
}

// The twins of the block, driven by a thread that offers the segments like the RTL harness.
SC_MODULE(ExecBench) {
  CoreParams p;
  CycleClock clk{50'000'000};
  PinRecorder pins;
  SegmentExecutorTwin exec;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse;
  tlm_utils::simple_initiator_socket<ExecBench> seg;
  tlm_utils::simple_target_socket<ExecBench> done;
  tlm_utils::simple_initiator_socket<ExecBench> status;  // (segment_prep's idle query; unused)
  tlm_utils::simple_initiator_socket<ExecBench> abort;
  std::vector<Job>* jobs = nullptr;
  std::vector<uint64_t> seeds;         // per job (the aborts' random stream)
  std::array<uint64_t, kHits> hits{};  // aborts by what they hit
  uint64_t aborts = 0, dropped = 0, abort_jobs = 0, arc_errs = 0;
  uint64_t fire_aborts = 0;  // aimed at the clock in which an arc move fires
  std::vector<RunResult> results;
  FeedRate rate{kExecRatePhase};
  // motion-rate requests, holds among them, and where they took effect: LINE, PROFILE, ARC,
  // dwell, other (HOLD / SETUP, idle)
  uint64_t rate_reqs = 0, rate_holds = 0, rate_jobs = 0;
  std::array<uint64_t, 5> rate_in{};
  std::vector<Cycle> seg_done, seg_done_v2;
  std::array<uint64_t, 4> stats{};   // zero gap, fast reversals, zero-length / HOLD on a last tick
  std::array<uint64_t, 3> pstats{};  // profiled: zero gap, reversing, never at cruise
  tlm::tlm_generic_payload gp;

  SC_CTOR(ExecBench)
      : exec("segment_executor", clk, p, pins),
        seg("seg"),
        done("done"),
        status("status"),
        abort("abort") {
    seg.bind(exec.segments);
    status.bind(exec.status);
    abort.bind(exec.abort);
    exec.done.bind(done);
    done.register_b_transport(this, &ExecBench::on_done);
    make_axis_twins(exec, clk, p, pins, dda, pulse);
    exec.rate = &rate;
    exec.laser_rate_gate = false;  // (cnc_core's gate, not the block's)
    SC_THREAD(run);
  }
  void on_done(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    seg_done.push_back(clk.at(d));
    if (payload<SegDone>(g).v2) seg_done_v2.push_back(clk.at(d));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  // One run of the twins on job j (from cycle 0 of the current base).
  void run_twins(const Job& j) {
    p.timing = j.timing;
    pins.clear();
    exec.reset();
    for (auto& x : pulse) x->reset();
    seg_done.clear();
    seg_done_v2.clear();
    rate.reset();
    for (const ExecRate& q : j.rate) rate.motion(q.from, q.hold, q.resume, q.feed, q.rapid, q.ramp);
    for (const ExecAbort& a : j.aborts) {
      AbortSpan s{a.first, a.last};
      transport(abort, gp, clk, s, a.first);
    }
    Cycle accept = 0;
    for (size_t i = 0; i < j.offers.size(); ++i) {
      const ExecSegment& e = j.offers[i].seg;
      Segment s{e.code, e.dir, e.steps, e.tmn, e.total, e.period, 0, e.power, e.v2, e.dir_fast};
      s.prof = e.prof;
      s.profile = e.profile;
      s.arc = e.arc;
      s.arc_frame = e.arc_frame;
      accept = transport(seg, gp, clk, s, accept + j.offers[i].gap);
    }
  }
  // Motion-rate requests at random clocks of the job's run at full rate (see the header).
  void add_rate(Job & j, uint64_t seed) {
    std::mt19937_64 g(seed * 0x9E3779B97F4A7C15ull + 0x4A7E);
    if (pick(g, 0, 99) >= g_rate_pct) return;
    run_twins(j);
    Cycle end = 1;
    for (const auto& t : exec.trace) end = std::max(end, t.end);
    auto rate_q15 = [&]() -> uint16_t {
      return static_cast<uint16_t>(pick(g, 0, 2) == 0 ? 0x8000 : pick(g, 328, 0x8000));
    };
    auto ramp = [&]() -> uint32_t {
      if (pick(g, 0, 9) == 0) return 0xFFFF'FFFFu;
      const uint32_t e = pick(g, 20, 31);
      return pick(g, 1u << e, e == 31 ? 0xFFFF'FFFEu : (2u << e) - 1);
    };
    ++rate_jobs;
    for (uint32_t n = pick(g, 1, 4); n > 0; --n) {
      const Cycle t = 1 + static_cast<Cycle>(std::uniform_int_distribution<uint64_t>(
                              0, static_cast<uint64_t>(end))(g));
      if (pick(g, 0, 1) == 0) {  // a hold and its resume
        const Cycle held = pick(g, 0, 1) ? pick(g, 1, 3'000) : pick(g, 3'000, 40'000);
        j.rate.push_back(ExecRate{t, true, false, rate_q15(), rate_q15(), ramp()});
        j.rate.push_back(ExecRate{t + held, false, true, rate_q15(), rate_q15(), ramp()});
        ++rate_holds;
      } else {
        const uint16_t f = rate_q15(), r = rate_q15();
        j.rate.push_back(ExecRate{t, false, false, f, r, ramp()});
        if (std::min(f, r) < 0x8000 / 5)
          j.rate.push_back(ExecRate{t + pick(g, 1, 20'000), false, false,
                                    static_cast<uint16_t>(pick(g, 0x8000 / 5, 0x8000)),
                                    static_cast<uint16_t>(pick(g, 0x8000 / 5, 0x8000)), ramp()});
      }
    }
    // in time order; two on one clock: the later one drawn wins its fields, a HOLD its flag
    std::stable_sort(j.rate.begin(), j.rate.end(),
                     [](const ExecRate& a, const ExecRate& b) { return a.from < b.from; });
    // the job ends at full rate: nothing held, a last request back to 100 %
    const bool held =
        std::any_of(j.rate.begin(), j.rate.end(), [](const ExecRate& q) { return q.hold; });
    j.rate.push_back(ExecRate{j.rate.back().from + 1, false, held, 0x8000, 0x8000, 0xFFFF'FFFFu});
  }
  // Aims the job's aborts one by one (each after the previous one's settle time) with the twins'
  // trace of the run with the aborts so far.
  void aim_aborts(Job & j, uint64_t seed) {
    std::mt19937_64 g(seed * 0x9E3779B97F4A7C15ull + 0xAB0127);
    if (pick(g, 0, 99) >= g_abort_pct) return;
    ++abort_jobs;
    Cycle after = 0;
    for (uint64_t k = 0; k < g_aborts; ++k) {
      run_twins(j);
      const auto& tr = exec.trace;
      // a phase to hit: 0 LINE run, 1 PROFILE run, 2 dwell, 3 HOLD, 4 SETUP, 5 ZERO, 6 anywhere,
      // 7 a zero-gap reversal's DIR write pending, 8 ARC run, 9 the clock in which an arc move
      // fires (its step request is on the next edge)
      const uint32_t want = pick(g, 0, 9);
      std::vector<std::pair<Cycle, Cycle>> win;  // candidate windows (lo, hi]: abort edge in it
      for (const auto& t : tr) {
        if (t.accept <= after || t.cut >= 0) continue;
        const char kinds[] = {'L', 'P', 'D'};
        if (want < 3 && t.kind == kinds[want] && t.end > t.run) win.emplace_back(t.run, t.end);
        if (want == 3 && t.dir_edge >= 0) win.emplace_back(t.accept, t.dir_edge);
        if (want == 4 && t.dir_edge >= 0 && t.run > t.dir_edge) win.emplace_back(t.dir_edge, t.run);
        if (want == 5 && t.kind == 'Z' && t.end > t.accept) win.emplace_back(t.accept, t.end);
        if (want == 6) win.emplace_back(t.accept - 5, t.end + 5);
        if (want == 7 && t.fast_dir > t.accept) win.emplace_back(t.accept, t.fast_dir);
        if (want == 8 && t.kind == 'A' && t.end > t.run) win.emplace_back(t.run, t.end);
      }
      if (want == 9)
        for (Cycle e : exec.arc_step_edges)
          if (e - 2 > after) win.emplace_back(e - 2, e - 1);  // abort edge e - 1
      const bool at_fire = want == 9 && !win.empty();
      if (win.empty())  // none of that phase left: any later segment
        for (const auto& t : tr)
          if (t.accept > after && t.cut < 0 && t.end > t.accept) win.emplace_back(t.accept, t.end);
      if (win.empty()) break;
      // spread the aborts over the job: one of the first 1/(aborts left) of the candidates
      const size_t band = std::max<size_t>(1, win.size() / (g_aborts - k));
      const auto w = win[pick(g, 0, static_cast<uint32_t>(band - 1))];
      const auto span = static_cast<uint64_t>(w.second - w.first - 1);
      const Cycle first = std::max(
          after + 1,
          w.first + 1 + static_cast<Cycle>(std::uniform_int_distribution<uint64_t>(0, span)(g)));
      const uint32_t n = std::array<uint32_t, 3>{1, 8, 300}[pick(g, 0, 2)];
      const Cycle last = first + pick(g, 0, n - 1);
      j.aborts.push_back(ExecAbort{first, last});
      if (at_fire) ++fire_aborts;
      after = last + 1;
    }
  }
  void run() {
    for (size_t ji = 0; ji < jobs->size(); ++ji) {
      Job& j = (*jobs)[ji];
      wait(sc_core::sc_time(1, sc_core::SC_US));
      const uint64_t per = clk.period_ps(), now = sc_core::sc_time_stamp().value();
      clk.set_base(sc_core::sc_time::from_value((now + per - 1) / per * per));
      if (g_rate_pct != 0) add_rate(j, seeds[ji]);
      if (g_aborts != 0 && g_abort_pct != 0) aim_aborts(j, seeds[ji]);
      run_twins(j);
      for (const ExecRate& q : j.rate) {
        ++rate_reqs;
        size_t k = 4;
        for (const auto& t : exec.trace)
          if (t.run <= q.from && q.from < t.end && t.cut < 0)
            k = t.kind == 'L' ? 0 : t.kind == 'P' ? 1 : t.kind == 'A' ? 2 : t.kind == 'D' ? 3 : 4;
        ++rate_in[k];
      }
      for (const ExecAbort& a : j.aborts) {
        ++aborts;
        ++hits[classify(exec.trace, a.first)];
      }
      dropped += exec.aborted;
      RunResult r;
      r.edges = pins.take_sorted();
      r.seg_start = exec.seg_start_cycles;
      r.seg_done = seg_done;
      r.seg_done_v2 = seg_done_v2;
      r.arc_err = exec.arc_err_cycles;
      {  // `violation` strobes: step_pulse's (on the request edge) and the arcs' DIR ones, per
         // clock
        std::vector<Cycle> v = exec.arc_violation_cycles;
        for (const auto& x : pulse)
          v.insert(v.end(), x->violation_strobes.begin(), x->violation_strobes.end());
        std::sort(v.begin(), v.end());
        r.violations = static_cast<uint64_t>(std::unique(v.begin(), v.end()) - v.begin());
      }
      arc_errs += exec.arc_err_cycles.size();
      stats[0] += exec.zero_gap;
      stats[1] += exec.fast_reversals;
      stats[2] += exec.zero_len_on_last_tick;
      stats[3] += exec.hold_on_last_tick;
      pstats[0] += exec.profiled_zero_gap;
      pstats[1] += exec.profiled_reversing;
      pstats[2] += exec.profiled_triangles;
      for (int a = 0; a < kAxes; ++a) r.position[a] = pulse[a]->position;
      r.end_cycle = r.edges.empty() ? 0 : static_cast<Cycle>(r.edges.back().cycle);
      results.push_back(std::move(r));
      // Time moves on past this job's last event before the next one starts.
      Cycle last = r.end_cycle;
      if (!results.back().seg_done.empty()) last = std::max(last, results.back().seg_done.back());
      wait(clk.delay_to(last + 1));
    }
  }
};

// Names where a job's runs first disagree: the segment running at the first differing edge (the
// last seg_start at or before it, on the RTL side), its kind, and the axis and clock.
std::string where(const Job& j, const RunResult& rtl, const RunResult& twin) {
  const size_t n = std::min(rtl.edges.size(), twin.edges.size());
  size_t k = 0;
  while (k < n && rtl.edges[k].cycle == twin.edges[k].cycle &&
         rtl.edges[k].signal == twin.edges[k].signal && rtl.edges[k].value == twin.edges[k].value)
    ++k;
  if (k == rtl.edges.size() && k == twin.edges.size()) return "";
  const auto& e = k < rtl.edges.size() ? rtl.edges[k] : twin.edges[k];
  const auto c =
      static_cast<Cycle>(k < twin.edges.size() ? std::min(e.cycle, twin.edges[k].cycle) : e.cycle);
  size_t seg = 0;
  while (seg < rtl.seg_start.size() && rtl.seg_start[seg] <= c) ++seg;
  // seg_start counts segments that ran (T > 0); map back to the offer index.
  size_t ran = 0, idx = 0;
  for (; idx < j.offers.size(); ++idx) {
    const auto& o = j.offers[idx].seg;
    if (o.prof || o.arc || o.total != 0) ++ran;
    if (ran == seg) break;
  }
  const int sig = e.signal;
  const std::string axis = sig < 4   ? fmt::format("STEP axis {}", sig)
                           : sig < 8 ? fmt::format("DIR axis {}", sig - 4)
                                     : std::string("LASER");
  std::string ab;
  for (size_t a = 0; a < j.aborts.size(); ++a)
    if (j.aborts[a].first <= c)
      ab = fmt::format("; abort #{} on edges {}..{} before it", a, j.aborts[a].first,
                       j.aborts[a].last);
  return fmt::format(" [segment #{} ({}), {}, clock {}{}]", seg == 0 ? 0 : idx,
                     idx >= j.offers.size()   ? "?"
                     : j.offers[idx].seg.prof ? "PROFILE"
                     : j.offers[idx].seg.arc  ? "ARC"
                                              : "LINE/DWELL",
                     axis, c, ab);
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t seed = 7, seeds = 12;
  size_t segments = 40;
  fpgacnc::cosim::Options opts("cosim_executor");
  opts.flag("--zero-pulse", &g_zero_pulse).u64("--seed", &seed).u64("--seeds", &seeds);
  opts.size("--segments", &segments);
  opts.u64("--profile-pct", &g_profile_pct).u64("--max-ticks", &g_max_ticks);
  opts.flag("--arc-dwell", &g_arc_dwell);
  opts.u64("--abort-pct", &g_abort_pct).u64("--aborts", &g_aborts).u64("--arc-pct", &g_arc_pct);
  opts.u64("--rate-pct", &g_rate_pct);
  if (!opts.parse(argc, argv)) return 2;
  seed = opts.seed(seed, seeds);
  std::vector<Job> jobs;
  for (uint64_t s = 0; s < seeds; ++s) jobs.push_back(random_job(seed + s, segments));
  ExecBench bench("bench");
  bench.jobs = &jobs;
  for (uint64_t s = 0; s < seeds; ++s) bench.seeds.push_back(seed + s);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  sc_core::sc_start();
  const double twin_s = std::chrono::duration<double>(clock::now() - t0).count();
  double rtl_s = 0;
  int bad = 0;
  uint64_t edges = 0, clocks = 0, profiled = 0, tiny_a = 0, arcs = 0, offers = 0;
  for (const Job& j : jobs)
    for (const auto& o : j.offers) {
      profiled += o.seg.prof ? 1 : 0;
      arcs += o.seg.arc ? 1 : 0;
      ++offers;
      tiny_a += o.seg.prof && o.seg.profile.accel <= 2000 ? 1 : 0;
    }
  for (size_t i = 0; i < jobs.size(); ++i) {
    const auto t1 = clock::now();
    const RunResult rtl = run_executor_rtl(jobs[i]);
    rtl_s += std::chrono::duration<double>(clock::now() - t1).count();
    clocks += static_cast<uint64_t>(std::max<Cycle>(rtl.end_cycle, 0));
    const std::string d =
        i < bench.results.size() ? compare_runs(rtl, bench.results[i]) : "not run";
    edges += rtl.edges.size();
    {  // DIR setup at the RTL's pins: a STEP rise less than max(setup, 1) after its axis's DIR edge
      std::array<int64_t, kAxes> last_dir;
      last_dir.fill(INT64_MIN / 2);
      uint64_t n = 0;
      Cycle first = -1;
      for (const auto& e : rtl.edges) {
        if (e.signal >= 4 && e.signal < 8) last_dir[e.signal - 4] = static_cast<int64_t>(e.cycle);
        if (e.signal < 4 && e.value == 1 &&
            static_cast<int64_t>(e.cycle) - last_dir[e.signal] <
                std::max<int64_t>(jobs[i].timing[e.signal].setup, 1)) {
          if (n++ == 0) first = static_cast<Cycle>(e.cycle);
        }
      }
      const bool has_arc = std::any_of(jobs[i].offers.begin(), jobs[i].offers.end(),
                                       [](const ExecOffer& o) { return o.seg.arc; });
      if (n != 0 && !has_arc)
        fmt::print(
            "cosim_executor seed {}: {} STEP rises within DIR setup of a DIR edge{} (first "
            "on cycle {})\n",
            seed + i, n, jobs[i].aborts.empty() ? "" : " (a job with aborts)", first);
    }
    if (!d.empty() && std::getenv("COSIM_DEBUG")) {
      const auto& t = bench.results[i];
      size_t k = 0;
      while (k < rtl.edges.size() && k < t.edges.size() && rtl.edges[k].cycle == t.edges[k].cycle &&
             rtl.edges[k].signal == t.edges[k].signal)
        ++k;
      for (size_t x = k > 8 ? k - 8 : 0; x < k + 6; ++x) {
        auto pr = [](const std::vector<fpgacnc::models::Edge>& v, size_t x) {
          return x < v.size() ? fmt::format("{} {} {}", v[x].cycle,
                                            fpgacnc::models::signal_name(v[x].signal), v[x].value)
                              : std::string("-");
        };
        fmt::print("  {:30} | {}\n", pr(rtl.edges, x), pr(t.edges, x));
      }
      for (size_t x = 0; x < rtl.seg_start.size() && x < t.seg_start.size(); ++x)
        if (rtl.seg_start[x] != t.seg_start[x] || x + 1 == rtl.seg_start.size()) {
          fmt::print("  seg_start #{}: rtl {} twin {}\n", x, rtl.seg_start[x], t.seg_start[x]);
          break;
        }
      const auto& j = jobs[i];
      const size_t from = std::getenv("COSIM_DEBUG_OFFER")
                              ? std::strtoull(std::getenv("COSIM_DEBUG_OFFER"), nullptr, 10)
                              : 0;  // first offer printed
      for (size_t x = from; x < j.offers.size() && x < from + 4; ++x) {
        const auto& o = j.offers[x].seg;
        fmt::print(
            "  offer {}: prof {} arc {} steps {} {} {} {} dir {}{}{}{} fast {} total {} gap {}", x,
            o.prof, o.arc, o.steps[0], o.steps[1], o.steps[2], o.steps[3], +o.dir[0], +o.dir[1],
            +o.dir[2], +o.dir[3], o.dir_fast, o.total, j.offers[x].gap);
        if (o.prof)
          fmt::print(" ve {} vc {} vx {} A {} D {} J {}", o.profile.v_entry, o.profile.v_cruise,
                     o.profile.v_exit, o.profile.accel, o.profile.decel_at,
                     run_profile(o.profile, o.steps).ticks_total);
        fmt::print("\n");
      }
      for (int a = 0; a < kAxes; ++a)
        fmt::print("  axis {} high {} low {} setup {} hold {}\n", a, j.timing[a].high,
                   j.timing[a].low, j.timing[a].setup, j.timing[a].hold);
    }
    if (!d.empty()) {
      ++bad;
      fmt::print("FAIL segment_executor seed {}: first difference: {}{}{}\n", seed + i, d,
                 i < bench.results.size() ? where(jobs[i], rtl, bench.results[i]) : "",
                 rtl.violations == 0
                     ? ""
                     : fmt::format(" (the RTL strobed `violation` {} times: a STEP timing "
                                   "violation is outside the twins' contract)",
                                   rtl.violations));
    }
  }
  fmt::print(
      "cosim_executor: {} jobs, {} segments ({} profiled; {} started with zero gap, {} of them "
      "reversing with dir_fast; {} zero-length and {} HOLD-path segments taken on a last tick), "
      "{} edges over {} clocks: {}\n",
      jobs.size(), offers, profiled, bench.stats[0], bench.stats[1], bench.stats[2], bench.stats[3],
      edges, clocks, bad ? "DIFFER" : "all identical");
  fmt::print(
      "cosim_executor: profiled {}: {} zero-gap joins, {} with a reversing axis (HOLD/SETUP), {} "
      "never at cruise (triangles), {} with A <= 2000\n",
      profiled, bench.pstats[0], bench.pstats[1], bench.pstats[2], tiny_a);
  std::string hit;
  for (int h = 0; h < kHits; ++h)
    hit += fmt::format("{}{} {}", h ? ", " : "", bench.hits[static_cast<size_t>(h)],
                       kHitNames[static_cast<size_t>(h)]);
  fmt::print(
      "cosim_executor: {} ARC segments ({} arc errors); {} aborts in {} jobs (hit: {}; {} on the "
      "clock an arc move fires in); {} segments dropped by them (no seg_done)\n",
      arcs, bench.arc_errs, bench.aborts, bench.abort_jobs, hit, bench.fire_aborts, bench.dropped);
  fmt::print(
      "cosim_executor: motion rate in {} jobs: {} requests ({} holds with their resumes), taking "
      "effect in a LINE {}, PROFILE {}, ARC {}, dwell {}, elsewhere {}\n",
      bench.rate_jobs, bench.rate_reqs, bench.rate_holds, bench.rate_in[0], bench.rate_in[1],
      bench.rate_in[2], bench.rate_in[3], bench.rate_in[4]);
  fmt::print("cosim_executor: twins {:.3f} s, RTL (Verilated) {:.3f} s: twins {:.1f}x faster\n",
             twin_s, rtl_s, twin_s > 0 ? rtl_s / twin_s : 0.0);
  return bad ? 1 : 0;
}
