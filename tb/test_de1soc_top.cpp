// Smoke test of the DE1-SoC top through its pins: reset button, a v1 init and a small G1 move on
// rx, STEP/DIR/laser on GPIO, the 0xAA on tx, LEDR busy/laser/dir, the HEX displays and the
// 1 Hz heartbeat (one toggle, checked at its exact cycle).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "Vde1soc_top.h"
#include "common/pin_harness.h"
#include "common/step_monitor.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"

namespace {

using fpgacnc::tb::put32;

using fpgacnc::tb::AxisTiming;

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

// The board's pins: X and Y STEP/DIR on GPIO, reset button KEY active low.
constexpr fpgacnc::tb::PinAccess<Vde1soc_top> kBoardPins{
    [](Vde1soc_top& m, bool asserted) { m.rst_n = asserted ? 0 : 1; },
    [](const Vde1soc_top& m) { return static_cast<uint32_t>(m.step_x | (m.step_y << 1)); },
    [](const Vde1soc_top& m) { return static_cast<uint32_t>(m.dir_x | (m.dir_y << 1)); },
    [](Vde1soc_top& m) {  // e-stop, hold and cycle-start buttons, probe released (active low)
      m.estop_n = 1;
      m.hold_n = 1;
      m.start_n = 1;
      m.probe_n = 1;
    },
};

// The board through its pins, checking LEDR and HEX4 against busy/laser/DIR every clock.
class BoardBench : public fpgacnc::tb::PinHarness<Vde1soc_top> {
 public:
  BoardBench() : PinHarness(2, kBoardPins) {}

  uint64_t busy_cycles() const { return busy_cycles_; }
  uint64_t laser_cycles() const { return laser_cycles_; }
  uint64_t bad_ledr() const { return bad_ledr_; }
  uint64_t bad_hex4() const { return bad_hex4_; }
  uint64_t first_bad_hex4() const { return first_bad_hex4_; }
  uint64_t laser_not_busy() const { return laser_not_busy_; }
  uint64_t step_not_busy() const { return step_not_busy_; }

 protected:
  void observe() override {
    const Vde1soc_top& m = dut();
    const bool busy = m.LEDR & 1u;
    if (busy) ++busy_cycles_;
    if (m.laser) ++laser_cycles_;
    if (((m.LEDR >> 1) & 1u) != m.laser) ++bad_ledr_;
    if (((m.LEDR >> 2) & 1u) != m.dir_x || ((m.LEDR >> 3) & 1u) != m.dir_y) ++bad_ledr_;
    if (m.laser && !busy) ++laser_not_busy_;
    if (m.HEX4 != (busy ? kHexB : kHex0)) {
      if (bad_hex4_ == 0) first_bad_hex4_ = cycle();
      ++bad_hex4_;
    }
    // Every STEP rising edge is requested while busy: busy was high in the clock before the edge
    // (the last STEP of a move rises on the same edge busy falls, after tick T, and stays high
    // its 100 clocks after that).
    const uint8_t steps = static_cast<uint8_t>(m.step_x | (m.step_y << 1));
    if ((steps & ~prev_steps_ & 3u) && !prev_busy_) ++step_not_busy_;
    prev_busy_ = busy;
    prev_steps_ = steps;
  }

 private:
  uint64_t busy_cycles_ = 0, laser_cycles_ = 0, bad_ledr_ = 0, bad_hex4_ = 0, first_bad_hex4_ = 0,
           laser_not_busy_ = 0, step_not_busy_ = 0;
  uint8_t prev_steps_ = 0;
  bool prev_busy_ = false;
};

TEST(De1SocTop, SmokeMoveLedsHexHeartbeat) {
  BoardBench b;
  b.reset(10, 1);                      // the button held for 10 clocks
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
  while (b.tx_bytes().empty() && ++guard < 200'000) b.tick();
  ASSERT_EQ(b.tx_bytes().size(), 1u) << "no ACK by cycle " << b.cycle();
  EXPECT_EQ(b.tx_bytes()[0].value, 0xAA);
  EXPECT_TRUE(b.tx_bytes()[0].framing_ok);
  b.idle(10'000);
  ASSERT_EQ(b.tx_bytes().size(), 1u) << "more than one ACK";

  const auto& x = b.mon().axis(0);
  const auto& y = b.mon().axis(1);
  ASSERT_EQ(x.rises.size(), 12u);
  ASSERT_EQ(y.rises.size(), 5u);
  for (int d : x.rise_dir) EXPECT_EQ(d, 1);
  for (int d : y.rise_dir) EXPECT_EQ(d, 0);
  for (size_t i = 1; i < x.rises.size(); ++i) EXPECT_EQ(x.rises[i] - x.rises[i - 1], 3125u);
  for (int a = 0; a < 2; ++a)
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  EXPECT_GT(b.tx_bytes()[0].start_cycle, x.rises.back());
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

// v2 on the board: HELLO -> IDENT with N_AXES = 2, LEDR[4] shows v2 mode until RELEASE.
TEST(De1SocTop, V2HelloIdentAndModeLed) {
  namespace v2 = fpgacnc::tb::v2;
  BoardBench b;
  b.reset(10, 1);
  b.idle(20);
  EXPECT_EQ(b.dut().LEDR & 0x10u, 0u) << "v2 LED after reset";
  b.send(v2::hello());
  v2::DeviceParser parser;
  std::vector<v2::DeviceMsg> msgs;
  size_t seen = 0;
  for (uint64_t i = 0; i < 30 * 4341 && msgs.empty(); ++i) {
    b.tick();
    for (; seen < b.tx_bytes().size(); ++seen)
      if (auto m = parser.push(b.tx_bytes()[seen].value)) msgs.push_back(*m);
  }
  ASSERT_EQ(msgs.size(), 1u) << "no IDENT";
  EXPECT_EQ(msgs[0].type, v2::kIdent);
  EXPECT_TRUE(msgs[0].crc_ok);
  EXPECT_EQ(msgs[0].u8(1), 2u) << "N_AXES";
  EXPECT_EQ(msgs[0].u16(2), 64u) << "FIFO depth";
  EXPECT_EQ(b.dut().LEDR & 0x10u, 0x10u) << "LEDR[4] v2 mode";
  b.send(v2::release(0));
  b.idle(30 * 4341);
  EXPECT_EQ(b.dut().LEDR & 0x10u, 0u) << "LEDR[4] after RELEASE";
  EXPECT_EQ(b.dut().LEDR & 0x20u, 0u) << "no fault";
}

}  // namespace
