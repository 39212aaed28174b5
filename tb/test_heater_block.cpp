// heater_block benches (docs/heater.md): the Verilated block (SAMPLE_CLKS 4096: one simulated
// second per 4096 clocks, PWM period 1024 clocks) in a loop with the plant models of
// models/include/fpgacnc/models/thermal_plant.h through the LTC2308 pin model: at each sample tick
// the plant advances one second with the duty the heater pin actually had over the last second
// (high clocks / 4096), the sensor reading is updated (bed: 1 s old) and the ADC master converts
// its thermistor voltage. Frames go straight into the block's frame port (the decoder is tested
// elsewhere).
//   Safety: every fault injected (sensor open, sensor short, heater disconnected during warm-up,
//   runaway while holding, host silent, e-stop): heater pin low within the documented time, fault
//   latched and in the status bytes, nothing restarts until FAULT_CLEAR and a new setpoint.
//   Closed loop: bed 20 -> 60 -> 85 degC with both tunings of heater.md; hot end 20 -> 200 degC.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "Vheater_block.h"
#include "fpgacnc/models/ltc2308_model.h"
#include "fpgacnc/models/pid_ref.h"
#include "fpgacnc/models/thermal_plant.h"
#include "fpgacnc/spec.h"
#include "verilated.h"

namespace {

using namespace fpgacnc;
namespace th = fpgacnc::models::thermal;

constexpr uint64_t kSampleClks = fpgacnc::spec::kBenchSampleClks;
constexpr int kPwmBits = 10;
// Documented reaction time (docs/heater.md): a MINTEMP/MAXTEMP reading taken at a sample tick
// drives the pin low 636 clocks after the tick strobe (ADC 619, two lookups, eval, PWM register).
constexpr uint64_t kTickToLow = 636;

enum : uint8_t { kCfg = 0x20, kSet = 0x21, kTab = 0x22, kSafe = 0x23, kWd = 0x24 };

struct Be {
  std::vector<uint8_t> b;
  Be& u8(int v) {
    b.push_back(static_cast<uint8_t>(v));
    return *this;
  }
  Be& u16(int v) {
    b.push_back(static_cast<uint8_t>((v >> 8) & 0xFF));
    b.push_back(static_cast<uint8_t>(v & 0xFF));
    return *this;
  }
  Be& u32(uint32_t v) {
    u16(static_cast<int>(v >> 16));
    return u16(static_cast<int>(v & 0xFFFF));
  }
};

class HeatBench {
 public:
  HeatBench()
      : ctx_(std::make_unique<VerilatedContext>()), m(std::make_unique<Vheater_block>(ctx_.get())) {
    adc.source = [this](int ch) {
      if (ch == 0) return open_[0] ? 3.3 : short_[0] ? 0.0 : therm.voltage(reading[0]);
      if (ch == 1) return open_[1] ? 3.3 : short_[1] ? 0.0 : therm.voltage(reading[1]);
      return 0.0;
    };
    m->frame_wr = 0;
    m->frame_ok = 0;
    m->fault_clear = 0;
    m->estop = 0;
    m->rst = 1;
    clock();
    clock();
    m->rst = 0;
    clock();
  }
  ~HeatBench() { m->final(); }

  void clock() {
    m->adc_sdo = static_cast<uint8_t>(sdo_);
    m->clk = 0;
    m->eval();
    m->clk = 1;
    m->eval();
    ++cycle;
    sdo_ = adc.tick(m->adc_convst, m->adc_sck, m->adc_sdi);
    for (int c = 0; c < 2; ++c) high_[c] += (m->heater >> c) & 1;
    if (m->tick) on_tick();
    if (m->sample_done) ++evals;
    if (per_clock) per_clock();
  }
  void run_clocks(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) clock();
  }
  void run_seconds(double s) { run_clocks(static_cast<uint64_t>(s * kSampleClks)); }

  void frame(uint8_t type, const std::vector<uint8_t>& pay) {
    m->frame_type = type;
    m->frame_len = static_cast<uint8_t>(pay.size());
    for (int w = 0; w < 5; ++w) m->frame_data[w] = 0;
    for (size_t i = 0; i < pay.size(); ++i)
      m->frame_data[i / 4] |= static_cast<uint32_t>(pay[i]) << (8 * (i % 4));
    m->frame_wr = 1;
    m->frame_ok = 1;
    clock();
    m->frame_wr = 0;
    m->frame_ok = 0;
    for (int i = 0; i < 12; ++i) clock();  // a table frame writes its entries
  }
  void load_table(int ch) {
    const th::Table t = th::thermistor_table(therm);
    for (int first = 0; first < th::kTableEntries; first += 8) {
      Be p;
      p.u8(ch).u8(first);
      for (int i = first; i < std::min(first + 8, th::kTableEntries); ++i)
        p.u16(t[static_cast<size_t>(i)]);
      frame(kTab, p.b);
    }
  }
  void config(int ch, th::HeatMode mode, const th::PidCoeffs& c) {
    Be p;
    p.u8(ch)
        .u8(static_cast<int>(mode))
        .u32(th::to_q8_24(c.kp))
        .u32(th::to_q8_24(c.ki))
        .u32(th::to_q8_24(c.kd));
    p.u16(th::to_q1_15(c.umax)).u16(th::to_u_q4(c.hyst)).u16(th::to_q1_15(c.manual));
    frame(kCfg, p.b);
  }
  void setpoint(int ch, double c) { frame(kSet, Be().u8(ch).u16(th::to_q4(c)).b); }
  void safety(int ch, double tmin, double tmax, double band, int rperiod, double wrise,
              int wperiod) {
    frame(kSafe, Be().u8(ch)
                     .u16(th::to_q4(tmin))
                     .u16(th::to_q4(tmax))
                     .u16(th::to_u_q4(band))
                     .u16(rperiod)
                     .u16(th::to_u_q4(wrise))
                     .u16(wperiod)
                     .b);
  }
  void fault_clear() {
    m->fault_clear = 1;
    clock();
    m->fault_clear = 0;
    clock();
  }

  // Status bytes of channel ch (8 bytes, see docs/protocol.md).
  uint64_t status(int ch) const {
    const uint64_t lo = m->heat_status[0] | (uint64_t{m->heat_status[1]} << 32);
    const uint64_t hi = m->heat_status[2] | (uint64_t{m->heat_status[3]} << 32);
    return ch == 0 ? hi : lo;
  }
  double status_temp(int ch) const { return static_cast<int16_t>(status(ch) >> 48) / 16.0; }
  int status_duty(int ch) const { return static_cast<int>((status(ch) >> 16) & 0xFFFF); }
  int status_mode(int ch) const { return static_cast<int>((status(ch) >> 8) & 0xFF); }
  int status_faults(int ch) const { return static_cast<int>(status(ch) & 0xFF); }
  bool pin(int ch) const { return (m->heater >> ch) & 1; }

  th::Thermistor therm;
  models::Ltc2308Model adc{50e6};
  th::BedPlant bed;
  th::HotEndPlant hot;
  th::DelayedSensor bed_sensor{1, 20.0};
  double reading[2] = {20.0, 20.0};  // what each thermistor sees now
  double duty[2] = {0.0, 0.0};       // duty over the last second
  bool disconnect[2] = {false, false};
  bool open_[2] = {false, false}, short_[2] = {false, false};
  uint64_t cycle = 0, evals = 0, ticks = 0;
  std::function<void()> per_clock;
  std::function<void()> per_tick;

 private:
  void on_tick() {
    ++ticks;
    for (int c = 0; c < 2; ++c) {
      duty[c] = static_cast<double>(high_[c]) / kSampleClks;
      high_[c] = 0;
    }
    hot.step(1.0, disconnect[0] ? 0.0 : duty[0]);
    bed.step(1.0, disconnect[1] ? 0.0 : duty[1]);
    reading[0] = hot.temperature();
    reading[1] = bed_sensor.sample(bed.temperature());
    if (per_tick) per_tick();
  }

  std::unique_ptr<VerilatedContext> ctx_;

 public:
  std::unique_ptr<Vheater_block> m;

 private:
  int sdo_ = 0;
  uint64_t high_[2] = {0, 0};
};

// ------------------------------------------------------------------------------------ safety
// Arms a channel in manual mode at full duty (pin high all the time) with only min/max checks,
// so the reaction time from the fault to the pin going low is visible on the pin.
void manual_full(HeatBench& b, int ch) {
  b.load_table(ch);
  th::PidCoeffs c;
  c.manual = 1.0;
  b.config(ch, th::HeatMode::kManual, c);
  b.safety(ch, 5.0, ch == 0 ? 275.0 : 120.0, 4.0, 0, 2.0, 0);
  b.setpoint(ch, 50.0);
  b.run_seconds(2.5);
  ASSERT_TRUE(b.pin(ch)) << "manual 100 %: pin high";
}

// Runs until the pin goes low; returns the clocks from `from` to that clock.
uint64_t clocks_until_low(HeatBench& b, int ch, uint64_t from, uint64_t limit) {
  while (b.pin(ch)) {
    b.clock();
    if (b.cycle - from > limit) {
      ADD_FAILURE() << "pin still high " << limit << " clocks after the fault";
      break;
    }
  }
  return b.cycle - from;
}

// After a fault: the pin stays low for `seconds`, the fault stays latched, a FAULT_CLEAR alone
// does not restart the heater, a setpoint after the clear does (when the cause is gone).
void expect_latched_until_cleared(HeatBench& b, int ch, int bit,
                                  const std::function<void()>& remove_cause) {
  uint64_t high = 0;
  b.per_clock = [&] { high += b.pin(ch); };
  b.run_seconds(20);
  EXPECT_EQ(high, 0u) << "the pin rose again before the fault was cleared";
  EXPECT_EQ(b.status_faults(ch) & (1 << bit), 1 << bit)
      << "fault bit " << bit << " latched in STATUS";
  EXPECT_EQ(b.status_duty(ch), 0) << "STATUS duty 0 while faulted";
  EXPECT_EQ(b.status_mode(ch) & 0x80, 0) << "channel disabled";
  remove_cause();
  b.setpoint(ch, 50.0);  // a setpoint while the fault is latched does not enable
  b.run_seconds(3);
  EXPECT_EQ(high, 0u) << "a setpoint before FAULT_CLEAR restarted the heater";
  b.fault_clear();
  b.run_seconds(3);
  EXPECT_EQ(high, 0u) << "FAULT_CLEAR alone restarted the heater";
  EXPECT_EQ(b.status_faults(ch), 0) << "fault cleared";
  b.setpoint(ch, 50.0);
  b.run_seconds(3);
  EXPECT_GT(high, 0u) << "a setpoint after FAULT_CLEAR restarts the heater";
  b.per_clock = nullptr;
}

TEST(HeaterSafety, SensorOpenTripsMintemp) {
  HeatBench b;
  manual_full(b, 0);
  b.open_[0] = true;  // the next conversion reads 3.3 V
  uint64_t t_tick = 0;
  while (t_tick == 0) {
    b.clock();
    if (b.m->tick) t_tick = b.cycle;
  }
  const uint64_t dt = clocks_until_low(b, 0, t_tick, 5000);
  std::printf("sensor open: heater low %llu clocks after the sample tick (documented <= %llu)\n",
              static_cast<unsigned long long>(dt), static_cast<unsigned long long>(kTickToLow));
  EXPECT_LE(dt, kTickToLow);
  EXPECT_NEAR(b.status_temp(0), -56.7, 0.2) << "an open sensor reads an impossible temperature";
  expect_latched_until_cleared(b, 0, 0, [&] { b.open_[0] = false; });
}

TEST(HeaterSafety, SensorShortTripsMaxtemp) {
  HeatBench b;
  manual_full(b, 1);
  b.short_[1] = true;
  uint64_t t_tick = 0;
  while (t_tick == 0) {
    b.clock();
    if (b.m->tick) t_tick = b.cycle;
  }
  const uint64_t dt = clocks_until_low(b, 1, t_tick, 5000);
  std::printf("sensor short: heater low %llu clocks after the sample tick (documented <= %llu)\n",
              static_cast<unsigned long long>(dt), static_cast<unsigned long long>(kTickToLow));
  EXPECT_LE(dt, kTickToLow);
  EXPECT_EQ(b.status_temp(1), 500.0);
  expect_latched_until_cleared(b, 1, 1, [&] { b.short_[1] = false; });
}

TEST(HeaterSafety, DisconnectedHeaterTripsHeatingWatch) {
  HeatBench b;
  b.load_table(0);
  b.config(0, th::HeatMode::kPid, th::pid_coeffs(1.2, 24.0, 1.0, 1.0, 24.0));
  b.safety(0, 5.0, 275.0, 4.0, 40, 2.0, 20);
  b.disconnect[0] = true;  // the pin toggles, the plant gets nothing
  b.setpoint(0, 200.0);
  const uint64_t t_set = b.cycle;
  uint64_t t_fault = 0;
  b.per_clock = [&] {
    if (t_fault == 0 && (b.status_faults(0) & 8)) t_fault = b.cycle;
  };
  b.run_seconds(25);
  b.per_clock = nullptr;
  ASSERT_NE(t_fault, 0u) << "no HEATING fault 25 s after the setpoint";
  const double s = static_cast<double>(t_fault - t_set) / kSampleClks;
  std::printf(
      "heater disconnected: HEATING fault %.3f s after the setpoint (watch 2 degC in 20 s)\n", s);
  EXPECT_GT(s, 20.0);  // armed on the first sample after the setpoint, fault on the 20th after
  EXPECT_LT(s, 21.0 + 700.0 / kSampleClks);  // + the eval latency
  EXPECT_FALSE(b.pin(0));
  expect_latched_until_cleared(b, 0, 3, [&] { b.disconnect[0] = false; });
}

TEST(HeaterSafety, RunawayWhileHolding) {
  HeatBench b;
  b.load_table(0);
  b.config(0, th::HeatMode::kPid, th::pid_coeffs(1.2, 24.0, 1.0, 1.0, 24.0));
  b.safety(0, 5.0, 275.0, 4.0, 40, 2.0, 20);
  b.setpoint(0, 150.0);
  b.run_seconds(240);
  ASSERT_EQ(b.status_faults(0), 0) << "warm-up faulted";
  ASSERT_TRUE(b.status_mode(0) & 0x40) << "holding after 240 s, T = " << b.status_temp(0);
  b.disconnect[0] = true;  // heater fails while holding: the temperature falls
  const uint64_t t_fail = b.cycle;
  uint64_t t_out = 0, t_fault = 0;
  b.per_clock = [&] {
    if (t_out == 0 && b.status_temp(0) < 146.0) t_out = b.cycle;
    if (t_fault == 0 && (b.status_faults(0) & 4)) t_fault = b.cycle;
  };
  b.run_seconds(120);
  b.per_clock = nullptr;
  ASSERT_NE(t_out, 0u);
  ASSERT_NE(t_fault, 0u) << "no RUNAWAY fault";
  const double out_s = static_cast<double>(t_fault - t_out) / kSampleClks;
  std::printf(
      "runaway: left the 4 degC band %.1f s after the failure, RUNAWAY %.3f s later "
      "(period 40 ticks)\n",
      static_cast<double>(t_out - t_fail) / kSampleClks, out_s);
  EXPECT_GT(out_s, 38.5);
  EXPECT_LT(out_s, 40.5);
  EXPECT_FALSE(b.pin(0));
  expect_latched_until_cleared(b, 0, 2, [&] { b.disconnect[0] = false; });
}

TEST(HeaterSafety, HostSilentTripsWatchdog) {
  HeatBench b;
  manual_full(b, 0);
  manual_full(b, 1);
  b.frame(kWd, Be().u16(5).b);  // 5 ticks; frame() also pulses frame_ok
  // Keep feeding for a while: no fault.
  for (int i = 0; i < 10; ++i) {
    b.run_seconds(3);
    b.m->frame_ok = 1;
    b.clock();
    b.m->frame_ok = 0;
  }
  ASSERT_EQ(b.m->wd_fault, 0) << "fed watchdog tripped";
  const uint64_t t_last = b.cycle;
  uint64_t t_fault = 0;
  b.per_clock = [&] {
    if (t_fault == 0 && b.m->wd_fault) t_fault = b.cycle;
  };
  while (t_fault == 0 && b.cycle - t_last < 10 * kSampleClks) b.clock();
  ASSERT_NE(t_fault, 0u) << "no watchdog fault";
  b.per_clock = nullptr;
  const uint64_t low0 = clocks_until_low(b, 0, t_fault, 10);
  const uint64_t low1 = b.pin(1) ? clocks_until_low(b, 1, t_fault, 10) : low0;
  const double s = static_cast<double>(t_fault - t_last) / kSampleClks;
  std::printf(
      "host silent: watchdog fault %.3f s after the last frame (5 ticks), heaters low %llu/%llu "
      "clocks later\n",
      s, static_cast<unsigned long long>(low0), static_cast<unsigned long long>(low1));
  EXPECT_GT(s, 4.0);
  EXPECT_LE(s, 5.01);
  EXPECT_LE(low0, 1u);
  EXPECT_LE(low1, 1u);
  // Latched: feeding again does not clear it; FAULT_CLEAR + setpoint restarts.
  b.m->frame_ok = 1;
  b.clock();
  b.m->frame_ok = 0;
  b.run_seconds(2);
  EXPECT_EQ(b.m->wd_fault, 1);
  EXPECT_FALSE(b.pin(0));
  EXPECT_FALSE(b.pin(1));
  b.frame(kWd, Be().u16(0).b);
  b.fault_clear();
  b.run_seconds(2);
  EXPECT_FALSE(b.pin(0)) << "FAULT_CLEAR alone restarted the heater";
  b.setpoint(0, 50.0);
  b.run_seconds(2);
  EXPECT_TRUE(b.pin(0));
}

TEST(HeaterSafety, EstopForcesBothHeatersLowNextClock) {
  HeatBench b;
  manual_full(b, 0);
  manual_full(b, 1);
  b.m->estop = 1;
  b.clock();
  std::printf("e-stop (block input): heaters low after 1 clock\n");
  EXPECT_FALSE(b.pin(0));
  EXPECT_FALSE(b.pin(1));
  b.run_seconds(3);
  EXPECT_FALSE(b.pin(0));
  EXPECT_EQ(b.status_mode(0) & 0x80, 0);
  b.m->estop = 0;  // the caller's latch is cleared by FAULT_CLEAR; the channels stay disabled
  b.run_seconds(2);
  EXPECT_FALSE(b.pin(0));
  EXPECT_FALSE(b.pin(1));
  b.setpoint(1, 50.0);
  b.run_seconds(2);
  EXPECT_TRUE(b.pin(1));
}

// ------------------------------------------------------------------------------------ closed loop
struct StepFigures {
  double overshoot = 0.0;       // max(T) - set after the step, true plant temperature
  double settle_s = -1.0;       // last time |T - set| > 0.5 (true), from the step
  double settle_meas_s = -1.0;  // the same on the measured temperature
  double sse_true = 0.0;        // mean(T - set) over the last 200 s, true
  double sse_meas = 0.0;        // ... measured (what the controller sees)
  double ripple = 0.0;          // max |T_meas - set| over the last 200 s
  double reach_s = -1.0;        // first time within 0.5 degC of set (true)
};

StepFigures step_response(HeatBench& b, int ch, double set, double seconds) {
  StepFigures f;
  const uint64_t t0 = b.ticks;
  const double start = ch == 1 ? b.bed.temperature() : b.hot.temperature();
  std::vector<double> tt, tm;
  b.per_tick = [&] { tt.push_back(ch == 1 ? b.bed.temperature() : b.hot.temperature()); };
  uint64_t last_eval = b.evals;
  b.per_clock = [&] {
    if (b.evals != last_eval) {
      last_eval = b.evals;
      tm.push_back(b.status_temp(ch));
    }
  };
  b.setpoint(ch, set);
  b.run_seconds(seconds);
  b.per_tick = nullptr;
  b.per_clock = nullptr;
  (void)t0;
  const double sign = set > start ? 1.0 : -1.0;
  for (double v : tt) f.overshoot = std::max(f.overshoot, sign * (v - set));
  for (size_t i = 0; i < tt.size(); ++i) {
    if (std::fabs(tt[i] - set) > 0.5) f.settle_s = static_cast<double>(i + 1);
    if (f.reach_s < 0 && std::fabs(tt[i] - set) <= 0.5) f.reach_s = static_cast<double>(i + 1);
  }
  for (size_t i = 0; i < tm.size(); ++i)
    if (std::fabs(tm[i] - set) > 0.5) f.settle_meas_s = static_cast<double>(i + 1);
  const size_t n = 200;
  double st = 0, sm = 0;
  for (size_t i = tt.size() - n; i < tt.size(); ++i) st += tt[i] - set;
  for (size_t i = tm.size() - n; i < tm.size(); ++i) {
    sm += tm[i] - set;
    f.ripple = std::max(f.ripple, std::fabs(tm[i] - set));
  }
  f.sse_true = st / n;
  f.sse_meas = sm / n;
  return f;
}

// The same loop with the double-precision law and an ideal sensor (1 s old, not quantised), the
// duty applied for the whole second: tells a miss of the law on this plant from one of the RTL.
StepFigures reference_loop(double kp, double ti, double td, double set0, double set1,
                           double seconds, StepFigures* first) {
  th::BedPlant bed;
  th::DelayedSensor sensor(1, 20.0);
  th::PidRef ref(th::pid_coeffs(kp, ti, td, 1.0, th::kBedSupplyV));
  double u = 0.0;
  StepFigures out;
  for (int step = 0; step < 2; ++step) {
    const double set = step == 0 ? set0 : set1;
    StepFigures f;
    std::vector<double> tt, tm;
    for (int k = 0; k < static_cast<int>(seconds); ++k) {
      bed.step(1.0, u);
      const double meas = sensor.sample(bed.temperature());
      u = ref.step(set, meas);
      tt.push_back(bed.temperature());
      tm.push_back(meas);
    }
    for (double v : tt) f.overshoot = std::max(f.overshoot, v - set);
    for (size_t i = 0; i < tt.size(); ++i)
      if (std::fabs(tt[i] - set) > 0.5) f.settle_s = static_cast<double>(i + 1);
    for (size_t i = tm.size() - 200; i < tm.size(); ++i)
      f.ripple = std::max(f.ripple, std::fabs(tm[i] - set));
    if (step == 0)
      *first = f;
    else
      out = f;
  }
  return out;
}

void bed_tuning(const char* name, double kp, double ti, double td, bool law_meets_targets) {
  HeatBench b;
  b.load_table(1);
  b.config(1, th::HeatMode::kPid, th::pid_coeffs(kp, ti, td, 1.0, th::kBedSupplyV));
  b.safety(1, 5.0, 120.0, 4.0, 40, 2.0, 60);
  const double seconds = 1500.0;
  const StepFigures a = step_response(b, 1, 60.0, seconds);
  const StepFigures c = step_response(b, 1, 85.0, seconds);
  for (const auto& [label, f] :
       {std::pair<const char*, StepFigures>{"20 -> 60", a}, {"60 -> 85", c}}) {
    std::printf(
        "bed %s %s degC: overshoot %.3f degC, settling (+-0.5 degC) %.0f s true / %.0f s measured, "
        "steady-state error %.4f degC true / %.4f measured, ripple %.4f degC\n",
        name, label, f.overshoot, f.settle_s, f.settle_meas_s, f.sse_true, f.sse_meas, f.ripple);
    EXPECT_LE(f.overshoot, 2.0) << name << " " << label;
    if (law_meets_targets) {
      EXPECT_LE(f.settle_meas_s, 900.0) << name << " " << label;
      EXPECT_LE(std::fabs(f.sse_meas), 0.0625)
          << name << " " << label << ": beyond the sensor resolution";
    }
  }
  StepFigures r60;
  const StepFigures r85 = reference_loop(kp, ti, td, 60.0, 85.0, seconds, &r60);
  std::printf(
      "  double-precision law, ideal sensor: 20 -> 60 overshoot %.3f settling %.0f s ripple %.3f; "
      "60 -> 85 overshoot %.3f settling %.0f s ripple %.3f\n",
      r60.overshoot, r60.settle_s, r60.ripple, r85.overshoot, r85.settle_s, r85.ripple);
  if (!law_meets_targets) {
    // docs/heater.md: on this plant model (10 s dead time + 1 s sensor delay) the relay tuning is
    // at the edge of stability and the literal law itself limit-cycles. If this starts to settle,
    // the plant or the law changed: assert the targets again.
    EXPECT_GT(std::max(r60.settle_s, r85.settle_s), 900.0)
        << "the law settles now: assert the targets";
  } else {
    EXPECT_LE(std::max(r60.settle_s, r85.settle_s), 900.0);
  }
  EXPECT_EQ(b.status_faults(1), 0) << "no safety fault during the steps";
  EXPECT_EQ(b.adc.violations(), 0u) << b.adc.first_violation();
}

TEST(HeaterClosedLoop, BedStepResponseTuning) {
  bed_tuning("step-response tuning (Kp 9.7, Ti 20, Td 5)", 9.7, 20.0, 5.0, true);
}
TEST(HeaterClosedLoop, BedRelayTuning) {
  bed_tuning("relay tuning (Kp 10.2, Ti 26.5, Td 6.4)", 10.2, 26.5, 6.4, false);
}

TEST(HeaterClosedLoop, HotEndWarmUpTo200) {
  HeatBench b;
  b.load_table(0);
  // SIMC tuning of the hot-end model as FOPDT (K 320 degC/duty, T 96 s, L ~3 s): Kc 0.05 duty/degC
  // (1.2 V/degC at 24 V), Ti 24 s, Td 1 s.
  b.config(0, th::HeatMode::kPid, th::pid_coeffs(1.2, 24.0, 1.0, 1.0, 24.0));
  b.safety(0, 5.0, 275.0, 4.0, 40, 2.0, 20);
  const StepFigures f = step_response(b, 0, 200.0, 400.0);
  std::printf(
      "hot end 20 -> 200 degC: within 0.5 degC after %.0f s, overshoot %.3f degC, settling %.0f s "
      "true / %.0f s measured, steady-state error %.4f true / %.4f measured, ripple %.4f\n",
      f.reach_s, f.overshoot, f.settle_s, f.settle_meas_s, f.sse_true, f.sse_meas, f.ripple);
  EXPECT_LE(f.overshoot, 5.0);
  EXPECT_LE(f.settle_meas_s, 240.0);
  EXPECT_LE(std::fabs(f.sse_meas), 0.15);  // 0.15 degC per ADC code at 200 degC
  EXPECT_EQ(b.status_faults(0), 0);
}

}  // namespace
