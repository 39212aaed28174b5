// System bench for cnc_core's lean build (N_AXES = 2, PROTO_V2 = 0: protocol v1 only, see the
// build options in rtl/cnc_core.v) through its pins: v1 bytes bit-banged onto rx at 115200 baud,
// the 0xAA ACKs decoded from tx, STEP/DIR recorded every clock. Checks a seeded v1 job with the
// host's handshake (exact STEP schedule R + ceil(k*T/n), DIR, laser, ACK after the move,
// positions), packets sent without waiting (run back to back, one ACK each), and that a v2 frame is
// not understood (no answer, cut by the 100 ms watchdog like any partial v1 packet).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "Vcnc_core_lean.h"
#include "common/core_pins.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"

namespace {

using fpgacnc::tb::AxisTiming;
using fpgacnc::tb::init_packet;
using fpgacnc::tb::motion_packet;

constexpr int kAxes = 2;
constexpr uint32_t kDefaultNumerator = 18'750'000;
constexpr uint64_t kFeed0Period = 62'500;
constexpr uint64_t kMinPeriod = 200;  // STEP high 100 + low 100 (reset values)
constexpr uint64_t kWatchdog = 5'000'000;
constexpr uint64_t kByteClocks = 4341;  // 10 bits at 115200 baud, rounded up

uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

uint64_t period_of(uint32_t num, uint16_t feed) {
  return std::max<uint64_t>(feed == 0 ? kFeed0Period : num / feed, kMinPeriod);
}

class LeanBench : public fpgacnc::tb::PinHarness<Vcnc_core_lean> {
 public:
  LeanBench() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_lean>()) {
    dut().estop = 0;
    dut().adc_sdo = 0;
    fpgacnc::tb::reset_core(*this);
  }
  // position is 64 bits (2 axes): axis a in bits [32a+31:32a]
  int32_t position(int a) {
    return static_cast<int32_t>(static_cast<uint32_t>(dut().position >> (32 * a)));
  }
  const std::vector<uint64_t>& starts() const { return starts_; }
  const std::vector<uint64_t>& dones() const { return dones_; }
  uint64_t laser_clocks() const { return laser_clocks_; }
  uint64_t laser_rises() const { return laser_rises_; }
  bool heater_seen() const { return heater_seen_; }

 protected:
  void observe() override {
    const Vcnc_core_lean& m = dut();
    if (m.seg_start) starts_.push_back(cycle());
    if (m.seg_done) dones_.push_back(cycle());
    if (m.laser) ++laser_clocks_;
    if (m.laser && !laser_prev_) ++laser_rises_;
    laser_prev_ = m.laser;
    if (m.heater || m.adc_convst || m.adc_sck) heater_seen_ = true;
  }

 private:
  std::vector<uint64_t> starts_, dones_;
  uint64_t laser_clocks_ = 0, laser_rises_ = 0;
  bool laser_prev_ = false, heater_seen_ = false;
};

struct Move {
  uint8_t code;
  int32_t sx, sy;
  uint16_t feed;
};

// Checks the STEP rises of one move that started at seg_start cycle `start`: count, DIR and the
// exact schedule start + ceil(k*T/n) per axis (T = P * n_dom).
void check_steps(LeanBench& b, const Move& mv, uint64_t start, uint64_t period,
                 const size_t rise0[2], int idx) {
  const int64_t steps[2] = {mv.sx, mv.sy};
  const uint64_t n_dom = std::max(mag(mv.sx), mag(mv.sy));
  const uint64_t T = period * n_dom;
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = b.mon().axis(a);
    const uint64_t n = mag(steps[a]);
    ASSERT_EQ(tr.rises.size() - rise0[a], n) << "move " << idx << " axis " << a << ": step count";
    for (uint64_t k = 1; k <= n; ++k) {
      const size_t i = rise0[a] + k - 1;
      ASSERT_EQ(tr.rises[i], start + (k * T + n - 1) / n)
          << "move " << idx << " axis " << a << " step " << k << "/" << n << " T=" << T
          << " R=" << start;
      ASSERT_EQ(tr.rise_dir[i], steps[a] > 0 ? 1 : 0) << "move " << idx << " axis " << a << " DIR";
    }
  }
}

TEST(CncCoreLean, V1JobWithHandshake) {
  const uint64_t seed = fpgacnc::tb::test_seed(20261122, "V1JobWithHandshake");
  std::mt19937_64 rng(seed);
  auto uni = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  LeanBench b;
  EXPECT_EQ(b.dut().numerator_x, kDefaultNumerator);
  // init with other numerators: applied while idle, no ACK
  const uint32_t num = 9'375'000;
  b.send(init_packet(num, num));
  b.idle(200);
  EXPECT_EQ(b.dut().numerator_x, num);
  EXPECT_EQ(b.dut().numerator_y, num);
  EXPECT_TRUE(b.tx_bytes().empty()) << "an init packet was acknowledged";

  std::vector<Move> job{{1, 32, -16, 600}};  // P = 15 625 (the worked example's period)
  for (int i = 0; i < 9; ++i) {
    Move mv{static_cast<uint8_t>(uni(0, 3)), static_cast<int32_t>(uni(-25, 25)),
            static_cast<int32_t>(uni(-25, 25)), static_cast<uint16_t>(uni(4000, 65535))};
    if (i == 4) mv.sx = mv.sy = 0;  // zero-step move: acknowledged at once
    if (i == 6) mv.feed = 65535;    // P = 143: raised to the minimum period 200
    job.push_back(mv);
  }
  int64_t net[2] = {0, 0};
  uint64_t lit = 0, lit_rises = 0;
  for (size_t i = 0; i < job.size(); ++i) {
    const Move& mv = job[i];
    const uint64_t p = period_of(num, mv.feed);
    const uint64_t n_dom = std::max(mag(mv.sx), mag(mv.sy));
    const size_t rise0[2] = {b.mon().axis(0).rises.size(), b.mon().axis(1).rises.size()};
    const size_t acks = b.tx_bytes().size(), starts = b.starts().size(), dones = b.dones().size();
    b.send(motion_packet(mv.code, mv.sx, mv.sy, mv.feed));
    ASSERT_TRUE(b.wait_bytes(acks, p * n_dom + 20 * kByteClocks + 100'000))
        << "no ACK for move " << i << " (seed " << seed << ") by cycle " << b.cycle();
    const auto& ack = b.tx_bytes()[acks];
    EXPECT_EQ(ack.value, 0xAA) << "move " << i;
    EXPECT_TRUE(ack.framing_ok) << "move " << i;
    ASSERT_EQ(b.dones().size(), dones + 1) << "move " << i << ": seg_done count";
    EXPECT_GT(ack.start_cycle, b.dones()[dones]) << "move " << i << ": ACK before seg_done";
    if (n_dom == 0) {
      EXPECT_EQ(b.starts().size(), starts) << "move " << i << ": a zero-step move ran";
    } else {
      ASSERT_EQ(b.starts().size(), starts + 1) << "move " << i << ": seg_start count";
      check_steps(b, mv, b.starts()[starts], p, rise0, static_cast<int>(i));
      if (HasFatalFailure()) {
        ADD_FAILURE() << "seed " << seed;
        return;
      }
      EXPECT_EQ(b.dut().last_period, p) << "move " << i << " feed " << mv.feed;
      if (mv.code != 0) {
        lit += p * n_dom;
        ++lit_rises;
      }
    }
    net[0] += mv.sx;
    net[1] += mv.sy;
    EXPECT_EQ(b.position(0), net[0]) << "move " << i;
    EXPECT_EQ(b.position(1), net[1]) << "move " << i;
  }
  b.idle(50'000);
  EXPECT_EQ(b.tx_bytes().size(), job.size()) << "ACK bytes: one per move";
  // laser high exactly T clocks per lit move (code != 0, power 0xFF in v1)
  EXPECT_EQ(b.laser_clocks(), lit);
  EXPECT_EQ(b.laser_rises(), lit_rises);
  for (int a = 0; a < kAxes; ++a) {
    EXPECT_EQ(b.mon().axis(a).position, net[a]) << "axis " << a << ": net steps from STEP edges";
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  }
  EXPECT_EQ(b.dut().violations, 0u);
  EXPECT_EQ(b.dut().packet_count, job.size() + 1);
  EXPECT_EQ(b.dut().faults, 0u);
  EXPECT_FALSE(b.heater_seen()) << "heater / ADC pins moved in a build without heaters";
  std::printf("lean v1 job: %zu moves, seed %llu, %llu clocks\n", job.size(),
              static_cast<unsigned long long>(seed), static_cast<unsigned long long>(b.cycle()));
}

// Three packets sent without waiting: decoder register, segment_prep and executor each hold one;
// the moves (same directions) run back to back with no idle clock, one ACK each.
TEST(CncCoreLean, PacketsSentAheadRunBackToBack) {
  LeanBench b;
  const Move mv[3] = {{1, 40, 10, 8000}, {0, 30, 30, 9000}, {2, 12, 40, 10000}};
  for (const Move& m : mv) b.queue(motion_packet(m.code, m.sx, m.sy, m.feed));
  ASSERT_TRUE(b.wait_bytes(2, 2'000'000)) << "three ACKs expected, got " << b.tx_bytes().size();
  ASSERT_EQ(b.starts().size(), 3u);
  for (int i = 0; i < 2; ++i) {
    const uint64_t p = period_of(kDefaultNumerator, mv[i].feed);
    const uint64_t T = p * std::max(mag(mv[i].sx), mag(mv[i].sy));
    EXPECT_EQ(b.starts()[i + 1] - b.starts()[i], T) << "gap between move " << i << " and " << i + 1;
  }
  b.idle(50'000);
  EXPECT_EQ(b.tx_bytes().size(), 3u);
  EXPECT_EQ(b.position(0), 82);
  EXPECT_EQ(b.position(1), 80);
  EXPECT_EQ(b.dut().overruns, 0u);
  EXPECT_EQ(b.dut().violations, 0u);
}

// A v2 HELLO frame is not understood by a v1-only build: it is a 6-byte partial v1 packet, dropped
// by the watchdog (timeouts), no answer, no motion; the v2 status stays 0; v1 works after it.
TEST(CncCoreLean, V2FrameIsNotUnderstood) {
  LeanBench b;
  b.send(fpgacnc::tb::v2::hello(0));
  EXPECT_TRUE(b.dut().rx_partial);
  b.idle(kWatchdog + 1000);
  EXPECT_FALSE(b.dut().rx_partial);
  EXPECT_TRUE(b.tx_bytes().empty()) << "the v1-only build answered a v2 frame";
  EXPECT_EQ(b.dut().timeouts, 1u);
  EXPECT_EQ(b.dut().v2_mode, 0u);
  EXPECT_EQ(b.dut().frames_ok, 0u);
  EXPECT_EQ(b.dut().unknown_types, 0u);
  EXPECT_EQ(b.dut().next_seq, 0u);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 0u);
  b.send(motion_packet(1, 5, -3, 12000));
  ASSERT_TRUE(b.wait_bytes(0, 200'000));
  EXPECT_EQ(b.tx_bytes()[0].value, 0xAA);
  EXPECT_EQ(b.position(0), 5);
  EXPECT_EQ(b.position(1), -3);
  EXPECT_EQ(b.dut().segments_done, 0u);
}

}  // namespace
