// Hard limits through cnc_core's pins (docs/machine.md): a 2-axis core (full-2axis) at 3 Mbaud
// with all four switches enabled, X min active low (its pin idles high), the others active high,
// and a debounce of kFilter clocks. Bouncing switch pins filtered to the clock (input_filter);
// a limit hit in the middle of a LINE and of an ARC: no STEP rising edge after the trip clock,
// none toward the switch after the filtered edge, the latency printed; laser low, FIFO flushed,
// positions kept (STATUS positions = STEP edges counted at the pins); the alarm names the switch
// in STATUS; FAULT_CLEAR while the switch is held does not clear, after the release it does;
// the positions-not-trusted bit stays; a step toward a switch already asserted trips without a
// STEP edge, a move away from it runs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "Vcnc_core_machine.h"
#include "common/machine_pins.h"
#include "common/pin_harness.h"
#include "common/v2_core_bench.h"
#include "common/v2_frames.h"
#include "fpgacnc/models/arc_walk.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
namespace arc = fpgacnc::models::arc;
using Model = Vcnc_core_machine;

constexpr int kAxes = 2;
constexpr uint64_t kFilter = 500;  // LIMIT_FILTER_CLKS of this build (tb/limits.cmake)
// The bound of docs/machine.md: a pin level first sampled on edge p is the filtered level from
// edge p + 1 + F; a STEP may still rise on the next edge (another axis, or away from the switch),
// and the alarm is latched on that edge too: no STEP rising edge after edge p + 2 + F.
constexpr uint64_t kFilteredAfter = 1 + kFilter;
constexpr uint64_t kTripAfter = 2 + kFilter;
constexpr uint8_t kStatePosUntrusted = fpgacnc::spec::kStatePosUntrusted;
constexpr uint8_t kFaultLimit = fpgacnc::spec::kFaultLimit;
// STATUS offsets for 2 axes (docs/protocol.md): limit byte, then the switch states u16.
constexpr size_t kLimitByte = 9 + 4 * kAxes + 18;
constexpr size_t kSwitches = kLimitByte + 1;

using Rise = fpgacnc::tb::StepRise;

class LimitBench : public fpgacnc::tb::V2CoreBench<Model, kAxes> {
 public:
  LimitBench() : V2CoreBench(fpgacnc::tb::kMachinePins) {}
  std::vector<uint64_t> state_changes, laser_falls;
  int short_pulses = 0;

  v2::DeviceMsg status() {
    const auto m = V2CoreBench::status();
    EXPECT_EQ(m.payload.size(), size_t{30 + 4 * kAxes + 16});
    return m;
  }

 protected:
  void observe_more() override {
    const Model& m = dut();
    for (int a = 0; a < kAxes; ++a) {
      const bool s = (m.step >> a) & 1u;
      if (s && !((step_prev_ >> a) & 1u)) rose_at_[a] = cycle();
      // Every STEP pulse keeps its high time (5 clocks), a trip included.
      if (!s && ((step_prev_ >> a) & 1u) && cycle() - rose_at_[a] != 5) ++short_pulses;
    }
    step_prev_ = m.step;
    if (m.limit_state != lstate_prev_) state_changes.push_back(cycle());
    lstate_prev_ = m.limit_state;
    if (!m.laser && laser_prev_) laser_falls.push_back(cycle());
    laser_prev_ = m.laser;
  }

 private:
  uint32_t step_prev_ = 0;
  bool laser_prev_ = false;
  uint32_t lstate_prev_ = 0;
  uint64_t rose_at_[kAxes] = {0, 0};
};

void put(std::vector<uint8_t>& b, uint64_t v, int bytes) {
  for (int k = bytes - 1; k >= 0; --k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
}

// An XY ARC frame at a constant tangential speed v steps per clock (docs/protocol.md "ARC").
std::vector<uint8_t> arc_frame(uint8_t seq, const arc::Geometry& g, double v) {
  const arc::Plan p = arc::plan(g);
  EXPECT_TRUE(p.ok);
  const uint64_t vc = arc::to_fixed48(v * arc::cost_per_step(g, p.c_total));
  std::vector<uint8_t> b{static_cast<uint8_t>(g.ccw ? 3 : 2), 255};
  for (int32_t c : {g.i, g.j, g.dx, g.dy}) put(b, static_cast<uint32_t>(c) & 0xFFFFFFu, 3);
  put(b, 0, 4);  // DZ
  put(b, p.n_ramp, 3);
  put(b, p.c_total, 6);
  put(b, vc, 8);
  put(b, vc, 8);
  put(b, vc, 8);
  put(b, 1, 6);          // A
  put(b, p.c_total, 6);  // D: no deceleration
  return v2::frame(v2::kArc, seq, b);
}

// The pins of the filtered state: bit a min of axis a, bit 2 + a max.
uint32_t state(LimitBench& b) {
  return b.dut().limit_state;
}

// A bounce shorter than the filter never reaches the filtered level; a level held exactly
// kFilter clocks does, on the clock the contract gives; release the same way. X min (active
// low) and Y max (active high). The machine is idle: no alarm.
TEST(Limits, BouncingSwitchIsFiltered) {
  LimitBench b;
  EXPECT_EQ(state(b), 0u) << "X min released (pin high), the others released (pin low)";
  // Bounces on Y max: 1, 7, 100 and kFilter - 1 clocks high, each followed by 50 clocks low.
  for (uint64_t len : {uint64_t{1}, uint64_t{7}, uint64_t{100}, kFilter - 1}) {
    b.dut().limit_max = 2;
    b.idle(len);
    b.dut().limit_max = 0;
    b.idle(50);
  }
  b.idle(kFilter + 10);
  EXPECT_TRUE(b.state_changes.empty()) << "a bounce shorter than the filter got through";
  // Held exactly kFilter clocks: accepted. The pin is first sampled on the next edge p.
  const uint64_t p = b.cycle() + 1;
  b.dut().limit_max = 2;
  b.idle(kFilter);
  b.dut().limit_max = 0;
  b.idle(5);
  ASSERT_EQ(b.state_changes.size(), 1u) << "a level held kFilter clocks was rejected";
  EXPECT_EQ(b.state_changes[0], p + kFilteredAfter) << "filtered edge, clocks after the pin";
  EXPECT_EQ(state(b), 0x8u) << "Y max asserted (the pin went back low: still inside the filter)";
  b.idle(kFilter);
  ASSERT_EQ(b.state_changes.size(), 2u) << "the release after kFilter clocks low";
  EXPECT_EQ(b.state_changes[1], p + kFilter + kFilteredAfter) << "the release, filtered";
  EXPECT_EQ(state(b), 0u);
  // X min, active low: the pin going low asserts it; a release bounce of kFilter - 1 clocks
  // is filtered (the level stays asserted).
  const uint64_t p2 = b.cycle() + 1;
  b.dut().limit_min = 0;
  b.idle(kFilter + 5);
  ASSERT_EQ(b.state_changes.size(), 3u);
  EXPECT_EQ(b.state_changes[2], p2 + kFilteredAfter);
  EXPECT_EQ(state(b), 0x1u) << "X min asserted with its pin low";
  b.dut().limit_min = 1;
  b.idle(kFilter - 1);
  b.dut().limit_min = 0;
  b.idle(kFilter + 5);
  EXPECT_EQ(b.state_changes.size(), 3u) << "a release bounce got through";
  const auto st = b.status();
  EXPECT_EQ(st.u16(kSwitches), 0x0001u) << "STATUS switch states: X min";
  EXPECT_EQ(st.u8(1) & kFaultLimit, 0u) << "no alarm while idle";
  EXPECT_EQ(st.u8(0) & kStatePosUntrusted, 0u);
  EXPECT_TRUE(b.trip_cycles.empty());
  std::printf("filter: pin to filtered level %llu clocks (LIMIT_FILTER_CLKS %llu)\n",
              static_cast<unsigned long long>(kFilteredAfter),
              static_cast<unsigned long long>(kFilter));
}

// A limit hit in the middle of a LINE: stops within the bound, laser low, FIFO flushed, the
// alarm names X max; FAULT_CLEAR while held does not clear; after the release it does.
TEST(Limits, LineStopsAtLimitAndClearsOnlyWhenReleased) {
  LimitBench b;
  // LINE X +4000, Y +3000 over 40 000 clocks (X at the fastest period the step timing allows,
  // 10 clocks), laser at power 200, then two more behind it.
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 200, 40000, {4000, 3000}, true)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 200, 20000, {300, 300}, true)).type, v2::kAck);
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 1, 200, 20000, {300, 300}, true)).type, v2::kAck);
  b.idle(20000);
  ASSERT_TRUE(b.dut().running) << "the first LINE runs";
  ASSERT_TRUE(b.dut().laser);
  const size_t before = b.rises.size();
  ASSERT_GT(before, 100u);
  const uint64_t p = b.cycle() + 1;
  b.dut().limit_max = 1;  // X max pressed
  b.idle(kFilter + 2000);
  ASSERT_EQ(b.trip_cycles.size(), 1u) << "no trip";
  const uint64_t trip = b.trip_cycles[0];
  EXPECT_EQ(trip, p + kTripAfter) << "alarm latched on edge p + 2 + F";
  EXPECT_LE(b.last_rise(), trip) << "a STEP rose after the trip";
  for (const auto& r : b.rises) {
    if (r.axis == 0 && r.dir) {
      EXPECT_LE(r.cycle, p + kFilteredAfter) << "X stepped into X max";
    }
  }
  ASSERT_FALSE(b.laser_falls.empty());
  EXPECT_EQ(b.laser_falls.back(), trip) << "laser low with the alarm";
  EXPECT_FALSE(b.dut().busy) << "executor, prep and FIFO dropped everything";
  EXPECT_EQ(b.dut().fifo_level, 0u);
  std::printf(
      "LINE stop (filter %llu clocks, %zu STEP rises before): switch pin first sampled "
      "on edge p, filtered level on p + %llu, alarm latched on p + %llu, last STEP rise "
      "on p + %llu\n",
      static_cast<unsigned long long>(kFilter), before,
      static_cast<unsigned long long>(kFilteredAfter), static_cast<unsigned long long>(trip - p),
      static_cast<unsigned long long>(b.last_rise() - p));

  auto st = b.status();
  EXPECT_EQ(st.u8(1), kFaultLimit) << "faults: LIMIT only";
  EXPECT_EQ(st.u8(0) & (kStatePosUntrusted | 0x04), kStatePosUntrusted | 0x04);
  EXPECT_EQ(st.u8(kLimitByte), 0x10u) << "the alarm names X max";
  EXPECT_EQ(st.u16(kSwitches), 0x0100u) << "switch states: X max";
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), b.pins_pos[a])
        << "position kept = STEP edges at the pins, axis " << a;
  EXPECT_LT(b.pins_pos[0], 4000) << "stopped in the middle";
  EXPECT_EQ(b.short_pulses, 0) << "a STEP pulse was cut below its high time";

  // FAULT_CLEAR while the switch is held: the alarm stays, nothing moves.
  ASSERT_EQ(b.exchange(v2::fault_clear(b.seq++)).type, v2::kAck);
  b.idle(100);
  st = b.status();
  EXPECT_EQ(st.u8(1), kFaultLimit) << "cleared while the switch is held";
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 5000, {-50, 0}, true)).type, v2::kAck);
  b.idle(8000);
  EXPECT_LE(b.last_rise(), trip) << "moved while the alarm is latched";
  // Released, filtered, then FAULT_CLEAR: cleared; positions still not trusted.
  b.dut().limit_max = 0;
  b.idle(kFilter + 10);
  ASSERT_EQ(b.exchange(v2::fault_clear(b.seq++)).type, v2::kAck);
  b.idle(100);
  st = b.status();
  EXPECT_EQ(st.u8(1), 0u) << "not cleared after the release";
  EXPECT_EQ(st.u8(0) & kStatePosUntrusted, kStatePosUntrusted) << "positions trusted again";
  EXPECT_EQ(st.u8(kLimitByte), 0x10u) << "the last trip is still named";
  EXPECT_EQ(st.u16(kSwitches), 0u);
  // Motion again: a LINE away from the switch runs to its end.
  const int64_t x0 = b.pins_pos[0];
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 5000, {-100, 0}, true)).type, v2::kAck);
  b.run_until_idle(20000);
  EXPECT_EQ(b.pins_pos[0], x0 - 100);
  EXPECT_EQ(b.trip_cycles.size(), 1u);
}

// A limit hit in the middle of an ARC (X min, active low: its pin goes low).
TEST(Limits, ArcStopsAtLimit) {
  LimitBench b;
  // A full circle of radius 400 steps about (0, -400) from the origin, CCW, 0.02 steps/clock.
  const arc::Geometry g{0, -400, 0, 0, true};
  ASSERT_EQ(b.exchange(arc_frame(b.seq++, g, 0.02)).type, v2::kAck);
  b.idle(60000);
  ASSERT_TRUE(b.dut().running) << "the arc runs";
  const size_t before = b.rises.size();
  ASSERT_GT(before, 200u);
  const uint64_t p = b.cycle() + 1;
  b.dut().limit_min = 0;  // X min pressed (pin low)
  b.idle(kFilter + 3000);
  ASSERT_EQ(b.trip_cycles.size(), 1u);
  const uint64_t trip = b.trip_cycles[0];
  EXPECT_EQ(trip, p + kTripAfter);
  EXPECT_LE(b.last_rise(), trip) << "a STEP rose after the trip";
  for (const auto& r : b.rises) {
    if (r.axis == 0 && !r.dir) {
      EXPECT_LE(r.cycle, p + kFilteredAfter) << "X stepped into X min";
    }
  }
  EXPECT_FALSE(b.dut().busy);
  EXPECT_EQ(b.short_pulses, 0) << "a STEP pulse was cut below its high time";
  const auto st = b.status();
  EXPECT_EQ(st.u8(1), kFaultLimit);
  EXPECT_EQ(st.u8(kLimitByte), 0x00u) << "the alarm names X min";
  EXPECT_EQ(st.u16(kSwitches), 0x0001u);
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), b.pins_pos[a]) << "axis " << a;
  std::printf(
      "ARC stop (filter %llu clocks, %zu STEP rises before): switch pin first sampled "
      "on edge p, filtered level on p + %llu, alarm latched on p + %llu, last STEP rise "
      "on p + %llu\n",
      static_cast<unsigned long long>(kFilter), before,
      static_cast<unsigned long long>(kFilteredAfter), static_cast<unsigned long long>(trip - p),
      static_cast<unsigned long long>(b.last_rise() - p));
}

// A switch asserted while idle is no alarm; a move away from it runs; the first step toward it
// trips without a STEP edge.
TEST(Limits, StepTowardAssertedSwitchTrips) {
  LimitBench b;
  b.dut().limit_max = 2;  // Y max pressed while idle
  b.idle(kFilter + 10);
  EXPECT_TRUE(b.trip_cycles.empty()) << "an alarm while idle";
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 4000, {0, -100}, true)).type, v2::kAck);
  b.run_until_idle(20000);
  EXPECT_EQ(b.pins_pos[1], -100) << "the move away from Y max";
  EXPECT_TRUE(b.trip_cycles.empty());
  const size_t n = b.rises.size();
  ASSERT_EQ(b.exchange(v2::line(b.seq++, 0, 0, 4000, {40, 100}, true)).type, v2::kAck);
  b.idle(6000);
  ASSERT_EQ(b.trip_cycles.size(), 1u);
  for (size_t k = n; k < b.rises.size(); ++k)
    EXPECT_NE(b.rises[k].axis, 1) << "Y stepped toward its asserted max switch";
  EXPECT_LE(b.last_rise(), b.trip_cycles[0]);
  const auto st = b.status();
  EXPECT_EQ(st.u8(1), kFaultLimit);
  EXPECT_EQ(st.u8(kLimitByte), 0x11u) << "the alarm names Y max";
  EXPECT_EQ(static_cast<int32_t>(st.u32(13)), -100) << "Y position";
}

}  // namespace
