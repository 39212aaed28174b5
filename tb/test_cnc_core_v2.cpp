// System bench for cnc_core speaking protocol v2 through its pins, at 3 Mbaud (BAUD=3000000
// build of the same RTL): frames bit-banged onto rx (UartDriver), the device's frames decoded
// from tx (UartMonitor + DeviceParser), STEP/DIR recorded every clock (StepMonitor). HELLO ->
// IDENT, CONFIG_AXIS applied, a burst of LINE/DWELL frames running back to back with zero idle
// clocks (R' = R + T) and exact step schedules, ACK/DONE credits and counts, STATUS fields, a bad
// CRC answered by NAK with nothing moving, NUMERATORS, and v1 again after RELEASE; OUTPUT frames
// between LINE_PROFILE segments (the outputs change on the edge the segment before them ends, the
// next segment starts on that edge: no gap), the fan PWM, OUTPUT field checks, outputs off on
// e-stop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "Vcnc_core_heat.h"
#include "common/core_pins.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
using fpgacnc::tb::AxisTiming;

constexpr int kAxes = 4;
constexpr double kBaud3M = 3'000'000;
constexpr uint64_t kByteClocks = 167;  // 10 bits at 3 Mbaud

uint64_t mag(int64_t v) {
  return static_cast<uint64_t>(v < 0 ? -v : v);
}

struct Interval {
  uint64_t from, to;
};

class V2Bench : public fpgacnc::tb::PinHarness<Vcnc_core_heat> {
 public:
  V2Bench() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_heat>(), true, kBaud3M) {
    fpgacnc::tb::reset_core(*this);
  }

  // Sends bytes and runs until they are all on the line.
  void send_frame(const std::vector<uint8_t>& f) { send(f); }
  // Runs until `n` more device messages arrived (false after `limit` clocks).
  bool wait_msgs(size_t n, uint64_t limit) {
    const size_t want = msgs_.size() + n;
    for (uint64_t i = 0; i < limit && msgs_.size() < want; ++i) tick();
    return msgs_.size() >= want;
  }
  // Runs until no message arrived for `quiet` clocks and the rx line is idle.
  void settle(uint64_t quiet) {
    uint64_t q = 0;
    size_t n = msgs_.size();
    while (q < quiet || !rx_idle()) {
      tick();
      if (msgs_.size() != n) {
        n = msgs_.size();
        q = 0;
      } else {
        ++q;
      }
    }
  }
  // The last frame of a type, or nullptr.
  const v2::DeviceMsg* last(uint8_t type) const {
    for (auto it = msgs_.rbegin(); it != msgs_.rend(); ++it)
      if (!it->v1_ack && it->type == type) return &*it;
    return nullptr;
  }

  const std::vector<v2::DeviceMsg>& msgs() const { return msgs_; }
  const std::vector<uint64_t>& starts() const { return starts_; }
  const std::vector<uint64_t>& dones() const { return dones_; }
  const std::vector<Interval>& laser() const { return laser_; }
  uint64_t not_running_between() const { return gaps_; }
  // Output pin edges: 0 flood, 1 mist, 2 fan, 3..6 dout[0..3], with the cycle they were seen.
  struct OutEdge {
    uint64_t cycle;
    int pin;
    uint32_t value;
  };
  const std::vector<OutEdge>& out_edges() const { return out_edges_; }
  std::vector<OutEdge> out_edges_of(int pin) const {
    std::vector<OutEdge> v;
    for (const auto& e : out_edges_)
      if (e.pin == pin) v.push_back(e);
    return v;
  }

 protected:
  void observe() override {
    const Vcnc_core_heat& m = dut();
    if (tx_bytes().size() != tx_seen_) {
      const auto& b = tx_bytes().back();
      tx_seen_ = tx_bytes().size();
      EXPECT_TRUE(b.framing_ok) << "tx framing error at cycle " << b.start_cycle;
      if (auto msg = parser_.push(b.value, b.start_cycle)) msgs_.push_back(*msg);
    }
    if (m.seg_start) starts_.push_back(cycle());
    if (m.seg_done) dones_.push_back(cycle());
    const uint32_t outs = (m.coolant_flood ? 1u : 0u) | (m.coolant_mist ? 2u : 0u) |
                          (m.fan ? 4u : 0u) | (static_cast<uint32_t>(m.dout) << 3);
    for (int i = 0; i < 7; ++i)
      if (((outs ^ outs_prev_) >> i) & 1u)
        out_edges_.push_back(OutEdge{cycle(), i, (outs >> i) & 1u});
    outs_prev_ = outs;
    if (m.laser && !laser_prev_) laser_.push_back(Interval{cycle(), 0});
    if (!m.laser && laser_prev_) laser_.back().to = cycle();
    laser_prev_ = m.laser;
  }

 private:
  size_t tx_seen_ = 0;
  v2::DeviceParser parser_;
  std::vector<v2::DeviceMsg> msgs_;
  std::vector<uint64_t> starts_, dones_;
  std::vector<Interval> laser_;
  bool laser_prev_ = false;
  uint64_t gaps_ = 0;
  uint32_t outs_prev_ = 0;
  std::vector<OutEdge> out_edges_;
};

void hello(V2Bench& b) {
  b.send_frame(v2::hello());
  ASSERT_TRUE(b.wait_msgs(1, 20 * 30 * kByteClocks)) << "no answer to HELLO";
  const auto& id = b.msgs().back();
  ASSERT_FALSE(id.v1_ack);
  ASSERT_TRUE(id.crc_ok);
  ASSERT_EQ(id.type, v2::kIdent);
}

TEST(CncCoreV2, HelloIdent) {
  V2Bench b;
  EXPECT_EQ(b.dut().v2_mode, 0);
  hello(b);
  if (HasFatalFailure()) return;
  const auto& id = b.msgs().back();
  ASSERT_EQ(id.payload.size(), 18u);
  EXPECT_EQ(id.seq, 0u) << "first device frame";
  EXPECT_EQ(id.u8(0), 2u) << "version";
  EXPECT_EQ(id.u8(1), 4u) << "N_AXES";
  EXPECT_EQ(id.u16(2), 64u) << "FIFO depth";
  EXPECT_EQ(id.u32(4), 50'000'000u) << "CLK_HZ";
  EXPECT_EQ(id.u32(8), 3'000'000u) << "BAUD";
  EXPECT_EQ(id.u32(12), fpgacnc::spec::kBuildId) << "BUILD_ID";
  EXPECT_EQ(id.u8(16), 0u) << "next_seq";
  EXPECT_EQ(id.u8(17), 64u) << "MAX_PAYLOAD";
  EXPECT_EQ(b.dut().v2_mode, 1);
  EXPECT_EQ(b.dut().frames_ok, 1u);
}

// CONFIG_AXIS sets an axis's STEP/DIR timing (applied while the machine is quiet).
TEST(CncCoreV2, ConfigAxisApplied) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  b.send_frame(v2::config_axis(0, 1, 5, 7, 11, 13));
  ASSERT_TRUE(b.wait_msgs(1, 40 * kByteClocks));
  const auto& ack = b.msgs().back();
  ASSERT_EQ(ack.type, v2::kAck);
  EXPECT_EQ(ack.u8(0), 1u) << "next_seq after CONFIG_AXIS";
  EXPECT_EQ(ack.u16(1), 64u) << "free slots";
  // Axis 1 reverses (5 steps back, then 5 forward): its DIR setup/hold are 11/13 now.
  b.send_frame(v2::line(1, 1, 255, 2000, {4, -5}, true));
  b.send_frame(v2::line(2, 1, 255, 2000, {-4, 5}, true));
  b.settle(20'000);
  EXPECT_EQ(b.dut().segments_done, 2u);
  const AxisTiming t1{5, 7, 11, 13};
  for (auto& v : b.mon().check_pulses(1, t1)) ADD_FAILURE() << v;
  for (auto& v : b.mon().check_pulses(0, AxisTiming{})) ADD_FAILURE() << v;
  const auto& y = b.mon().axis(1);
  ASSERT_EQ(y.rises.size(), 10u);
  ASSERT_EQ(y.falls.size(), 10u);
  for (size_t i = 0; i < y.rises.size(); ++i)
    EXPECT_EQ(y.falls[i] - y.rises[i], 5u) << "axis 1 STEP high, step " << i;
  EXPECT_EQ(b.mon().axis(0).falls[0] - b.mon().axis(0).rises[0], 100u) << "axis 0 unchanged";
  EXPECT_EQ(b.dut().violations, 0u);
}

struct Seg {
  bool dwell = false;
  uint8_t code = 1, power = 255;
  uint32_t t = 0;
  std::vector<int32_t> steps;
};

// A burst of LINE (and DWELL) frames sent back to back: every segment starts on the edge the
// previous one ends (R' = R + T, zero idle clocks), every step at R + ceil(k*T/n), the laser
// exactly over the lit segments, ACK/DONE credits and counts, then STATUS.
TEST(CncCoreV2, BurstZeroGapExactSchedule) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260520, "BurstZeroGapExactSchedule");
  std::mt19937_64 rng(seed);
  auto uni = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  const int kSegs = 48;
  std::vector<Seg> segs;
  std::vector<uint8_t> bytes;
  int64_t net[kAxes] = {0, 0, 0, 0};
  for (int i = 0; i < kSegs; ++i) {
    Seg s;
    // T long enough for the next frame (<= 28 bytes) to arrive and be prepared; P = T / n_dom
    // >= 500 >= DIR hold + setup, so reversals are dir_fast (zero gap) and nothing is clamped.
    s.t = static_cast<uint32_t>(uni(5000, 12000));
    if (i % 11 == 5) {
      s.dwell = true;
      s.code = 0;
      s.power = 0;
      bytes = v2::dwell(static_cast<uint8_t>(i), s.t);
    } else {
      s.code = static_cast<uint8_t>(uni(0, 3));
      s.power = static_cast<uint8_t>(uni(0, 3) == 0 ? 0 : uni(1, 255));
      const int k = static_cast<int>(uni(0, kAxes));
      for (int a = 0; a < k; ++a) s.steps.push_back(static_cast<int32_t>(uni(-10, 10)));
      const bool short_form = uni(0, 1) == 1;
      bytes = v2::line(static_cast<uint8_t>(i), s.code, s.power, s.t, s.steps, short_form);
    }
    for (size_t a = 0; a < s.steps.size(); ++a) net[a] += s.steps[a];
    segs.push_back(s);
    b.queue(bytes);
  }
  // Run until every segment is done and reported.
  uint64_t guard = 0;
  while ((b.dut().segments_done < kSegs || !b.rx_idle()) && ++guard < 2'000'000) b.tick();
  ASSERT_EQ(b.dut().segments_done, static_cast<uint32_t>(kSegs)) << "by cycle " << b.cycle();
  b.settle(10 * 20 * kByteClocks);

  // Zero gap: seg_start of segment i+1 exactly T_i after seg_start of segment i.
  ASSERT_EQ(b.starts().size(), static_cast<size_t>(kSegs));
  for (int i = 0; i + 1 < kSegs; ++i)
    ASSERT_EQ(b.starts()[i + 1] - b.starts()[i], segs[i].t)
        << "segment " << i + 1 << " start: idle clocks between segments " << i << " and " << i + 1
        << " (R=" << b.starts()[i] << ") seed " << seed;
  // Exact step schedule per axis, DIR at every step.
  for (int a = 0; a < kAxes; ++a) {
    std::vector<uint64_t> want;
    std::vector<int> want_dir;
    for (int i = 0; i < kSegs; ++i) {
      const auto& s = segs[i];
      if (static_cast<size_t>(a) >= s.steps.size()) continue;
      const uint64_t n = mag(s.steps[a]);
      for (uint64_t k = 1; k <= n; ++k) {
        want.push_back(b.starts()[i] + (k * s.t + n - 1) / n);
        want_dir.push_back(s.steps[a] > 0 ? 1 : 0);
      }
    }
    const auto& tr = b.mon().axis(a);
    ASSERT_EQ(tr.rises.size(), want.size()) << "axis " << a << " step count, seed " << seed;
    for (size_t j = 0; j < want.size(); ++j) {
      ASSERT_EQ(tr.rises[j], want[j]) << "axis " << a << " step " << j << " seed " << seed;
      ASSERT_EQ(tr.rise_dir[j], want_dir[j]) << "axis " << a << " DIR at step " << j;
    }
    EXPECT_EQ(static_cast<int32_t>(b.dut().position[a]), net[a]) << "axis " << a;
    for (auto& v : b.mon().check_pulses(a, AxisTiming{})) ADD_FAILURE() << v;
  }
  // Laser: high exactly over the segments with code != 0 and power != 0 (merged when adjacent).
  std::vector<Interval> lit;
  for (int i = 0; i < kSegs; ++i) {
    const auto& s = segs[i];
    if (s.dwell || s.code == 0 || s.power == 0) continue;
    const uint64_t from = b.starts()[i], to = b.starts()[i] + s.t;
    if (!lit.empty() && lit.back().to == from)
      lit.back().to = to;
    else
      lit.push_back(Interval{from, to});
  }
  ASSERT_EQ(b.laser().size(), lit.size()) << "laser intervals, seed " << seed;
  for (size_t j = 0; j < lit.size(); ++j) {
    EXPECT_EQ(b.laser()[j].from, lit[j].from) << "laser interval " << j;
    EXPECT_EQ(b.laser()[j].to, lit[j].to) << "laser interval " << j;
  }
  // Answers: every frame well formed; ACK next_seq never decreases and ends at kSegs; DONE
  // counts rise to kSegs; free slots within the FIFO.
  uint32_t last_seq = 0, last_done = 0;
  size_t acks = 0, dones = 0;
  uint8_t dev_seq = 0;
  for (const auto& m : b.msgs()) {
    ASSERT_FALSE(m.v1_ack) << "0xAA in a v2 session";
    ASSERT_TRUE(m.crc_ok);
    EXPECT_EQ(m.seq, dev_seq++) << "device SEQ";
    if (m.type != v2::kAck && m.type != v2::kDone) continue;
    (m.type == v2::kAck ? acks : dones)++;
    EXPECT_GE(m.u8(0), last_seq) << "ACK next_seq went back";
    EXPECT_LE(m.u16(1), 64u);
    EXPECT_GE(m.u32(3), last_done) << "segments done went back";
    last_seq = m.u8(0);
    last_done = m.u32(3);
  }
  EXPECT_EQ(last_seq, static_cast<uint32_t>(kSegs));
  EXPECT_EQ(last_done, static_cast<uint32_t>(kSegs));
  EXPECT_GT(acks, 5u);
  EXPECT_GT(dones, 0u);
  EXPECT_EQ(b.dut().fifo_level, 0u);
  EXPECT_EQ(b.dut().busy, 0);
  EXPECT_EQ(b.dut().violations, 0u);
  EXPECT_EQ(b.dut().clamped, 0u);

  // STATUS.
  b.send_frame(v2::status_query());
  ASSERT_TRUE(b.wait_msgs(1, 80 * kByteClocks));
  const auto& st = b.msgs().back();
  ASSERT_EQ(st.type, v2::kStatus);
  ASSERT_EQ(st.payload.size(), 62u);  // 46 + the heater block (docs/protocol.md)
  EXPECT_EQ(st.u8(0), 0x02u) << "state: idle, v2 mode, no fault";
  EXPECT_EQ(st.u8(1), 0u) << "faults";
  EXPECT_EQ(st.u16(2), 0u) << "FIFO level";
  EXPECT_EQ(st.u8(4), static_cast<uint32_t>(kSegs)) << "next_seq";
  EXPECT_EQ(st.u32(5), static_cast<uint32_t>(kSegs)) << "segments done";
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), net[a]) << "position axis " << a;
  EXPECT_EQ(st.u16(25), static_cast<uint32_t>(kSegs + 2)) << "frames ok (HELLO, frames, query)";
  for (int c = 1; c < 9; ++c) EXPECT_EQ(st.u16(25 + 2 * c), 0u) << "counter " << c;
  std::printf("burst: %d segments, %zu ACK, %zu DONE, %llu clocks\n", kSegs, acks, dones,
              static_cast<unsigned long long>(b.cycle()));
}

// A LINE with a bad CRC is answered NAK BAD_CRC and nothing moves; the retransmission runs.
TEST(CncCoreV2, BadCrcNakNothingMoves) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  auto f = v2::line(0, 1, 255, 4000, {20, -20}, true);
  f.back() ^= 0x40;
  b.send_frame(f);
  ASSERT_TRUE(b.wait_msgs(1, 40 * kByteClocks));
  const auto& nak = b.msgs().back();
  ASSERT_EQ(nak.type, v2::kNak);
  EXPECT_EQ(nak.u8(0), 0u) << "SEQ of the rejected frame";
  EXPECT_EQ(nak.u8(1), v2::kBadCrc);
  EXPECT_EQ(nak.u8(2), 0u) << "next_seq";
  EXPECT_EQ(nak.u16(3), 64u) << "free";
  b.idle(20'000);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 0u);
  EXPECT_TRUE(b.starts().empty());
  EXPECT_EQ(b.dut().crc_errors, 1u);
  EXPECT_EQ(b.dut().naks, 1u);
  EXPECT_EQ(b.dut().next_seq, 0u);
  b.send_frame(v2::line(0, 1, 255, 4000, {20, -20}, true));
  b.settle(10'000);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 20u);
  EXPECT_EQ(b.mon().axis(1).rises.size(), 20u);
  EXPECT_EQ(b.dut().segments_done, 1u);
  EXPECT_EQ(b.dut().next_seq, 1u);
}

// Soft limits (docs/machine.md "Soft limits"): CONFIG_TRAVEL X [-100, 100], Y [0, 50] steps; a
// LINE whose end leaves them is NAK TRAVEL and never queued (only the accepted lines run: their
// steps and segments done are counted); one ending exactly on both limits is accepted; bad
// CONFIG_TRAVEL fields are BAD_FIELD; after an e-stop flush the queued end is the position
// counters' (a LINE that fits only from there is accepted, one that fits only from the flushed
// queue's end is refused).
TEST(CncCoreV2, SoftLimitsNakTravelAndResync) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  auto expect_nak = [&](const std::vector<uint8_t>& f, uint8_t seq, uint8_t reason,
                        const char* why) {
    b.send_frame(f);
    ASSERT_TRUE(b.wait_msgs(1, 40 * kByteClocks)) << why;
    const auto& m = b.msgs().back();
    ASSERT_EQ(m.type, v2::kNak) << why;
    EXPECT_EQ(m.u8(0), seq) << why;
    EXPECT_EQ(m.u8(1), reason) << why;
    EXPECT_EQ(m.u8(2), seq) << why << ": next_seq unchanged";
  };
  auto expect_ack = [&](const std::vector<uint8_t>& f, const char* why) {
    b.send_frame(f);
    ASSERT_TRUE(b.wait_msgs(1, 40 * kByteClocks)) << why;
    EXPECT_EQ(b.msgs().back().type, v2::kAck) << why;
  };
  // Bad fields first: axis 4 of 4, a reserved flag bit, MIN > MAX while enabled.
  expect_nak(v2::config_travel(0, 4, true, -100, 100), 0, v2::kBadField, "axis 4");
  expect_nak(v2::config_travel(0, 0, true, -100, 100, 0x02), 0, v2::kBadField, "flag bit 1");
  expect_nak(v2::config_travel(0, 0, true, 100, -100), 0, v2::kBadField, "min > max");
  expect_nak(v2::frame(v2::kConfigTravel, 0, {0, 1, 0, 0}), 0, v2::kBadLength, "LEN 4");
  // Off after reset: anything goes until CONFIG_TRAVEL.
  expect_ack(v2::config_travel(0, 0, true, -100, 100), "travel X");
  expect_ack(v2::config_travel(1, 1, true, 0, 50), "travel Y");
  expect_ack(v2::line(2, 1, 0, 20'000, {60, 20}, true), "X 60 Y 20");
  expect_nak(v2::line(3, 1, 0, 20'000, {41, 0}, true), 3, v2::kTravel, "X 101");
  expect_nak(v2::line(3, 1, 0, 20'000, {0, 31}, false), 3, v2::kTravel, "Y 51 (int32 steps)");
  expect_ack(v2::line(3, 1, 0, 20'000, {40, -20}, true), "X 100 Y 0: on both limits");
  expect_nak(v2::line(4, 1, 0, 20'000, {0, -1}, true), 4, v2::kTravel, "Y -1");
  // Z has no travel: any Z move passes.
  expect_ack(v2::line(4, 0, 0, 20'000, {0, 0, -50}, false), "Z -50");
  b.settle(200'000);
  EXPECT_EQ(b.dut().segments_done, 3u);
  EXPECT_EQ(b.mon().axis(0).rises.size(), 100u);
  EXPECT_EQ(b.mon().axis(1).rises.size(), 40u);
  EXPECT_EQ(static_cast<int32_t>(b.dut().position[0]), 100);
  EXPECT_EQ(static_cast<int32_t>(b.dut().position[1]), 0);
  // A long move toward X -100, stopped half-way by the e-stop: the FIFO is flushed.
  expect_ack(v2::line(5, 1, 0, 2'000'000, {-200}, false), "X -100, slowly");
  expect_ack(v2::line(6, 1, 0, 20'000, {50}, true), "then X -50 (flushed)");
  b.idle(700'000);
  b.dut().estop = 1;
  b.idle(1000);
  b.dut().estop = 0;
  b.idle(100);
  const auto p = static_cast<int32_t>(b.dut().position[0]);
  ASSERT_GT(p, -50);  // so that the line below fits only from the position, not from X -50
  ASSERT_LT(p, 100);
  expect_ack(v2::fault_clear(7), "FAULT_CLEAR");
  // From the queue's end before the flush (X -50) this would end at -50 - (p + 100) < -100.
  expect_ack(v2::line(8, 1, 0, 2'000'000, {-(p + 100)}, false), "to X -100 from the position");
  expect_nak(v2::line(9, 1, 0, 20'000, {-1}, true), 9, v2::kTravel, "X -101");
  b.settle(2'000'000);
  EXPECT_EQ(static_cast<int32_t>(b.dut().position[0]), -100);
}

// NUMERATORS (a FIFO entry: DONE counts it), RELEASE, then v1 with the new numerators and 0xAA.
TEST(CncCoreV2, NumeratorsReleaseThenV1) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  b.send_frame(v2::numerators(0, 9'375'000, 4'000'000));
  b.settle(5'000);
  EXPECT_EQ(b.dut().numerator_x, 9'375'000u);
  EXPECT_EQ(b.dut().numerator_y, 4'000'000u);
  EXPECT_EQ(b.dut().segments_done, 1u) << "an applied NUMERATORS entry counts as done";
  const auto* done = b.last(v2::kDone);
  const auto* ack = b.last(v2::kAck);
  ASSERT_TRUE(ack != nullptr);
  EXPECT_EQ(ack->u8(0), 1u);
  const uint32_t reported = std::max(done ? done->u32(3) : 0u, ack->u32(3));
  EXPECT_EQ(reported, 1u) << "segments done reported by ACK/DONE";
  b.send_frame(v2::release(1));
  b.settle(5'000);
  EXPECT_EQ(b.dut().v2_mode, 0);
  ASSERT_EQ(b.msgs().back().type, v2::kAck);
  EXPECT_EQ(b.msgs().back().u8(0), 2u);
  // v1: X dominant, 9 375 000 / 1200 = 7812 clocks.
  const size_t n0 = b.msgs().size();
  b.send(fpgacnc::tb::motion_packet(0, -20, 5, 1200));
  ASSERT_TRUE(b.wait_msgs(1, 20 * 7812 + 100'000)) << "no 0xAA";
  ASSERT_EQ(b.msgs().size(), n0 + 1);
  EXPECT_TRUE(b.msgs().back().v1_ack);
  const auto& x = b.mon().axis(0);
  ASSERT_EQ(x.rises.size(), 20u);
  for (size_t i = 1; i < x.rises.size(); ++i) EXPECT_EQ(x.rises[i] - x.rises[i - 1], 7812u);
  EXPECT_GT(b.msgs().back().cycle, x.rises.back()) << "0xAA before the last step";
  EXPECT_EQ(b.dut().segments_done, 1u) << "a v1 move is not a v2 segment";
}

// Fan PWM of the default build: FAN_PWM_HZ 1000 at 50 MHz: 256 counts of
// round(50e6 / 256 000) = 195 clocks (docs/protocol.md "OUTPUT").
constexpr uint64_t kFanCount = 195, kFanPeriod = 256 * kFanCount;

// LINE_PROFILE at a constant 500 clocks per dominant step (V_entry = V_cruise = V_exit, no
// deceleration), +X and +Y: no reversal, so the next one can start with zero gap.
std::vector<uint8_t> constant_profile(uint8_t seq, int32_t n) {
  const uint64_t v = (uint64_t{1} << 48) / 500;
  return v2::line_profile(seq, 1, 255, v, v, v, 0, static_cast<uint32_t>(n), {n, n / 2}, true);
}

// OUTPUT frames between two LINE_PROFILE segments, all sent back to back: the outputs of an
// OUTPUT change on the edge the segment before it ends (its last STEP rise, seg_done), the next
// segment starts on that edge (seg_start in the same clock as the previous seg_done: no gap), two
// OUTPUT frames after the last segment are applied together when it ends; DONE counts every one.
TEST(CncCoreV2, OutputBetweenProfilesNoGap) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  const int32_t n = 40;  // 20 000 clocks each: the frames behind arrive and are prepared in time
  b.queue(constant_profile(0, n));
  // M8, M62 P2, M106 S128
  b.queue(v2::output(1, v2::kOutFlood | v2::out_dout(2) | v2::kOutFan,
                     v2::kOutFlood | v2::out_dout(2), 128));
  b.queue(constant_profile(2, n));
  // M9 with M106 S255, then M63 P2
  b.queue(v2::output(3, v2::kOutFlood | v2::kOutMist | v2::kOutFan, 0, 255));
  b.queue(v2::output(4, v2::out_dout(2), 0, 0));
  uint64_t guard = 0;
  while ((b.dut().segments_done < 5 || !b.rx_idle()) && ++guard < 200'000) b.tick();
  ASSERT_EQ(b.dut().segments_done, 5u) << "2 segments and 3 OUTPUT entries by cycle " << b.cycle();
  b.idle(3 * kFanPeriod);
  ASSERT_EQ(b.starts().size(), 2u);
  ASSERT_EQ(b.dones().size(), 2u);
  const uint64_t e_a = b.dones()[0], e_b = b.dones()[1];
  // No gap: the second segment's tick 1 is the clock after the first one's end edge.
  EXPECT_EQ(b.starts()[1], e_a) << "seg_start of the second segment vs seg_done of the first";
  // Each segment's last STEP rise is on its end edge (seen in the same clock as seg_done).
  ASSERT_EQ(b.mon().axis(0).rises.size(), 2u * n);
  EXPECT_EQ(b.mon().axis(0).rises[n - 1], e_a);
  EXPECT_EQ(b.mon().axis(0).rises[2 * n - 1], e_b);
  // Flood and dout[2] on at the first segment's end, off at the second's; mist never.
  const auto flood = b.out_edges_of(0);
  ASSERT_EQ(flood.size(), 2u);
  EXPECT_EQ(flood[0].cycle, e_a);
  EXPECT_EQ(flood[0].value, 1u);
  EXPECT_EQ(flood[1].cycle, e_b);
  EXPECT_EQ(flood[1].value, 0u);
  const auto d2 = b.out_edges_of(5);
  ASSERT_EQ(d2.size(), 2u);
  EXPECT_EQ(d2[0].cycle, e_a);
  EXPECT_EQ(d2[1].cycle, e_b);
  EXPECT_TRUE(b.out_edges_of(1).empty()) << "mist";
  for (int p : {3, 4, 6}) EXPECT_TRUE(b.out_edges_of(p).empty()) << "dout " << p - 3;
  // Fan: 128 of 256 counts high from the first PWM period boundary after e_a, in whole periods;
  // from the first boundary after e_b on always high (255).
  const auto fan = b.out_edges_of(2);
  ASSERT_GE(fan.size(), 3u);
  EXPECT_GE(fan[0].cycle, e_a);
  EXPECT_LT(fan[0].cycle, e_a + kFanPeriod) << "first fan rise within one PWM period";
  // rise, fall pairs of 128 counts, rises one period apart, then the last rise stays high
  ASSERT_EQ(fan.size() % 2, 1u) << "fan edges";
  for (size_t i = 0; i < fan.size(); i += 2) {
    EXPECT_EQ(fan[i].value, 1u) << "fan edge " << i;
    if (i >= 2) {
      EXPECT_EQ(fan[i].cycle - fan[i - 2].cycle, kFanPeriod) << "fan period, edge " << i;
    }
    if (i + 1 < fan.size()) {
      EXPECT_EQ(fan[i + 1].value, 0u) << "fan edge " << i + 1;
      EXPECT_EQ(fan[i + 1].cycle - fan[i].cycle, 128 * kFanCount) << "fan high time, edge " << i;
    }
  }
  EXPECT_GT(fan.back().cycle, e_b) << "fan always on from the first boundary after S255";
  EXPECT_LE(fan.back().cycle, e_b + kFanPeriod);
  EXPECT_EQ(b.dut().fan, 1);
  EXPECT_EQ(b.dut().violations, 0u);
  // Every ACK/DONE in order; the last count 5.
  uint32_t last_done = 0;
  for (const auto& m : b.msgs()) {
    if (!m.v1_ack && (m.type == v2::kAck || m.type == v2::kDone)) last_done = m.u32(3);
  }
  EXPECT_EQ(last_done, 5u);
}

// OUTPUT field and length rules (NAK BAD_FIELD / BAD_LENGTH, nothing changes), an OUTPUT on an
// idle machine acting on the edge it is handed over, and every output low within 2 clocks of the
// e-stop pin, staying low after FAULT_CLEAR.
TEST(CncCoreV2, OutputRulesIdleAndEstop) {
  V2Bench b;
  hello(b);
  if (HasFatalFailure()) return;
  struct Bad {
    std::vector<uint8_t> frame;
    uint8_t reason;
    const char* why;
  };
  const std::vector<Bad> bad = {
      {v2::output(0, 0, 0, 0), v2::kBadField, "empty mask"},
      {v2::output(0, v2::kOutFlood, fpgacnc::spec::kOutLaserDyn, 0), v2::kBadField,
       "value bit 7 outside the mask"},
      {v2::output(0, v2::kOutFlood, v2::kOutMist, 0), v2::kBadField, "value outside the mask"},
      {v2::output(0, v2::kOutFan, v2::kOutFan, 10), v2::kBadField, "value bit 2"},
      {v2::output(0, v2::kOutFlood, 1, 7), v2::kBadField, "duty without the fan bit"},
      {v2::frame(v2::kOutput, 0, {1, 1}), v2::kBadLength, "LEN 2"},
      {v2::frame(v2::kOutput, 0, {1, 1, 0, 0}), v2::kBadLength, "LEN 4"},
  };
  for (const auto& x : bad) {
    b.send_frame(x.frame);
    ASSERT_TRUE(b.wait_msgs(1, 40 * kByteClocks)) << x.why;
    const auto& nak = b.msgs().back();
    ASSERT_EQ(nak.type, v2::kNak) << x.why;
    EXPECT_EQ(nak.u8(1), x.reason) << x.why;
    EXPECT_EQ(nak.u8(2), 0u) << x.why << ": next_seq";
  }
  b.idle(1000);
  EXPECT_TRUE(b.out_edges().empty()) << "a rejected OUTPUT changed a pin";
  // All on, machine idle: the pins change together, on the edge after the frame's entry is taken.
  b.send_frame(v2::output(0, 0x7B, 0x7B, 0));  // flood, mist, dout 0..3; fan unchanged
  b.settle(2000);
  ASSERT_EQ(b.out_edges().size(), 6u);
  for (const auto& e : b.out_edges()) {
    EXPECT_EQ(e.value, 1u);
    EXPECT_EQ(e.cycle, b.out_edges()[0].cycle) << "pin " << e.pin;
  }
  EXPECT_EQ(b.dut().segments_done, 1u);
  b.send_frame(v2::output(1, v2::kOutFan, 0, 255));
  b.idle(2 * kFanPeriod);
  EXPECT_EQ(b.dut().fan, 1);
  // e-stop: two-flop synchronizer, then every output low (combinational gate).
  const size_t before = b.out_edges().size();
  b.dut().estop = 1;
  b.idle(5);
  const uint64_t pressed = b.cycle() - 5;
  ASSERT_EQ(b.out_edges().size(), before + 7);
  for (size_t k = before; k < b.out_edges().size(); ++k) {
    EXPECT_EQ(b.out_edges()[k].value, 0u);
    EXPECT_EQ(b.out_edges()[k].cycle, pressed + 2) << "pin " << b.out_edges()[k].pin;
  }
  b.dut().estop = 0;
  b.idle(10);
  b.send_frame(v2::fault_clear(2));
  b.settle(2000);
  EXPECT_EQ(b.dut().faults, 0u);
  b.idle(2 * kFanPeriod);
  EXPECT_EQ(b.out_edges().size(), before + 7) << "outputs stay off after the e-stop is cleared";
}

}  // namespace
