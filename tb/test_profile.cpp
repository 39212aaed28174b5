// Profiled segments (LINE_PROFILE): FIFO entries -> segment_prep -> segment_executor
// (profile_gen + dda_profile) against an exact integer reference of the profile arithmetic
// (docs/protocol.md "LINE_PROFILE", docs/timing.md "Profiled segments").
//
// Reference: per clock c, U(c+1) = U(c) + V(c), V(c+1) by the decel/accel rule; axis i is at
// floor(U(c)*n_i / (n_dom*2^48)) steps after clock c (computed by 128-bit products, not by the
// RTL's remainder recurrence); the segment ends at the first clock with U >= n_dom*2^48. A step
// whose position increments between clocks c and c+1 (tick j = c+1) rises at edge R + j.
// Checks, per segment: every STEP rise edge equal to the reference (all axes, all segments, in
// order); the real-valued ideal time of each step (the time the piecewise-linear path reaches
// k*n_dom/n_i) lies in (j-1, j], i.e. 0 <= t_rtl - t_ideal < 1 clock; exact counts and
// positions; measured speed (dominant STEP intervals) never above V_cruise beyond the one-step
// quantisation (interval >= floor(2^48 / V_cruise) clocks); measured acceleration from three
// consecutive dominant rises within A*((d1+d2)/2 + 2) + 1/(d1(d1-1)) + 1/(d2(d2-1)) steps/clock
// (staircase + one-clock quantisation of each edge); exit rate: a segment planned with the
// stopping rule ends at V_exit (reference) and the last measured dominant interval agrees with
// V_exit within the same quantisation; zero gap between queued segments with no reversing axis.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "Vcnc_core_heat.h"
#include "Vsegment_executor.h"
#include "Vsegment_prep.h"
#include "common/core_pins.h"
#include "common/fifo_entry.h"
#include "common/pin_harness.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v2_frames.h"
#include "verilated.h"

namespace {

using fpgacnc::tb::Entry;
using fpgacnc::tb::StepMonitor;
using u128 = unsigned __int128;

constexpr int kAxes = 4;
constexpr uint64_t kOne = uint64_t{1} << 48;
constexpr uint64_t kPrepLatency = 25 + kAxes;  // LINE_PROFILE (segment_prep header)

uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

struct Prof {
  int64_t steps[kAxes] = {0, 0, 0, 0};
  uint64_t ve = 0, vc = 0, vx = 1;
  uint32_t a = 0, d = 0;
  int code = 1, power = 255;
  bool planned_stop = false;  // D from the stopping rule (V_exit is reached before the end)
  uint64_t n_dom() const {
    uint64_t n = 0;
    for (int64_t s : steps) n = std::max(n, mag(s));
    return n;
  }
  Entry entry() const {
    Entry e = fpgacnc::tb::line_profile(code, power, ve, vc, vx, a, d, {});
    for (int i = 0; i < kAxes; ++i) e.steps[i] = static_cast<int32_t>(steps[i]);
    return e;
  }
};

uint64_t next_v(uint64_t v, bool dec, const Prof& p) {
  if (dec) return v >= p.vx + p.a ? v - p.a : p.vx;
  return v + p.a <= p.vc ? v + p.a : p.vc;
}

struct RefRun {
  uint64_t ticks = 0;                     // J: the last tick
  std::vector<uint64_t> ticks_of[kAxes];  // tick j of each step
  uint64_t v_last = 0;                    // V during the last clock (c = J-1)
  bool reached_exit = false;              // V == V_exit at the end, reached in deceleration
  bool jump = false;  // V changed by more than A in a clock (decel began below V_exit; unplanned)
  std::string ideal_error;  // first ideal-time violation (empty = none)
};

RefRun reference(const Prof& p) {
  RefRun r;
  const uint64_t n = p.n_dom();
  const u128 M = static_cast<u128>(n) << 48;
  u128 u = 0;
  uint64_t v = p.ve;
  uint64_t pos[kAxes] = {0, 0, 0, 0};
  bool decel_seen = false;
  for (uint64_t c = 0;; ++c) {
    const u128 un = u + v;
    for (int i = 0; i < kAxes; ++i) {
      const uint64_t ni = mag(p.steps[i]);
      if (ni == 0) continue;
      // next step k = pos+1 reached when U*n_i >= k*M (at most one per clock: V < 1/2 step)
      if (un * ni >= static_cast<u128>(pos[i] + 1) * M) {
        ++pos[i];
        r.ticks_of[i].push_back(c + 1);
        if (r.ideal_error.empty()) {
          // ideal time c + (k*M/n_i - U(c)) / V(c): must lie in (c, c+1]
          const u128 num = static_cast<u128>(pos[i]) * M - u * ni;
          const long double frac = static_cast<long double>(num) /
                                   (static_cast<long double>(v) * static_cast<long double>(ni));
          if (!(frac > 0.0L && frac <= 1.0L))
            r.ideal_error = "axis " + std::to_string(i) + " step " + std::to_string(pos[i]) +
                            ": ideal offset " + std::to_string(static_cast<double>(frac)) +
                            " clocks into tick " + std::to_string(c + 1);
        }
      }
    }
    u = un;
    if (u >= M) {
      r.ticks = c + 1;
      r.v_last = v;
      r.reached_exit = decel_seen && v == p.vx;
      return r;
    }
    const bool dec = u >= (static_cast<u128>(p.d) << 48);
    const uint64_t v_prev = v;
    v = next_v(v, dec, p);
    if ((v > v_prev ? v - v_prev : v_prev - v) > p.a) r.jump = true;
    if (dec && v == p.vx) decel_seen = true;
    if (c > 200'000'000) throw std::runtime_error("reference: segment does not finish");
  }
}

// The largest D for which deceleration reaches V_exit before the end (the host's stopping rule,
// found on the accelerate-only trajectory: decel starting at the first clock c with U(c) >= D*2^48
// from W = V(c-1) covers sum_{i=1}^{m-1} (W - i*A), m = ceil((W - V_exit)/A), before V = V_exit).
// Returns false when even D = 0 cannot stop in time.
bool stopping_d(const Prof& p, uint32_t* d_out) {
  const uint64_t n = p.n_dom();
  const u128 M = static_cast<u128>(n) << 48;
  auto fits = [&](u128 u_c, uint64_t w) {
    if (w <= p.vx) return u_c < M;
    const u128 m = (static_cast<u128>(w - p.vx) + p.a - 1) / p.a;
    const u128 k = m - 1;
    const u128 dist = k * w - static_cast<u128>(p.a) * k * (k + 1) / 2;
    return u_c + dist < M;
  };
  bool any = false;
  // D = 0: c_D = 1, W = V_entry, U(1) = V_entry
  if (fits(p.ve, p.ve)) {
    any = true;
    *d_out = 0;
  } else {
    return false;
  }
  u128 u = 0;
  uint64_t v = p.ve;
  for (uint64_t c = 0; c < 100'000'000; ++c) {
    const u128 un = u + v;
    if (un >= M) break;
    const uint64_t d_hi = static_cast<uint64_t>(un >> 48);
    if ((un >> 48) > (u >> 48)) {
      // D = d_hi: first clock with U >= D*2^48 is c+1, W = v
      if (!fits(un, v)) break;
      *d_out = static_cast<uint32_t>(d_hi);
    }
    u = un;
    v = next_v(v, false, p);
  }
  return any;
}

// prep + executor as in cnc_core; entries always offered (back to back).
class ProfBench {
 public:
  ProfBench() : ctx_(std::make_unique<VerilatedContext>()), mon_(kAxes) {
    prep_ = std::make_unique<Vsegment_prep>(ctx_.get());
    ex_ = std::make_unique<Vsegment_executor>(ctx_.get());
    prep_->min_period = 2;
    ex_->cfg_step_high = ex_->cfg_step_low = 0;
    ex_->cfg_dir_setup = ex_->cfg_dir_hold = 0;
    for (int a = 0; a < kAxes; ++a) {
      ex_->cfg_step_high |= uint64_t{1} << (16 * a);
      ex_->cfg_step_low |= uint64_t{1} << (16 * a);
      ex_->cfg_dir_setup |= uint64_t{3} << (16 * a);
      ex_->cfg_dir_hold |= uint64_t{2} << (16 * a);
    }
    prep_->cfg_dir_setup = ex_->cfg_dir_setup;
    prep_->cfg_dir_hold = ex_->cfg_dir_hold;
    ex_->adv = 1;  // the motion rate at 100 %
    prep_->rst = ex_->rst = 1;
    clock();
    clock();
    prep_->rst = ex_->rst = 0;
    clock();
  }
  ~ProfBench() {
    prep_->final();
    ex_->final();
  }

  // abort_at: abort is high in the clock after edge abort_at (0: never).
  void run(const std::vector<Entry>& entries, uint64_t abort_at = 0) {
    size_t next = 0;
    uint64_t quiet = 0;
    while (quiet < 3) {
      // (Verilator names the port `abort`, a C++ word, __SYM__abort)
      prep_->__SYM__abort = ex_->__SYM__abort = (abort_at != 0 && cycle_ == abort_at) ? 1 : 0;
      if (prep_->__SYM__abort) {
        ex_->eval();  // laser is gated by abort combinationally
        laser_in_abort_clock = ex_->laser;
      }
      const bool offering = next < entries.size();
      if (offering) entries[next].pack(prep_->s_axis_tdata);
      prep_->s_axis_tvalid = offering;
      connect();
      prep_->eval();
      const bool prep_take = offering && prep_->s_axis_tready;
      clock();
      if (prep_take) prep_accepts.push_back(cycle_), ++next;
      if (!offering && !prep_->busy && !ex_->busy && ex_->idle)
        ++quiet;
      else
        quiet = 0;
      if (cycle_ > uint64_t{2000000000}) throw std::runtime_error("bench does not finish");
    }
  }

  std::vector<uint64_t> prep_accepts, starts, dones, valid_rises;
  int laser_in_abort_clock = -1;
  uint64_t violations = 0, laser_on_cycles = 0;
  StepMonitor& mon() { return mon_; }
  Vsegment_executor& ex() { return *ex_; }
  uint64_t cycle() const { return cycle_; }

 private:
  void connect() {
    auto& p = *prep_;
    auto& e = *ex_;
    e.s_axis_code = p.m_axis_code;
    e.s_axis_power = p.m_axis_power;
    e.s_axis_v2 = p.m_axis_v2;
    e.s_axis_dir_fast = p.m_axis_dir_fast;
    e.s_axis_dir = p.m_axis_dir;
    for (int w = 0; w < kAxes; ++w) e.s_axis_steps[w] = p.m_axis_steps[w];
    for (int w = 0; w < 2 * kAxes; ++w) e.s_axis_tmn[w] = p.m_axis_tmn[w];
    e.s_axis_total = p.m_axis_total;
    e.s_axis_kind = p.m_axis_kind;
    e.s_axis_prof_u1 = p.m_axis_prof_u1;
    e.s_axis_prof_v1 = p.m_axis_prof_v1;
    e.s_axis_prof_op1 = p.m_axis_prof_op1;
    e.s_axis_prof_accel = p.m_axis_prof_accel;
    e.s_axis_prof_vcruise = p.m_axis_prof_vcruise;
    e.s_axis_prof_vexit = p.m_axis_prof_vexit;
    e.s_axis_prof_vcma = p.m_axis_prof_vcma;
    e.s_axis_prof_vxpa = p.m_axis_prof_vxpa;
    e.s_axis_prof_decel_at = p.m_axis_prof_decel_at;
    e.s_axis_prof_n_dom = p.m_axis_prof_n_dom;
    for (int w = 0; w < 9; ++w) {
      e.s_axis_prof_v0[w] = p.m_axis_prof_v0[w];
      e.s_axis_prof_vc[w] = p.m_axis_prof_vc[w];
      e.s_axis_prof_vx[w] = p.m_axis_prof_vx[w];
    }
    for (int w = 0; w < 7; ++w) e.s_axis_prof_acc[w] = p.m_axis_prof_acc[w];
    e.s_axis_tvalid = p.m_axis_tvalid;
    p.m_axis_tready = e.s_axis_tready;
    p.exec_idle = e.idle;
  }
  void clock() {
    connect();
    prep_->clk = ex_->clk = 0;
    prep_->eval();
    ex_->eval();
    prep_->clk = ex_->clk = 1;
    prep_->eval();
    ex_->eval();
    ++cycle_;
    mon_.sample(cycle_, ex_->step, ex_->dir);
    if (ex_->violation) ++violations;
    if (ex_->seg_start) starts.push_back(cycle_);
    if (ex_->seg_done) dones.push_back(cycle_);
    if (ex_->laser) ++laser_on_cycles;
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_prep> prep_;
  std::unique_ptr<Vsegment_executor> ex_;
  StepMonitor mon_;
  uint64_t cycle_ = 0;
};

// Random profiled segment. `prev` gives the previous directions (reversals with probability
// `p_rev` per moving axis).
template <class Rng>
Prof random_prof(Rng& rng, const Prof* prev, double p_rev, const char** kind) {
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  auto real = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  Prof p;
  const uint64_t r = uni(0, 99);
  uint64_t n;
  if (r < 20)
    n = uni(1, 8);
  else if (r < 99)
    n = uni(9, 400);
  else
    n = uni(20'000, 40'000);
  const int axes = static_cast<int>(uni(1, kAxes));
  const int dom = static_cast<int>(uni(0, static_cast<uint64_t>(axes - 1)));
  for (int i = 0; i < axes; ++i) {
    const uint64_t m = (i == dom) ? n : (uni(0, 3) == 0 ? uni(0, 1) : uni(0, n));
    int sign = (uni(0, 1) != 0) ? 1 : -1;
    if (prev && prev->steps[i] != 0) {
      sign = prev->steps[i] > 0 ? 1 : -1;
      if (real(0, 1) < p_rev) sign = -sign;
    }
    p.steps[i] = sign * static_cast<int64_t>(m);
  }
  // speeds in steps/clock: cruise 0.004 .. 0.499 (log-uniform), big moves fast
  const double vc =
      n > 10'000 ? real(0.2, 0.499) : std::exp(real(std::log(0.004), std::log(0.499)));
  p.vc = std::min<uint64_t>(static_cast<uint64_t>(vc * static_cast<double>(kOne)), (kOne >> 1) - 1);
  // acceleration: 20 % tiny (1 .. V_cruise * 1e-4 per clock), else log-uniform up to V_cruise / 4
  const double vcd = static_cast<double>(p.vc);
  const double a_lo = uni(0, 4) == 0 ? 1.0 : vcd * 1e-4;
  const double a_hi = uni(0, 4) == 0 && a_lo == 1.0 ? vcd * 1e-4 : std::min(vcd / 4.0, 4.0e9);
  p.a = static_cast<uint32_t>(
      std::max(1.0, std::exp(real(std::log(a_lo), std::log(std::max(a_hi, a_lo + 1.0))))));
  const bool tiny_a = static_cast<double>(p.a) < static_cast<double>(p.vc) * 1e-4;
  // entry / exit speeds
  const uint64_t vmin = std::max<uint64_t>(1, p.vc / 40);
  p.ve = (uni(0, 4) == 0) ? 0 : uni(vmin, p.vc);
  if (tiny_a) p.ve = uni(p.vc / 3, p.vc);  // a tiny A from rest would take ~10^7 clocks
  p.vx = uni(vmin, p.vc);
  if (tiny_a) p.vx = uni(p.vc / 3, p.vc);
  // D: the stopping rule (80 %), no deceleration (10 %), anywhere (10 %)
  const uint64_t dr = uni(0, 99);
  *kind = "random D";
  if (dr < 80) {
    uint32_t d = 0;
    if (stopping_d(p, &d)) {
      p.d = d;
      p.planned_stop = true;
      *kind = "stopping D";
    } else {
      p.d = 0;
      *kind = "D = 0 (cannot stop)";
    }
  } else if (dr < 90) {
    p.d = static_cast<uint32_t>(n + uni(0, 3));
    *kind = "no deceleration";
  } else {
    p.d = static_cast<uint32_t>(uni(0, n));
  }
  p.code = static_cast<int>(uni(0, 3));
  p.power = static_cast<int>(uni(0, 3) == 0 ? 0 : uni(1, 255));
  return p;
}

std::string describe(const Prof& p) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "steps {%lld, %lld, %lld, %lld} Ve %llu Vc %llu Vx %llu A %u D %u",
                static_cast<long long>(p.steps[0]), static_cast<long long>(p.steps[1]),
                static_cast<long long>(p.steps[2]), static_cast<long long>(p.steps[3]),
                static_cast<unsigned long long>(p.ve), static_cast<unsigned long long>(p.vc),
                static_cast<unsigned long long>(p.vx), p.a, p.d);
  return buf;
}

struct Figures {
  uint64_t segments = 0, steps = 0, planned = 0, reached_exit = 0, triangles = 0, zero_gap = 0,
           holds = 0, tiny_a = 0, clocks = 0, jumps = 0;
  double worst_speed_margin = 1e9, worst_accel_ratio = 0;
};

// Runs `streams` streams of `per_stream` random profiled segments queued back to back and checks
// everything listed in the file header. Returns the figures.
Figures run_random(uint64_t seed, int streams, int per_stream, double p_rev) {
  std::mt19937_64 rng(seed);
  Figures f;
  ProfBench b;
  std::vector<Prof> all;
  std::vector<RefRun> refs;
  std::vector<Entry> entries;
  std::vector<std::string> kinds;
  for (int s = 0; s < streams; ++s) {
    const Prof* prev = nullptr;
    for (int k = 0; k < per_stream; ++k) {
      const char* kind = "";
      all.push_back(random_prof(rng, prev, p_rev, &kind));
      kinds.emplace_back(kind);
      prev = &all.back();
    }
  }
  for (const auto& p : all) {
    entries.push_back(p.entry());
    refs.push_back(reference(p));
  }
  b.run(entries);
  EXPECT_EQ(b.starts.size(), all.size()) << "seg_start strobes";
  EXPECT_EQ(b.dones.size(), all.size()) << "seg_done strobes";
  EXPECT_EQ(b.violations, 0u) << "STEP timing violations";
  if (b.starts.size() != all.size() || b.dones.size() != all.size()) return f;

  size_t idx[kAxes] = {0, 0, 0, 0};
  int64_t net[kAxes] = {0, 0, 0, 0};
  int dir_track[kAxes] = {0, 0, 0, 0};  // DIR level (reset: low)
  int failures = 0;
  for (size_t s = 0; s < all.size() && failures < 5; ++s) {
    const Prof& p = all[s];
    const RefRun& r = refs[s];
    const uint64_t start = b.starts[s];  // seg_start is high after edge R: recorded as cycle R
    const uint64_t edge_r = start;       // tick j's STEP rises at edge R + j
    ++f.segments;
    f.clocks += r.ticks;
    EXPECT_EQ(b.dones[s], edge_r + r.ticks) << "segment " << s << " end edge, " << describe(p);
    if (!r.ideal_error.empty()) {
      ADD_FAILURE() << "segment " << s << ": " << r.ideal_error << ", " << describe(p);
      ++failures;
    }
    const uint64_t n = p.n_dom();
    int dom = 0;
    for (int i = 0; i < kAxes; ++i)
      if (mag(p.steps[i]) == n) {
        dom = i;
        break;
      }
    std::vector<uint64_t> dom_rises;
    for (int i = 0; i < kAxes; ++i) {
      const auto& tr = b.mon().axis(i);
      const uint64_t ni = mag(p.steps[i]);
      if (r.ticks_of[i].size() != ni) {
        ADD_FAILURE() << "segment " << s << " axis " << i << ": reference made "
                      << r.ticks_of[i].size() << " steps, expected " << ni;
        ++failures;
      }
      for (size_t k = 0; k < r.ticks_of[i].size(); ++k) {
        const uint64_t want = edge_r + r.ticks_of[i][k];
        if (idx[i] >= tr.rises.size()) {
          ADD_FAILURE() << "segment " << s << " axis " << i << " step " << k + 1
                        << ": expected a rise at cycle " << want << ", got none";
          ++failures;
          break;
        }
        const uint64_t got = tr.rises[idx[i]];
        const int dir = tr.rise_dir[idx[i]];
        ++idx[i];
        if (got != want || dir != (p.steps[i] > 0 ? 1 : 0)) {
          ADD_FAILURE() << "segment " << s << " axis " << i << " step " << k + 1 << " of " << ni
                        << ": expected rise at cycle " << want << " dir " << (p.steps[i] > 0)
                        << ", got " << got << " dir " << dir << " (" << describe(p) << ", "
                        << kinds[s] << ")";
          ++failures;
          break;
        }
        if (i == dom) dom_rises.push_back(got);
      }
      net[i] += p.steps[i];
      f.steps += ni;
    }
    // measured speed: dominant STEP intervals >= floor(2^48 / V_cruise)
    const uint64_t min_iv = static_cast<uint64_t>((static_cast<u128>(kOne)) / p.vc);
    const double vc = static_cast<double>(p.vc) / static_cast<double>(kOne);
    const double a = static_cast<double>(p.a) / static_cast<double>(kOne);
    for (size_t k = 1; k < dom_rises.size(); ++k) {
      const uint64_t iv = dom_rises[k] - dom_rises[k - 1];
      if (iv < min_iv) {
        ADD_FAILURE() << "segment " << s << ": dominant interval " << iv << " clocks at cycle "
                      << dom_rises[k] << " < floor(1/V_cruise) = " << min_iv << ", " << describe(p);
        ++failures;
        break;
      }
      f.worst_speed_margin =
          std::min(f.worst_speed_margin, static_cast<double>(iv) * vc);  // >= ~1 - vc
    }
    // measured acceleration from three consecutive rises (not for a planned jump)
    if (r.jump) ++f.jumps;
    for (size_t k = 2; k < dom_rises.size() && !r.jump; ++k) {
      const double d1 = static_cast<double>(dom_rises[k - 1] - dom_rises[k - 2]);
      const double d2 = static_cast<double>(dom_rises[k] - dom_rises[k - 1]);
      const double dv = std::fabs(1.0 / d2 - 1.0 / d1);
      const double q = 1.0 / (d1 * (d1 - 1.0)) + 1.0 / (d2 * (d2 - 1.0));
      const double bound = a * ((d1 + d2) / 2.0 + 2.0) + q;
      if (dv > bound * (1 + 1e-9)) {
        ADD_FAILURE() << "segment " << s << ": speed change " << dv << " steps/clock over rises "
                      << dom_rises[k - 2] << ", " << dom_rises[k - 1] << ", " << dom_rises[k]
                      << " exceeds A bound " << bound << ", " << describe(p);
        ++failures;
        break;
      }
      if (dv > q)
        f.worst_accel_ratio =
            std::max(f.worst_accel_ratio, (dv - q) / (a * ((d1 + d2) / 2.0 + 2.0)));
    }
    // stopping distance / exit rate
    if (p.planned_stop) {
      ++f.planned;
      if (!r.reached_exit) {
        ADD_FAILURE() << "segment " << s << ": planned with the stopping rule but V at the end "
                      << r.v_last << " != V_exit " << p.vx << ", " << describe(p);
        ++failures;
      } else {
        ++f.reached_exit;
      }
      if (dom_rises.size() >= 2) {
        const double d = static_cast<double>(dom_rises.back() - dom_rises[dom_rises.size() - 2]);
        const double vx = static_cast<double>(p.vx) / static_cast<double>(kOne);
        // the last interval's mean ideal speed lies in [V_exit, V_exit + A (d + 2)]; measured
        // interval within one clock of the ideal
        if (!(vx <= 1.0 / (d - 1.0) + 1e-12 && 1.0 / (d + 1.0) <= vx + a * (d + 2.0) + 1e-12)) {
          ADD_FAILURE() << "segment " << s << ": last dominant interval " << d
                        << " clocks disagrees with V_exit " << vx << " steps/clock, "
                        << describe(p);
          ++failures;
        }
      }
    }
    if (r.v_last < p.vc && p.d < n && p.ve < p.vc) ++f.triangles;  // never cruised at the end
    if (static_cast<double>(p.a) < static_cast<double>(p.vc) * 1e-4) ++f.tiny_a;
    // zero gap: queued, prepared in time, no reversing axis
    bool rev = false;
    for (int i = 0; i < kAxes; ++i) {
      if (p.steps[i] == 0) continue;
      const int d = p.steps[i] > 0 ? 1 : 0;
      if (d != dir_track[i]) rev = true;
      dir_track[i] = d;
    }
    if (s > 0) {
      const uint64_t prev_end = b.dones[s - 1];
      if (!rev && refs[s - 1].ticks > kPrepLatency + 4) {
        EXPECT_EQ(start, prev_end) << "segment " << s << ": zero gap expected";
        if (start == prev_end) ++f.zero_gap;
      } else if (rev) {
        ++f.holds;
        EXPECT_GT(start, prev_end) << "segment " << s << ": reversal must wait DIR hold/setup";
      }
    }
  }
  for (int i = 0; i < kAxes; ++i) {
    EXPECT_EQ(idx[i], b.mon().axis(i).rises.size()) << "axis " << i << ": extra STEP rises";
    const int32_t pos = static_cast<int32_t>(b.ex().position[i]);
    EXPECT_EQ(pos, net[i]) << "axis " << i << " position";
    const auto bad = b.mon().check_pulses(i, fpgacnc::tb::AxisTiming{1, 1, 3, 2});
    EXPECT_TRUE(bad.empty()) << "axis " << i << ": " << (bad.empty() ? "" : bad.front());
  }
  return f;
}

// FPGACNC_PROFILE_STREAMS streams of 20 segments (30 in CTest, 400 in `make soak`); the counts
// below scale with them.
TEST(Profile, RandomSegmentsEdgeForEdgeWithTheReference) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261106, "Profile.RandomSegments");
  const char* ns = std::getenv("FPGACNC_PROFILE_STREAMS");
  const int streams = ns ? std::max(1, std::atoi(ns)) : 30;
  const uint64_t n = static_cast<uint64_t>(streams) * 20;
  const Figures f = run_random(seed, streams, 20, 0.1);
  std::printf(
      "%llu segments, %llu steps, %llu clocks; %llu planned stops (%llu reached V_exit), "
      "%llu ended below cruise, %llu tiny A, %llu zero-gap joins, %llu reversal holds, "
      "%llu with an unplanned jump to V_exit (no accel check); "
      "worst interval*V_cruise %.4f, worst accel / bound %.3f\n",
      (unsigned long long)f.segments, (unsigned long long)f.steps, (unsigned long long)f.clocks,
      (unsigned long long)f.planned, (unsigned long long)f.reached_exit,
      (unsigned long long)f.triangles, (unsigned long long)f.tiny_a, (unsigned long long)f.zero_gap,
      (unsigned long long)f.holds, (unsigned long long)f.jumps, f.worst_speed_margin,
      f.worst_accel_ratio);
  EXPECT_GE(f.segments, n);
  EXPECT_GT(f.planned, n / 2);
  EXPECT_EQ(f.reached_exit, f.planned);
  EXPECT_GT(f.zero_gap, n / 4);
  EXPECT_GT(f.holds, n / 40);
  EXPECT_GT(f.tiny_a, n / 100);
}

// The worked example of docs/protocol.md: 5 972 080 clocks, V_exit reached before the end.
TEST(Profile, WorkedExample) {
  Prof p;
  p.steps[0] = 320;
  p.steps[1] = -160;
  p.vc = 18'014'398'509;
  p.vx = 1'000'000'000;
  p.a = 18'014;
  p.d = 288;
  const RefRun r = reference(p);
  EXPECT_EQ(r.ticks, 5'972'080u);
  EXPECT_TRUE(r.reached_exit);
  uint32_t d = 0;
  ASSERT_TRUE(stopping_d(p, &d));
  EXPECT_EQ(d, 288u);
  ProfBench b;
  b.run({p.entry()});
  ASSERT_EQ(b.starts.size(), 1u);
  ASSERT_EQ(b.dones.size(), 1u);
  EXPECT_EQ(b.dones[0] - b.starts[0], r.ticks);
  for (int i = 0; i < 2; ++i) {
    const auto& tr = b.mon().axis(i);
    ASSERT_EQ(tr.rises.size(), r.ticks_of[i].size());
    for (size_t k = 0; k < tr.rises.size(); ++k)
      ASSERT_EQ(tr.rises[k], b.starts[0] + r.ticks_of[i][k]) << "axis " << i << " step " << k;
  }
  EXPECT_EQ(b.laser_on_cycles, r.ticks);
}

// abort (e-stop) while a profiled segment runs with the next one prepared: no STEP rise after the
// abort clock, laser low in it, both segments dropped (no seg_done), pulses already high keep their
// high time; then a new segment runs exactly as the reference from its own start.
TEST(Profile, AbortDropsRunningAndPreparedSegments) {
  Prof a;
  a.steps[0] = -400;
  a.steps[1] = -123;
  a.vc = kOne / 10;
  a.ve = kOne / 40;
  a.vx = kOne / 40;
  a.a = 1 << 30;
  uint32_t d = 0;
  ASSERT_TRUE(stopping_d(a, &d));
  a.d = d;
  Prof c = a;
  c.steps[0] = -50;
  c.steps[1] = -7;
  ASSERT_TRUE(stopping_d(c, &d));
  c.d = d;
  const RefRun ra = reference(a);
  const RefRun rc = reference(c);
  ProfBench b;
  // find A's start with a dry run of the same bench timing: start = first seg_start
  ProfBench probe;
  probe.run({a.entry()});
  ASSERT_EQ(probe.starts.size(), 1u);
  // prep latency (25 + N_AXES), then taken by the idle executor on the next edge (no reversal)
  ASSERT_EQ(probe.prep_accepts.size(), 1u);
  EXPECT_EQ(probe.starts[0], probe.prep_accepts[0] + kPrepLatency + 1) << "LINE_PROFILE latency";
  const uint64_t abort_edge = probe.starts[0] + ra.ticks / 2;
  b.run({a.entry(), c.entry()}, abort_edge);
  ASSERT_EQ(b.starts.size(), 1u) << "only A started";
  EXPECT_EQ(b.starts[0], probe.starts[0]);
  EXPECT_TRUE(b.dones.empty()) << "aborted segments report no seg_done";
  EXPECT_EQ(b.laser_in_abort_clock, 0) << "laser low in the abort clock";
  for (int ax = 0; ax < 2; ++ax) {
    const auto& tr = b.mon().axis(ax);
    size_t want = 0;
    for (uint64_t t : ra.ticks_of[ax])
      if (b.starts[0] + t <= abort_edge) ++want;
    ASSERT_EQ(tr.rises.size(), want) << "axis " << ax << ": rises up to the abort edge only";
    for (size_t k = 0; k < want; ++k) EXPECT_EQ(tr.rises[k], b.starts[0] + ra.ticks_of[ax][k]);
    const auto bad = b.mon().check_pulses(ax, fpgacnc::tb::AxisTiming{1, 1, 3, 2});
    EXPECT_TRUE(bad.empty()) << (bad.empty() ? "" : bad.front());
  }
  EXPECT_FALSE(b.ex().busy);
  // afterwards a new segment runs normally
  const size_t r0 = b.mon().axis(0).rises.size(), r1 = b.mon().axis(1).rises.size();
  b.run({c.entry()});
  ASSERT_EQ(b.starts.size(), 2u);
  ASSERT_EQ(b.dones.size(), 1u);
  EXPECT_EQ(b.dones[0] - b.starts[1], rc.ticks);
  for (int ax = 0; ax < 2; ++ax) {
    const auto& tr = b.mon().axis(ax);
    const size_t base = ax == 0 ? r0 : r1;
    ASSERT_EQ(tr.rises.size() - base, rc.ticks_of[ax].size());
    for (size_t k = 0; k < rc.ticks_of[ax].size(); ++k)
      EXPECT_EQ(tr.rises[base + k], b.starts[1] + rc.ticks_of[ax][k]);
  }
}

// ---------------------------------------------------------------- cnc_core through the pins
// LINE_PROFILE frames at 3 Mbaud: frame -> FIFO -> prep -> executor; every STEP edge equal to the
// reference from each segment's seg_start, zero gap between the queued segments (no reversal),
// DONE counts; then frames breaking each field rule are NAKed BAD_FIELD (BAD_LENGTH for a short
// payload) and nothing moves.
class CoreBench : public fpgacnc::tb::PinHarness<Vcnc_core_heat> {
 public:
  CoreBench() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_heat>(), true, 3'000'000.0) {
    fpgacnc::tb::reset_core(*this);
  }
  std::vector<uint64_t> starts;
  std::vector<fpgacnc::tb::v2::DeviceMsg> msgs;

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
  fpgacnc::tb::v2::DeviceParser parser_;
};

std::vector<uint8_t> profile_frame(uint8_t seq, const Prof& p, bool short_steps) {
  std::vector<uint8_t> b;
  b.push_back(static_cast<uint8_t>(p.code | (short_steps ? 0x80 : 0)));
  b.push_back(static_cast<uint8_t>(p.power));
  for (uint64_t v : {p.ve, p.vc, p.vx})
    for (int k = 5; k >= 0; --k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
  for (uint32_t v : {p.a, p.d})
    for (int k = 3; k >= 0; --k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
  for (int i = 0; i < kAxes; ++i) {
    const auto s = static_cast<uint32_t>(static_cast<int32_t>(p.steps[i]));
    for (int k = short_steps ? 1 : 3; k >= 0; --k) b.push_back(static_cast<uint8_t>(s >> (8 * k)));
  }
  return fpgacnc::tb::v2::frame(0x12, seq, b);
}

TEST(ProfileCore, FramesThroughThePinsZeroGapAndBadFields) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261107, "ProfileCore");
  std::mt19937_64 rng(seed);
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  CoreBench b;
  b.send(fpgacnc::tb::v2::hello());
  for (int i = 0; i < 30000 && b.msgs.empty(); ++i) b.tick();
  ASSERT_FALSE(b.msgs.empty()) << "no IDENT";
  constexpr int kSegs = 10;
  std::vector<Prof> segs;
  for (int i = 0; i < kSegs; ++i) {
    Prof p;
    // negative directions only (DIR low after reset): no reversal, so every join is zero-gap;
    // each segment lasts longer than one 42-byte frame (~7 000 clocks at 3 Mbaud)
    // (no STEP timing violation: checked below)
    const uint64_t n = i == 0 ? 150 : uni(30, 100);
    p.steps[0] = -static_cast<int64_t>(n);
    p.steps[1] = -static_cast<int64_t>(uni(0, n));
    p.steps[2] = -static_cast<int64_t>(uni(0, 1));
    // the core's default STEP high + low is 200 clocks: V_cruise below 1/200 step per clock
    p.vc = uni(kOne / 1000, kOne / 400);
    p.ve = uni(kOne / 4000, p.vc);
    p.vx = uni(kOne / 4000, p.vc);
    p.a = static_cast<uint32_t>(uni(3'000, 100'000));
    uint32_t d = 0;
    p.d = stopping_d(p, &d) ? d : 0;
    p.code = 1;
    p.power = static_cast<int>(uni(0, 255));
    segs.push_back(p);
    b.queue(profile_frame(static_cast<uint8_t>(i), p, i % 2 == 0));
  }
  uint64_t guard = 0;
  while ((b.dut().segments_done < kSegs || !b.rx_idle()) && ++guard < 5'000'000) b.tick();
  ASSERT_EQ(b.dut().segments_done, static_cast<uint32_t>(kSegs)) << "by cycle " << b.cycle();
  for (int i = 0; i < 200; ++i) b.tick();
  ASSERT_EQ(b.starts.size(), static_cast<size_t>(kSegs));
  for (int a = 0; a < kAxes; ++a)
    for (auto& v : b.mon().check_pulses(a, fpgacnc::tb::AxisTiming{})) ADD_FAILURE() << v;
  std::vector<uint64_t> want[kAxes];
  for (int i = 0; i < kSegs; ++i) {
    const RefRun r = reference(segs[i]);
    if (i + 1 < kSegs) {
      EXPECT_EQ(b.starts[i + 1] - b.starts[i], r.ticks) << "segment " << i + 1 << ": zero gap";
    }
    for (int a = 0; a < kAxes; ++a)
      for (uint64_t t : r.ticks_of[a]) want[a].push_back(b.starts[i] + t);
  }
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = b.mon().axis(a);
    ASSERT_EQ(tr.rises.size(), want[a].size()) << "axis " << a << " steps, seed " << seed;
    for (size_t k = 0; k < want[a].size(); ++k)
      ASSERT_EQ(tr.rises[k], want[a][k]) << "axis " << a << " step " << k << ", seed " << seed;
  }
  // Rule breakers: each NAKed with the reason, nothing queued.
  Prof ok;
  ok.steps[0] = -10;
  ok.vc = kOne / 100;
  ok.vx = kOne / 200;
  ok.a = 1000;
  struct Bad {
    const char* what;
    Prof p;
    bool short_steps;
    int cut;
    uint8_t reason;
  };
  std::vector<Bad> bad;
  auto with = [&](auto f) {
    Prof p = ok;
    f(p);
    return p;
  };
  bad.push_back({"V_exit = 0", with([](Prof& p) { p.vx = 0; }), true, 0, 7});
  bad.push_back({"V_entry > V_cruise", with([](Prof& p) { p.ve = p.vc + 1; }), true, 0, 7});
  bad.push_back({"V_exit > V_cruise", with([](Prof& p) { p.vx = p.vc + 1; }), false, 0, 7});
  bad.push_back({"V_cruise = 2^47", with([](Prof& p) { p.vc = kOne / 2; }), true, 0, 7});
  bad.push_back({"A = 0, V_entry = 0", with([](Prof& p) { p.a = 0; }), true, 0, 7});
  bad.push_back({"no steps", with([](Prof& p) { p.steps[0] = 0; }), true, 0, 7});
  bad.push_back({"n = 2^24", with([](Prof& p) { p.steps[1] = 1 << 24; }), false, 0, 7});
  bad.push_back({"n = -2^24", with([](Prof& p) { p.steps[3] = -(1 << 24); }), false, 0, 7});
  bad.push_back({"payload 27 bytes", ok, true, 9, 2});
  const uint32_t done_before = b.dut().segments_done;
  const size_t rises_before =
      b.mon().axis(0).rises.size() + b.mon().axis(1).rises.size() + b.mon().axis(3).rises.size();
  uint8_t seq = kSegs;
  for (const auto& x : bad) {
    auto f = profile_frame(seq, x.p, x.short_steps);
    if (x.cut) {
      std::vector<uint8_t> pl(f.begin() + 4, f.end() - 2);
      pl.resize(pl.size() - static_cast<size_t>(x.cut));
      f = fpgacnc::tb::v2::frame(0x12, seq, pl);
    }
    const size_t n0 = b.msgs.size();
    b.send(f);
    auto answered = [&] {  // a NAK or ACK after n0 (a pending DONE may come first)
      for (size_t k = n0; k < b.msgs.size(); ++k)
        if (b.msgs[k].type != fpgacnc::tb::v2::kDone) return true;
      return false;
    };
    for (int i = 0; i < 30000 && !answered(); ++i) b.tick();
    ASSERT_TRUE(answered()) << x.what << ": no answer";
    const auto& m = b.msgs.back();
    EXPECT_EQ(m.type, fpgacnc::tb::v2::kNak) << x.what;
    if (m.type == fpgacnc::tb::v2::kNak) {
      EXPECT_EQ(m.u8(0), seq) << x.what;
      EXPECT_EQ(m.u8(1), x.reason) << x.what;
    }
  }
  // the first good one after them is accepted with the same seq (nothing was consumed)
  const size_t n0 = b.msgs.size();
  b.send(profile_frame(seq, ok, true));
  for (int i = 0; i < 30000 && b.msgs.size() == n0; ++i) b.tick();
  ASSERT_GT(b.msgs.size(), n0);
  EXPECT_EQ(b.msgs.back().type, fpgacnc::tb::v2::kAck);
  guard = 0;
  while (b.dut().segments_done == done_before && ++guard < 1'000'000) b.tick();
  EXPECT_EQ(b.dut().segments_done, done_before + 1);
  EXPECT_EQ(
      b.mon().axis(0).rises.size() + b.mon().axis(1).rises.size() + b.mon().axis(3).rises.size(),
      rises_before + 10);
}

}  // namespace
