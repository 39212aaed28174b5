// ExecHarness: drives segment_executor (vexec) directly: timing settings, one clock per tick()
// with STEP/DIR sampled into a StepMonitor, run(Segment) offering one segment on the input stream
// and running it to the end, and run_queue() offering a list of segments back to back (always
// valid). Plus the ideal k*T/n schedule the executor must follow.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "Vsegment_executor.h"
#include "common/step_monitor.h"
#include "verilated.h"

namespace fpgacnc::tb {

inline constexpr int kExecAxes = 4;

inline uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

struct Segment {
  int code = 1;
  int64_t steps[kExecAxes] = {0, 0, 0, 0};  // signed
  uint64_t period = 0;                      // dominant period P, clocks (v1: T = P * n_dom)
  int power = 255;                          // laser power (v1: 255)
  bool v2 = false;                          // reported back with seg_done (seg_done_v2)
  int64_t t = -1;                           // T given (v2 LINE, DWELL); -1: T = period * n_dom
  int dir_fast = -1;  // -1: computed as segment_prep does (dir_fast_ref); 0 or 1: forced

  uint64_t n_dom() const {
    uint64_t n = 0;
    for (int64_t s : steps) n = std::max(n, mag(s));
    return n;
  }
  uint64_t total() const {  // T
    return t >= 0 ? static_cast<uint64_t>(t) : period * n_dom();
  }
};

// Cycle of step k of n in a run of T clocks starting at R: R + ceil(k*T/n).
inline uint64_t scheduled_rise(uint64_t R, uint64_t k, uint64_t T, uint64_t n) {
  const unsigned __int128 kt = static_cast<unsigned __int128>(k) * T;
  return R + static_cast<uint64_t>((kt + n - 1) / n);
}
// The ideal (real-valued) time of that step: R + k*T/n.
inline double ideal_rise(uint64_t R, uint64_t k, uint64_t T, uint64_t n) {
  return static_cast<double>(R) +
         static_cast<double>(k) * static_cast<double>(T) / static_cast<double>(n);
}
// The shortest period the settings allow: max(STEP high + low) over the axes.
inline uint64_t min_period(const std::vector<AxisTiming>& t) {
  uint64_t pmin = 0;
  for (auto& at : t) pmin = std::max<uint64_t>(pmin, at.high + at.low);
  return pmin;
}
// Random settings: STEP high/low 1..`pulse_max`, DIR setup/hold 1..`dir_max` clocks.
template <class Uni>
AxisTiming random_timing(Uni& uni, uint64_t pulse_max, uint64_t dir_max) {
  return AxisTiming{uint32_t(uni(1, pulse_max)), uint32_t(uni(1, pulse_max)),
                    uint32_t(uni(1, dir_max)), uint32_t(uni(1, dir_max))};
}
// A DIR setting of 0 counts as 1 clock.
inline uint64_t at_least_1(uint32_t v) {
  return v == 0 ? 1 : v;
}

// Reference of segment_prep's dir_fast (the rtl-back contract): with `track` the DIR level each
// axis has when the segment starts, dir_fast = 1 iff every moving axis whose direction differs has
// floor(T / n_dom) >= max(hold, 1) + max(setup, 1). Updates `track` for the moving axes.
inline bool dir_fast_ref(const Segment& s, const std::vector<AxisTiming>& t, int* track) {
  const uint64_t n = s.n_dom();
  bool fast = true;
  for (int a = 0; a < kExecAxes; ++a) {
    if (s.steps[a] == 0) continue;
    const int d = s.steps[a] > 0 ? 1 : 0;
    if (d != track[a]) {
      const uint64_t p = s.total() / n;
      if (p < at_least_1(t[a].hold) + at_least_1(t[a].setup)) fast = false;
    }
    track[a] = d;
  }
  return fast;
}

class ExecHarness {
 public:
  explicit ExecHarness(const std::vector<AxisTiming>& timing)
      : ctx_(std::make_unique<VerilatedContext>()), mon_(kExecAxes) {
    m_ = std::make_unique<Vsegment_executor>(ctx_.get());
    set_timing(timing);
    m_->adv = 1;  // the motion rate at 100 %: every RUN clock is a tick
    m_->rst = 1;
    tick();
    tick();
    m_->rst = 0;
    tick();
  }
  ~ExecHarness() { m_->final(); }
  ExecHarness(const ExecHarness&) = delete;
  ExecHarness& operator=(const ExecHarness&) = delete;

  // The DIR hold counters start as if every STEP had risen on this edge (the first edge after
  // reset is released).
  static constexpr uint64_t kResetRiseEdge = 3;

  void set_timing(const std::vector<AxisTiming>& t) {
    timing_ = t;
    m_->cfg_step_high = m_->cfg_step_low = m_->cfg_dir_setup = m_->cfg_dir_hold = 0;
    for (int a = 0; a < kExecAxes; ++a) {
      m_->cfg_step_high |= static_cast<uint64_t>(t[a].high) << (16 * a);
      m_->cfg_step_low |= static_cast<uint64_t>(t[a].low) << (16 * a);
      m_->cfg_dir_setup |= static_cast<uint64_t>(t[a].setup) << (16 * a);
      m_->cfg_dir_hold |= static_cast<uint64_t>(t[a].hold) << (16 * a);
    }
  }

  void tick() {
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    mon_.sample(cycle_, m_->step, m_->dir);
    if (m_->violation) ++violations_;
    if (m_->seg_start) starts_.push_back(cycle_);
    if (m_->seg_done) dones_.push_back({cycle_, m_->seg_done_v2 != 0});
    if (m_->laser) ++laser_cycles_;
    if ((m_->laser != 0) != laser_prev_) {
      (m_->laser ? laser_rises_ : laser_falls_).push_back(cycle_);
      laser_prev_ = m_->laser != 0;
    }
  }

  // Drives the segment onto the input stream (tvalid not changed). dir_fast: forced, or computed
  // by dir_fast_ref with the harness's tracked directions.
  void load(const Segment& s) {
    const uint64_t total = s.total();
    const bool fast = dir_fast_ref(s, timing_, track_);
    m_->s_axis_code = s.code;
    m_->s_axis_power = s.power;
    m_->s_axis_v2 = s.v2;
    m_->s_axis_dir_fast = s.dir_fast >= 0 ? (s.dir_fast != 0) : fast;
    m_->s_axis_dir = 0;
    for (int a = 0; a < kExecAxes; ++a) {
      if (s.steps[a] > 0) m_->s_axis_dir |= 1u << a;
      m_->s_axis_steps[a] = static_cast<uint32_t>(mag(s.steps[a]));
      const uint64_t tmn = total - mag(s.steps[a]);
      m_->s_axis_tmn[2 * a] = static_cast<uint32_t>(tmn);
      m_->s_axis_tmn[2 * a + 1] = static_cast<uint32_t>(tmn >> 32);
    }
    m_->s_axis_total = total;
  }

  // Offers one segment and runs until it is done. Returns the run start cycle R (first cycle with
  // seg_start observed) or 0 for an empty segment; `accept` receives the accept edge. A segment
  // still running T + 1e6 clocks after the accept is abandoned and stalled() is set.
  uint64_t run(const Segment& s, uint64_t* accept = nullptr) {
    while (!m_->s_axis_tready) tick();
    load(s);
    m_->s_axis_tvalid = 1;
    stalled_ = false;
    const size_t starts_before = starts_.size();
    tick();
    if (accept) *accept = cycle_;
    m_->s_axis_tvalid = 0;
    finish(s.total());
    return starts_.size() > starts_before ? starts_.back() : 0;
  }

  // Offers the segments back to back (the next one valid on the clock after the previous one was
  // taken) and runs until the executor is idle again. accepts[i] = accept edge of segs[i].
  std::vector<uint64_t> run_queue(const std::vector<Segment>& segs) {
    std::vector<uint64_t> accepts;
    if (segs.empty()) return accepts;
    uint64_t total = 0;
    for (auto& s : segs) total += s.total();
    const uint64_t limit = cycle_ + total + 1'000'000 + 100'000 * segs.size();
    size_t i = 0;
    load(segs[0]);
    m_->s_axis_tvalid = 1;
    stalled_ = false;
    while (i < segs.size()) {
      const bool take = m_->s_axis_tready;  // depends on registers only
      tick();
      if (take) {
        accepts.push_back(cycle_);
        if (++i < segs.size()) load(segs[i]);
      }
      if (cycle_ > limit) {
        stalled_ = true;
        break;
      }
    }
    m_->s_axis_tvalid = 0;
    finish(total);
    return accepts;
  }
  bool stalled() const { return stalled_; }

  void idle_until_pulses_done() {
    while (!m_->idle) tick();
  }
  void idle(uint64_t clocks) {
    for (uint64_t i = 0; i < clocks; ++i) tick();
  }

  Vsegment_executor& dut() { return *m_; }
  StepMonitor& mon() { return mon_; }
  uint64_t cycle() const { return cycle_; }
  uint64_t violations() const { return violations_; }
  uint64_t laser_cycles() const { return laser_cycles_; }
  const std::vector<AxisTiming>& timing() const { return timing_; }
  int32_t position(int a) const { return static_cast<int32_t>(m_->position[a]); }
  const std::vector<uint64_t>& starts() const { return starts_; }
  struct Done {
    uint64_t cycle;
    bool v2;
  };
  const std::vector<Done>& dones() const { return dones_; }
  const std::vector<uint64_t>& laser_rises() const { return laser_rises_; }
  const std::vector<uint64_t>& laser_falls() const { return laser_falls_; }

 private:
  // Runs until the executor is back in its idle state, then one more clock so that the last STEP
  // edge and seg_done are sampled.
  void finish(uint64_t total) {
    uint64_t guard = 0;
    while (m_->busy) {
      tick();
      if (++guard > total + 1'000'000) {
        stalled_ = true;
        break;
      }
    }
    tick();
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_executor> m_;
  StepMonitor mon_;
  std::vector<AxisTiming> timing_;
  std::vector<uint64_t> starts_, laser_rises_, laser_falls_;
  std::vector<Done> dones_;
  int track_[kExecAxes] = {0, 0, 0, 0};
  uint64_t cycle_ = 0, violations_ = 0, laser_cycles_ = 0;
  bool stalled_ = false, laser_prev_ = false;
};

}  // namespace fpgacnc::tb
