// System bench for cnc_core through its pins: protocol v1 bytes bit-banged onto rx at 115200 baud
// (UartDriver), the ACK decoded from tx (UartMonitor), STEP/DIR recorded every clock
// (StepMonitor). Checks the worked example end to end, random move sequences with the v1 host's
// handshake, the laser rule, init deferral, runtime step timing and the packet watchdog.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "common/core_pins.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"

namespace {

using fpgacnc::tb::init_packet;
using fpgacnc::tb::motion_packet;

using fpgacnc::tb::AxisTiming;

constexpr int kAxes = fpgacnc::tb::kCoreAxes;
constexpr uint32_t kDefaultNumerator = 18'750'000;
constexpr uint64_t kFeed0Period = 62'500;
constexpr uint64_t kWatchdog = 5'000'000;
constexpr uint64_t kByteClocks = 4341;  // 10 bits at 115200 baud, rounded up

uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

// The protocol's period: NUMERATOR_dom / feed, FEED0_PERIOD for feed 0, raised to the minimum
// period max(STEP high + low) of the step timing in force.
uint64_t expected_period(uint32_t num_dom, uint16_t feed, uint64_t min_period) {
  const uint64_t p = feed == 0 ? kFeed0Period : num_dom / feed;
  return std::max(p, min_period);
}

struct Interval {
  uint64_t from, to;  // [from, to): first cycle seen high, first cycle seen low again
};

// cnc_core through its pins, recording seg_start/seg_done, laser intervals and numerator_x changes.
class CoreBench : public fpgacnc::tb::PinHarness<Vcnc_core> {
 public:
  CoreBench() : PinHarness(kAxes, fpgacnc::tb::kCorePins) {
    fpgacnc::tb::reset_core(*this);
    num_changes_.clear();  // the reset value is not a change
  }

  void cfg_write(int axis, int field, uint16_t value) {
    dut().cfg_wr = 1;
    dut().cfg_addr = static_cast<uint8_t>(axis * 4 + field);
    dut().cfg_wdata = value;
    tick();
    dut().cfg_wr = 0;
  }

  int32_t position(int a) { return static_cast<int32_t>(dut().position[a]); }

  struct NumChange {
    uint64_t cycle;
    uint32_t value;
    bool busy;
  };

  const std::vector<uint64_t>& starts() const { return starts_; }
  const std::vector<uint64_t>& dones() const { return dones_; }
  const std::vector<Interval>& laser() const { return laser_; }
  const std::vector<NumChange>& num_changes() const { return num_changes_; }

 protected:
  void observe() override {
    const Vcnc_core& m = dut();
    if (m.seg_start) starts_.push_back(cycle());
    if (m.seg_done) dones_.push_back(cycle());
    if (m.laser && !laser_prev_) laser_.push_back(Interval{cycle(), 0});
    if (!m.laser && laser_prev_) laser_.back().to = cycle();
    laser_prev_ = m.laser;
    if (m.numerator_x != prev_num_x_) {
      num_changes_.push_back(NumChange{cycle(), m.numerator_x, m.busy != 0});
      prev_num_x_ = m.numerator_x;
    }
  }

 private:
  bool laser_prev_ = false;
  uint32_t prev_num_x_ = 0;
  std::vector<uint64_t> starts_, dones_;
  std::vector<Interval> laser_;
  std::vector<NumChange> num_changes_;
};

struct Move {
  uint8_t code = 1;
  int32_t sx = 0, sy = 0;
  uint16_t feed = 0;
};

// Result of one move sent the v1 way (packet, then wait for the ACK).
struct MoveResult {
  bool acked = false;
  uint64_t ack_cycle = 0;              // falling start edge of the 0xAA
  uint64_t start = 0;                  // seg_start cycle R (0 when no run)
  uint64_t done = 0;                   // seg_done cycle
  size_t rise0[kAxes] = {0, 0, 0, 0};  // index of the move's first rise per axis
};

// Sends a move and waits for its ACK (limit: the move's length plus margin).
MoveResult run_move(CoreBench& b, const Move& mv, uint64_t period_hint) {
  MoveResult r;
  for (int a = 0; a < kAxes; ++a) r.rise0[a] = b.mon().axis(a).rises.size();
  const size_t acks = b.tx_bytes().size(), starts = b.starts().size(), dones = b.dones().size();
  b.send(motion_packet(mv.code, mv.sx, mv.sy, mv.feed));
  const uint64_t n = std::max(mag(mv.sx), mag(mv.sy));
  r.acked = b.wait_bytes(acks, period_hint * n + 20 * kByteClocks + 100'000);
  if (r.acked) r.ack_cycle = b.tx_bytes()[acks].start_cycle;
  if (b.starts().size() > starts) r.start = b.starts()[starts];
  if (b.dones().size() > dones) r.done = b.dones()[dones];
  EXPECT_LE(b.starts().size(), starts + 1) << "more than one seg_start for one move";
  EXPECT_LE(b.dones().size(), dones + 1) << "more than one seg_done for one move";
  return r;
}

// Checks a move's steps: count and DIR per axis, exact R + ceil(k*T/n) schedule, the ACK after
// the last STEP rise and after seg_done. Returns false on a fatal mismatch.
void check_move(CoreBench& b, const Move& mv, const MoveResult& r, uint64_t period) {
  const int64_t steps[2] = {mv.sx, mv.sy};
  const uint64_t n_dom = std::max(mag(mv.sx), mag(mv.sy));
  const uint64_t T = period * n_dom;
  ASSERT_TRUE(r.acked) << "no ACK for move code " << int(mv.code) << " (" << mv.sx << ", " << mv.sy
                       << ") feed " << mv.feed << " by cycle " << b.cycle();
  ASSERT_NE(r.done, 0u) << "no seg_done for the move";
  ASSERT_EQ(b.tx_bytes().back().value, 0xAA);
  ASSERT_TRUE(b.tx_bytes().back().framing_ok);
  EXPECT_GT(r.ack_cycle, r.done) << "ACK start bit at " << r.ack_cycle << " not after seg_done at "
                                 << r.done;
  if (n_dom == 0) {
    EXPECT_EQ(r.start, 0u) << "a zero-step move started a run";
  } else {
    ASSERT_NE(r.start, 0u) << "no seg_start";
  }
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = b.mon().axis(a);
    const uint64_t n = a < 2 ? mag(steps[a]) : 0;
    ASSERT_EQ(tr.rises.size() - r.rise0[a], n)
        << "axis " << a << ": step count, move at R=" << r.start << " (" << mv.sx << ", " << mv.sy
        << ")";
    for (uint64_t k = 1; k <= n; ++k) {
      const size_t i = r.rise0[a] + k - 1;
      const uint64_t expect = r.start + (k * T + n - 1) / n;
      ASSERT_EQ(tr.rises[i], expect) << "axis " << a << " step " << k << "/" << n << " T=" << T
                                     << " P=" << period << " R=" << r.start;
      ASSERT_EQ(tr.rise_dir[i], steps[a] > 0 ? 1 : 0) << "axis " << a << " DIR at step " << k;
      if (k == n) {
        EXPECT_GT(r.ack_cycle, tr.rises[i]) << "axis " << a << ": ACK at " << r.ack_cycle
                                            << " before the last STEP rise at " << tr.rises[i];
      }
    }
  }
}

// Protocol worked examples end to end: init then G1 (320, -160) at feed 1200.
TEST(CncCore, WorkedExampleEndToEnd) {
  CoreBench b;
  EXPECT_EQ(b.dut().numerator_x, kDefaultNumerator);
  b.send(init_packet(18'750'000, 18'750'000));
  b.idle(200);
  EXPECT_EQ(b.dut().numerator_x, 18'750'000u);
  EXPECT_EQ(b.dut().numerator_y, 18'750'000u);
  const Move mv{1, 320, -160, 1200};
  const MoveResult r = run_move(b, mv, 15625);
  check_move(b, mv, r, 15625);
  if (HasFatalFailure()) return;
  const auto& x = b.mon().axis(0);
  const auto& y = b.mon().axis(1);
  ASSERT_EQ(x.rises.size(), 320u);
  ASSERT_EQ(y.rises.size(), 160u);
  for (int d : x.rise_dir) ASSERT_EQ(d, 1);
  for (int d : y.rise_dir) ASSERT_EQ(d, 0);
  // Dominant period: every X interval is exactly 15 625 clocks.
  for (size_t i = 1; i < x.rises.size(); ++i)
    ASSERT_EQ(x.rises[i] - x.rises[i - 1], 15625u) << "X interval before step " << i + 1;
  for (size_t i = 1; i < y.rises.size(); ++i)
    ASSERT_EQ(y.rises[i] - y.rises[i - 1], 31250u) << "Y interval before step " << i + 1;
  EXPECT_EQ(b.dut().last_period, 15625u);
  for (int a = 0; a < 2; ++a)
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  // DIR setup before the first STEP of the move (X changes DIR, Y was low already).
  ASSERT_EQ(x.dir_edges.size(), 1u);
  EXPECT_GE(x.rises[0] - x.dir_edges[0], 200u);
  EXPECT_TRUE(y.dir_edges.empty());
  // ACK: exactly one 0xAA, after the last STEP rise and after seg_done.
  b.idle(200'000);
  ASSERT_EQ(b.tx_bytes().size(), 1u) << "expected exactly one ACK byte";
  EXPECT_EQ(b.tx_bytes()[0].value, 0xAA);
  EXPECT_GT(b.tx_bytes()[0].start_cycle, x.rises.back());
  EXPECT_GT(b.tx_bytes()[0].start_cycle, y.rises.back());
  ASSERT_EQ(b.dones().size(), 1u);
  EXPECT_GT(b.tx_bytes()[0].start_cycle, b.dones()[0]);
  EXPECT_EQ(b.position(0), 320);
  EXPECT_EQ(b.position(1), -160);
  // Laser: one interval, [R, R + T).
  ASSERT_EQ(b.laser().size(), 1u);
  EXPECT_EQ(b.laser()[0].from, r.start);
  EXPECT_EQ(b.laser()[0].to, r.start + 320u * 15625u);
  EXPECT_EQ(b.dut().violations, 0u);
  EXPECT_EQ(b.dut().packet_count, 2u);
}

// ~30 random seeded moves with the v1 handshake.
TEST(CncCore, RandomMovesHandshakeAndLaser) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260502, "RandomMovesHandshakeAndLaser");
  std::mt19937_64 rng(seed);
  auto uni = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  CoreBench b;
  int64_t net[2] = {0, 0};
  size_t lit = 0;
  const int kMoves = 30;
  for (int i = 0; i < kMoves; ++i) {
    Move mv;
    mv.code = static_cast<uint8_t>(uni(0, 3));
    if (i % 7 == 3) {
      mv.sx = mv.sy = 0;  // zero-step move
    } else {
      mv.sx = static_cast<int32_t>(uni(-40, 40));
      mv.sy = static_cast<int32_t>(uni(-40, 40));
      if (i % 5 == 0) mv.sx = -static_cast<int32_t>(net[0] % 41);  // reversal towards home
    }
    const uint64_t n = std::max(mag(mv.sx), mag(mv.sy));
    // Keep each move under ~100k clocks; feed 0 (62 500-clock period) only for 1-step moves.
    if (n <= 1 && uni(0, 1)) {
      mv.feed = 0;
    } else {
      mv.feed = static_cast<uint16_t>(uni(8000, 65535));
    }
    const uint64_t p = expected_period(kDefaultNumerator, mv.feed, 200);
    const size_t laser_before = b.laser().size();
    const MoveResult r = run_move(b, mv, p);
    check_move(b, mv, r, p);
    if (HasFatalFailure()) {
      ADD_FAILURE() << "move " << i << " seed " << seed;
      return;
    }
    if (n > 0) {
      EXPECT_EQ(b.dut().last_period, p) << "move " << i << " feed " << mv.feed;
    }
    // Laser: for code 1..3 with steps exactly [R, R + T); otherwise never.
    if (mv.code != 0 && n > 0) {
      ASSERT_EQ(b.laser().size(), laser_before + 1) << "move " << i << ": laser not lit";
      EXPECT_EQ(b.laser().back().from, r.start) << "move " << i << ": laser on";
      EXPECT_EQ(b.laser().back().to, r.start + p * n) << "move " << i << ": laser off";
      ++lit;
    } else {
      EXPECT_EQ(b.laser().size(), laser_before)
          << "move " << i << " code " << int(mv.code) << " n " << n << ": laser lit";
    }
    net[0] += mv.sx;
    net[1] += mv.sy;
    EXPECT_EQ(b.tx_bytes().size(), static_cast<size_t>(i + 1)) << "ACK count after move " << i;
    EXPECT_EQ(b.position(0), net[0]) << "move " << i;
    EXPECT_EQ(b.position(1), net[1]) << "move " << i;
  }
  b.idle(100'000);
  EXPECT_EQ(b.tx_bytes().size(), static_cast<size_t>(kMoves)) << "extra ACK bytes";
  for (auto& t : b.tx_bytes()) EXPECT_EQ(t.value, 0xAA);
  EXPECT_EQ(b.laser().size(), lit) << "laser lit outside the code 1..3 moves";
  EXPECT_FALSE(b.dut().laser);
  for (int a = 0; a < 2; ++a) {
    EXPECT_EQ(b.mon().axis(a).position, net[a]) << "axis " << a << " net steps from STEP edges";
    EXPECT_EQ(b.position(a), net[a]);
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  }
  EXPECT_EQ(b.mon().axis(2).rises.size(), 0u);
  EXPECT_EQ(b.mon().axis(3).rises.size(), 0u);
  EXPECT_EQ(b.dut().violations, 0u);
  std::printf("random moves: %d moves, %zu lit, %llu clocks\n", kMoves, lit,
              static_cast<unsigned long long>(b.cycle()));
}

TEST(CncCore, ZeroStepMoveIsAcknowledged) {
  CoreBench b;
  for (uint8_t code : {uint8_t{1}, uint8_t{0}}) {
    const Move mv{code, 0, 0, 1200};
    const size_t acks = b.tx_bytes().size();
    const MoveResult r = run_move(b, mv, 0);
    check_move(b, mv, r, 0);
    if (HasFatalFailure()) return;
    EXPECT_EQ(b.tx_bytes().size(), acks + 1);
    // Completes at once: ACK within a few hundred clocks of the last byte (prep + tx start).
    EXPECT_LT(r.ack_cycle - r.done, 10u);
  }
  EXPECT_TRUE(b.laser().empty());
  EXPECT_EQ(b.mon().axis(0).rises.size(), 0u);
}

// Init sent right behind a motion packet is applied only after the move.
TEST(CncCore, InitDeferredUntilMoveEnds) {
  CoreBench b;
  const Move mv{1, 40, -3, 1200};  // P = 15 625, T = 625 000
  b.queue(motion_packet(mv.code, mv.sx, mv.sy, mv.feed));
  b.queue(init_packet(9'375'000, 4'000'000));
  ASSERT_TRUE(b.wait_bytes(0, 40 * 15625 + 40 * kByteClocks)) << "no ACK";
  b.idle(1000);
  const auto& x = b.mon().axis(0);
  ASSERT_EQ(x.rises.size(), 40u);
  for (size_t i = 1; i < x.rises.size(); ++i)
    ASSERT_EQ(x.rises[i] - x.rises[i - 1], 15625u)
        << "X interval before step " << i + 1 << ": the running move changed period";
  ASSERT_EQ(b.dones().size(), 1u);
  // The init bytes were all received long before the move ended.
  ASSERT_LT(b.starts()[0] + 20 * kByteClocks, b.dones()[0]);
  ASSERT_EQ(b.num_changes().size(), 1u)
      << "numerator_x changed " << b.num_changes().size() << " times";
  const auto& c = b.num_changes()[0];
  EXPECT_EQ(c.value, 9'375'000u);
  EXPECT_EQ(b.dut().numerator_y, 4'000'000u);
  EXPECT_GT(c.cycle, x.rises.back())
      << "numerator_x changed at " << c.cycle << " before the move's last step";
  EXPECT_GE(c.cycle, b.dones()[0])
      << "numerator_x changed at " << c.cycle << " before seg_done at " << b.dones()[0];
  EXPECT_FALSE(c.busy) << "numerator_x changed at cycle " << c.cycle << " while busy was high";
  // The next move uses the new numerators: X dominant 9 375 000 / 1200 = 7812.
  const Move mv2{0, -20, 5, 1200};
  const MoveResult r2 = run_move(b, mv2, 7812);
  check_move(b, mv2, r2, 7812);
  EXPECT_EQ(b.dut().last_period, 7812u);
  // Y dominant: 4 000 000 / 1000 = 4000.
  const Move mv3{0, 2, -9, 1000};
  const MoveResult r3 = run_move(b, mv3, 4000);
  check_move(b, mv3, r3, 4000);
  EXPECT_EQ(b.dut().last_period, 4000u);
}

// Runtime STEP timing through the cfg port: 1-clock settings and the minimum period clamp.
TEST(CncCore, CfgPortOneClockTimingAndPeriodClamp) {
  CoreBench b;
  for (int a = 0; a < kAxes; ++a)
    for (int f = 0; f < 4; ++f) b.cfg_write(a, f, 1);
  b.idle(10);
  b.send(init_packet(100'000, 100'000));
  b.idle(200);
  const AxisTiming one{1, 1, 1, 1};
  struct Case {
    Move mv;
    uint64_t period;
  };
  const Case cases[] = {
      {{1, 50, -20, 65535}, 2},  // 100 000 / 65 535 = 1 -> clamped to 2
      {{1, 30, 30, 50000}, 2},   // 2 (not clamped)
      {{0, -17, 40, 20000}, 5},  // 5
      {{3, 25, 7, 1000}, 100},   // 100: STEP still 1 clock high
  };
  for (const auto& c : cases) {
    EXPECT_EQ(c.period, expected_period(100'000, c.mv.feed, 2));
    const uint64_t from = b.cycle();
    const MoveResult r = run_move(b, c.mv, c.period);
    check_move(b, c.mv, r, c.period);
    if (HasFatalFailure()) return;
    EXPECT_EQ(b.dut().last_period, c.period) << "feed " << c.mv.feed;
    const int dom = mag(c.mv.sx) >= mag(c.mv.sy) ? 0 : 1;
    const auto& tr = b.mon().axis(dom);
    for (size_t i = r.rise0[dom] + 1; i < tr.rises.size(); ++i)
      ASSERT_EQ(tr.rises[i] - tr.rises[i - 1], c.period) << "dominant interval, feed " << c.mv.feed;
    for (int a = 0; a < 2; ++a)
      for (auto& v : b.mon().check_pulses(a, one, from, b.cycle())) ADD_FAILURE() << v;
  }
  EXPECT_EQ(b.dut().violations, 0u);
}

// A packet cut off after 6 bytes, 100 ms of silence on the pins, then a valid move executes.
TEST(CncCore, CutPacketDroppedThenMoveRuns) {
  CoreBench b;
  const auto cut = motion_packet(1, 1000, 1000, 1);
  b.send(std::vector<uint8_t>(cut.begin(), cut.begin() + 6));
  b.idle(kWatchdog + kByteClocks);
  EXPECT_EQ(b.dut().timeouts, 1u);
  EXPECT_EQ(b.dut().packet_count, 0u);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 0u);
  const Move mv{1, 10, -10, 6000};
  const uint64_t p = expected_period(kDefaultNumerator, 6000, 200);
  const MoveResult r = run_move(b, mv, p);
  check_move(b, mv, r, p);
  EXPECT_EQ(b.position(0), 10);
  EXPECT_EQ(b.position(1), -10);
  EXPECT_EQ(b.tx_bytes().size(), 1u);
  EXPECT_EQ(b.dut().timeouts, 1u);
}

// Protocol v2 at the default 115 200 baud: HELLO -> IDENT, one LINE -> ACK then DONE, the steps.
TEST(CncCore, V2HelloAndLineAt115200) {
  namespace v2 = fpgacnc::tb::v2;
  CoreBench b;
  v2::DeviceParser parser;
  std::vector<v2::DeviceMsg> msgs;
  size_t seen = 0;
  auto pump = [&](size_t want, uint64_t limit) {
    for (uint64_t i = 0; i < limit && msgs.size() < want; ++i) {
      b.tick();
      for (; seen < b.tx_bytes().size(); ++seen)
        if (auto m = parser.push(b.tx_bytes()[seen].value, b.tx_bytes()[seen].start_cycle))
          msgs.push_back(*m);
    }
    return msgs.size() >= want;
  };
  b.send(v2::hello());
  ASSERT_TRUE(pump(1, 30 * kByteClocks)) << "no IDENT";
  ASSERT_EQ(msgs[0].type, v2::kIdent);
  ASSERT_TRUE(msgs[0].crc_ok);
  EXPECT_EQ(msgs[0].u32(8), 115'200u) << "BAUD";
  EXPECT_EQ(msgs[0].u8(1), 4u) << "N_AXES";
  // LINE seq 0: X +30, Y -10 over T = 60 000 clocks (P = 2000).
  b.send(v2::line(0, 1, 255, 60'000, {30, -10}, true));
  ASSERT_TRUE(pump(3, 60'000 + 40 * kByteClocks)) << "expected ACK and DONE";
  EXPECT_EQ(msgs[1].type, v2::kAck);
  EXPECT_EQ(msgs[1].u8(0), 1u) << "ACK next_seq";
  EXPECT_EQ(msgs[2].type, v2::kDone);
  EXPECT_EQ(msgs[2].u32(3), 1u) << "DONE segments done";
  EXPECT_GT(msgs[2].cycle, b.mon().axis(0).rises.back()) << "DONE before the last step";
  EXPECT_EQ(b.mon().axis(0).rises.size(), 30u);
  EXPECT_EQ(b.mon().axis(1).rises.size(), 10u);
  const auto& x = b.mon().axis(0);
  for (size_t i = 1; i < x.rises.size(); ++i) EXPECT_EQ(x.rises[i] - x.rises[i - 1], 2000u);
  EXPECT_EQ(b.position(0), 30);
  EXPECT_EQ(b.position(1), -10);
  EXPECT_EQ(b.dut().segments_done, 1u);
  EXPECT_EQ(b.dut().v2_mode, 1);
}

}  // namespace
