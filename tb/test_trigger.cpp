// Homing and probing through cnc_core's pins (docs/machine.md "Homing and probing (hardware)"): a
// 2-axis core (full-2axis) at 3 Mbaud, its four limit switches wired (X min active low, the others
// active high, kFilter clocks of debounce) and the probe (active high, kProbeFilter clocks). The
// bench plays the machine: a max endstop per axis is pressed while the axis's STEP count at the
// pins is at or beyond its position, and the probe follows a rule on the X count (a plate). Every
// latched position is checked against the STEP rising edges counted at the pins up to the clock of
// the filtered edge (pin first sampled on edge p: filtered from edge p + 1 + F, input_filter's
// contract), the stopping distance after a probe contact against the ramp, the positions in STATUS
// against the pins; TRIGGER_REPORT, SET_POSITION and the refusals of bad frames through the UART.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "Vcnc_core_machine.h"
#include "common/machine_pins.h"
#include "common/pin_harness.h"
#include "common/v2_core_bench.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
namespace spec = fpgacnc::spec;
using Model = Vcnc_core_machine;

constexpr int kAxes = 2;
constexpr uint64_t kFilter = 500;       // LIMIT_FILTER_CLKS of this build (tb/limits.cmake)
constexpr uint64_t kProbeFilter = 200;  // PROBE_FILTER_CLKS
constexpr uint8_t kStatePosUntrusted = spec::kStatePosUntrusted;
constexpr uint8_t kStateProbe = spec::kStateProbe;
constexpr uint8_t kFaultLimit = spec::kFaultLimit;
constexpr size_t kLimitByte = 9 + 4 * kAxes + 18;  // STATUS: the limit byte (2 axes)
constexpr int64_t kNone = std::numeric_limits<int64_t>::max();
constexpr uint8_t kDisarm = 0, kHome = 1, kProbe = 2, kProbeRelease = 3;
constexpr uint8_t kArmed = 0x01, kDone = 0x02;  // TRIGGER_REPORT flags
// MOTION ramp of the probe tests: 100 % to 0 in 100 rate periods of 256 clocks.
constexpr uint32_t kRamp = 42949673;  // ceil(2^32 / 100)

using Rise = fpgacnc::tb::StepRise;

std::vector<uint8_t> trigger(uint8_t seq, uint8_t mode, uint16_t mask) {
  std::vector<uint8_t> p{mode};
  v2::be16(p, mask);
  return v2::frame(spec::kTypeTrigger, seq, p);
}
std::vector<uint8_t> set_position(uint8_t seq, uint16_t mask, int32_t x, int32_t y) {
  std::vector<uint8_t> p;
  v2::be16(p, mask);
  v2::be32(p, static_cast<uint32_t>(x));
  v2::be32(p, static_cast<uint32_t>(y));
  return v2::frame(spec::kTypeSetPosition, seq, p);
}
std::vector<uint8_t> motion(uint8_t flags, uint16_t feed, uint16_t rapid, uint32_t ramp) {
  std::vector<uint8_t> p{flags};
  v2::be16(p, feed);
  v2::be16(p, rapid);
  v2::be32(p, ramp);
  return v2::frame(spec::kTypeMotion, 0, p);
}

struct Report {
  uint8_t mode = 0, flags = 0;
  uint16_t fired = 0;
  int32_t pos[kAxes] = {0, 0};
};

class TriggerBench : public fpgacnc::tb::V2CoreBench<Model, kAxes> {
 public:
  TriggerBench() : V2CoreBench(fpgacnc::tb::kMachinePins) {}
  // The machine: max endstop of each axis (pressed at or beyond), the probe rule.
  int64_t endstop_max[kAxes] = {kNone, kNone};
  std::function<bool(const int64_t*)> probe_rule;
  bool model_switches = true;  // false: the test drives limit_max itself
  // Edge that first samples each change of a switch or probe pin: {edge, what (0..3 switch, 4
  // probe), level}.
  struct PinChange {
    uint64_t edge;
    int what;
    bool level;
  };
  std::vector<PinChange> pin_changes;

  Report report() {
    const auto m = exchange(v2::frame(spec::kTypeTriggerQuery, 0, {}));
    EXPECT_EQ(m.type, spec::kTypeTriggerReport);
    EXPECT_TRUE(m.crc_ok);
    Report r;
    if (m.payload.size() != 4 + 4 * kAxes) {
      ADD_FAILURE() << "TRIGGER_REPORT of " << m.payload.size() << " bytes";
      return r;
    }
    r.mode = static_cast<uint8_t>(m.u8(0));
    r.flags = static_cast<uint8_t>(m.u8(1));
    r.fired = static_cast<uint16_t>(m.u16(2));
    for (int a = 0; a < kAxes; ++a) r.pos[a] = static_cast<int32_t>(m.u32(4 + 4 * a));
    return r;
  }
  // STEP rises of axis a on edges <= e: the position counter's value in clock e.
  int64_t pos_at(int a, uint64_t e) const {
    int64_t p = 0;
    for (const auto& r : rises)
      if (r.axis == a && r.cycle <= e) p += r.dir ? 1 : -1;
    return p + pos0[a];
  }
  int64_t pos0[kAxes] = {0, 0};  // position counters when the rise record started
  const PinChange* first_change(int what, bool level) const {
    for (const auto& c : pin_changes)
      if (c.what == what && c.level == level) return &c;
    return nullptr;
  }

 protected:
  void observe_more() override {
    Model& m = dut();
    // The machine's switches and probe, from the STEP count: the new level is first sampled on
    // the next edge.
    uint32_t maxes = 0;
    for (int a = 0; a < kAxes; ++a)
      if (endstop_max[a] != kNone && pins_pos[a] >= endstop_max[a]) maxes |= 1u << a;
    if (model_switches && maxes != m.limit_max) {
      for (int a = 0; a < kAxes; ++a)
        if (((maxes ^ m.limit_max) >> a) & 1u)
          pin_changes.push_back({cycle() + 1, 2 + a, static_cast<bool>((maxes >> a) & 1u)});
      m.limit_max = maxes;
    }
    if (probe_rule) {
      const uint8_t pr = probe_rule(pins_pos) ? 1 : 0;
      if (pr != m.probe_in) {
        pin_changes.push_back({cycle() + 1, 4, pr != 0});
        m.probe_in = pr;
      }
    }
  }
};

// HOME on X max and Y max together, the switches at different positions: the LINE drives both
// axes toward them; Y reaches its switch first and stops there while X goes on; when X's switch
// fires too the segment and the one queued behind it are dropped. Each latched position is the
// axis's STEP count in the clock its switch's filtered level rose, and the axis stays there.
TEST(Trigger, HomeTwoAxesTogether) {
  TriggerBench b;
  b.endstop_max[0] = 300;
  b.endstop_max[1] = 120;
  ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0300)).type, v2::kAck);
  auto r = b.report();
  EXPECT_EQ(r.mode, kHome);
  EXPECT_EQ(r.flags, kArmed);
  EXPECT_EQ(r.fired, 0u);
  // X and Y +1000 over 40 000 clocks (a step every 40 clocks), then another LINE queued.
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 40000, {1000, 1000}, true)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 40000, {1000, 1000}, true)).type, v2::kAck);
  b.run_until_idle(200000);
  ASSERT_FALSE(b.dut().busy);
  EXPECT_EQ(b.dut().fifo_level, 0u) << "the queued LINE was dropped";
  EXPECT_TRUE(b.trip_cycles.empty()) << "an armed switch tripped the hard limit";
  const auto* px = b.first_change(2, true);
  const auto* py = b.first_change(3, true);
  ASSERT_NE(px, nullptr);
  ASSERT_NE(py, nullptr);
  ASSERT_LT(py->edge, px->edge) << "Y reaches its switch first";
  const uint64_t fy = py->edge + 1 + kFilter, fx = px->edge + 1 + kFilter;  // filtered edges
  r = b.report();
  EXPECT_EQ(r.mode, kHome);
  EXPECT_EQ(r.flags, kDone);
  EXPECT_EQ(r.fired, 0x0300u);
  EXPECT_EQ(r.pos[0], b.pos_at(0, fx)) << "X latched at its filtered edge";
  EXPECT_EQ(r.pos[1], b.pos_at(1, fy)) << "Y latched at its filtered edge";
  EXPECT_EQ(b.pins_pos[1], r.pos[1]) << "Y stopped at its switch";
  EXPECT_EQ(b.pins_pos[0], r.pos[0]) << "X stopped at its switch";
  EXPECT_GT(b.pins_pos[0], 300);
  EXPECT_LT(b.pins_pos[0], 1000) << "the segment was dropped";
  int x_after_y = 0;
  for (const auto& rr : b.rises)
    if (rr.axis == 0 && rr.cycle > fy) ++x_after_y;
  EXPECT_GT(x_after_y, 150) << "X went on after Y stopped";
  EXPECT_LE(b.last_rise(), fx + 1) << "a STEP rose after the flush";
  const auto st = b.status();
  EXPECT_EQ(st.u8(1), 0u) << "no fault";
  EXPECT_EQ(st.u8(0) & (kStatePosUntrusted | 0x01), 0u) << "positions trusted, not busy";
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), b.pins_pos[a]) << "axis " << a;
  std::printf(
      "HOME X max at 300, Y max at 120 (filter %llu clocks, a step every 40 clocks): Y latched "
      "%d (pin at edge %llu, filtered %llu), X latched %d (pin %llu, filtered %llu), last STEP "
      "rise %llu, %d X steps after Y stopped\n",
      static_cast<unsigned long long>(kFilter), r.pos[1], static_cast<unsigned long long>(py->edge),
      static_cast<unsigned long long>(fy), r.pos[0], static_cast<unsigned long long>(px->edge),
      static_cast<unsigned long long>(fx), static_cast<unsigned long long>(b.last_rise()),
      x_after_y);
  // A move away from the switches runs.
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 4000, {-20, -20}, true)).type, v2::kAck);
  b.run_until_idle(20000);
  EXPECT_EQ(b.pins_pos[0], r.pos[0] - 20);
  EXPECT_EQ(b.pins_pos[1], r.pos[1] - 20);
}

// A switch that never trips: the move ends, the trigger stays armed; DISARM disarms.
TEST(Trigger, SwitchNeverTrips) {
  TriggerBench b;
  ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0001)).type, v2::kAck);  // X min
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 8000, {200, 100}, true)).type, v2::kAck);
  b.run_until_idle(50000);
  EXPECT_EQ(b.pins_pos[0], 200) << "the move ran to its end";
  EXPECT_EQ(b.pins_pos[1], 100);
  auto r = b.report();
  EXPECT_EQ(r.mode, kHome);
  EXPECT_EQ(r.flags, kArmed) << "still armed, not done";
  EXPECT_EQ(r.fired, 0u);
  ASSERT_EQ(b.exchange(trigger(b.seq++, kDisarm, 0)).type, v2::kAck);
  r = b.report();
  EXPECT_EQ(r.mode, kDisarm);
  EXPECT_EQ(r.flags, 0u);
}

// With a HOME armed on X max, Y max (not armed) still trips the hard limit.
TEST(Trigger, UnarmedSwitchStillTrips) {
  TriggerBench b;
  b.endstop_max[1] = 50;
  ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0100)).type, v2::kAck);  // X max
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 20000, {500, 500}, true)).type, v2::kAck);
  b.run_until_idle(100000);
  ASSERT_EQ(b.trip_cycles.size(), 1u) << "Y max did not trip";
  const auto* py = b.first_change(3, true);
  ASSERT_NE(py, nullptr);
  EXPECT_EQ(b.trip_cycles[0], py->edge + 2 + kFilter) << "trip on edge p + 2 + F";
  const auto st = b.status();
  EXPECT_EQ(st.u8(1), kFaultLimit);
  EXPECT_EQ(st.u8(kLimitByte), 0x11u) << "the alarm names Y max";
  EXPECT_EQ(st.u8(0) & kStatePosUntrusted, kStatePosUntrusted);
  const auto r = b.report();
  EXPECT_EQ(r.flags, kArmed) << "X max never fired";
}

// PROBE (G38.2-like): the plate at X = 400; contact in the middle of the move latches both axes
// at the probe's filtered edge, then the motion stops along the ramp (a CANCEL): the stopping
// distance is measured and checked against the ramp; positions trusted, queue dropped.
TEST(Trigger, ProbeContactStopsAlongTheRamp) {
  TriggerBench b;
  ASSERT_EQ(b.exchange(motion(0, 0x8000, 0x8000, kRamp)).type, v2::kStatus);
  b.probe_rule = [](const int64_t* p) { return p[0] >= 400; };
  ASSERT_EQ(b.exchange(trigger(b.seq++, kProbe, 0)).type, v2::kAck);
  // X +2000, Y +1000 over 100 000 clocks: X 0.02 steps per clock.
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 100000, {2000, 1000}, true)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 100000, {2000, 1000}, true)).type, v2::kAck);
  b.run_until_idle(400000);
  ASSERT_FALSE(b.dut().busy);
  EXPECT_EQ(b.dut().fifo_level, 0u);
  const auto* pc = b.first_change(4, true);
  ASSERT_NE(pc, nullptr);
  const uint64_t f = pc->edge + 1 + kProbeFilter;
  const auto r = b.report();
  EXPECT_EQ(r.mode, kProbe);
  EXPECT_EQ(r.flags, kDone);
  EXPECT_EQ(r.fired, 0u);
  EXPECT_EQ(r.pos[0], b.pos_at(0, f)) << "X latched at the probe's filtered edge";
  EXPECT_EQ(r.pos[1], b.pos_at(1, f)) << "Y latched at the probe's filtered edge";
  // Stopping distance: full speed until the first rate period ends (at most 256 clocks), then
  // 99 periods at r = 1 - k ramp / 2^32 (k = 1..99), then 0: 0.02 * 256 * sum(1 - k / 100) =
  // 253.4 X steps, plus at most 0.02 * 258 from the first, partial period, +-1 for the DDA.
  const int64_t stop_x = b.pins_pos[0] - r.pos[0];
  double expect = 0;
  for (int k = 1; k <= 99; ++k) expect += 0.02 * 256.0 * (1.0 - k * (kRamp / 4294967296.0));
  EXPECT_GE(stop_x, static_cast<int64_t>(expect) - 1) << "stopped faster than the ramp";
  EXPECT_LE(stop_x, static_cast<int64_t>(expect + 0.02 * 258) + 2) << "stopped slower";
  uint64_t stop_clocks = b.last_rise() - f;
  const auto st = b.status();
  EXPECT_EQ(st.u8(1), 0u) << "no fault";
  EXPECT_EQ(st.u8(0) & (kStatePosUntrusted | 0x01 | 0x20), 0u) << "trusted, not busy, no hold";
  EXPECT_EQ(st.u8(0) & kStateProbe, kStateProbe) << "STATUS PROBE: touching";
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), b.pins_pos[a]) << "axis " << a;
  std::printf(
      "PROBE contact at X 400 (filter %llu clocks, X 0.02 steps/clock, ramp 2^32/100 per 256 "
      "clocks): latched X %d Y %d at the filtered edge %llu; X stopped %lld steps further "
      "(ramp model %.1f .. %.1f), last STEP %llu clocks after the edge\n",
      static_cast<unsigned long long>(kProbeFilter), r.pos[0], r.pos[1],
      static_cast<unsigned long long>(f), static_cast<long long>(stop_x), expect,
      expect + 0.02 * 258, static_cast<unsigned long long>(stop_clocks));
}

// The latch clock, exactly: the probe pin rises at every phase of the X step period (50 clocks);
// in every run the latched X equals the STEP rises up to and including the filtered edge's clock f
// (a STEP rising on edge f counts, one rising on f + 1 does not), and the phases include runs with
// a STEP rising on f and runs with one rising on f + 1, so a latch one clock early or late fails.
TEST(Trigger, ProbeLatchClockAtEveryPhase) {
  int on_edge = 0, after_edge = 0;
  for (uint64_t phase = 0; phase < 50; ++phase) {
    TriggerBench b;
    ASSERT_EQ(b.exchange(motion(0, 0x8000, 0x8000, kRamp)).type, v2::kStatus);
    ASSERT_EQ(b.exchange(trigger(b.seq++, kProbe, 0)).type, v2::kAck);
    ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 100000, {2000, 0}, true)).type, v2::kAck);
    b.idle(10000 + phase);
    const uint64_t p = b.cycle() + 1;
    b.dut().probe_in = 1;
    b.run_until_idle(200000);
    const uint64_t f = p + 1 + kProbeFilter;
    const auto r = b.report();
    ASSERT_EQ(r.flags, kDone) << "phase " << phase;
    EXPECT_EQ(r.pos[0], b.pos_at(0, f)) << "phase " << phase;
    if (b.pos_at(0, f) != b.pos_at(0, f - 1)) ++on_edge;
    if (b.pos_at(0, f + 1) != b.pos_at(0, f)) ++after_edge;
  }
  EXPECT_GT(on_edge, 0) << "no run with a STEP rising on the latch clock's edge";
  EXPECT_GT(after_edge, 0) << "no run with a STEP rising on the edge after it";
  std::printf("probe latch over 50 phases: %d runs with a STEP on edge f, %d on edge f + 1\n",
              on_edge, after_edge);
}

// The same for HOME: X max pressed at every phase of the X step period (40 clocks) while X moves
// toward it: latched X = the STEP rises up to edge f, and X stays there (its step in clock f is
// blocked); runs with a STEP rising on edge f are among them.
TEST(Trigger, HomeLatchClockAtEveryPhase) {
  int on_edge = 0;
  for (uint64_t phase = 0; phase < 40; ++phase) {
    TriggerBench b;
    b.model_switches = false;
    ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0100)).type, v2::kAck);
    ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 40000, {1000, 300}, true)).type, v2::kAck);
    b.idle(8000 + phase);
    const uint64_t p = b.cycle() + 1;
    b.dut().limit_max = 1;
    b.run_until_idle(100000);
    const uint64_t f = p + 1 + kFilter;
    const auto r = b.report();
    ASSERT_EQ(r.flags, kDone) << "phase " << phase;
    EXPECT_EQ(r.pos[0], b.pos_at(0, f)) << "phase " << phase;
    EXPECT_EQ(b.pins_pos[0], r.pos[0]) << "phase " << phase;
    EXPECT_TRUE(b.trip_cycles.empty());
    if (b.pos_at(0, f) != b.pos_at(0, f - 1)) ++on_edge;
  }
  EXPECT_GT(on_edge, 0) << "no run with a STEP rising on the latch clock's edge";
}

// PROBE to release (G38.4-like): the probe touches at rest; arming mode 3 and moving off the
// plate latches at the release's filtered edge.
TEST(Trigger, ProbeRelease) {
  TriggerBench b;
  b.probe_rule = [](const int64_t* p) { return p[0] > -150; };  // touching until X < -150
  ASSERT_EQ(b.exchange(motion(0, 0x8000, 0x8000, kRamp)).type, v2::kStatus);
  b.idle(kProbeFilter + 10);
  EXPECT_EQ(b.status().u8(0) & kStateProbe, kStateProbe);
  ASSERT_EQ(b.exchange(trigger(b.seq++, kProbeRelease, 0)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 50000, {-1000, 0}, true)).type, v2::kAck);
  b.run_until_idle(400000);
  const auto* pc = b.first_change(4, false);
  ASSERT_NE(pc, nullptr);
  const uint64_t f = pc->edge + 1 + kProbeFilter;
  const auto r = b.report();
  EXPECT_EQ(r.mode, kProbeRelease);
  EXPECT_EQ(r.flags, kDone);
  EXPECT_EQ(r.pos[0], b.pos_at(0, f));
  EXPECT_LT(r.pos[0], -150);
  EXPECT_GT(b.pins_pos[0], -1000) << "stopped before the end of the move";
  EXPECT_EQ(b.status().u8(0) & kStateProbe, 0u);
}

// A probe that never touches, and one touching already when armed for contact: the moves end,
// the trigger stays armed.
TEST(Trigger, ProbeNeverTouches) {
  TriggerBench b;
  ASSERT_EQ(b.exchange(trigger(b.seq++, kProbe, 0)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 8000, {300, 0}, true)).type, v2::kAck);
  b.run_until_idle(50000);
  EXPECT_EQ(b.pins_pos[0], 300);
  EXPECT_EQ(b.report().flags, kArmed);
  // The probe touching (held) before arming: no edge, nothing fires.
  b.probe_rule = [](const int64_t*) { return true; };
  b.idle(kProbeFilter + 10);
  ASSERT_EQ(b.exchange(trigger(b.seq++, kProbe, 0)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 8000, {-300, 0}, true)).type, v2::kAck);
  b.run_until_idle(50000);
  EXPECT_EQ(b.pins_pos[0], 0);
  EXPECT_EQ(b.report().flags, kArmed);
}

// Probe bounce: pulses shorter than the probe filter while armed and moving do not fire; the
// level held the filter length does, latched at its filtered edge.
TEST(Trigger, ProbeBounceDoesNotFire) {
  TriggerBench b;
  ASSERT_EQ(b.exchange(motion(0, 0x8000, 0x8000, kRamp)).type, v2::kStatus);
  ASSERT_EQ(b.exchange(trigger(b.seq++, kProbe, 0)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 0, 200000, {2000, 0}, true)).type, v2::kAck);
  b.idle(20000);
  ASSERT_TRUE(b.dut().running);
  for (uint64_t len : {uint64_t{1}, uint64_t{20}, kProbeFilter - 1}) {
    b.dut().probe_in = 1;
    b.idle(len);
    b.dut().probe_in = 0;
    b.idle(300);
  }
  EXPECT_EQ(b.report().flags, kArmed) << "a bounce fired the probe";
  ASSERT_TRUE(b.dut().running);
  const uint64_t p = b.cycle() + 1;
  b.dut().probe_in = 1;
  b.run_until_idle(400000);
  const auto r = b.report();
  EXPECT_EQ(r.flags, kDone);
  EXPECT_EQ(r.pos[0], b.pos_at(0, p + 1 + kProbeFilter));
}

// Switch bounce during a HOME: pulses of X max shorter than the switch filter while X moves toward
// it neither fire the trigger nor trip; the level held the filter length fires, latched at its
// filtered edge.
TEST(Trigger, HomeSwitchBounceDoesNotFire) {
  TriggerBench b;
  b.model_switches = false;
  ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0100)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 80000, {2000, 0}, true)).type, v2::kAck);
  b.idle(5000);
  ASSERT_TRUE(b.dut().running);
  for (uint64_t len : {uint64_t{1}, uint64_t{50}, kFilter - 1}) {
    b.dut().limit_max = 1;
    b.idle(len);
    b.dut().limit_max = 0;
    b.idle(200);
  }
  auto r = b.report();
  EXPECT_EQ(r.flags, kArmed) << "a bounce fired the HOME";
  EXPECT_EQ(r.fired, 0u);
  EXPECT_TRUE(b.trip_cycles.empty());
  ASSERT_TRUE(b.dut().running);
  const uint64_t p = b.cycle() + 1;
  b.dut().limit_max = 1;
  b.run_until_idle(200000);
  r = b.report();
  EXPECT_EQ(r.flags, kDone);
  EXPECT_EQ(r.pos[0], b.pos_at(0, p + 1 + kFilter));
  EXPECT_EQ(b.pins_pos[0], r.pos[0]);
  EXPECT_TRUE(b.trip_cycles.empty());
}

// SET_POSITION: sets the counters (STATUS, the travel check's queued end), refused while busy,
// clears POS_UNTRUSTED after a hard-limit trip.
TEST(Trigger, SetPosition) {
  TriggerBench b;
  auto a = b.exchange(set_position(b.seq++, 0x0003, 1000, -5));
  ASSERT_EQ(a.type, v2::kAck);
  auto st = b.status();
  EXPECT_EQ(static_cast<int32_t>(st.u32(9)), 1000);
  EXPECT_EQ(static_cast<int32_t>(st.u32(13)), -5);
  // Only Y.
  ASSERT_EQ(b.exchange(set_position(b.seq++, 0x0002, 77, 12)).type, v2::kAck);
  st = b.status();
  EXPECT_EQ(static_cast<int32_t>(st.u32(9)), 1000) << "X not in the mask";
  EXPECT_EQ(static_cast<int32_t>(st.u32(13)), 12);
  // The travel check starts from the new position: X travel [0, 1100].
  ASSERT_EQ(b.exchange(v2::config_travel(b.seq++, 0, true, 0, 1100)).type, v2::kAck);
  a = b.exchange(v2::line(b.seq, 0, 0, 8000, {200, 0}, true));
  ASSERT_EQ(a.type, v2::kNak);
  EXPECT_EQ(a.u8(1), v2::kTravel) << "1000 + 200 leaves [0, 1100]";
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 8000, {50, 0}, true)).type, v2::kAck);
  // Busy: refused, nothing changed.
  b.idle(1000);
  ASSERT_TRUE(b.dut().busy);
  a = b.exchange(set_position(b.seq, 0x0001, 0, 0));
  ASSERT_EQ(a.type, v2::kNak);
  EXPECT_EQ(a.u8(1), spec::kNakBusy);
  b.run_until_idle(50000);
  st = b.status();
  EXPECT_EQ(static_cast<int32_t>(st.u32(9)), 1050) << "the refused SET_POSITION changed X";
  EXPECT_EQ(b.pins_pos[0], 50);
  // A hard-limit trip, release, FAULT_CLEAR: still not trusted; SET_POSITION trusts again.
  b.endstop_max[1] = 12 + 30;
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 8000, {0, 100}, true)).type, v2::kAck);
  b.run_until_idle(100000);
  ASSERT_EQ(b.trip_cycles.size(), 1u);
  b.endstop_max[1] = kNone;
  b.idle(kFilter + 10);
  ASSERT_EQ(b.exchange(v2::fault_clear(b.seq++)).type, v2::kAck);
  st = b.status();
  EXPECT_EQ(st.u8(1), 0u);
  EXPECT_EQ(st.u8(0) & kStatePosUntrusted, kStatePosUntrusted);
  ASSERT_EQ(b.exchange(set_position(b.seq++, 0x0003, 0, 0)).type, v2::kAck);
  st = b.status();
  EXPECT_EQ(st.u8(0) & kStatePosUntrusted, 0u) << "SET_POSITION did not trust the positions";
  EXPECT_EQ(st.u32(9), 0u);
  EXPECT_EQ(st.u32(13), 0u);
}

// The worked frames of docs/protocol.md (CRCs computed there by an independent bit-serial
// CRC-16/CCITT-FALSE) are the frames this bench sends, and the device takes them.
TEST(Trigger, DocumentedFrames) {
  EXPECT_EQ(v2::hex(trigger(5, kHome, 0x0300)), "A5 03 05 0A 01 03 00 E9 6F");
  EXPECT_EQ(v2::hex(trigger(6, kProbe, 0)), "A5 03 06 0A 02 00 00 0B BE");
  EXPECT_EQ(v2::hex(set_position(7, 0x0003, 0, -10)),
            "A5 0A 07 0B 00 03 00 00 00 00 FF FF FF F6 5E 0D");
  EXPECT_EQ(v2::hex(v2::frame(spec::kTypeTriggerQuery, 0, {})), "A5 00 00 0C 0D 10");
  TriggerBench b;
  while (b.seq < 5) ASSERT_EQ(b.exchange(v2::dwell(b.seq++, 10)).type, v2::kAck);
  ASSERT_EQ(b.exchange(trigger(5, kHome, 0x0300)).type, v2::kAck);
  EXPECT_EQ(b.report().flags, kArmed);
  ASSERT_EQ(b.exchange(trigger(6, kProbe, 0)).type, v2::kAck);
  EXPECT_EQ(b.report().mode, kProbe);
  ASSERT_EQ(b.exchange(set_position(7, 0x0003, 0, -10)).type, v2::kAck);
  EXPECT_EQ(static_cast<int32_t>(b.status().u32(13)), -10);
}

// Bad frames: reserved modes, masks beyond N_AXES, masks where none belongs, wrong lengths. A
// TRIGGER lost on the wire makes the LINE after it OUT_OF_ORDER.
TEST(Trigger, BadFramesAreRefused) {
  TriggerBench b;
  const auto nak = [&](const std::vector<uint8_t>& f, uint8_t reason) {
    const auto m = b.exchange(f);
    EXPECT_EQ(m.type, v2::kNak) << v2::hex(f);
    EXPECT_EQ(m.u8(1), reason) << v2::hex(f);
  };
  nak(trigger(b.seq, 4, 0), v2::kBadField);           // mode 4
  nak(trigger(b.seq, 0x81, 0), v2::kBadField);        // reserved bits
  nak(trigger(b.seq, kHome, 0), v2::kBadField);       // HOME without switches
  nak(trigger(b.seq, kHome, 0x0004), v2::kBadField);  // axis 2 min (2 axes)
  nak(trigger(b.seq, kHome, 0x0400), v2::kBadField);  // axis 2 max
  nak(trigger(b.seq, kProbe, 0x0001), v2::kBadField);
  nak(trigger(b.seq, kDisarm, 0x0100), v2::kBadField);
  nak(set_position(b.seq, 0, 1, 1), v2::kBadField);
  nak(set_position(b.seq, 0x0004, 1, 1), v2::kBadField);
  nak(set_position(b.seq, 0x8001, 1, 1), v2::kBadField);
  nak(v2::frame(spec::kTypeTrigger, b.seq, {1, 0}), v2::kBadLength);
  nak(v2::frame(spec::kTypeSetPosition, b.seq, {0, 1, 0, 0, 0, 0}), v2::kBadLength);
  nak(v2::frame(spec::kTypeTriggerQuery, 0, {0}), v2::kBadLength);
  EXPECT_EQ(b.report().flags, 0u) << "a refused TRIGGER armed";
  EXPECT_EQ(b.status().u32(9), 0u) << "a refused SET_POSITION wrote";
  // A TRIGGER with a bad CRC: NAK BAD_CRC; the LINE after it (next SEQ) is OUT_OF_ORDER.
  auto f = trigger(b.seq, kHome, 0x0100);
  f.back() ^= 0x01;
  nak(f, v2::kBadCrc);
  nak(v2::line(static_cast<uint8_t>(b.seq + 1), 0, 0, 8000, {100, 0}, true), v2::kOutOfOrder);
  EXPECT_FALSE(b.dut().busy) << "a move ran unarmed";
  ASSERT_EQ(b.exchange(trigger(b.seq++, kHome, 0x0100)).type, v2::kAck);
  EXPECT_EQ(b.report().flags, kArmed);
}

}  // namespace
