// Smoke test of the DE1-SoC top through its pins: reset button, a v1 init and a small G1 move on
// rx, STEP/DIR/laser on GPIO, the 0xAA on tx, LEDR busy/laser/dir, the HEX displays and the
// 1 Hz heartbeat (one toggle, checked at its exact cycle).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "Vde1soc_top.h"
#include "common/step_monitor.h"
#include "common/uart_bits.h"
#include "common/v1_packets.h"
#include "verilated.h"

namespace {

using fpgacnc::tb::init_packet;
using fpgacnc::tb::motion_packet;
using fpgacnc::tb::put32;

using fpgacnc::tb::AxisTiming;
using fpgacnc::tb::StepMonitor;
using fpgacnc::tb::UartDriver;
using fpgacnc::tb::UartMonitor;

constexpr double kClkHz = 50e6;
constexpr double kBaud = 115200;
constexpr uint64_t kHalfSecond = 25'000'000;  // CLK_HZ / 2

// Active-low segment patterns (bit 0 = a ... bit 6 = g).
constexpr uint8_t seg_n(uint8_t active_high) {
  return static_cast<uint8_t>(~active_high & 0x7F);
}
constexpr uint8_t kHexB = seg_n(0b1111100);
constexpr uint8_t kHex0 = seg_n(0b0111111);
constexpr uint8_t kHex1 = seg_n(0b0000110);
constexpr uint8_t kHex2 = seg_n(0b1011011);
constexpr uint8_t kHex7 = seg_n(0b0000111);

class BoardBench {
 public:
  BoardBench()
      : ctx_(std::make_unique<VerilatedContext>()),
        drv_(kClkHz, kBaud),
        umon_(kClkHz, kBaud),
        mon_(2) {
    m_ = std::make_unique<Vde1soc_top>(ctx_.get());
    m_->rx = 1;
    m_->rst_n = 1;
  }
  ~BoardBench() { m_->final(); }

  void tick() {
    m_->rx = static_cast<uint8_t>(drv_.tick());
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    mon_.sample(cycle_, m_->step_x | (m_->step_y << 1), m_->dir_x | (m_->dir_y << 1));
    if (auto b = umon_.sample(m_->tx, cycle_)) tx_.push_back(*b);
    const bool busy = m_->LEDR & 1u;
    if (busy) ++busy_cycles_;
    if (m_->laser) ++laser_cycles_;
    if (((m_->LEDR >> 1) & 1u) != m_->laser) ++bad_ledr_;
    if (((m_->LEDR >> 2) & 1u) != m_->dir_x || ((m_->LEDR >> 3) & 1u) != m_->dir_y) ++bad_ledr_;
    if (m_->laser && !busy) ++laser_not_busy_;
    if (m_->HEX4 != (busy ? kHexB : kHex0)) {
      if (bad_hex4_ == 0) first_bad_hex4_ = cycle_;
      ++bad_hex4_;
    }
    // Every STEP rising edge is requested while busy: busy was high in the clock before the edge
    // (the last STEP of a move rises on the same edge busy falls, after tick T, and stays high
    // its 100 clocks after that).
    const uint8_t steps = static_cast<uint8_t>(m_->step_x | (m_->step_y << 1));
    if ((steps & ~prev_steps_ & 3u) && !prev_busy_) ++step_not_busy_;
    prev_busy_ = busy;
    prev_steps_ = steps;
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) tick();
  }
  void send(const std::vector<uint8_t>& bytes) {
    for (uint8_t b : bytes) drv_.push(b);
    while (!drv_.idle()) tick();
  }

  Vde1soc_top& dut() { return *m_; }
  StepMonitor& mon() { return mon_; }
  uint64_t cycle() const { return cycle_; }
  const std::vector<UartMonitor::Byte>& tx() const { return tx_; }
  uint64_t busy_cycles() const { return busy_cycles_; }
  uint64_t laser_cycles() const { return laser_cycles_; }
  uint64_t bad_ledr() const { return bad_ledr_; }
  uint64_t bad_hex4() const { return bad_hex4_; }
  uint64_t first_bad_hex4() const { return first_bad_hex4_; }
  uint64_t laser_not_busy() const { return laser_not_busy_; }
  uint64_t step_not_busy() const { return step_not_busy_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vde1soc_top> m_;
  UartDriver drv_;
  UartMonitor umon_;
  StepMonitor mon_;
  uint64_t cycle_ = 0, busy_cycles_ = 0, laser_cycles_ = 0, bad_ledr_ = 0, bad_hex4_ = 0,
           first_bad_hex4_ = 0, laser_not_busy_ = 0, step_not_busy_ = 0;
  uint8_t prev_steps_ = 0;
  bool prev_busy_ = false;
  std::vector<UartMonitor::Byte> tx_;
};

TEST(De1SocTop, SmokeMoveLedsHexHeartbeat) {
  BoardBench b;
  b.dut().rst_n = 0;
  b.idle(10);
  b.dut().rst_n = 1;
  b.tick();
  const uint64_t release = b.cycle();  // first edge with rst_n high
  b.idle(20);
  EXPECT_EQ(b.dut().tx, 1);
  EXPECT_EQ(b.dut().LEDR & 1u, 0u) << "busy after reset";
  EXPECT_EQ(b.dut().HEX4, kHex0);

  // init 18 750 000 (worked example) and G1 (12, -5) at feed 6000: P = 3125, T = 37 500.
  b.send({0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30});
  std::vector<uint8_t> mv{0x01};
  put32(mv, 12);
  put32(mv, static_cast<uint32_t>(-5));
  mv.push_back(0x17);  // 6000 = 0x1770
  mv.push_back(0x70);
  b.send(mv);
  uint64_t guard = 0;
  while (b.tx().empty() && ++guard < 200'000) b.tick();
  ASSERT_EQ(b.tx().size(), 1u) << "no ACK by cycle " << b.cycle();
  EXPECT_EQ(b.tx()[0].value, 0xAA);
  EXPECT_TRUE(b.tx()[0].framing_ok);
  b.idle(10'000);
  ASSERT_EQ(b.tx().size(), 1u) << "more than one ACK";

  const auto& x = b.mon().axis(0);
  const auto& y = b.mon().axis(1);
  ASSERT_EQ(x.rises.size(), 12u);
  ASSERT_EQ(y.rises.size(), 5u);
  for (int d : x.rise_dir) EXPECT_EQ(d, 1);
  for (int d : y.rise_dir) EXPECT_EQ(d, 0);
  for (size_t i = 1; i < x.rises.size(); ++i) EXPECT_EQ(x.rises[i] - x.rises[i - 1], 3125u);
  for (int a = 0; a < 2; ++a)
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  EXPECT_GT(b.tx()[0].start_cycle, x.rises.back());
  EXPECT_EQ(b.laser_cycles(), 12u * 3125u) << "laser high for T clocks";
  EXPECT_GE(b.busy_cycles(), 12u * 3125u) << "LEDR[0] busy during the move";
  EXPECT_EQ(b.laser_not_busy(), 0u);
  EXPECT_EQ(b.step_not_busy(), 0u) << "STEP rose while LEDR[0] (busy) was low";
  EXPECT_EQ(b.bad_ledr(), 0u) << "LEDR[1..3] disagree with laser/dir_x/dir_y";
  EXPECT_EQ(b.bad_hex4(), 0u) << "HEX4 not 'b' while busy / '0' while idle, first at cycle "
                              << b.first_bad_hex4();
  EXPECT_EQ(b.dut().dir_x, 1);
  EXPECT_EQ(b.dut().dir_y, 0);
  EXPECT_EQ(b.dut().LEDR & 0x30Fu, 0x4u) << "idle: busy/laser off, dir_x high, no error LEDs";
  EXPECT_EQ(b.dut().HEX4, kHex0);
  EXPECT_EQ(b.dut().HEX5, kHex1) << "last motion code";
  EXPECT_EQ(b.dut().HEX3, kHex0) << "packet count high nibble";
  EXPECT_EQ(b.dut().HEX2, kHex2) << "packet count low nibble";
  EXPECT_EQ(b.dut().HEX1, kHex7) << "last feed 0x1770, bits 7:4";
  EXPECT_EQ(b.dut().HEX0, kHex0) << "last feed 0x1770, bits 3:0";

  // Heartbeat: the reset synchronizer releases rst one edge after the button; the counter then
  // counts CLK_HZ/2 clocks, so LEDR[7] is first seen high at release + 1 + CLK_HZ/2.
  const uint64_t toggle = release + 1 + kHalfSecond;
  ASSERT_LT(b.cycle(), toggle - 1);
  while (b.cycle() < toggle - 1) {
    b.tick();
    if (b.dut().LEDR & 0x80u) {
      ADD_FAILURE() << "heartbeat LEDR[7] rose at cycle " << b.cycle() << ", expected " << toggle;
      return;
    }
  }
  b.tick();
  EXPECT_EQ(b.dut().LEDR & 0x80u, 0x80u) << "heartbeat LEDR[7] not high at cycle " << toggle;
}

}  // namespace
