// Bench for segment_prep: v1 timing semantics (period = NUMERATOR_dom / feed, feed 0 -> 62 500,
// raised to min_period), T = P * N, T - |steps| per axis, fixed latency, init only when idle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>

#include "Vsegment_prep.h"
#include "common/seed.h"
#include "verilated.h"

namespace {

class PrepBench {
 public:
  PrepBench() : ctx_(std::make_unique<VerilatedContext>()) {
    m_ = std::make_unique<Vsegment_prep>(ctx_.get());
    m_->min_period = 200;
    m_->exec_idle = 1;
    m_->rst = 1;
    tick();
    m_->rst = 0;
    tick();
  }
  void tick() {
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
  }
  // Sends a command; returns the clocks from the accept edge to the first cycle with tvalid.
  uint64_t send(bool init, int code, uint32_t a, uint32_t b, uint16_t feed) {
    m_->s_axis_tuser = init;
    m_->s_axis_tdata[0] = feed | (b << 16);
    m_->s_axis_tdata[1] = (b >> 16) | (a << 16);
    m_->s_axis_tdata[2] = (a >> 16) | (static_cast<uint32_t>(code) << 16);
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
    if (init) return 0;
    while (!m_->m_axis_tvalid) tick();
    return cycle_ - accepted;
  }
  void take() {
    m_->m_axis_tready = 1;
    tick();
    m_->m_axis_tready = 0;
  }
  Vsegment_prep& dut() { return *m_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_prep> m_;
  uint64_t cycle_ = 0;
};

uint64_t tmn(const Vsegment_prep& m, int a) {
  return (static_cast<uint64_t>(m.m_axis_tmn[2 * a + 1]) << 32) | m.m_axis_tmn[2 * a];
}

TEST(SegmentPrep, WorkedExampleDefaults) {
  PrepBench b;
  // G1 320, -160 at feed 1200 with the default numerator 18 750 000
  const uint64_t lat = b.send(false, 1, 320, static_cast<uint32_t>(-160), 1200);
  auto& m = b.dut();
  EXPECT_EQ(lat, 68u) << "documented latency PREP_LATENCY";
  EXPECT_EQ(m.m_axis_period, 15625u);
  EXPECT_EQ(m.m_axis_total, 320ull * 15625ull);
  EXPECT_EQ(m.m_axis_dir & 3u, 1u);  // +X, -Y
  EXPECT_EQ(m.m_axis_steps[0], 320u);
  EXPECT_EQ(m.m_axis_steps[1], 160u);
  EXPECT_EQ(tmn(m, 1), 320ull * 15625ull - 160);
  EXPECT_EQ(m.m_axis_code, 1u);
  b.take();
  // feed 0: period 62 500
  b.send(false, 0, 0, 5, 0);
  EXPECT_EQ(m.m_axis_period, 62500u);
  EXPECT_EQ(m.m_axis_total, 5ull * 62500);
  b.take();
}

TEST(SegmentPrep, InitOnlyWhenIdle) {
  PrepBench b;
  auto& m = b.dut();
  m.exec_idle = 0;
  m.s_axis_tuser = 1;
  m.s_axis_tvalid = 1;
  for (int i = 0; i < 100; ++i) {
    m.eval();
    EXPECT_FALSE(m.s_axis_tready) << "init accepted while the executor is busy";
    b.tick();
  }
  EXPECT_EQ(m.numerator_x, 18750000u);
  m.exec_idle = 1;
  b.send(true, 3, 1000000, 2000000, 0);
  EXPECT_EQ(m.numerator_x, 1000000u);
  EXPECT_EQ(m.numerator_y, 2000000u);
  // Y dominant uses NUMERATOR_Y
  b.send(false, 1, 3, static_cast<uint32_t>(-7), 1000);
  EXPECT_EQ(m.m_axis_period, 2000u);
  b.take();
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
    b.send(true, 3, nx, ny, 0);
    int32_t sx = static_cast<int32_t>(rng());
    int32_t sy = static_cast<int32_t>(rng());
    if (i % 3 == 0) sx >>= (rng() % 31);
    if (i % 7 == 0) sy = 0;
    if (i == 1) sx = INT32_MIN;
    if (i == 2) sy = INT32_MAX;
    uint16_t feed = static_cast<uint16_t>(rng());
    if (i % 11 == 0) feed = 0;
    const int code = static_cast<int>(rng() % 4);
    const uint64_t lat =
        b.send(false, code, static_cast<uint32_t>(sx), static_cast<uint32_t>(sy), feed);
    ASSERT_EQ(lat, 68u);
    const uint64_t ax = static_cast<uint64_t>(sx < 0 ? -static_cast<int64_t>(sx) : sx);
    const uint64_t ay = static_cast<uint64_t>(sy < 0 ? -static_cast<int64_t>(sy) : sy);
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
}

}  // namespace
