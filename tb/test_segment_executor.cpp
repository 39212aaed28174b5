// Bench for segment_executor (with dda_linear and step_pulse): exact step counts, step times
// against the ideal k*T/n schedule, STEP/DIR pulse rules and jitter, over thousands of random
// seeded segments with random timing settings down to 1 clock.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "Vsegment_prep.h"
#include "common/exec_harness.h"
#include "common/fifo_entry.h"
#include "common/seed.h"
#include "common/step_monitor.h"

namespace {

using fpgacnc::tb::AxisTiming;
using fpgacnc::tb::mag;
using fpgacnc::tb::Segment;
using fpgacnc::tb::StepMonitor;

constexpr int kAxes = fpgacnc::tb::kExecAxes;

// The harness with the default step timing, failing the test when a segment does not finish.
class ExecBench : public fpgacnc::tb::ExecHarness {
 public:
  ExecBench() : ExecHarness(std::vector<AxisTiming>(kAxes)) {}

  uint64_t run(const Segment& s, uint64_t* accept = nullptr) {
    const uint64_t R = ExecHarness::run(s, accept);
    if (stalled()) ADD_FAILURE() << "segment did not finish within T + 1e6 clocks, T=" << s.total();
    return R;
  }
};

struct SegmentCheck {
  double worst_error = 0;     // |rise - ideal| in clocks
  uint64_t worst_jitter = 0;  // max - min step interval within a segment, per axis
};

// Checks one executed segment: counts, exact ceil(k*T/n) schedule, ideal error < 1 clock,
// direction at every rise, last step of every axis at R + T, jitter <= 1.
void check_segment(const StepMonitor& mon, const Segment& s, uint64_t R, size_t* idx,
                   SegmentCheck* out) {
  const uint64_t T = s.total();
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = mon.axis(a);
    const uint64_t n = mag(s.steps[a]);
    // rises belonging to this segment: the next n rises in the trace
    ASSERT_GE(tr.rises.size(), idx[a] + n)
        << "axis " << a << ": expected " << n << " steps, got " << tr.rises.size() - idx[a]
        << " (segment at " << R << ")";
    uint64_t min_iv = UINT64_MAX, max_iv = 0, prev = R;
    for (uint64_t k = 1; k <= n; ++k) {
      const uint64_t rise = tr.rises[idx[a] + k - 1];
      const uint64_t expect = fpgacnc::tb::scheduled_rise(R, k, T, n);
      ASSERT_EQ(rise, expect) << "axis " << a << " step " << k << "/" << n << " T=" << T
                              << " P=" << s.period << " start R=" << R;
      const double ideal = fpgacnc::tb::ideal_rise(R, k, T, n);
      out->worst_error = std::max(out->worst_error, std::abs(static_cast<double>(rise) - ideal));
      ASSERT_EQ(tr.rise_dir[idx[a] + k - 1], s.steps[a] > 0 ? 1 : 0)
          << "axis " << a << " DIR wrong at step " << k << " cycle " << rise;
      if (k > 1) {
        min_iv = std::min(min_iv, rise - prev);
        max_iv = std::max(max_iv, rise - prev);
      }
      prev = rise;
    }
    if (n > 0) {
      ASSERT_EQ(prev, R + T) << "axis " << a << ": last step not at the segment end";
      ASSERT_GT(prev, R + T - s.period) << "axis " << a << ": last step before the last period";
    }
    if (n > 2) {
      ASSERT_LE(max_iv - min_iv, 1u) << "axis " << a << " jitter, segment at " << R;
      out->worst_jitter = std::max(out->worst_jitter, max_iv - min_iv);
    }
    idx[a] += n;
  }
}

TEST(SegmentExecutor, DiagonalExample) {
  ExecBench b;
  Segment s;
  s.code = 1;
  s.steps[0] = 320;
  s.steps[1] = -160;
  s.period = 15625;  // 18 750 000 / 1200
  size_t idx[kAxes] = {0, 0, 0, 0};
  SegmentCheck c;
  const uint64_t R = b.run(s);
  ASSERT_NE(R, 0u);
  check_segment(b.mon(), s, R, idx, &c);
  EXPECT_EQ(b.position(0), 320);
  EXPECT_EQ(b.position(1), -160);
  EXPECT_EQ(b.violations(), 0u);
  // laser high for the whole run: T clocks
  EXPECT_EQ(b.laser_cycles(), 320u * 15625u);
  for (int a = 0; a < 2; ++a)
    for (auto& v : b.mon().check_pulses(a, b.timing()[a])) ADD_FAILURE() << v;
}

TEST(SegmentExecutor, ZeroStepSegmentCompletesAtOnce) {
  ExecBench b;
  Segment s;
  s.period = 100;
  uint64_t accept = 0;
  const uint64_t R = b.run(s, &accept);
  EXPECT_EQ(R, 0u) << "an empty segment must not start a run";
  EXPECT_EQ(b.mon().axis(0).rises.size(), 0u);
  EXPECT_LE(b.cycle() - accept, 2u) << "empty segment should complete at once";
}

TEST(SegmentExecutor, RapidNeverLightsLaser) {
  ExecBench b;
  Segment s;
  s.code = 0;
  s.steps[0] = -50;
  s.steps[2] = 7;
  s.period = 300;
  b.run(s);
  EXPECT_EQ(b.laser_cycles(), 0u);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 50u);
  EXPECT_EQ(b.mon().axis(2).rises.size(), 7u);
}

TEST(SegmentExecutor, DirectionReversalRespectsHoldAndSetup) {
  ExecBench b;
  std::vector<AxisTiming> t(kAxes, AxisTiming{3, 2, 500, 700});
  b.set_timing(t);
  size_t idx[kAxes] = {0, 0, 0, 0};
  SegmentCheck c;
  for (int rep = 0; rep < 6; ++rep) {
    Segment s;
    s.steps[0] = (rep % 2) ? -40 : 40;
    s.steps[1] = (rep % 2) ? 13 : -13;
    s.period = 5;
    const uint64_t R = b.run(s);
    check_segment(b.mon(), s, R, idx, &c);
  }
  for (int a = 0; a < 2; ++a)
    for (auto& v : b.mon().check_pulses(a, t[a])) ADD_FAILURE() << v;
  EXPECT_EQ(b.mon().axis(0).dir_edges.size(), 6u);
  EXPECT_EQ(b.violations(), 0u);
}

// The main regression: random segments (21 per batch) in batches with random timing settings.
TEST(SegmentExecutor, RandomSegmentsExactTiming) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261121, "RandomSegmentsExactTiming");
  std::mt19937_64 rng(seed);
  ExecBench b;
  size_t idx[kAxes] = {0, 0, 0, 0};
  SegmentCheck c;
  int64_t expect_pos[kAxes] = {0, 0, 0, 0};
  int segments = 0, one_clock_batches = 0;
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  auto log_uniform = [&](uint64_t hi) {
    const double x = std::uniform_real_distribution<double>(0.0, std::log(double(hi) + 1))(rng);
    return std::min<uint64_t>(hi, static_cast<uint64_t>(std::exp(x)));
  };
  // FPGACNC_EXEC_BATCHES batches of random timing (12 in CTest, 400 in `make soak`).
  const char* nb = std::getenv("FPGACNC_EXEC_BATCHES");
  const int batches = nb ? std::atoi(nb) : 12;
  std::printf("%d batches (FPGACNC_EXEC_BATCHES)\n", batches);
  for (int batch = 0; batch < batches; ++batch) {
    std::vector<AxisTiming> t(kAxes);
    const int kind = static_cast<int>(uni(0, 9));
    for (auto& at : t) {
      if (kind < 3) {
        at = AxisTiming{1, 1, 1, 1};  // the fastest settings
      } else if (kind < 8) {
        at = fpgacnc::tb::random_timing(uni, 12, 40);
      } else {
        at = AxisTiming{uint32_t(uni(1, 150)), uint32_t(uni(1, 150)), uint32_t(uni(1, 400)),
                        uint32_t(uni(0, 400))};
      }
    }
    if (kind < 3) ++one_clock_batches;
    const uint64_t pmin = fpgacnc::tb::min_period(t);
    b.idle(1000);  // every DIR hold of the previous batch has elapsed
    b.set_timing(t);
    const uint64_t batch_start = b.cycle();
    for (int i = 0; i < 21; ++i) {
      Segment s;
      s.code = static_cast<int>(uni(0, 3));
      for (int a = 0; a < kAxes; ++a) {
        // Counts up to 100 000; large counts mostly with short periods so the run fits CI.
        const uint64_t cap = kind >= 8 ? 3000 : (i % 4 == 0 ? 100000 : 5000);
        const uint64_t n = uni(0, 9) == 0 ? 0 : log_uniform(cap);
        s.steps[a] = uni(0, 1) ? static_cast<int64_t>(n) : -static_cast<int64_t>(n);
      }
      if (batch == 0 && i == 0) {
        s.steps[0] = 100000;  // the largest count, both signs, once
        s.steps[1] = -99999;
      }
      s.period = pmin + uni(0, pmin < 20 ? 3 : pmin);
      const uint64_t R = b.run(s);
      if (s.n_dom() == 0) {
        ASSERT_EQ(R, 0u);
      } else {
        check_segment(b.mon(), s, R, idx, &c);
        if (HasFatalFailure()) {
          ADD_FAILURE() << "batch " << batch << " segment " << i << " seed " << seed;
          return;
        }
      }
      for (int a = 0; a < kAxes; ++a) expect_pos[a] += s.steps[a];
      ++segments;
    }
    b.idle_until_pulses_done();
    for (int a = 0; a < kAxes; ++a)
      for (auto& v : b.mon().check_pulses(a, t[a], batch_start, b.cycle()))
        ADD_FAILURE() << "batch " << batch << ": " << v;
  }
  for (int a = 0; a < kAxes; ++a) {
    EXPECT_EQ(b.position(a), static_cast<int32_t>(expect_pos[a])) << "axis " << a;
    EXPECT_EQ(b.mon().axis(a).position, expect_pos[a]) << "axis " << a;
  }
  EXPECT_EQ(b.violations(), 0u);
  EXPECT_EQ(segments, batches * 21);
  EXPECT_GT(one_clock_batches, 0);
  std::printf("segments %d, clocks %llu, worst step error %.3f clocks, worst jitter %llu clocks\n",
              segments, static_cast<unsigned long long>(b.cycle()), c.worst_error,
              static_cast<unsigned long long>(c.worst_jitter));
  EXPECT_LT(c.worst_error, 1.0);
  EXPECT_LE(c.worst_jitter, 1u);
}

// ---------------------------------------------------------------- queued segments
// Reference model of the executor's schedule for segments offered back to back (always valid),
// from docs/timing.md "Queued segments". It predicts every accept edge, run start R, DIR write,
// seg_done, laser interval and STEP rise.
struct Planned {
  uint64_t accept = 0, R = 0, end = 0;  // R = 0: zero-length (no run); end = seg_done edge
  bool zero_gap = false;  // R = the previous segment's end (accepted on its last tick)
  bool reversal = false, fast = false;
};

class QueueModel {
 public:
  QueueModel(const std::vector<AxisTiming>& t, uint64_t first_accept, const uint64_t* last_rise,
             const int* dir)
      : t_(t), next_accept_(first_accept) {
    for (int a = 0; a < kAxes; ++a) {
      last_rise_[a] = last_rise[a];
      dir_[a] = dir[a];
    }
  }

  Planned add(const Segment& s, bool dir_fast) {
    Planned p;
    p.accept = next_accept_;
    const bool from_run = from_run_;
    const uint64_t T = s.total();
    uint32_t rev = 0;
    for (int a = 0; a < kAxes; ++a) {
      if (s.steps[a] == 0) continue;
      const int d = s.steps[a] > 0 ? 1 : 0;
      if (d != dir_[a]) rev |= 1u << a;
      dir_[a] = d;
    }
    p.reversal = rev != 0;
    p.fast = dir_fast;
    if (T == 0) {
      p.end = from_run ? p.accept + 1 : p.accept;
      next_accept_ = from_run ? p.accept + 2 : p.accept + 1;
      from_run_ = false;
      return p;
    }
    if (rev != 0 && !(from_run && dir_fast)) {
      // HOLD: every reversing axis's hold since its last rise, DIR on D, then SETUP
      uint64_t D = p.accept + 1;
      uint64_t setup = 0;
      for (int a = 0; a < kAxes; ++a)
        if (rev & (1u << a)) {
          D = std::max(D, last_rise_[a] + fpgacnc::tb::at_least_1(t_[a].hold));
          setup = std::max<uint64_t>(setup, t_[a].setup);
        }
      for (int a = 0; a < kAxes; ++a)
        if (rev & (1u << a)) dir_edges_[a].push_back(D);
      p.R = D + std::max<uint64_t>(setup, 1);
    } else {
      p.R = p.accept;
      p.zero_gap = from_run;
      for (int a = 0; a < kAxes; ++a)
        if (rev & (1u << a))
          dir_edges_[a].push_back(
              std::max(p.accept + 1, last_rise_[a] + fpgacnc::tb::at_least_1(t_[a].hold)));
    }
    p.end = p.R + T;
    for (int a = 0; a < kAxes; ++a) {
      const uint64_t n = mag(s.steps[a]);
      for (uint64_t k = 1; k <= n; ++k)
        rises_[a].push_back(fpgacnc::tb::scheduled_rise(p.R, k, T, n));
      if (n > 0) last_rise_[a] = p.end;
    }
    if (s.code != 0 && s.power != 0) {
      if (!laser_.empty() && laser_.back().second == p.R)
        laser_.back().second = p.end;  // back to back: one interval
      else
        laser_.push_back({p.R, p.end});
    }
    next_accept_ = p.end;
    from_run_ = true;
    return p;
  }

  const std::vector<uint64_t>& rises(int a) const { return rises_[a]; }
  const std::vector<uint64_t>& dir_edges(int a) const { return dir_edges_[a]; }
  const std::vector<std::pair<uint64_t, uint64_t>>& laser() const { return laser_; }

 private:
  std::vector<AxisTiming> t_;
  uint64_t next_accept_;
  bool from_run_ = false;
  uint64_t last_rise_[kAxes];
  int dir_[kAxes];
  std::vector<uint64_t> rises_[kAxes], dir_edges_[kAxes];
  std::vector<std::pair<uint64_t, uint64_t>> laser_;
};

struct QueueStats {
  uint64_t segments = 0, zero_gap = 0, fast_reversals = 0, hold_reversals = 0, zero_len = 0,
           dwells = 0, idle_clocks = 0, run_clocks = 0;
};

// Runs `segs` back to back on a fresh harness after `settle` idle clocks and checks everything
// against QueueModel: accept edges, seg_start at R, seg_done (edge and v2 bit), every STEP rise
// (exact R + ceil(kT/n)) and its DIR level, every DIR edge, the laser intervals, the pulse rules
// (STEP high/low, DIR setup/hold at every DIR change), positions, no violation.
void check_queue(const std::vector<AxisTiming>& timing, const std::vector<Segment>& segs,
                 QueueStats* st, const std::string& what) {
  ExecBench b;
  b.set_timing(timing);
  b.idle(5);
  // the harness's dir_fast reference, run ahead to know what each segment gets
  std::vector<bool> fast(segs.size());
  {
    int track[kAxes] = {0, 0, 0, 0};
    for (size_t i = 0; i < segs.size(); ++i) {
      const bool f = fpgacnc::tb::dir_fast_ref(segs[i], timing, track);
      fast[i] = segs[i].dir_fast >= 0 ? segs[i].dir_fast != 0 : f;
    }
  }
  const uint64_t reset_rise[kAxes] = {ExecBench::kResetRiseEdge, ExecBench::kResetRiseEdge,
                                      ExecBench::kResetRiseEdge, ExecBench::kResetRiseEdge};
  const int dir0[kAxes] = {0, 0, 0, 0};
  QueueModel model(timing, b.cycle() + 1, reset_rise, dir0);
  std::vector<Planned> plan;
  for (size_t i = 0; i < segs.size(); ++i) plan.push_back(model.add(segs[i], fast[i]));

  const std::vector<uint64_t> accepts = b.run_queue(segs);
  ASSERT_FALSE(b.stalled()) << what;
  ASSERT_EQ(accepts.size(), segs.size()) << what;
  std::vector<uint64_t> starts, dones;
  std::vector<bool> done_v2;
  int64_t pos[kAxes] = {0, 0, 0, 0};
  for (size_t i = 0; i < segs.size(); ++i) {
    const Planned& p = plan[i];
    ASSERT_EQ(accepts[i], p.accept) << what << ": segment " << i << " accept edge";
    if (p.R) starts.push_back(p.R);
    dones.push_back(p.end);
    done_v2.push_back(segs[i].v2);
    for (int a = 0; a < kAxes; ++a) pos[a] += segs[i].steps[a];
    if (i > 0 && p.R && plan[i - 1].R && p.zero_gap) {
      // the zero-gap rule: R' = R + T
      ASSERT_EQ(p.R, plan[i - 1].R + segs[i - 1].total()) << what << ": segment " << i;
    }
    ++st->segments;
    if (p.zero_gap) ++st->zero_gap;
    if (p.R && p.reversal) (p.zero_gap ? st->fast_reversals : st->hold_reversals)++;
    if (!p.R) ++st->zero_len;
    if (p.R && segs[i].n_dom() == 0) ++st->dwells;
    if (p.R) st->run_clocks += segs[i].total();
  }
  // seg_start / seg_done
  ASSERT_EQ(b.starts().size(), starts.size()) << what << ": seg_start count";
  for (size_t i = 0; i < starts.size(); ++i)
    ASSERT_EQ(b.starts()[i], starts[i]) << what << ": run start " << i;
  ASSERT_EQ(b.dones().size(), dones.size()) << what << ": seg_done count";
  for (size_t i = 0; i < dones.size(); ++i) {
    ASSERT_EQ(b.dones()[i].cycle, dones[i]) << what << ": seg_done of segment " << i;
    ASSERT_EQ(b.dones()[i].v2, done_v2[i]) << what << ": seg_done_v2 of segment " << i;
  }
  // STEP rises, DIR at each rise, DIR edges
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = b.mon().axis(a);
    const auto& want = model.rises(a);
    ASSERT_EQ(tr.rises.size(), want.size()) << what << ": axis " << a << " step count";
    for (size_t k = 0; k < want.size(); ++k)
      ASSERT_EQ(tr.rises[k], want[k]) << what << ": axis " << a << " rise " << k;
    const auto& wd = model.dir_edges(a);
    ASSERT_EQ(tr.dir_edges.size(), wd.size()) << what << ": axis " << a << " DIR edge count";
    for (size_t k = 0; k < wd.size(); ++k)
      ASSERT_EQ(tr.dir_edges[k], wd[k]) << what << ": axis " << a << " DIR edge " << k;
    for (auto& v : b.mon().check_pulses(a, timing[a])) ADD_FAILURE() << what << ": " << v;
    EXPECT_EQ(b.position(a), static_cast<int32_t>(pos[a])) << what << ": axis " << a;
    EXPECT_EQ(tr.position, pos[a]) << what << ": axis " << a;
  }
  // laser
  const auto& lz = model.laser();
  ASSERT_EQ(b.laser_rises().size(), lz.size()) << what << ": laser rises";
  ASSERT_EQ(b.laser_falls().size(), lz.size()) << what << ": laser falls";
  for (size_t k = 0; k < lz.size(); ++k) {
    ASSERT_EQ(b.laser_rises()[k], lz[k].first) << what << ": laser rise " << k;
    ASSERT_EQ(b.laser_falls()[k], lz[k].second) << what << ": laser fall " << k;
  }
  EXPECT_EQ(b.violations(), 0u) << what;
  // total time: sum of T plus the documented gaps only (HOLD/SETUP waits, zero-length entries)
  uint64_t gaps = 0, sum_t = 0;
  for (size_t i = 0; i < segs.size(); ++i) {
    if (i > 0) gaps += plan[i].accept - plan[i - 1].end;
    gaps += plan[i].R ? plan[i].R - plan[i].accept : plan[i].end - plan[i].accept;
    sum_t += segs[i].total();
  }
  ASSERT_EQ(b.dones().back().cycle - accepts[0], sum_t + gaps) << what << ": total time";
  st->idle_clocks += gaps;
}

Segment line(std::initializer_list<int64_t> steps, uint64_t t, int code = 1, int power = 255) {
  Segment s;
  s.v2 = true;
  s.t = static_cast<int64_t>(t);
  s.code = code;
  s.power = power;
  int a = 0;
  for (int64_t v : steps) s.steps[a++] = v;
  return s;
}

// DIR is low after reset: the queues start with negative moves so that only the reversals the
// tests intend happen.
TEST(SegmentExecutorQueue, SameDirectionZeroGapAndLaserStaysHigh) {
  const std::vector<AxisTiming> t(kAxes, AxisTiming{3, 2, 50, 70});
  // cutting, cutting, cutting (merged laser interval), rapid, power 0, cutting
  std::vector<Segment> q = {line({-10, -3}, 1000),     line({-7, -2}, 501),  line({-1}, 5),
                            line({-4, 0, -2}, 333, 0), line({-4}, 40, 2, 0), line({0, -5}, 64, 3)};
  QueueStats st;
  check_queue(t, q, &st, "same direction");
  EXPECT_EQ(st.zero_gap, 5u);
  EXPECT_EQ(st.idle_clocks, 0u);
  EXPECT_EQ(st.hold_reversals, 0u);
}

TEST(SegmentExecutorQueue, ReversalWithAndWithoutDirFast) {
  const std::vector<AxisTiming> t(kAxes, AxisTiming{2, 2, 30, 40});
  QueueStats st;
  // P = 100, 100, 70 >= hold 40 + setup 30: dir_fast, zero gap, DIR written during the run (hold
  // after the previous segment's last step, which is on the accept edge)
  check_queue(t, {line({-10}, 1000), line({10}, 1000), line({-10, -10}, 700), line({7, 7}, 490)},
              &st, "dir_fast reversals");
  EXPECT_EQ(st.fast_reversals, 3u);
  EXPECT_EQ(st.hold_reversals, 0u);
  EXPECT_EQ(st.idle_clocks, 0u);
  // P = 69 < 70: HOLD/SETUP gap
  QueueStats st2;
  check_queue(t, {line({-10}, 690), line({10}, 690)}, &st2, "slow reversal");
  EXPECT_EQ(st2.fast_reversals, 0u);
  EXPECT_EQ(st2.hold_reversals, 1u);
  EXPECT_EQ(st2.idle_clocks, 40u + 30u) << "hold after the last step on the accept edge, setup";
  // dir_fast forced low: the HOLD path even when fast would be allowed
  QueueStats st3;
  Segment back = line({10}, 1000);
  back.dir_fast = 0;
  check_queue(t, {line({-10}, 1000), back}, &st3, "dir_fast 0");
  EXPECT_EQ(st3.hold_reversals, 1u);
}

TEST(SegmentExecutorQueue, DwellsAndZeroLength) {
  const std::vector<AxisTiming> t(kAxes, AxisTiming{1, 1, 1, 1});
  Segment dwell = line({}, 37, 0, 0);
  Segment zero = line({}, 0);
  Segment lit = line({}, 12, 1, 77);  // a timed LINE with no steps: laser on, no steps
  Segment v1;
  v1.steps[0] = 5;
  v1.period = 3;
  QueueStats st;
  check_queue(t,
              {line({3}, 9), dwell, line({-3}, 9), zero, zero, line({2}, 4), lit, v1, zero, dwell},
              &st, "dwells and zero-length");
  EXPECT_EQ(st.zero_len, 3u);
  EXPECT_EQ(st.dwells, 3u);
}

// The main queued regression: random back-to-back streams with random settings.
TEST(SegmentExecutorQueue, RandomQueues) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261205, "SegmentExecutorQueue.RandomQueues");
  std::mt19937_64 rng(seed);
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  QueueStats st;
  int one_clock = 0;
  for (int batch = 0; batch < 150; ++batch) {
    std::vector<AxisTiming> t(kAxes);
    const int kind = static_cast<int>(uni(0, 9));
    for (auto& at : t) {
      if (kind < 3)
        at = AxisTiming{1, 1, 1, 1};
      else if (kind < 8)
        at = fpgacnc::tb::random_timing(uni, 12, 40);
      else
        at = AxisTiming{uint32_t(uni(1, 60)), uint32_t(uni(1, 60)), uint32_t(uni(0, 300)),
                        uint32_t(uni(0, 300))};
    }
    if (kind < 3) ++one_clock;
    const uint64_t pmin = fpgacnc::tb::min_period(t);
    uint64_t hs_max = 0;
    for (auto& at : t)
      hs_max =
          std::max(hs_max, fpgacnc::tb::at_least_1(at.hold) + fpgacnc::tb::at_least_1(at.setup));
    std::vector<Segment> q;
    const int len = static_cast<int>(uni(20, 60));
    for (int i = 0; i < len; ++i) {
      Segment s;
      s.code = static_cast<int>(uni(0, 3));
      s.power = uni(0, 5) == 0 ? 0 : static_cast<int>(uni(1, 255));
      const int what = static_cast<int>(uni(0, 19));
      if (what == 0) {  // zero-length
        s.v2 = uni(0, 1);
        s.t = 0;
      } else if (what == 1) {  // dwell
        s.v2 = true;
        s.code = 0;
        s.power = 0;
        s.t = static_cast<int64_t>(uni(1, 300));
      } else {
        // few axes, often reversing; small counts so runs stay short
        const int axes = static_cast<int>(uni(1, kAxes));
        for (int a = 0; a < axes; ++a) {
          const uint64_t n = uni(0, 4) == 0 ? 0 : uni(1, uni(0, 3) == 0 ? 400 : 20);
          s.steps[a] = uni(0, 1) ? static_cast<int64_t>(n) : -static_cast<int64_t>(n);
        }
        const uint64_t nd = s.n_dom();
        // P around hold + setup so that dir_fast goes both ways
        const uint64_t p = std::max(pmin, uni(0, 1) ? uni(pmin, pmin + 3) : uni(1, hs_max * 2));
        if (what < 8) {  // v1-style: T = P * n_dom
          s.period = p;
        } else {
          s.v2 = true;
          s.t = static_cast<int64_t>(nd * p + (nd ? uni(0, nd - 1) : uni(0, 50)));
        }
        if (uni(0, 15) == 0) s.dir_fast = 0;
      }
      q.push_back(s);
    }
    check_queue(t, q, &st, "batch " + std::to_string(batch) + " seed " + std::to_string(seed));
    if (HasFatalFailure()) return;
  }
  std::printf(
      "segments %llu: zero gap %llu, reversals dir_fast %llu / HOLD %llu, zero-length %llu, "
      "timed no-step %llu, run clocks %llu, idle clocks %llu\n",
      (unsigned long long)st.segments, (unsigned long long)st.zero_gap,
      (unsigned long long)st.fast_reversals, (unsigned long long)st.hold_reversals,
      (unsigned long long)st.zero_len, (unsigned long long)st.dwells,
      (unsigned long long)st.run_clocks, (unsigned long long)st.idle_clocks);
  EXPECT_GT(one_clock, 0);
  EXPECT_GT(st.fast_reversals, 50u);
  EXPECT_GT(st.hold_reversals, 50u);
  EXPECT_GT(st.zero_len, 20u);
  EXPECT_GT(st.dwells, 20u);
  EXPECT_GT(st.zero_gap, st.segments / 2);
}

// ---------------------------------------------------------------- segment_prep -> executor
// Both blocks connected as in cnc_core (prep's m_axis to the executor, exec_idle back), FIFO
// entries always valid at prep's input. Checks the end-to-end rule of docs/timing.md "Queued
// segments": the executor takes segment i on edge A_i = max(ready edge after segment i-1, P_i + L_i
// + 1), P_i = prep's accept edge = A_{i-1} + 1, L_i = PREP_LATENCY (68 v1, 67 + N_AXES v2); a
// segment taken on the previous one's end edge with no reversal (or with dir_fast) starts there
// (zero gap); prep's dir_fast equals the reference; pulse and DIR rules; positions.
class Chain {
 public:
  explicit Chain(const std::vector<AxisTiming>& t)
      : ctx_(std::make_unique<VerilatedContext>()), mon_(kAxes), timing_(t) {
    prep_ = std::make_unique<Vsegment_prep>(ctx_.get());
    ex_ = std::make_unique<Vsegment_executor>(ctx_.get());
    prep_->min_period = fpgacnc::tb::min_period(t);
    ex_->cfg_step_high = ex_->cfg_step_low = ex_->cfg_dir_setup = ex_->cfg_dir_hold = 0;
    for (int a = 0; a < kAxes; ++a) {
      ex_->cfg_step_high |= static_cast<uint64_t>(t[a].high) << (16 * a);
      ex_->cfg_step_low |= static_cast<uint64_t>(t[a].low) << (16 * a);
      ex_->cfg_dir_setup |= static_cast<uint64_t>(t[a].setup) << (16 * a);
      ex_->cfg_dir_hold |= static_cast<uint64_t>(t[a].hold) << (16 * a);
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
  ~Chain() {
    prep_->final();
    ex_->final();
  }

  struct Taken {
    uint64_t edge;
    bool fast;
    uint64_t total;
  };

  // Feeds the entries (always valid) and runs until everything is done.
  void run(const std::vector<fpgacnc::tb::Entry>& entries) {
    size_t next = 0;
    uint64_t quiet = 0;
    while (quiet < 3) {
      const bool offering = next < entries.size();
      if (offering) entries[next].pack(prep_->s_axis_tdata);
      prep_->s_axis_tvalid = offering;
      connect();
      prep_->eval();  // s_axis_tready depends on the entry's kind and exec_idle
      const bool prep_take = offering && prep_->s_axis_tready;
      const bool ex_take = ex_->s_axis_tvalid && ex_->s_axis_tready;
      const Taken tk{cycle_ + 1, prep_->m_axis_dir_fast != 0, prep_->m_axis_total};
      clock();
      if (prep_take) prep_accepts.push_back(cycle_), ++next;
      if (ex_take) ex_accepts.push_back(tk);
      if (!offering && !prep_->busy && !ex_->busy && ex_->idle)
        ++quiet;
      else
        quiet = 0;
      if (cycle_ > 500'000'000) throw std::runtime_error("chain does not finish");
    }
  }

  std::vector<uint64_t> prep_accepts, starts, dones, inits;
  std::vector<Taken> ex_accepts;
  uint64_t violations = 0;
  StepMonitor& mon() { return mon_; }
  Vsegment_executor& ex() { return *ex_; }

 private:
  void connect() {
    ex_->s_axis_code = prep_->m_axis_code;
    ex_->s_axis_power = prep_->m_axis_power;
    ex_->s_axis_v2 = prep_->m_axis_v2;
    ex_->s_axis_dir_fast = prep_->m_axis_dir_fast;
    ex_->s_axis_dir = prep_->m_axis_dir;
    for (int w = 0; w < kAxes; ++w) ex_->s_axis_steps[w] = prep_->m_axis_steps[w];
    for (int w = 0; w < 2 * kAxes; ++w) ex_->s_axis_tmn[w] = prep_->m_axis_tmn[w];
    ex_->s_axis_total = prep_->m_axis_total;
    ex_->s_axis_tvalid = prep_->m_axis_tvalid;
    prep_->m_axis_tready = ex_->s_axis_tready;
    prep_->exec_idle = ex_->idle;
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
    if (prep_->init_applied) {
      inits.push_back(cycle_);
      if (ex_->busy)
        ADD_FAILURE() << "NUMERATORS applied while the executor is busy, cycle " << cycle_;
    }
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_prep> prep_;
  std::unique_ptr<Vsegment_executor> ex_;
  StepMonitor mon_;
  std::vector<AxisTiming> timing_;
  uint64_t cycle_ = 0;
};

TEST(SegmentPrepExecutorChain, RandomStreamsZeroGapWhenPrepared) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261206, "SegmentPrepExecutorChain");
  std::mt19937_64 rng(seed);
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  using fpgacnc::tb::Entry;
  uint64_t zero_gap = 0, late = 0, segments = 0;
  for (int batch = 0; batch < 40; ++batch) {
    std::vector<AxisTiming> t(kAxes);
    for (auto& at : t)
      at = uni(0, 3) == 0 ? AxisTiming{1, 1, 1, 1} : fpgacnc::tb::random_timing(uni, 10, 40);
    const uint64_t pmin = fpgacnc::tb::min_period(t);
    Chain c(t);
    std::vector<Entry> entries;
    const int len = static_cast<int>(uni(30, 60));
    for (int i = 0; i < len; ++i) {
      const int what = static_cast<int>(uni(0, 29));
      if (what == 0) {
        entries.push_back(fpgacnc::tb::dwell(static_cast<uint32_t>(uni(0, 200))));
      } else if (what == 1) {
        entries.push_back(fpgacnc::tb::numerators(static_cast<uint32_t>(uni(100000, 40000000)),
                                                  static_cast<uint32_t>(uni(100000, 40000000)),
                                                  uni(0, 1)));
      } else if (what < 6) {
        // v1: both numerators and feed random; small counts
        entries.push_back(fpgacnc::tb::v1_motion(
            static_cast<int>(uni(0, 3)), static_cast<int32_t>(uni(0, 20)) - 10,
            static_cast<int32_t>(uni(0, 20)) - 10, static_cast<uint16_t>(uni(1000, 65535))));
      } else {
        Entry e;
        e.v2 = true;
        e.code = static_cast<int>(uni(0, 3));
        e.power = static_cast<int>(uni(0, 255));
        uint64_t n = 0;
        for (int a = 0; a < kAxes; ++a) {
          e.steps[a] = static_cast<int32_t>(uni(0, 3) == 0 ? 0 : uni(0, 16)) - 8;
          n = std::max<uint64_t>(n, mag(e.steps[a]));
        }
        // T from below the prep latency to several times it
        e.t = static_cast<uint32_t>(std::max<uint64_t>(n, 1) * uni(pmin, pmin + 60) + uni(0, 20));
        entries.push_back(e);
      }
    }
    c.run(entries);
    // replay: which entries reached the executor, their latencies and directions
    struct Seg {
      uint64_t T, latency;
      int64_t steps[kAxes];
      bool v2;
    };
    std::vector<Seg> segs;
    std::vector<bool> after_numerators;
    bool prev_num = false;
    for (const Entry& e : entries) {
      if (e.kind == fpgacnc::tb::kNumerators) {
        prev_num = true;
        continue;
      }
      Seg s{};
      s.v2 = e.v2;
      s.latency = e.v2 ? 67 + kAxes : 68;
      for (int a = 0; a < kAxes; ++a)
        s.steps[a] = (e.kind == fpgacnc::tb::kMotion && (e.v2 || a < 2)) ? e.steps[a] : 0;
      segs.push_back(s);
      after_numerators.push_back(prev_num);
      prev_num = false;
    }
    ASSERT_EQ(c.ex_accepts.size(), segs.size()) << "batch " << batch;
    int track[kAxes] = {0, 0, 0, 0};
    uint64_t ready = 0, R_prev = 0, T_prev = 0;
    size_t start_idx = 0;
    int64_t pos[kAxes] = {0, 0, 0, 0};
    for (size_t i = 0; i < segs.size(); ++i) {
      const auto& tk = c.ex_accepts[i];
      const uint64_t T = tk.total;
      // dir_fast reference
      uint64_t n = 0;
      for (int a = 0; a < kAxes; ++a) n = std::max<uint64_t>(n, mag(segs[i].steps[a]));
      bool fast = true, rev = false;
      for (int a = 0; a < kAxes; ++a) {
        if (segs[i].steps[a] == 0) continue;
        const int d = segs[i].steps[a] > 0;
        if (d != track[a]) {
          rev = true;
          if (T / n < fpgacnc::tb::at_least_1(t[a].hold) + fpgacnc::tb::at_least_1(t[a].setup))
            fast = false;
        }
        track[a] = d;
        pos[a] += segs[i].steps[a];
      }
      ASSERT_EQ(tk.fast, fast) << "batch " << batch << " segment " << i << " dir_fast";
      if (i > 0 && !after_numerators[i]) {
        // prep took the entry on the edge after the executor took the previous segment
        const uint64_t P = c.ex_accepts[i - 1].edge + 1;
        ASSERT_EQ(tk.edge, std::max(ready, P + segs[i].latency + 1))
            << "batch " << batch << " segment " << i << " accept edge (seed " << seed << ")";
      }
      if (T == 0) {
        ready = tk.edge + (tk.edge == ready && T_prev ? 2 : 1);
        T_prev = 0;
        continue;
      }
      ASSERT_LT(start_idx, c.starts.size());
      const uint64_t R = c.starts[start_idx++];
      if (T_prev && tk.edge == R_prev + T_prev && (!rev || fast)) {
        ASSERT_EQ(R, R_prev + T_prev) << "batch " << batch << " segment " << i << " zero gap";
        ++zero_gap;
      } else if (i > 0) {
        ++late;
      }
      if (!rev) {
        ASSERT_EQ(R, tk.edge) << "batch " << batch << " segment " << i;
      }
      R_prev = R;
      T_prev = T;
      ready = R + T;
      ++segments;
    }
    ASSERT_EQ(start_idx, c.starts.size());
    for (int a = 0; a < kAxes; ++a) {
      for (auto& v : c.mon().check_pulses(a, t[a])) ADD_FAILURE() << "batch " << batch << ": " << v;
      EXPECT_EQ(c.mon().axis(a).position, pos[a]) << "batch " << batch << " axis " << a;
    }
    EXPECT_EQ(c.violations, 0u) << "batch " << batch;
    if (HasFailure()) return;
  }
  std::printf("chain: segments %llu, zero gap %llu, not zero gap %llu\n",
              (unsigned long long)segments, (unsigned long long)zero_gap, (unsigned long long)late);
  EXPECT_GT(zero_gap, segments / 4);
  EXPECT_GT(late, segments / 10);
}

}  // namespace
