// System bench for cnc_core's reduced configurations (spec/configs.toml), first v1-board
// (N_AXES = 2, PROTO_V2 = 0: protocol v1 only, see the build options in rtl/cnc_core.v) through
// its pins: v1 bytes bit-banged onto rx at 115200 baud, the 0xAA ACKs decoded from tx, STEP/DIR
// recorded every clock. Checks a seeded v1 job with the host's handshake (exact STEP schedule R +
// ceil(k*T/n), DIR, laser, ACK after the move, positions), packets sent without waiting (run back
// to back, one ACK each), and that a v2 frame is not understood (no answer, cut by the 100 ms
// watchdog like any partial v1 packet); lines-2axis answers the frames it lacks NAK UNKNOWN_TYPE.
// Lockstep: the trimmed v1 datapath (v1-board, LEAN_TRIM = 1) and the fixed step timing
// (v1-board-fixed, STEP_CFG = 0) against the general datapath (v1-board-untrimmed), every output on
// every clock of a random v1 session.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "Vcnc_core_lines_2axis.h"
#include "Vcnc_core_v1_board.h"
#include "Vcnc_core_v1_board_fast.h"
#include "Vcnc_core_v1_board_fixed_fast.h"
#include "Vcnc_core_v1_board_untrimmed_fast.h"
#include "common/core_pins.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"
#include "fpgacnc/models/uart_bits.h"

namespace {

using fpgacnc::models::UartDriver;
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

class V1BoardBench : public fpgacnc::tb::PinHarness<Vcnc_core_v1_board> {
 public:
  V1BoardBench() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_v1_board>()) {
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
    const Vcnc_core_v1_board& m = dut();
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
void check_steps(V1BoardBench& b, const Move& mv, uint64_t start, uint64_t period,
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
  V1BoardBench b;
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
  std::printf("v1-board job: %zu moves, seed %llu, %llu clocks\n", job.size(),
              static_cast<unsigned long long>(seed), static_cast<unsigned long long>(b.cycle()));
}

// Three packets sent without waiting: decoder register, segment_prep and executor each hold one;
// the moves (same directions) run back to back with no idle clock, one ACK each.
TEST(CncCoreLean, PacketsSentAheadRunBackToBack) {
  V1BoardBench b;
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
  V1BoardBench b;
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

// v2 build with LINE/DWELL only: LINE_PROFILE, ARC, heater and trigger frames are unknown types.
TEST(CncCoreLean, LinesOnlyBuildAnswersUnknownType) {
  namespace v2 = fpgacnc::tb::v2;
  fpgacnc::tb::PinHarness<Vcnc_core_lines_2axis> b(kAxes,
                                                   fpgacnc::tb::core_pins<Vcnc_core_lines_2axis>());
  b.dut().estop = 0;
  b.dut().adc_sdo = 0;
  fpgacnc::tb::reset_core(b);
  v2::DeviceParser parser;
  size_t parsed = 0;
  // Runs until the next device frame (or v1 byte) is complete; nullopt after `limit` clocks.
  auto next_msg = [&](uint64_t limit) -> std::optional<v2::DeviceMsg> {
    const uint64_t end = b.cycle() + limit;
    while (b.cycle() < end) {
      while (parsed < b.tx_bytes().size()) {
        const auto& t = b.tx_bytes()[parsed++];
        if (auto m = parser.push(t.value, t.start_cycle)) return m;
      }
      b.tick();
    }
    return std::nullopt;
  };
  // type, payload length (the length each type requires when it is built)
  // (TRIGGER 0x0A, SET_POSITION 0x0B, TRIGGER_QUERY 0x0C: lines-2axis has TRIGGER 0)
  const std::pair<uint8_t, size_t> off[] = {{0x12, 36}, {0x13, 63}, {0x20, 20}, {0x21, 3},
                                            {0x22, 4},  {0x23, 13}, {0x24, 2},  {0x0A, 3},
                                            {0x0B, 10}, {0x0C, 0}};
  uint16_t unknown = 0;
  for (const auto& [type, len] : off) {
    b.send(v2::frame(type, 0, std::vector<uint8_t>(len, 0)));
    const auto m = next_msg(200'000);
    ASSERT_TRUE(m.has_value()) << "no answer to type 0x" << std::hex << int(type);
    EXPECT_TRUE(m->crc_ok);
    ASSERT_EQ(m->type, v2::kNak) << "type 0x" << std::hex << int(type) << " answered 0x"
                                 << int(m->type);
    EXPECT_EQ(m->u8(0), 0u) << "NAK SEQ, type 0x" << std::hex << int(type);
    EXPECT_EQ(m->u8(1), v2::kUnknownType) << "NAK reason, type 0x" << std::hex << int(type);
    EXPECT_EQ(m->u8(2), 0u) << "next_seq moved, type 0x" << std::hex << int(type);
    ++unknown;
    EXPECT_EQ(b.dut().unknown_types, unknown);
  }
  EXPECT_EQ(b.dut().next_seq, 0u);
  EXPECT_EQ(b.dut().fifo_level, 0u);
  EXPECT_EQ(b.dut().heater, 0u);
  EXPECT_EQ(b.dut().faults, 0u);
  // A LINE (seq 0) is accepted and runs: ACK, then DONE, exact net steps.
  b.send(v2::line(0, 1, 200, 20'000, {40, -25}, true));
  const auto ack = next_msg(200'000);
  ASSERT_TRUE(ack.has_value());
  EXPECT_EQ(ack->type, v2::kAck);
  const auto done = next_msg(400'000);
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->type, v2::kDone);
  EXPECT_EQ(b.mon().axis(0).position, 40);
  EXPECT_EQ(b.mon().axis(1).position, -25);
  EXPECT_EQ(b.dut().next_seq, 1u);
  EXPECT_EQ(b.dut().violations, 0u);
}

// ---------------------------------------------------------------- lockstep (LEAN_TRIM, STEP_CFG)
// Two v1 builds driven with the same pins every clock; every output compared every clock. The
// models (tb/lean.cmake) have a 2.5 Mbaud UART, a 20 000-clock watchdog and STEP high 3 / low 2,
// DIR setup 6 / hold 4, so one random v1 session holds hundreds of moves.
constexpr double kFastBaud = 2.5e6;
constexpr uint64_t kFastByte = 200;  // 10 bits of 20 clocks

template <class A, class B>
class Lockstep {
 public:
  Lockstep()
      : ca_(std::make_unique<VerilatedContext>()),
        cb_(std::make_unique<VerilatedContext>()),
        a_(std::make_unique<A>(ca_.get())),
        b_(std::make_unique<B>(cb_.get())),
        drv_(50e6, kFastBaud) {
    set([](auto& m) {
      m.rx = 1;
      m.estop = 0;
      m.adc_sdo = 0;
      m.cfg_wr = 0;
      m.cfg_addr = 0;
      m.cfg_wdata = 0;
      m.rst = 1;
    });
    for (int i = 0; i < 4; ++i) tick();
    set([](auto& m) { m.rst = 0; });
  }
  ~Lockstep() {
    a_->final();
    b_->final();
  }
  template <class F>
  void set(F f) {
    f(*a_);
    f(*b_);
  }
  A& a() { return *a_; }
  UartDriver& uart() { return drv_; }
  uint64_t cycle() const { return cycle_; }
  const std::string& mismatch() const { return mismatch_; }
  uint64_t step_rises() const { return step_rises_; }
  uint64_t dir_changes() const { return dir_changes_; }

  // One clock; false (and mismatch() set) when an output differs.
  bool tick() {
    const int rx = drv_.tick();
    set([rx](auto& m) {
      m.rx = rx;
      m.clk = 0;
      m.eval();
      m.clk = 1;
      m.eval();
    });
    ++cycle_;
    const A& x = *a_;
    const B& y = *b_;
#define LOCKSTEP_CMP(f)                                                                  \
  if (x.f != y.f) {                                                                      \
    mismatch_ = std::string(#f) + " differs at cycle " + std::to_string(cycle_) +        \
                ": expected (reference) " + std::to_string(static_cast<uint64_t>(y.f)) + \
                ", got " + std::to_string(static_cast<uint64_t>(x.f));                   \
    return false;                                                                        \
  }
    LOCKSTEP_CMP(tx)
    LOCKSTEP_CMP(step)
    LOCKSTEP_CMP(dir)
    LOCKSTEP_CMP(laser)
    LOCKSTEP_CMP(heater)
    LOCKSTEP_CMP(adc_convst)
    LOCKSTEP_CMP(adc_sck)
    LOCKSTEP_CMP(adc_sdi)
    LOCKSTEP_CMP(busy)
    LOCKSTEP_CMP(running)
    LOCKSTEP_CMP(seg_start)
    LOCKSTEP_CMP(seg_done)
    LOCKSTEP_CMP(position)
    LOCKSTEP_CMP(last_code)
    LOCKSTEP_CMP(last_feed)
    LOCKSTEP_CMP(last_period)
    LOCKSTEP_CMP(packet_count)
    LOCKSTEP_CMP(frame_errors)
    LOCKSTEP_CMP(timeouts)
    LOCKSTEP_CMP(overruns)
    LOCKSTEP_CMP(violations)
    LOCKSTEP_CMP(numerator_x)
    LOCKSTEP_CMP(numerator_y)
    LOCKSTEP_CMP(fifo_level)
    LOCKSTEP_CMP(rx_partial)
    LOCKSTEP_CMP(faults)
#undef LOCKSTEP_CMP
    step_rises_ += __builtin_popcount(static_cast<unsigned>(x.step & ~step_prev_));
    dir_changes_ += __builtin_popcount(static_cast<unsigned>(x.dir ^ dir_prev_));
    step_prev_ = x.step;
    dir_prev_ = x.dir;
    return true;
  }

 private:
  std::unique_ptr<VerilatedContext> ca_, cb_;
  std::unique_ptr<A> a_;
  std::unique_ptr<B> b_;
  UartDriver drv_;
  uint64_t cycle_ = 0, step_rises_ = 0, dir_changes_ = 0;
  uint32_t step_prev_ = 0, dir_prev_ = 0;
  std::string mismatch_;
};

struct SessionStats {
  uint64_t moves = 0, inits = 0, partials = 0, huge = 0, estops = 0, cfg_writes = 0;
};

// A random v1 session: motion packets (small moves at periods near the minimum and above, zero-step
// moves, feed 0, packets sent ahead of the ACK), init packets, partial packets cut by the watchdog,
// huge moves (|steps| up to 2^31, numerators up to 2^32 - 1: 64-bit T) stopped by an e-stop and a
// reset, and (cfg = true) random cfg port writes at any time.
template <class A, class B>
SessionStats run_session(Lockstep<A, B>& ls, uint64_t seed, uint64_t clocks, bool cfg) {
  std::mt19937_64 rng(seed);
  auto uni = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  SessionStats st;
  uint32_t num = 150'000;
  auto run = [&](uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) {
      if (cfg && uni(0, 999) == 0) {
        const auto addr = static_cast<uint8_t>(uni(0, 9));  // 8, 9: no such axis
        const auto val = static_cast<uint16_t>(uni(0, 7));
        ls.set([&](auto& m) {
          m.cfg_wr = 1;
          m.cfg_addr = addr;
          m.cfg_wdata = val;
        });
        ++st.cfg_writes;
      } else {
        ls.set([](auto& m) { m.cfg_wr = 0; });
      }
      if (!ls.tick()) return false;
    }
    return true;
  };
  auto send = [&](const std::vector<uint8_t>& bytes) {
    for (uint8_t v : bytes) ls.uart().push(v);
  };
  while (ls.cycle() < clocks) {
    const int64_t ev = uni(0, 99);
    uint64_t wait = 0;
    if (ev < 72) {
      int32_t sx = static_cast<int32_t>(uni(-40, 40)), sy = static_cast<int32_t>(uni(-40, 40));
      if (uni(0, 9) == 0) sx = sy = 0;
      uint16_t feed = static_cast<uint16_t>(std::clamp<int64_t>(num / uni(3, 120), 0, 65535));
      if (uni(0, 29) == 0) feed = 0;  // FEED0_PERIOD
      send(motion_packet(static_cast<uint8_t>(uni(0, 3)), sx, sy, feed));
      ++st.moves;
      const uint64_t p = feed == 0 ? 700 : std::max<uint64_t>(num / feed, 5);
      const uint64_t t = p * std::max(mag(sx), mag(sy));
      wait = uni(0, 3) == 0 ? uni(0, 3000) : 11 * kFastByte + uni(0, static_cast<int64_t>(t + 50));
    } else if (ev < 80) {
      num = static_cast<uint32_t>(uni(20'000, 400'000));
      send(init_packet(num, static_cast<uint32_t>(uni(20'000, 400'000))));
      ++st.inits;
      wait = 9 * kFastByte + uni(0, 2000);
    } else if (ev < 84) {
      const int n = static_cast<int>(uni(1, 10));
      for (int i = 0; i < n; ++i) ls.uart().push(static_cast<uint8_t>(uni(0, 255)));
      ++st.partials;
      wait = n * kFastByte + 20'000 + uni(0, 50);
    } else if (ev < 87) {
      // a huge move: 64-bit T; runs a while, then e-stop (latched in v1) and reset
      const uint32_t n2 = static_cast<uint32_t>(uni(1, std::numeric_limits<uint32_t>::max()));
      send(init_packet(n2, n2));
      const auto big = [&]() {
        const int64_t k = uni(0, 3);
        return k == 0 ? std::numeric_limits<int32_t>::min()
                      : static_cast<int32_t>(uni(std::numeric_limits<int32_t>::min() + 1,
                                                 std::numeric_limits<int32_t>::max()));
      };
      send(motion_packet(static_cast<uint8_t>(uni(0, 3)), big(), big(),
                         static_cast<uint16_t>(uni(1, 65535))));
      ++st.huge;
      if (!run(20 * kFastByte + uni(0, 20'000))) return st;
      ls.set([](auto& m) { m.estop = 1; });
      if (!run(uni(3, 50))) return st;
      ls.set([](auto& m) { m.estop = 0; });
      if (!run(uni(0, 300))) return st;
      ls.set([](auto& m) { m.rst = 1; });
      if (!run(3)) return st;
      ls.set([](auto& m) { m.rst = 0; });
      num = 150'000;
      ++st.estops;
      continue;
    } else {
      wait = uni(0, 5000);
    }
    if (!run(wait)) return st;
  }
  return st;
}

template <class A, class B>
void lockstep_test(const char* name, uint64_t fallback_seed, bool cfg) {
  const uint64_t seed = fpgacnc::tb::test_seed(fallback_seed, name);
  Lockstep<A, B> ls;
  const SessionStats st = run_session(ls, seed, 1'200'000, cfg);
  ASSERT_TRUE(ls.mismatch().empty()) << ls.mismatch() << " (seed " << seed << ")";
  std::printf(
      "%s: %llu clocks, %llu moves, %llu inits, %llu partial packets, %llu huge moves "
      "(e-stop + reset), %llu cfg writes; %llu STEP rises, %llu DIR changes, %u "
      "packets since the last reset, %u timeouts, %u overruns\n",
      name, static_cast<unsigned long long>(ls.cycle()), static_cast<unsigned long long>(st.moves),
      static_cast<unsigned long long>(st.inits), static_cast<unsigned long long>(st.partials),
      static_cast<unsigned long long>(st.huge), static_cast<unsigned long long>(st.cfg_writes),
      static_cast<unsigned long long>(ls.step_rises()),
      static_cast<unsigned long long>(ls.dir_changes()), static_cast<unsigned>(ls.a().packet_count),
      static_cast<unsigned>(ls.a().timeouts), static_cast<unsigned>(ls.a().overruns));
  // the session did what it is meant to (else the comparison proves little)
  EXPECT_GT(ls.step_rises(), 2'000u);
  EXPECT_GT(ls.dir_changes(), 50u);
  EXPECT_GT(st.huge, 0u);
  EXPECT_GT(st.partials, 0u);
  if (cfg) {
    EXPECT_GT(st.cfg_writes, 50u);
  }
}

// LEAN_TRIM = 1 (segment_prep V1_ONLY, executor TMN_FROM_TOTAL) against LEAN_TRIM = 0, cfg port
// writes included.
TEST(CncCoreLean, TrimmedDatapathMatchesGeneralInLockstep) {
  lockstep_test<Vcnc_core_v1_board_fast, Vcnc_core_v1_board_untrimmed_fast>(
      "v1-board trim lockstep", 20261123, true);
}

// STEP_CFG = 0 (fixed step timing) against v1-board-untrimmed with the cfg port idle.
TEST(CncCoreLean, FixedStepTimingMatchesIdleCfgPortInLockstep) {
  lockstep_test<Vcnc_core_v1_board_fixed_fast, Vcnc_core_v1_board_untrimmed_fast>(
      "v1-board-fixed lockstep", 20261124, false);
}

}  // namespace
