// Unit benches of the heater blocks (docs/heater.md):
//   pwm          duty sequence against a per-clock model, duty taken only at period boundaries,
//                force_off latency;
//   pid_incr     the controller output against the double-precision law
//   (models/include/fpgacnc/models/pid_ref.h)
//                over long random error sequences in every mode: u equal exactly, the PWM duty
//                floor(u * 2^PWM_BITS) (the documented bound: at most one count below u_ref);
//   ltc2308_spi  against the LTC2308 pin model: codes of random voltages on both channels, no
//                timing violation, the documented read time;
//   temp_table   random tables and codes against models::thermal::table_lookup (bit exact).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>

#include "Vltc2308_spi.h"
#include "Vpid_incr.h"
#include "Vpwm.h"
#include "Vtemp_table.h"
#include "common/seed.h"
#include "fpgacnc/models/ltc2308_model.h"
#include "fpgacnc/models/pid_ref.h"
#include "fpgacnc/models/thermal_plant.h"
#include "verilated.h"

namespace {

using namespace fpgacnc;
using models::thermal::HeatMode;

template <class M>
class Dut {
 public:
  Dut() : ctx_(std::make_unique<VerilatedContext>()), m(std::make_unique<M>(ctx_.get())) {}
  ~Dut() { m->final(); }
  void tick() {
    m->clk = 0;
    m->eval();
    m->clk = 1;
    m->eval();
    ++cycle;
  }
  void reset() {
    m->rst = 1;
    tick();
    tick();
    m->rst = 0;
  }

 private:
  std::unique_ptr<VerilatedContext> ctx_;

 public:
  std::unique_ptr<M> m;
  uint64_t cycle = 0;
};

// ------------------------------------------------------------------------------------ pwm
// Verilated with PWM_BITS 4, PWM_DIV 3: period 48 clocks.
constexpr int kPwmBits = 4;
constexpr int kPwmDiv = 3;

TEST(Pwm, DutyFollowsPeriodBoundariesAndForceOffActsNextClock) {
  const uint64_t seed = tb::test_seed(11, "Pwm");
  std::mt19937_64 rng(seed);
  Dut<Vpwm> d;
  d.m->duty = 0;
  d.m->force_off = 0;
  d.reset();
  // Model: counter position (div, cnt) after reset is (0, 0); the output in the clock after an
  // edge is (cnt_next < active_next) where the active duty is reloaded when a period begins.
  int div = 0, cnt = 0, active = 0;
  int requested = 0;
  uint64_t high = 0, periods = 0;
  bool force = false;
  for (int i = 0; i < 20000; ++i) {
    if (rng() % 37 == 0)
      requested = static_cast<int>(rng() % ((1 << kPwmBits) + 3));  // up to 2^B + 2
    if (rng() % 301 == 0) force = !force;
    d.m->duty = static_cast<uint8_t>(requested);
    d.m->force_off = force;
    // Edge: advance the model with the inputs of this clock.
    const bool wrap = (div == kPwmDiv - 1);
    const bool boundary = wrap && cnt == (1 << kPwmBits) - 1;
    div = wrap ? 0 : div + 1;
    if (wrap) cnt = (cnt + 1) % (1 << kPwmBits);
    if (boundary) {
      active = requested;
      ++periods;
    }
    const bool expect = !force && cnt < active;
    d.tick();
    ASSERT_EQ(d.m->out, expect ? 1 : 0)
        << "clock " << d.cycle << " duty " << active << " cnt " << cnt << " force_off " << force;
    ASSERT_EQ(d.m->period_start, boundary ? 1 : 0) << "clock " << d.cycle;
    ASSERT_EQ(d.m->active, active) << "clock " << d.cycle;
    high += d.m->out;
  }
  std::printf("pwm: %llu periods, %llu high clocks\n", static_cast<unsigned long long>(periods),
              static_cast<unsigned long long>(high));
  EXPECT_GT(periods, 400u);
}

// ------------------------------------------------------------------------------------ pid
struct PidRaw {
  int mode;
  uint32_t kp, ki, kd;
  uint16_t umax, hyst, manual;
};

models::thermal::PidCoeffs coeffs_of(const PidRaw& r) {
  models::thermal::PidCoeffs c;
  c.mode = static_cast<HeatMode>(r.mode);
  c.kp = r.kp / 16777216.0;
  c.ki = r.ki / 16777216.0;
  c.kd = r.kd / 16777216.0;
  c.umax = r.umax / 32768.0;
  c.hyst = r.hyst / 16.0;
  c.manual = std::min(r.manual / 32768.0, c.umax);
  return c;
}

class PidBench {
 public:
  PidBench() {
    d.m->start = 0;
    d.m->enable = 1;
    d.m->restart = 0;
    d.reset();
  }
  void set(const PidRaw& r) {
    d.m->mode = static_cast<uint8_t>(r.mode);
    d.m->kp = r.kp;
    d.m->ki = r.ki;
    d.m->kd = r.kd;
    d.m->umax = r.umax;
    d.m->hyst = r.hyst;
    d.m->manual = r.manual;
  }
  void restart() {
    d.m->restart = 1;
    d.tick();
    d.m->restart = 0;
  }
  // One sample; returns u (Q1.28) and the clocks from start to done.
  uint32_t sample(int set_q4, int temp_q4, int* clocks) {
    d.m->setpoint = static_cast<uint16_t>(set_q4);
    d.m->temp = static_cast<uint16_t>(temp_q4);
    d.m->start = 1;
    d.tick();
    d.m->start = 0;
    int n = 0;
    while (!d.m->done) {
      d.tick();
      if (++n > 1000) ADD_FAILURE() << "pid_incr: no done within 1000 clocks";
      if (n > 1000) break;
    }
    *clocks = n;
    return d.m->u;
  }
  Dut<Vpid_incr> d;
};

TEST(PidIncr, EqualsDoubleReferenceOverRandomSequences) {
  const uint64_t seed = tb::test_seed(7, "PidIncr");
  std::mt19937_64 rng(seed);
  PidBench b;
  uint64_t samples = 0, saturated = 0, skipped_integral = 0;
  int max_clocks = 0;
  double worst_duty_gap = 0.0;  // u_ref * 2^10 - duty counts
  constexpr int kSeq = 40, kLen = 1500;
  for (int s = 0; s < kSeq; ++s) {
    PidRaw r{};
    // Mostly PID; gains from realistic (heater.md bed, hot end) to extreme.
    const int mode_pick = static_cast<int>(rng() % 10);
    r.mode = mode_pick < 6 ? 4 : static_cast<int>(mode_pick - 6 + 1);  // 4 x6, 1..4
    const double scale = std::pow(10.0, std::uniform_real_distribution<double>(-3.0, 1.0)(rng));
    r.kp = models::thermal::to_q8_24(scale * std::uniform_real_distribution<double>(0.0, 1.0)(rng));
    r.ki = models::thermal::to_q8_24(scale * std::uniform_real_distribution<double>(0.0, 0.1)(rng));
    r.kd = models::thermal::to_q8_24(scale * std::uniform_real_distribution<double>(0.0, 5.0)(rng));
    if (s == 0) {  // the extreme corner: maximum gains
      r.kp = r.ki = r.kd = 0xFFFFFFFFu;
    }
    r.umax = static_cast<uint16_t>(rng() % 4 == 0 ? 0x8000 : rng() % 0x8001);
    r.hyst = static_cast<uint16_t>(rng() % 64);
    r.manual = static_cast<uint16_t>(rng() % 0x9000 > 0x8000 ? 0x8000 : rng() % 0x8001);
    b.set(r);
    b.restart();
    models::thermal::PidRef ref(coeffs_of(r));
    ref.restart();
    int set = static_cast<int>(rng() % 4000);
    double temp = static_cast<double>(rng() % 4000);
    for (int k = 0; k < kLen; ++k) {
      // Error sequences: random walk of the temperature, setpoint jumps, occasional wild readings
      // (the full s16 range) to exercise the saturation and the 20-bit differences.
      if (rng() % 200 == 0) set = static_cast<int>(rng() % 4800) - 800;
      temp += std::normal_distribution<double>(0.0, 20.0)(rng);
      temp = std::clamp(temp, -2000.0, 6000.0);
      int tq = static_cast<int>(std::lround(temp));
      if (rng() % 500 == 0) tq = static_cast<int>(rng() % 65536) - 32768;
      if (rng() % 500 == 0) set = static_cast<int>(rng() % 65536) - 32768;
      const double u_prev = ref.output();
      const double e = (set - tq) / 16.0;
      const double u_ref = ref.step(set / 16.0, tq / 16.0);
      int clocks = 0;
      const uint32_t u = b.sample(set, tq, &clocks);
      max_clocks = std::max(max_clocks, clocks);
      const double u_scaled = u_ref * 268435456.0;
      ASSERT_EQ(u_scaled, std::floor(u_scaled)) << "reference not on the Q1.28 grid";
      ASSERT_EQ(static_cast<double>(u), u_scaled)
          << "sequence " << s << " sample " << k << " mode " << r.mode << " set " << set << " temp "
          << tq << ": expected u " << u_scaled << " got " << u << " (seed " << seed << ")";
      const uint32_t duty = u >> (28 - 10);
      const double gap = u_ref * 1024.0 - duty;
      ASSERT_GE(gap, 0.0);
      ASSERT_LT(gap, 1.0) << "duty bound, sample " << k;
      worst_duty_gap = std::max(worst_duty_gap, gap);
      ++samples;
      if (u_ref == 0.0 || u_ref >= r.umax / 32768.0) ++saturated;
      if (r.mode == 4 && k > 0 && ((u_prev >= r.umax / 32768.0 && e > 0) || (u_prev <= 0 && e < 0)))
        ++skipped_integral;
    }
  }
  std::printf(
      "pid_incr: %llu samples equal to the reference (%llu saturated, %llu with the integral "
      "skipped); duty gap max %.4f counts (< 1); max %d clocks per sample\n",
      static_cast<unsigned long long>(samples), static_cast<unsigned long long>(saturated),
      static_cast<unsigned long long>(skipped_integral), worst_duty_gap, max_clocks);
  EXPECT_GT(saturated, 100u);
  EXPECT_GT(skipped_integral, 100u);
  EXPECT_LE(max_clocks, 70);
}

TEST(PidIncr, DisabledOutputsZeroAndRestartsWithoutKick) {
  PidBench b;
  PidRaw r{4,
           models::thermal::to_q8_24(0.4),
           models::thermal::to_q8_24(0.02),
           models::thermal::to_q8_24(2.0),
           0x8000,
           16,
           0};
  b.set(r);
  models::thermal::PidRef ref(coeffs_of(r));
  int clocks;
  for (int k = 0; k < 50; ++k) {
    const double u_ref = ref.step(60.0, 20.0 + k * 0.5);
    ASSERT_EQ(b.sample(960, 320 + k * 8, &clocks) / 268435456.0, u_ref) << "sample " << k;
  }
  b.d.m->enable = 0;
  ASSERT_EQ(b.sample(960, 700, &clocks), 0u) << "disabled: u must be 0";
  b.d.m->enable = 1;
  ref.restart();
  // First sample after re-enable: e1 = e2 = e, so only the integral term acts: u = ki * e.
  const double u_ref = ref.step(60.0, 43.75);
  EXPECT_EQ(b.sample(960, 700, &clocks) / 268435456.0, u_ref);
  EXPECT_NEAR(u_ref, 0.02 * 16.25, 1e-6);
}

// ------------------------------------------------------------------------------------ adc
TEST(Ltc2308Spi, ReadsBothChannelsAgainstThePinModel) {
  const uint64_t seed = tb::test_seed(5, "Ltc2308Spi");
  std::mt19937_64 rng(seed);
  Dut<Vltc2308_spi> d;
  models::Ltc2308Model adc(50e6);
  d.m->start = 0;
  d.m->adc_sdo = 0;
  d.reset();
  int sdo = 0;
  auto clock = [&] {
    d.m->adc_sdo = static_cast<uint8_t>(sdo);
    d.tick();
    sdo = adc.tick(d.m->adc_convst, d.m->adc_sck, d.m->adc_sdi);
  };
  uint64_t read_clocks = 0;
  for (int r = 0; r < 300; ++r) {
    // Channels 0 and 1 random; the others hold values that must never be read.
    for (size_t c = 0; c < 8; ++c) adc.volts[c] = 4.5;
    adc.volts[0] = std::uniform_real_distribution<double>(-0.2, 4.3)(rng);
    adc.volts[1] = std::uniform_real_distribution<double>(-0.2, 4.3)(rng);
    if (r == 0) adc.volts[0] = 0.0, adc.volts[1] = 4.2;
    d.m->start = 1;
    clock();
    d.m->start = 0;
    const uint64_t t0 = d.cycle;
    while (!d.m->done) {
      clock();
      ASSERT_LT(d.cycle - t0, 5000u) << "no done";
    }
    read_clocks = d.cycle - t0 + 1;
    ASSERT_EQ(d.m->code_a, models::thermal::adc_code(adc.volts[0]))
        << "read " << r << " channel 0, " << adc.volts[0] << " V";
    ASSERT_EQ(d.m->code_b, models::thermal::adc_code(adc.volts[1]))
        << "read " << r << " channel 1, " << adc.volts[1] << " V";
    for (int i = 0; i < static_cast<int>(rng() % 50); ++i) clock();
  }
  EXPECT_EQ(adc.violations(), 0u) << adc.first_violation();
  // Conversions: three per read: (whatever the previous word said), 0, 1.
  ASSERT_EQ(adc.conversions.size(), 900u);
  for (size_t i = 0; i < adc.conversions.size(); i += 3) {
    EXPECT_EQ(adc.conversions[i + 1].channel, 0) << "conversion " << i + 1;
    EXPECT_EQ(adc.conversions[i + 2].channel, 1) << "conversion " << i + 2;
  }
  std::printf("ltc2308_spi: 300 reads, %llu clocks from start to done (documented 619)\n",
              static_cast<unsigned long long>(read_clocks));
  EXPECT_EQ(read_clocks, 3u * (85 + 1 + 24 * 5) + 1);
}

// ------------------------------------------------------------------------------------ table
TEST(TempTable, InterpolationIsBitExact) {
  const uint64_t seed = tb::test_seed(3, "TempTable");
  std::mt19937_64 rng(seed);
  Dut<Vtemp_table> d;
  d.m->wr = 0;
  d.m->start = 0;
  d.reset();
  // No table loaded since reset: -2048 degC (0x8000).
  d.m->ch = 1;
  d.m->code = 1234;
  d.m->start = 1;
  d.tick();
  d.m->start = 0;
  for (int i = 0; i < 6; ++i) d.tick();
  EXPECT_EQ(d.m->temp, 0x8000) << "lookup before the table's last entry was written";
  std::array<models::thermal::Table, 2> tabs{};
  tabs[0] = models::thermal::thermistor_table();
  for (auto& v : tabs[1]) v = static_cast<int16_t>(rng() % 65536);  // any s16, steep steps
  tabs[1][0] = 32767;
  tabs[1][1] = -32768;
  for (int ch = 0; ch < 2; ++ch) {
    for (int i = 0; i < models::thermal::kTableEntries; ++i) {
      d.m->wr = 1;
      d.m->wr_ch = static_cast<uint8_t>(ch);
      d.m->wr_idx = static_cast<uint8_t>(i);
      d.m->wr_data = static_cast<uint16_t>(tabs[static_cast<size_t>(ch)][static_cast<size_t>(i)]);
      d.tick();
    }
  }
  d.m->wr = 0;
  int latency = 0;
  for (int n = 0; n < 20000; ++n) {
    const int ch = static_cast<int>(rng() % 2);
    const int code = (n < 4096) ? n : static_cast<int>(rng() % 4096);
    d.m->ch = static_cast<uint8_t>(ch);
    d.m->code = static_cast<uint16_t>(code);
    d.m->start = 1;
    d.tick();
    d.m->start = 0;
    int k = 1;
    while (!d.m->done) {
      d.tick();
      ++k;
      ASSERT_LT(k, 20);
    }
    latency = k;
    const int expect = models::thermal::table_lookup(tabs[static_cast<size_t>(ch)], code);
    ASSERT_EQ(static_cast<int16_t>(d.m->temp), expect) << "channel " << ch << " code " << code;
  }
  std::printf("temp_table: 20000 lookups bit exact, start to done %d clocks\n", latency);
  EXPECT_EQ(latency, 6);
}

}  // namespace
