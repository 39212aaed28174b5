// Bench for segment_fifo (WIDTH 40, DEPTH 16): random pushes and pops against a C++ queue, the
// full and empty edges, level/free, the write-to-output latency and one entry per clock.
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <random>

#include "Vsegment_fifo.h"
#include "common/seed.h"
#include "verilated.h"

namespace {

constexpr unsigned kDepth = 16;
constexpr uint64_t kMask = (uint64_t{1} << 40) - 1;

class FifoBench {
 public:
  FifoBench() : ctx_(std::make_unique<VerilatedContext>()) {
    m_ = std::make_unique<Vsegment_fifo>(ctx_.get());
    m_->s_axis_tvalid = 0;
    m_->m_axis_tready = 0;
    m_->rst = 1;
    step(false, 0, false);
    step(false, 0, false);
    m_->rst = 0;
    step(false, 0, false);
  }
  ~FifoBench() { m_->final(); }

  // One clock with the given inputs; checks the model before the edge and updates it at the edge.
  void step(bool push, uint64_t data, bool pop) {
    m_->s_axis_tvalid = push;
    m_->s_axis_tdata = data;
    m_->m_axis_tready = pop;
    m_->clk = 0;
    m_->eval();
    if (!m_->rst) check();
    const bool pushed = push && m_->s_axis_tready;
    const bool popped = pop && m_->m_axis_tvalid;
    if (popped) {
      const uint64_t got = m_->m_axis_tdata;
      EXPECT_FALSE(q_.empty()) << "pop from an empty model at cycle " << cycle_;
      if (!q_.empty()) {
        EXPECT_EQ(got, q_.front()) << "entry " << popped_ << " at cycle " << cycle_;
        q_.pop_front();
      }
      ++popped_;
    }
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    if (pushed) {
      q_.push_back(data);
      written_at_.push_back(cycle_);
    }
    if (popped) written_at_.pop_front();
  }

  void check() {
    ASSERT_EQ(m_->level, q_.size()) << "level at cycle " << cycle_;
    ASSERT_EQ(m_->free, kDepth - q_.size()) << "free at cycle " << cycle_;
    ASSERT_EQ(m_->s_axis_tready, q_.size() < kDepth) << "tready at cycle " << cycle_;
    // First word fall through: the head is valid from the edge after the one that wrote it.
    if (!q_.empty()) {
      const bool due = cycle_ >= written_at_.front() + 1;
      if (due) {
        ASSERT_TRUE(m_->m_axis_tvalid)
            << "head written at " << written_at_.front() << " not valid at cycle " << cycle_;
      }
    } else {
      ASSERT_FALSE(m_->m_axis_tvalid) << "valid while empty at cycle " << cycle_;
    }
  }

  Vsegment_fifo& dut() { return *m_; }
  size_t size() const { return q_.size(); }
  uint64_t popped() const { return popped_; }
  uint64_t cycle() const { return cycle_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vsegment_fifo> m_;
  std::deque<uint64_t> q_;
  std::deque<uint64_t> written_at_;
  uint64_t cycle_ = 0, popped_ = 0;
};

TEST(SegmentFifo, RandomPushPopAgainstQueue) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260510, "RandomPushPopAgainstQueue");
  std::mt19937_64 rng(seed);
  FifoBench b;
  uint64_t full_seen = 0, empty_seen = 0;
  for (int i = 0; i < 200'000; ++i) {
    // Phases biased towards filling or draining so that both ends are reached often.
    const int phase = (i / 500) % 3;
    const unsigned p_push = phase == 0 ? 80 : phase == 1 ? 20 : 50;
    const bool push = rng() % 100 < p_push;
    const bool pop = rng() % 100 < 100 - p_push;
    b.step(push, rng() & kMask, pop);
    if (HasFatalFailure()) {
      ADD_FAILURE() << "seed " << seed;
      return;
    }
    if (b.size() == kDepth) ++full_seen;
    if (b.size() == 0) ++empty_seen;
  }
  EXPECT_GT(full_seen, 1000u);
  EXPECT_GT(empty_seen, 1000u);
  EXPECT_GT(b.popped(), 50'000u);
}

TEST(SegmentFifo, FullEmptyLatencyAndThroughput) {
  FifoBench b;
  // Latency: written on edge W, valid from edge W + 1 (checked every clock by check()).
  b.step(true, 0x123, false);
  const uint64_t w = b.cycle();
  EXPECT_FALSE(b.dut().m_axis_tvalid) << "valid on the write edge";
  b.step(false, 0, false);
  EXPECT_TRUE(b.dut().m_axis_tvalid) << "not valid at edge " << w + 1;
  EXPECT_EQ(b.dut().m_axis_tdata, 0x123u);
  // Fill: exactly DEPTH entries are taken, more are refused.
  for (unsigned i = 1; i < kDepth + 5; ++i) b.step(true, i, false);
  EXPECT_EQ(b.size(), kDepth);
  EXPECT_EQ(b.dut().level, kDepth);
  EXPECT_EQ(b.dut().free, 0u);
  EXPECT_FALSE(b.dut().s_axis_tready);
  // Simultaneous push and pop while full: the pop frees a slot only after its edge.
  b.step(true, 999, true);
  EXPECT_EQ(b.size(), kDepth - 1);
  // Drain at one entry per clock while pushing at one per clock: level stays.
  for (int i = 0; i < 100; ++i) b.step(true, 1000 + i, true);
  EXPECT_EQ(b.size(), kDepth - 1);
  const uint64_t p0 = b.popped();
  for (unsigned i = 0; i < 40; ++i) b.step(false, 0, true);
  EXPECT_EQ(b.popped() - p0, kDepth - 1) << "not one entry per clock";
  EXPECT_EQ(b.size(), 0u);
  EXPECT_EQ(b.dut().level, 0u);
  EXPECT_EQ(b.dut().free, kDepth);
  // From empty, push and pop every clock: two entries held in the steady state.
  for (int i = 0; i < 50; ++i) b.step(true, 5000 + i, true);
  EXPECT_EQ(b.size(), 2u) << "one entry in the output register, one behind it";
}

}  // namespace
