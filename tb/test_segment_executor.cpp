// Bench for segment_executor (with dda_linear and step_pulse): exact step counts, step times
// against the ideal k*T/n schedule, STEP/DIR pulse rules and jitter, over thousands of random
// seeded segments with random timing settings down to 1 clock.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "common/exec_harness.h"
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

// The main regression: >= 2000 random segments in batches with random timing settings.
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
  for (int batch = 0; batch < 100; ++batch) {
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
  EXPECT_GE(segments, 2000);
  EXPECT_GT(one_clock_batches, 0);
  std::printf("segments %d, clocks %llu, worst step error %.3f clocks, worst jitter %llu clocks\n",
              segments, static_cast<unsigned long long>(b.cycle()), c.worst_error,
              static_cast<unsigned long long>(c.worst_jitter));
  EXPECT_LT(c.worst_error, 1.0);
  EXPECT_LE(c.worst_jitter, 1u);
}

}  // namespace
