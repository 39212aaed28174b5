// Bench for rtl/protocol/uart_rx.v and rtl/protocol/uart_tx.v (CLK_HZ 50 MHz at 115200, 1 000 000
// and 3 000 000 baud, one Verilated pair per rate).
//
// Each test owns a VerilatedContext, drives the clock itself and asserts on observed cycles.
// Cycle numbering: observation k happens just before rising edge k (inputs applied, outputs
// settled); after edge k the bench is in cycle k + 1, so a register loaded on edge k shows its
// new value in cycle k + 1. Transfers and strobes are reported with the edge number k.
//
// rx's input comes from tx's txd (round trip), from a UartDriver (rate-offset senders, framing
// errors, overrun) or from a level set by the test (glitches). tx's txd also feeds a UartMonitor
// and an edge recorder that checks every bit boundary against the exact rational schedule.
//
// Randomized tests print their seed; FPGACNC_SEED=<n> reproduces a run.
#include <gtest/gtest.h>

// Verilator 5.006's headers trip -Wextra (unused parameters); they are not project code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <verilated.h>

#include "Vuart_rx_1000000.h"
#include "Vuart_rx_115200.h"
#include "Vuart_rx_3000000.h"
#include "Vuart_tx_1000000.h"
#include "Vuart_tx_115200.h"
#include "Vuart_tx_3000000.h"
#pragma GCC diagnostic pop

#include <algorithm>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fpgacnc/models/uart_bits.h"

namespace {

using fpgacnc::models::UartDriver;
using fpgacnc::models::UartMonitor;

constexpr uint64_t kClkHz = 50'000'000;
constexpr uint64_t kDefaultSeed = 0x5eed'0ca7;

uint64_t test_seed() {
  uint64_t seed = kDefaultSeed;
  if (const char* env = std::getenv("FPGACNC_SEED"); env != nullptr && *env != '\0') {
    seed = std::strtoull(env, nullptr, 0);
  }
  std::printf("[ seed     ] FPGACNC_SEED=%" PRIu64 "\n", seed);
  ::testing::Test::RecordProperty("seed", std::to_string(seed));
  return seed;
}

std::string hex(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%02x", v);
  return buf;
}

enum class RxSource { kTx, kDriver, kLevel };

struct RxByte {
  uint8_t value;
  uint64_t cycle;  // edge of the m_axis transfer
};

template <class Rx, class Tx, uint64_t kBaud>
class UartBench {
 public:
  static constexpr uint64_t baud = kBaud;
  static constexpr double kClocksPerBit = static_cast<double>(kClkHz) / static_cast<double>(kBaud);

  UartBench()
      : ctx_(std::make_unique<VerilatedContext>()),
        rx_(std::make_unique<Rx>(ctx_.get(), "rx")),
        tx_(std::make_unique<Tx>(ctx_.get(), "tx")),
        driver_(kClkHz, kBaud),
        monitor_(kClkHz, kBaud) {
    rx_->rst = 1;
    tx_->rst = 1;
    for (int i = 0; i < 4; ++i) step();
    rx_->rst = 0;
    tx_->rst = 0;
    clear_records();
  }
  ~UartBench() {
    rx_->final();
    tx_->final();
  }

  // One clock: apply inputs, observe the settled cycle, rising edge.
  void step() {
    int line = 1;
    switch (source_) {
      case RxSource::kTx:
        line = tx_->txd;
        break;
      case RxSource::kDriver:
        line = driver_.tick();
        break;
      case RxSource::kLevel:
        line = level_;
        break;
    }
    rx_->rxd = static_cast<uint8_t>(line);
    rx_->m_axis_tready = rx_ready_ ? 1 : 0;
    tx_->s_axis_tvalid = tx_queue_.empty() ? 0 : 1;
    tx_->s_axis_tdata = tx_queue_.empty() ? 0 : tx_queue_.front();
    rx_->clk = 0;
    tx_->clk = 0;
    rx_->eval();
    tx_->eval();

    if (rx_->m_axis_tvalid && rx_->m_axis_tready) received_.push_back({rx_->m_axis_tdata, cycle_});
    if (rx_->frame_error) frame_errors_.push_back(cycle_);
    if (rx_->overrun_error) overruns_.push_back(cycle_);
    if (rx_->busy) rx_was_busy_ = true;
    if (tx_->s_axis_tvalid && tx_->s_axis_tready) {
      accepted_.push_back(cycle_);
      tx_queue_.pop_front();
    }
    const bool tx_busy_before = tx_->busy;

    rx_->clk = 1;
    tx_->clk = 1;
    rx_->eval();
    tx_->eval();
    ctx_->timeInc(1);
    ++cycle_;

    if (tx_->txd != last_txd_) {
      txd_edges_.push_back(cycle_);
      last_txd_ = tx_->txd;
    }
    if (tx_busy_before && !tx_->busy) tx_idle_cycles_.push_back(cycle_);
    if (auto b = monitor_.sample(tx_->txd, cycle_)) tx_line_bytes_.push_back(*b);
  }

  void run(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) step();
  }
  // Steps until pred() holds or max_cycles pass; returns whether pred() held.
  template <class Pred>
  bool run_until(Pred pred, uint64_t max_cycles) {
    for (uint64_t i = 0; i < max_cycles; ++i) {
      if (pred()) return true;
      step();
    }
    return pred();
  }
  uint64_t bits(double n) const { return static_cast<uint64_t>(n * kClocksPerBit + 0.5); }

  void clear_records() {
    received_.clear();
    frame_errors_.clear();
    overruns_.clear();
    accepted_.clear();
    txd_edges_.clear();
    tx_idle_cycles_.clear();
    tx_line_bytes_.clear();
    rx_was_busy_ = false;
  }

  Rx& rx() { return *rx_; }
  Tx& tx() { return *tx_; }
  UartDriver& driver() { return driver_; }
  uint64_t cycle() const { return cycle_; }

  RxSource source_ = RxSource::kTx;
  int level_ = 1;
  bool rx_ready_ = true;
  std::deque<uint8_t> tx_queue_;

  std::vector<RxByte> received_;
  std::vector<uint64_t> frame_errors_;
  std::vector<uint64_t> overruns_;
  std::vector<uint64_t> accepted_;
  std::vector<uint64_t> txd_edges_;       // first cycle of each new txd level
  std::vector<uint64_t> tx_idle_cycles_;  // first cycle with tx busy low after a frame
  std::vector<UartMonitor::Byte> tx_line_bytes_;
  bool rx_was_busy_ = false;

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Rx> rx_;
  std::unique_ptr<Tx> tx_;
  UartDriver driver_;
  UartMonitor monitor_;
  uint64_t cycle_ = 0;
  uint8_t last_txd_ = 1;
};

std::vector<uint8_t> all_bytes_then_random(std::mt19937_64& rng, size_t n_random) {
  std::vector<uint8_t> bytes;
  for (int v = 0; v < 256; ++v) bytes.push_back(static_cast<uint8_t>(v));
  std::uniform_int_distribution<int> dist(0, 255);
  for (size_t i = 0; i < n_random; ++i) bytes.push_back(static_cast<uint8_t>(dist(rng)));
  return bytes;
}

template <class B>
void expect_received(const B& b, const std::vector<uint8_t>& expected) {
  ASSERT_EQ(b.received_.size(), expected.size())
      << "expected " << expected.size() << " bytes, got " << b.received_.size()
      << " (last at cycle " << (b.received_.empty() ? 0 : b.received_.back().cycle) << ")";
  for (size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(b.received_[i].value, expected[i])
        << "byte " << i << ": expected " << hex(expected[i]) << " got " << hex(b.received_[i].value)
        << " at cycle " << b.received_[i].cycle;
  }
}

// Distance, in units of 1/BAUD clock, from d clocks to the nearest ideal boundary m * P.
int64_t boundary_error(uint64_t d, uint64_t baud, uint64_t* m_out) {
  const uint64_t m = (d * baud + kClkHz / 2) / kClkHz;
  *m_out = m;
  return static_cast<int64_t>(d * baud) - static_cast<int64_t>(m * kClkHz);
}

// tx -> rx round trip of all 256 values then a seeded random stream, sent back to back. Checks
// the bytes, the accept -> start-bit latency and every txd bit boundary against the exact
// schedule m * CLK_HZ / BAUD from the first start edge (error < 1 clock, no accumulation).
template <class B>
void round_trip(size_t n_random) {
  std::mt19937_64 rng(test_seed());
  const std::vector<uint8_t> bytes = all_bytes_then_random(rng, n_random);
  B b;
  b.source_ = RxSource::kTx;
  b.run(b.bits(2));
  b.tx_queue_.assign(bytes.begin(), bytes.end());
  const uint64_t budget = b.bits(10.0 * static_cast<double>(bytes.size()) + 4);
  ASSERT_TRUE(b.run_until([&] { return b.received_.size() == bytes.size(); }, budget))
      << "expected " << bytes.size() << " bytes within " << budget << " cycles, got "
      << b.received_.size() << " by cycle " << b.cycle();
  b.run(b.bits(2));
  expect_received(b, bytes);
  EXPECT_TRUE(b.frame_errors_.empty()) << "unexpected frame_error at cycle " << b.frame_errors_[0];
  EXPECT_TRUE(b.overruns_.empty()) << "unexpected overrun_error at cycle " << b.overruns_[0];

  // Accept -> start bit: txd low in the cycle right after the accepting edge (1 clock).
  ASSERT_EQ(b.accepted_.size(), bytes.size());
  ASSERT_FALSE(b.txd_edges_.empty());
  const uint64_t s0 = b.txd_edges_.front();
  EXPECT_EQ(s0, b.accepted_.front() + 1)
      << "expected start edge at cycle " << b.accepted_.front() + 1 << " got " << s0;

  // The line, decoded independently, carries the same bytes with good stop bits, each frame
  // starting at the ideal time 10 * j * P (within 1 clock) and accepted 1 clock before.
  ASSERT_EQ(b.tx_line_bytes_.size(), bytes.size());
  for (size_t j = 0; j < bytes.size(); ++j) {
    const auto& f = b.tx_line_bytes_[j];
    ASSERT_EQ(f.value, bytes[j]) << "txd frame " << j << ": expected " << hex(bytes[j]) << " got "
                                 << hex(f.value) << " at cycle " << f.start_cycle;
    ASSERT_TRUE(f.framing_ok) << "txd frame " << j << " stop bit low, start cycle "
                              << f.start_cycle;
    uint64_t m = 0;
    const int64_t err = boundary_error(f.start_cycle - s0, B::baud, &m);
    ASSERT_EQ(m, 10 * j) << "txd frame " << j << " starts at cycle " << f.start_cycle;
    ASSERT_LT(std::llabs(err), static_cast<int64_t>(B::baud))
        << "txd frame " << j << ": expected start at " << s0 << " + " << 10 * j << " * "
        << B::kClocksPerBit << " got cycle " << f.start_cycle;
    ASSERT_EQ(b.accepted_[j] + 1, f.start_cycle)
        << "frame " << j << ": accepted at edge " << b.accepted_[j] << ", start bit at cycle "
        << f.start_cycle;
  }
  // Every level change of txd lies within 1 clock of an ideal boundary s0 + m * P, so every bit
  // (between any two boundaries) is within 1 clock of its ideal length.
  for (uint64_t t : b.txd_edges_) {
    uint64_t m = 0;
    const int64_t err = boundary_error(t - s0, B::baud, &m);
    ASSERT_LT(std::llabs(err), static_cast<int64_t>(B::baud))
        << "txd edge at cycle " << t << ": expected within 1 clock of s0 + " << m << " * "
        << B::kClocksPerBit << " = " << static_cast<double>(s0) + m * B::kClocksPerBit;
  }
  // The last stop bit ends (busy falls) at s0 + 10 * N * P, within 1 clock.
  ASSERT_EQ(b.tx_idle_cycles_.size(), 1u) << "tx went idle inside a back-to-back stream";
  uint64_t m = 0;
  const int64_t err = boundary_error(b.tx_idle_cycles_.back() - s0, B::baud, &m);
  EXPECT_EQ(m, 10 * bytes.size());
  EXPECT_LT(std::llabs(err), static_cast<int64_t>(B::baud))
      << "expected the stream to end at " << static_cast<double>(s0) + m * B::kClocksPerBit
      << " got cycle " << b.tx_idle_cycles_.back();
}

// rx fed by a sender whose bit rate is off by `rate` (1.02 = 2% fast), frames back to back.
template <class B>
void rate_offset(double rate, size_t n_random) {
  std::mt19937_64 rng(test_seed());
  const std::vector<uint8_t> bytes = all_bytes_then_random(rng, n_random);
  B b;
  b.source_ = RxSource::kDriver;
  b.driver().set_rate(kClkHz, B::baud, rate);
  for (uint8_t v : bytes) b.driver().push(v);
  const uint64_t budget = b.bits(10.0 * static_cast<double>(bytes.size()) / rate + 4);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, budget));
  b.run(b.bits(2));
  expect_received(b, bytes);
  EXPECT_TRUE(b.frame_errors_.empty()) << "unexpected frame_error at cycle " << b.frame_errors_[0];
  EXPECT_TRUE(b.overruns_.empty()) << "unexpected overrun_error at cycle " << b.overruns_[0];
}

// A frame with a low stop bit is dropped with exactly one 1-clock frame_error strobe inside its
// stop bit; after the line idles the next good byte decodes.
template <class B>
void bad_stop_bit() {
  B b;
  b.source_ = RxSource::kDriver;
  b.run(b.bits(1));
  b.driver().push(0x55);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(12)));
  const uint64_t bad_start = b.cycle();  // the driver starts the next frame on this edge
  b.driver().push_bad_stop(0xa5);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(12)));
  b.run(b.bits(2));  // line idle: the receiver re-arms only after seeing it high
  b.driver().push(0x3c);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(12)));
  b.run(b.bits(2));

  expect_received(b, {0x55, 0x3c});
  ASSERT_EQ(b.frame_errors_.size(), 1u)
      << "expected one frame_error clock, got " << b.frame_errors_.size()
      << (b.frame_errors_.empty() ? std::string()
                                  : " (first at cycle " + std::to_string(b.frame_errors_[0]) + ")");
  const uint64_t lo = bad_start + b.bits(9.0);
  const uint64_t hi = bad_start + b.bits(10.0) + 4;
  EXPECT_GE(b.frame_errors_[0], lo)
      << "frame_error at cycle " << b.frame_errors_[0] << ", expected inside the stop bit [" << lo
      << ", " << hi << ")";
  EXPECT_LT(b.frame_errors_[0], hi)
      << "frame_error at cycle " << b.frame_errors_[0] << ", expected inside the stop bit [" << lo
      << ", " << hi << ")";
  EXPECT_TRUE(b.overruns_.empty()) << "unexpected overrun_error at cycle " << b.overruns_[0];
}

// Low pulses shorter than half a bit start no byte: no tvalid, no frame_error, rx idle again;
// then a real byte decodes.
template <class B>
void short_glitch() {
  B b;
  b.source_ = RxSource::kLevel;
  b.level_ = 1;
  b.run(b.bits(2));
  for (double width : {0.05, 0.25, 0.4}) {
    const uint64_t glitch_at = b.cycle();
    b.level_ = 0;
    b.run(std::max<uint64_t>(1, b.bits(width)));
    b.level_ = 1;
    b.run(b.bits(12));
    EXPECT_TRUE(b.received_.empty())
        << "glitch of " << width << " bit at cycle " << glitch_at << ": expected no byte, got "
        << hex(b.received_[0].value) << " at cycle " << b.received_[0].cycle;
    EXPECT_TRUE(b.frame_errors_.empty())
        << "glitch of " << width << " bit at cycle " << glitch_at
        << ": expected no frame_error, got one at cycle " << b.frame_errors_[0];
    EXPECT_FALSE(b.rx().m_axis_tvalid) << "tvalid high after glitch, cycle " << b.cycle();
    EXPECT_FALSE(b.rx().busy) << "rx still busy " << b.bits(12) << " clocks after glitch at cycle "
                              << glitch_at;
  }
  EXPECT_TRUE(b.rx_was_busy_) << "rx never checked a start bit (glitches not seen at all?)";
  b.source_ = RxSource::kDriver;
  b.driver().push(0xc3);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(12)));
  b.run(b.bits(2));
  expect_received(b, {0xc3});
  EXPECT_TRUE(b.frame_errors_.empty());
}

// Two bytes with tready low: the first is held (tvalid high, tdata stable), the second is
// dropped with one overrun_error strobe inside its stop bit; raising tready delivers the first,
// and later bytes decode normally.
template <class B>
void overrun() {
  B b;
  b.source_ = RxSource::kDriver;
  b.rx_ready_ = false;
  b.run(b.bits(1));
  const uint64_t first_start = b.cycle();
  b.driver().push(0x81);
  b.driver().push(0x7e);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(24)));
  b.run(b.bits(2));
  EXPECT_TRUE(b.received_.empty());
  ASSERT_TRUE(b.rx().m_axis_tvalid) << "expected tvalid held high at cycle " << b.cycle();
  EXPECT_EQ(b.rx().m_axis_tdata, 0x81)
      << "expected held byte 0x81, got " << hex(b.rx().m_axis_tdata) << " at cycle " << b.cycle();
  ASSERT_EQ(b.overruns_.size(), 1u)
      << "expected one overrun_error clock, got " << b.overruns_.size();
  const uint64_t lo = first_start + b.bits(19.0);
  const uint64_t hi = first_start + b.bits(20.0) + 4;
  EXPECT_GE(b.overruns_[0], lo) << "overrun_error at cycle " << b.overruns_[0]
                                << ", expected in the second stop bit [" << lo << ", " << hi << ")";
  EXPECT_LT(b.overruns_[0], hi) << "overrun_error at cycle " << b.overruns_[0]
                                << ", expected in the second stop bit [" << lo << ", " << hi << ")";
  EXPECT_TRUE(b.frame_errors_.empty());

  b.rx_ready_ = true;
  b.run(2);
  expect_received(b, {0x81});
  EXPECT_FALSE(b.rx().m_axis_tvalid) << "tvalid still high after the transfer, cycle " << b.cycle();
  b.driver().push(0x42);
  ASSERT_TRUE(b.run_until([&] { return b.driver().idle(); }, b.bits(12)));
  b.run(b.bits(2));
  expect_received(b, {0x81, 0x42});
  EXPECT_EQ(b.overruns_.size(), 1u);
}

using Bench115200 = UartBench<Vuart_rx_115200, Vuart_tx_115200, 115200>;
using Bench1M = UartBench<Vuart_rx_1000000, Vuart_tx_1000000, 1000000>;
using Bench3M = UartBench<Vuart_rx_3000000, Vuart_tx_3000000, 3000000>;

#define FPGACNC_UART_TESTS(SUITE, BENCH, N_RANDOM)       \
  TEST(SUITE, RoundTripAllBytesAndRandomStream) {        \
    round_trip<BENCH>(N_RANDOM);                         \
  }                                                      \
  TEST(SUITE, SenderTwoPercentFast) {                    \
    rate_offset<BENCH>(1.02, N_RANDOM);                  \
  }                                                      \
  TEST(SUITE, SenderTwoPercentSlow) {                    \
    rate_offset<BENCH>(0.98, N_RANDOM);                  \
  }                                                      \
  TEST(SUITE, BadStopBitDropsByteAndStrobesFrameError) { \
    bad_stop_bit<BENCH>();                               \
  }                                                      \
  TEST(SUITE, ShortLowGlitchStartsNoByte) {              \
    short_glitch<BENCH>();                               \
  }                                                      \
  TEST(SUITE, OverrunDropsSecondByteAndStrobes) {        \
    overrun<BENCH>();                                    \
  }

FPGACNC_UART_TESTS(UartRtl115200, Bench115200, 256)
FPGACNC_UART_TESTS(UartRtl1M, Bench1M, 1024)
FPGACNC_UART_TESTS(UartRtl3M, Bench3M, 1024)

}  // namespace
