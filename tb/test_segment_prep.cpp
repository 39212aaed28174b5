// Bench for segment_prep: the command-FIFO entry in, prepared segments out.
// v1 timing semantics (period = NUMERATOR_dom / feed, feed 0 -> 62 500, raised to min_period),
// T = P * N, T - |steps| per axis, fixed latency, NUMERATORS only when idle; v2 LINE (T given,
// P = floor(T / n_dom), clamp to min_period with the `clamped` strobe), DWELL, kind 3, and the
// dir_fast flag against a C++ reference on random sequences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <stdexcept>

#include "Vsegment_prep.h"
#include "common/fifo_entry.h"
#include "common/seed.h"
#include "verilated.h"

namespace {

constexpr int kAxes = fpgacnc::tb::kEntryAxes;
constexpr uint64_t kLatencyV1 = 68;
constexpr uint64_t kLatencyV2 = 67 + kAxes;

using fpgacnc::tb::Entry;
using fpgacnc::tb::kDwell;
using fpgacnc::tb::kKind3;
using fpgacnc::tb::kMotion;
using fpgacnc::tb::kNumerators;
using fpgacnc::tb::numerators;
using fpgacnc::tb::v1_motion;
using fpgacnc::tb::v2_line;

uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

class PrepBench {
 public:
  PrepBench() : ctx_(std::make_unique<VerilatedContext>()) {
    m_ = std::make_unique<Vsegment_prep>(ctx_.get());
    m_->min_period = 200;
    m_->exec_idle = 1;
    set_dir_timing(200, 200);
    m_->rst = 1;
    tick();
    m_->rst = 0;
    tick();
  }
  void set_dir_timing(uint16_t setup, uint16_t hold) {
    for (int a = 0; a < kAxes; ++a) set_dir_timing(a, setup, hold);
  }
  void set_dir_timing(int a, uint16_t setup, uint16_t hold) {
    const uint64_t m = ~(0xFFFFull << (16 * a));
    m_->cfg_dir_setup = (m_->cfg_dir_setup & m) | (static_cast<uint64_t>(setup) << (16 * a));
    m_->cfg_dir_hold = (m_->cfg_dir_hold & m) | (static_cast<uint64_t>(hold) << (16 * a));
  }
  void tick() {
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    if (m_->clamped) ++clamped_;
    if (m_->init_applied) {
      ++inits_;
      last_init_v2_ = m_->init_v2 != 0;
    }
  }
  void drive(const Entry& e) { e.pack(m_->s_axis_tdata); }
  // Offers an entry until it is taken; returns the clocks from the accept edge to the first cycle
  // with m_axis_tvalid (0 for NUMERATORS).
  uint64_t send(const Entry& e) {
    drive(e);
    m_->s_axis_tvalid = 1;
    while (true) {
      m_->eval();
      const bool take = m_->s_axis_tready;
      tick();
      if (take) break;
      if (cycle_ > 10'000'000) throw std::runtime_error("never accepted");
    }
    m_->s_axis_tvalid = 0;
    const uint64_t accepted = cycle_;
    if (e.kind == kNumerators) return 0;
    while (!m_->m_axis_tvalid) {
      tick();
      if (cycle_ - accepted > 1000) throw std::runtime_error("never prepared");
    }
    return cycle_ - accepted;
  }
  void take() {
    m_->m_axis_tready = 1;
    tick();
    m_->m_axis_tready = 0;
  }
  Vsegment_prep& dut() { return *m_; }
  uint64_t cycle() const { return cycle_; }
  uint64_t clamped_strobes() const { return clamped_; }
  uint64_t init_strobes() const { return inits_; }
  bool last_init_v2() const { return last_init_v2_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_prep> m_;
  uint64_t cycle_ = 0, clamped_ = 0, inits_ = 0;
  bool last_init_v2_ = false;
};

uint64_t tmn(const Vsegment_prep& m, int a) {
  return (static_cast<uint64_t>(m.m_axis_tmn[2 * a + 1]) << 32) | m.m_axis_tmn[2 * a];
}

TEST(SegmentPrep, WorkedExampleDefaults) {
  PrepBench b;
  // G1 320, -160 at feed 1200 with the default numerator 18 750 000
  const uint64_t lat = b.send(v1_motion(1, 320, -160, 1200));
  auto& m = b.dut();
  EXPECT_EQ(lat, 68u) << "documented latency PREP_LATENCY";
  EXPECT_EQ(m.m_axis_period, 15625u);
  EXPECT_EQ(m.m_axis_total, 320ull * 15625ull);
  EXPECT_EQ(m.m_axis_dir & 3u, 1u);  // +X, -Y
  EXPECT_EQ(m.m_axis_steps[0], 320u);
  EXPECT_EQ(m.m_axis_steps[1], 160u);
  EXPECT_EQ(tmn(m, 1), 320ull * 15625ull - 160);
  EXPECT_EQ(m.m_axis_code, 1u);
  EXPECT_EQ(m.m_axis_power, 0xFFu);
  EXPECT_EQ(m.m_axis_v2, 0u);
  EXPECT_EQ(m.m_axis_feed, 1200u);
  b.take();
  // feed 0: period 62 500
  b.send(v1_motion(0, 0, 5, 0));
  EXPECT_EQ(m.m_axis_period, 62500u);
  EXPECT_EQ(m.m_axis_total, 5ull * 62500);
  b.take();
}

TEST(SegmentPrep, InitOnlyWhenIdle) {
  PrepBench b;
  auto& m = b.dut();
  m.exec_idle = 0;
  b.drive(numerators(1, 2));
  m.s_axis_tvalid = 1;
  for (int i = 0; i < 100; ++i) {
    m.eval();
    EXPECT_FALSE(m.s_axis_tready) << "init accepted while the executor is busy, cycle "
                                  << b.cycle();
    b.tick();
  }
  EXPECT_EQ(m.numerator_x, 18750000u);
  m.exec_idle = 1;
  b.send(numerators(1000000, 2000000));
  EXPECT_EQ(m.numerator_x, 1000000u);
  EXPECT_EQ(m.numerator_y, 2000000u);
  EXPECT_EQ(b.init_strobes(), 1u);
  EXPECT_FALSE(b.last_init_v2());
  // Y dominant uses NUMERATOR_Y
  b.send(v1_motion(1, 3, -7, 1000));
  EXPECT_EQ(m.m_axis_period, 2000u);
  b.take();
}

// NUMERATORS wait for a prepared segment to be taken and for the executor to be idle; the motion
// entries after them use the new values, the ones before the old values.
TEST(SegmentPrep, NumeratorsOrdering) {
  PrepBench b;
  auto& m = b.dut();
  b.send(v1_motion(1, 100, 0, 1000));  // prepared, waits on m_axis
  EXPECT_EQ(m.m_axis_period, 18750u);
  b.drive(numerators(3000000, 5000000, true));
  m.s_axis_tvalid = 1;
  for (int i = 0; i < 50; ++i) {
    m.eval();
    ASSERT_FALSE(m.s_axis_tready) << "NUMERATORS accepted while a segment waits, cycle "
                                  << b.cycle();
    b.tick();
  }
  // the executor takes it and runs: still not accepted
  m.exec_idle = 0;
  m.m_axis_tready = 1;
  b.tick();
  m.m_axis_tready = 0;
  for (int i = 0; i < 50; ++i) {
    m.eval();
    ASSERT_FALSE(m.s_axis_tready) << "NUMERATORS accepted while the executor runs, cycle "
                                  << b.cycle();
    b.tick();
  }
  EXPECT_EQ(b.init_strobes(), 0u);
  m.exec_idle = 1;
  m.eval();
  EXPECT_TRUE(m.s_axis_tready);
  b.tick();
  m.s_axis_tvalid = 0;
  EXPECT_EQ(m.init_applied, 1u) << "init_applied strobes on the clock after the accept edge";
  EXPECT_EQ(m.init_v2, 1u);
  b.tick();
  EXPECT_EQ(m.init_applied, 0u) << "init_applied is a 1-clock strobe";
  EXPECT_EQ(b.init_strobes(), 1u);
  EXPECT_TRUE(b.last_init_v2());
  EXPECT_EQ(m.numerator_x, 3000000u);
  EXPECT_EQ(m.numerator_y, 5000000u);
  b.send(v1_motion(1, 100, 0, 1000));
  EXPECT_EQ(m.m_axis_period, 3000u);
  b.take();
  b.send(v1_motion(1, 10, -100, 1000));
  EXPECT_EQ(m.m_axis_period, 5000u);
  b.take();
  // a v2 LINE does not use the numerators
  b.send(v2_line(1, 10, 100000, {10, -100}));
  EXPECT_EQ(m.m_axis_period, 1000u);
  b.take();
}

// v1 moves use steps[0] and steps[1] only.
TEST(SegmentPrep, V1IgnoresOtherAxes) {
  PrepBench b;
  auto& m = b.dut();
  Entry e = v1_motion(1, 10, 20, 1000);
  e.steps[2] = 1000;
  e.steps[3] = -5;
  b.send(e);
  EXPECT_EQ(m.m_axis_steps[2], 0u);
  EXPECT_EQ(m.m_axis_steps[3], 0u);
  EXPECT_EQ(m.m_axis_total, 20ull * 18750);
  EXPECT_EQ(tmn(m, 2), 20ull * 18750);
  b.take();
}

TEST(SegmentPrep, V2LineGivenT) {
  PrepBench b;
  auto& m = b.dut();
  // The protocol's LINE example: T = 5 000 000, X +320, Y -160 -> P = 15 625.
  const uint64_t lat = b.send(v2_line(1, 0x80, 5000000, {320, -160}));
  EXPECT_EQ(lat, kLatencyV2);
  EXPECT_EQ(m.m_axis_period, 15625u);
  EXPECT_EQ(m.m_axis_total, 5000000u);
  EXPECT_EQ(m.m_axis_steps[0], 320u);
  EXPECT_EQ(m.m_axis_steps[1], 160u);
  EXPECT_EQ(tmn(m, 0), 5000000u - 320);
  EXPECT_EQ(tmn(m, 1), 5000000u - 160);
  EXPECT_EQ(tmn(m, 2), 5000000u);
  EXPECT_EQ(m.m_axis_dir & 3u, 1u);
  EXPECT_EQ(m.m_axis_code, 1u);
  EXPECT_EQ(m.m_axis_power, 0x80u);
  EXPECT_EQ(m.m_axis_v2, 1u);
  EXPECT_EQ(m.m_axis_feed, 0u);
  EXPECT_EQ(b.clamped_strobes(), 0u);
  b.take();
  // T not a multiple of n_dom: P = floor, T kept; dominant axis Z
  m.min_period = 100;
  b.send(v2_line(2, 1, 1001, {0, 3, -7, 2}));
  EXPECT_EQ(m.m_axis_period, 143u);  // floor(1001 / 7)
  EXPECT_EQ(m.m_axis_total, 1001u);
  EXPECT_EQ(m.m_axis_steps[2], 7u);
  EXPECT_EQ(tmn(m, 3), 1001u - 2);
  EXPECT_EQ(b.clamped_strobes(), 0u);
  b.take();
  // the same with min_period 200: 143 < 200, T raised to 7 * 200
  m.min_period = 200;
  b.send(v2_line(2, 1, 1001, {0, 3, -7, 2}));
  EXPECT_EQ(m.m_axis_period, 200u);
  EXPECT_EQ(m.m_axis_total, 1400u);
  EXPECT_EQ(tmn(m, 3), 1398u);
  EXPECT_EQ(b.clamped_strobes(), 1u);
  b.take();
}

TEST(SegmentPrep, V2ClampRaisesT) {
  PrepBench b;
  auto& m = b.dut();
  m.min_period = 250;
  const uint64_t before = b.cycle();
  b.send(v2_line(1, 255, 1000, {-10, 4}));  // P = 100 < 250
  EXPECT_EQ(b.clamped_strobes(), 1u);
  EXPECT_EQ(m.m_axis_period, 250u);
  EXPECT_EQ(m.m_axis_total, 2500u);
  EXPECT_EQ(tmn(m, 0), 2490u);
  EXPECT_EQ(tmn(m, 1), 2496u);
  EXPECT_GT(b.cycle(), before);
  b.take();
  // exactly at the limit: not clamped
  b.send(v2_line(1, 255, 2500, {-10, 4}));
  EXPECT_EQ(b.clamped_strobes(), 1u);
  EXPECT_EQ(m.m_axis_total, 2500u);
  b.take();
  // one clock short: floor(2499/10) = 249 -> clamped to 2500
  b.send(v2_line(1, 255, 2499, {-10, 4}));
  EXPECT_EQ(b.clamped_strobes(), 2u);
  EXPECT_EQ(m.m_axis_total, 2500u);
  b.take();
  // T = 0 with steps: raised to n_dom * min_period; large counts exceed 32 bits
  m.min_period = 65535 * 2;
  b.send(v2_line(0, 0, 0, {0, 0, 0, INT32_MIN}));
  EXPECT_EQ(b.clamped_strobes(), 3u);
  EXPECT_EQ(m.m_axis_total, 2147483648ull * 131070ull);
  EXPECT_EQ(m.m_axis_steps[3], 2147483648u);
  EXPECT_EQ(m.m_axis_dir & 8u, 0u);
  b.take();
}

TEST(SegmentPrep, V2NoStepsDwellAndKind3) {
  PrepBench b;
  auto& m = b.dut();
  // LINE with no steps: T kept (a timed segment), P = 0, never clamped
  EXPECT_EQ(b.send(v2_line(1, 9, 777, {})), kLatencyV2);
  EXPECT_EQ(m.m_axis_total, 777u);
  EXPECT_EQ(m.m_axis_period, 0u);
  EXPECT_EQ(m.m_axis_code, 1u);
  EXPECT_EQ(m.m_axis_power, 9u);
  EXPECT_EQ(tmn(m, 0), 777u);
  b.take();
  // LINE with T = 0 and no steps: zero-length
  b.send(v2_line(1, 9, 0, {}));
  EXPECT_EQ(m.m_axis_total, 0u);
  b.take();
  // DWELL: T clocks, laser off, no steps
  Entry d;
  d.v2 = true;
  d.kind = kDwell;
  d.code = 3;
  d.power = 200;
  d.t = 50000000;
  EXPECT_EQ(b.send(d), kLatencyV2);
  EXPECT_EQ(m.m_axis_total, 50000000u);
  EXPECT_EQ(m.m_axis_code, 0u);
  EXPECT_EQ(m.m_axis_power, 0u);
  EXPECT_EQ(m.m_axis_v2, 1u);
  for (int a = 0; a < kAxes; ++a) EXPECT_EQ(m.m_axis_steps[a], 0u);
  b.take();
  // kind 3: a zero-length segment, whatever the fields
  Entry k3 = v2_line(1, 255, 1234, {5, 6, 7, 8});
  k3.kind = kKind3;
  EXPECT_EQ(b.send(k3), kLatencyV2);
  EXPECT_EQ(m.m_axis_total, 0u);
  EXPECT_EQ(m.m_axis_code, 0u);
  for (int a = 0; a < kAxes; ++a) EXPECT_EQ(m.m_axis_steps[a], 0u);
  b.take();
  EXPECT_EQ(b.clamped_strobes(), 0u);
}

TEST(SegmentPrep, RandomArithmetic) {
  const uint64_t seed = fpgacnc::tb::test_seed(7, "SegmentPrep.RandomArithmetic");
  std::mt19937_64 rng(seed);
  PrepBench b;
  auto& m = b.dut();
  for (int i = 0; i < 3000; ++i) {
    const uint32_t nx = (i % 4 == 0) ? 18750000u : static_cast<uint32_t>(rng());
    const uint32_t ny = (i % 5 == 0) ? 18750000u : static_cast<uint32_t>(rng());
    const uint32_t minp = 2 + static_cast<uint32_t>(rng() % 400);
    m.min_period = minp;
    b.send(numerators(nx, ny));
    int32_t sx = static_cast<int32_t>(rng());
    int32_t sy = static_cast<int32_t>(rng());
    if (i % 3 == 0) sx >>= (rng() % 31);
    if (i % 7 == 0) sy = 0;
    if (i == 1) sx = INT32_MIN;
    if (i == 2) sy = INT32_MAX;
    uint16_t feed = static_cast<uint16_t>(rng());
    if (i % 11 == 0) feed = 0;
    const int code = static_cast<int>(rng() % 4);
    const uint64_t lat = b.send(v1_motion(code, sx, sy, feed));
    ASSERT_EQ(lat, 68u);
    const uint64_t ax = mag(sx);
    const uint64_t ay = mag(sy);
    const bool xdom = ax >= ay;
    uint64_t p = feed == 0 ? 62500 : (xdom ? nx : ny) / feed;
    p = std::max<uint64_t>(p, minp);
    const uint64_t n = std::max(ax, ay);
    ASSERT_EQ(m.m_axis_period, p) << "i=" << i << " feed=" << feed;
    ASSERT_EQ(m.m_axis_total, p * n) << "i=" << i;
    ASSERT_EQ(m.m_axis_steps[0], ax);
    ASSERT_EQ(m.m_axis_steps[1], ay);
    ASSERT_EQ(m.m_axis_steps[2], 0u);
    ASSERT_EQ(tmn(m, 0), p * n - ax);
    ASSERT_EQ(tmn(m, 1), p * n - ay);
    ASSERT_EQ(tmn(m, 3), p * n);
    ASSERT_EQ(m.m_axis_dir & 3u, (sx >= 0 ? 1u : 0u) | (sy >= 0 ? 2u : 0u));
    ASSERT_EQ(m.m_axis_code, static_cast<uint32_t>(code));
    b.take();
  }
  EXPECT_EQ(b.clamped_strobes(), 0u) << "v1 moves never strobe clamped";
}

// Random v1/v2/dwell sequences: arithmetic, clamped strobe, and dir_fast against a reference that
// tracks each axis's direction over the prepared segments.
TEST(SegmentPrep, RandomV2AndDirFast) {
  const uint64_t seed = fpgacnc::tb::test_seed(11, "SegmentPrep.RandomV2AndDirFast");
  std::mt19937_64 rng(seed);
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  PrepBench b;
  auto& m = b.dut();
  int track[kAxes] = {0, 0, 0, 0};  // DIR level after reset: low
  uint64_t clamps = 0, fast = 0, slow = 0, entries = 0;
  uint16_t setup[kAxes] = {200, 200, 200, 200}, hold[kAxes] = {200, 200, 200, 200};
  for (int i = 0; i < 3000; ++i) {
    if (i % 100 == 0) {  // new DIR settings now and then (0 counts as 1)
      for (int a = 0; a < kAxes; ++a) {
        setup[a] = static_cast<uint16_t>(uni(0, 3) == 0 ? uni(0, 2) : uni(0, 65535) >> uni(0, 12));
        hold[a] = static_cast<uint16_t>(uni(0, 3) == 0 ? uni(0, 2) : uni(0, 65535) >> uni(0, 12));
        b.set_dir_timing(a, setup[a], hold[a]);
      }
    }
    const uint32_t minp = static_cast<uint32_t>(uni(0, 1) ? uni(2, 400) : uni(2, 131070));
    m.min_period = minp;
    const int what = static_cast<int>(uni(0, 9));
    Entry e;
    if (what < 7) {
      e.v2 = true;
      e.code = static_cast<int>(uni(0, 3));
      e.power = static_cast<int>(uni(0, 255));
      for (int a = 0; a < kAxes; ++a) {
        const uint64_t n =
            uni(0, 4) == 0 ? 0 : (uni(0, 1) ? uni(1, 20) : uni(1, 1u << 31) >> uni(0, 31));
        e.steps[a] = static_cast<int32_t>(
            uni(0, 1) ? -static_cast<int64_t>(n)
                      : static_cast<int64_t>(std::min<uint64_t>(n, INT32_MAX)));
      }
      const uint64_t nd = [&] {
        uint64_t n = 0;
        for (int32_t s : e.steps) n = std::max(n, mag(s));
        return n;
      }();
      // T around n_dom * (hold + setup) so dir_fast goes both ways; sometimes anything
      const uint64_t k = uni(0, 3) == 0 ? uni(0, 0xFFFFFFFFull) : nd * uni(1, 3000) + uni(0, nd);
      e.t = static_cast<uint32_t>(std::min<uint64_t>(k, 0xFFFFFFFFull));
    } else if (what < 9) {
      e = v1_motion(static_cast<int>(uni(0, 3)), static_cast<int32_t>(rng()) >> uni(0, 31),
                    static_cast<int32_t>(rng()) >> uni(0, 31), static_cast<uint16_t>(rng()));
    } else {
      e.v2 = true;
      e.kind = kDwell;
      e.t = static_cast<uint32_t>(rng()) >> uni(0, 31);
    }
    const uint64_t clamps_before = b.clamped_strobes();
    const uint64_t lat = b.send(e);
    ASSERT_EQ(lat, e.v2 ? kLatencyV2 : kLatencyV1) << "i=" << i;
    // reference
    uint64_t abs_s[kAxes] = {0, 0, 0, 0};
    int d[kAxes];
    uint64_t n = 0;
    for (int a = 0; a < kAxes; ++a) {
      const bool used = e.kind == kMotion && (e.v2 || a < 2);
      abs_s[a] = used ? mag(e.steps[a]) : 0;
      d[a] = e.steps[a] >= 0 ? 1 : 0;
      n = std::max(n, abs_s[a]);
    }
    uint64_t p = 0, T = 0;
    bool clamp = false;
    if (!e.v2) {
      const uint16_t feed = static_cast<uint16_t>(e.t);
      p = std::max<uint64_t>(feed == 0 ? 62500 : 18750000u / feed, minp);  // default numerators
      T = p * n;
    } else if (n == 0) {
      T = e.t;
    } else {
      p = e.t / n;
      T = e.t;
      if (p < minp) {
        clamp = true;
        p = minp;
        T = n * minp;
      }
    }
    bool fast_ref = true, rev_any = false;
    for (int a = 0; a < kAxes; ++a) {
      if (abs_s[a] == 0) continue;
      if (d[a] != track[a]) {
        rev_any = true;
        const uint64_t hs = std::max<uint16_t>(hold[a], 1) + std::max<uint16_t>(setup[a], 1);
        if (p < hs) fast_ref = false;
      }
      track[a] = d[a];
    }
    ASSERT_EQ(m.m_axis_period, p) << "i=" << i << " T=" << e.t << " n=" << n;
    ASSERT_EQ(m.m_axis_total, T) << "i=" << i << " T=" << e.t << " n=" << n << " minp=" << minp;
    ASSERT_EQ(b.clamped_strobes() - clamps_before, clamp ? 1u : 0u) << "i=" << i;
    for (int a = 0; a < kAxes; ++a) {
      ASSERT_EQ(m.m_axis_steps[a], abs_s[a]) << "i=" << i << " axis " << a;
      ASSERT_EQ(tmn(m, a), T - abs_s[a]) << "i=" << i << " axis " << a;
      if (abs_s[a] != 0) {
        ASSERT_EQ((m.m_axis_dir >> a) & 1u, static_cast<uint32_t>(d[a])) << "i=" << i;
      }
    }
    ASSERT_EQ(m.m_axis_dir_fast, fast_ref ? 1u : 0u)
        << "i=" << i << " P=" << p << " cycle " << b.cycle();
    ASSERT_EQ(m.m_axis_v2, e.v2 ? 1u : 0u);
    ASSERT_EQ(m.m_axis_code, static_cast<uint32_t>(e.kind == kMotion ? e.code : 0));
    ASSERT_EQ(m.m_axis_power, static_cast<uint32_t>(e.kind == kMotion ? e.power : 0));
    clamps += clamp;
    if (rev_any) (fast_ref ? fast : slow)++;
    ++entries;
    b.take();
  }
  std::printf("entries %llu, clamped %llu, reversals with dir_fast %llu, without %llu\n",
              static_cast<unsigned long long>(entries), static_cast<unsigned long long>(clamps),
              static_cast<unsigned long long>(fast), static_cast<unsigned long long>(slow));
  EXPECT_GT(clamps, 100u);
  EXPECT_GT(fast, 100u);
  EXPECT_GT(slow, 100u);
}

}  // namespace
