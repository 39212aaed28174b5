// The laser / spindle PWM through cnc_core's pins (docs/machine.md "Laser and spindle PWM"): a
// 2-axis core (full-2axis) at 3 Mbaud driven with v2 frames; the spindle_pwm and laser pins'
// edges are recorded and the PWM's frequency and duty measured at the pin: M3 (constant power)
// for several powers, low at power 0, in rapids and from the e-stop's clock; M4 (OUTPUT mask bit
// 7) along an accelerating and decelerating LINE_PROFILE against the profile's recurrence, and
// through a feed hold's ramp against the rate's, M3 through the same hold.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "Vcnc_core_pwm.h"
#include "common/pin_harness.h"
#include "common/v2_core_bench.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
namespace spec = fpgacnc::spec;
using Model = Vcnc_core_pwm;

// The PWM of this build (LASER_PWM_HZ at its default): 256 counts of kDiv clocks; the first rise
// kLat + 1 clocks after the laser's (laser_scale's latency).
constexpr uint64_t kDiv =
    (spec::kDefaultClkHz + 128 * spec::kDefaultLaserPwmHz) / (256 * spec::kDefaultLaserPwmHz);
constexpr uint64_t kPeriod = 256 * kDiv;
constexpr uint64_t kLat = spec::kDefaultLaserScaleClks;

constexpr fpgacnc::tb::PinAccess<Model> kPins{
    [](Model& m, bool asserted) { m.rst = asserted ? 1 : 0; },
    [](const Model& m) { return static_cast<uint32_t>(m.step); },
    [](const Model& m) { return static_cast<uint32_t>(m.dir); },
    [](Model& m) {
      m.cfg_wr = 0;
      m.limit_min = 0;
      m.limit_max = 0;
      m.probe_in = 0;
      m.estop = 0;
      m.hold_in = 0;
      m.start_in = 0;
    },
};

struct Edge {
  uint64_t cycle;
  bool high;
};
// One high pulse of spindle_pwm: rise and fall clocks (fall 0: still high).
struct Pulse {
  uint64_t rise, fall;
};

class PwmBench : public fpgacnc::tb::V2CoreBench<Model, 2> {
 public:
  PwmBench() : V2CoreBench(kPins) {}
  std::vector<Edge> pwm, laser;

  std::vector<Pulse> pulses() const {
    std::vector<Pulse> p;
    for (const Edge& e : pwm) {
      if (e.high)
        p.push_back({e.cycle, 0});
      else if (!p.empty())
        p.back().fall = e.cycle;
    }
    return p;
  }
  void ack(const std::vector<uint8_t>& f) { ASSERT_EQ(exchange(f).type, v2::kAck) << v2::hex(f); }
  // Runs until the laser pin has changed `n` times in all (at most `limit` clocks).
  bool wait_laser_edges(size_t n, uint64_t limit) {
    for (uint64_t i = 0; i < limit && laser.size() < n; ++i) tick();
    return laser.size() >= n;
  }

 protected:
  void observe_more() override {
    const Model& m = dut();
    if (m.spindle_pwm != pwm_prev_) pwm.push_back({cycle(), m.spindle_pwm != 0});
    if (m.laser != laser_prev_) laser.push_back({cycle(), m.laser != 0});
    pwm_prev_ = m.spindle_pwm;
    laser_prev_ = m.laser;
  }

 private:
  uint8_t pwm_prev_ = 0, laser_prev_ = 0;
};

std::vector<uint8_t> motion(uint8_t flags, uint32_t ramp) {
  std::vector<uint8_t> p{flags};
  v2::be16(p, spec::kRateOne);
  v2::be16(p, spec::kRateOne);
  v2::be32(p, ramp);
  return v2::frame(spec::kTypeMotion, 0, p);
}
std::vector<uint8_t> m4(uint8_t seq, bool on) {
  return v2::output(seq, spec::kOutLaserDyn, on ? spec::kOutLaserDyn : 0, 0);
}

// M3: for each power the pin rises kLat + 1 clocks after the laser, then at every period
// boundary (kPeriod clocks apart), high for power * kDiv clocks (255: the whole time), and falls
// with the laser at the segment's end.
TEST(LaserPwm, ConstantPowerDutyAndFrequency) {
  PwmBench b;
  for (uint8_t power : {1, 64, 128, 200, 254, 255}) {
    b.pwm.clear();
    b.laser.clear();
    const uint64_t t = 3 * kPeriod + kPeriod / 2;
    b.ack(v2::line(b.seq++, 1, power, static_cast<uint32_t>(t), {100, 7}, true));
    ASSERT_TRUE(b.wait_laser_edges(2, t + 100'000)) << "power " << int{power};
    b.idle(1000);
    const uint64_t on = b.laser[0].cycle, off = b.laser[1].cycle;
    EXPECT_EQ(off - on, t) << "laser time, power " << int{power};
    const auto p = b.pulses();
    ASSERT_FALSE(p.empty()) << "power " << int{power};
    EXPECT_EQ(p[0].rise, on + kLat + 1) << "first rise, power " << int{power};
    if (power == 255) {
      ASSERT_EQ(p.size(), 1u);
      EXPECT_EQ(p[0].fall, off) << "255: high until the laser falls";
      continue;
    }
    size_t n = 0;
    for (uint64_t r = on + kLat + 1; r < off; r += kPeriod) ++n;
    ASSERT_EQ(p.size(), n) << "pulses, power " << int{power};
    for (size_t i = 0; i < p.size(); ++i) {
      EXPECT_EQ(p[i].rise, on + kLat + 1 + i * kPeriod) << "rise " << i << ", power " << int{power};
      EXPECT_EQ(p[i].fall, std::min(p[i].rise + power * kDiv, off))
          << "fall " << i << ", power " << int{power};
    }
  }
}

// Power 0 and rapids (code 0, power 200) leave the laser and the PWM low; an e-stop during a cut
// drops the PWM in the same clock as the laser, and it stays low.
TEST(LaserPwm, LowAtPowerZeroInRapidsAndAfterEstop) {
  PwmBench b;
  b.ack(v2::line(b.seq++, 1, 0, static_cast<uint32_t>(2 * kPeriod), {100, 0}, true));
  b.ack(v2::line(b.seq++, 0, 200, static_cast<uint32_t>(2 * kPeriod), {-100, 0}, true));
  b.run_until_idle(5 * kPeriod);
  EXPECT_TRUE(b.laser.empty()) << "laser at power 0 / in a rapid";
  EXPECT_TRUE(b.pwm.empty()) << "PWM at power 0 / in a rapid";
  b.ack(v2::line(b.seq++, 1, 128, static_cast<uint32_t>(10 * kPeriod), {1000, 0}, false));
  ASSERT_TRUE(b.wait_laser_edges(1, 100'000));
  const uint64_t on = b.laser[0].cycle;
  while (b.cycle() < on + 2 * kPeriod + kPeriod / 4) b.tick();  // within a high pulse
  ASSERT_FALSE(b.pwm.empty());
  ASSERT_TRUE(b.pwm.back().high);
  b.dut().estop = 1;
  ASSERT_TRUE(b.wait_laser_edges(2, 100));
  b.idle(2 * kPeriod);
  ASSERT_FALSE(b.pwm.back().high);
  EXPECT_EQ(b.pwm.back().cycle, b.laser[1].cycle) << "PWM and laser fall together";
  EXPECT_EQ(b.laser.size(), 2u);
  EXPECT_EQ(b.pulses().size(), 3u) << "no rise after the e-stop";
}

// The profile's V per tick as profile_gen computes it (docs/timing.md "Profiled segments"):
// U(1) = V_entry, V(1) from V(0) = V_entry; V(c+1) from U(c+1) = U(c) + V(c).
struct ProfileRef {
  uint64_t ve, vc, vx, a, d;
  std::vector<uint64_t> v;  // v[j] = V(j), j >= 1
  ProfileRef(uint64_t ve_, uint64_t vc_, uint64_t vx_, uint64_t a_, uint64_t d_, uint64_t n,
             uint64_t ticks)
      : ve(ve_), vc(vc_), vx(vx_), a(a_), d(d_) {
    const unsigned __int128 dd = static_cast<unsigned __int128>(d) << 48;
    auto next = [&](unsigned __int128 u, uint64_t vv) {
      if (u >= dd) return vv >= vx + a ? vv - a : vx;
      return vv + a <= vc ? vv + a : vc;
    };
    unsigned __int128 u = ve;
    v.push_back(0);
    v.push_back(next(u, ve));
    for (uint64_t j = 1; j < ticks && (u >> 48) < n; ++j) {
      u += v[j];
      v.push_back(next(u, v[j]));
    }
  }
};

// M4 along a LINE_PROFILE (V_entry = V_exit = V_cruise / 10, 5 periods of acceleration, 2 of
// cruise, 5 of deceleration): each period's duty is power * V / V_cruise (laser_scale's
// arithmetic on V at the clock sampled for it, the clock kLat + 1 before the period), rising
// through the acceleration to the power at cruise and falling again; whole counts.
TEST(LaserPwm, DynamicFollowsProfileSpeed) {
  PwmBench b;
  b.ack(m4(b.seq++, true));
  const uint8_t power = 200;
  const uint64_t vc = (uint64_t{1} << 48) / 100, ve = vc / 10, ta = 5 * kPeriod;
  const uint64_t a = (vc - ve) / ta;
  const double da = static_cast<double>(ve + vc) / 2 * static_cast<double>(ta) / 0x1p48;
  const double dc = static_cast<double>(vc) * static_cast<double>(2 * kPeriod) / 0x1p48;
  const auto n = static_cast<int32_t>(2 * da + dc);
  const auto d = static_cast<uint32_t>(n - static_cast<int32_t>(da));
  b.ack(v2::line_profile(b.seq++, 1, power, ve, vc, ve, static_cast<uint32_t>(a), d, {n, n / 3},
                         false));
  ASSERT_TRUE(b.wait_laser_edges(2, 20 * kPeriod));
  b.idle(1000);
  const uint64_t on = b.laser[0].cycle, off = b.laser[1].cycle;
  const ProfileRef ref(ve, vc, ve, a, d, static_cast<uint64_t>(n), off - on + 1);
  const auto p = b.pulses();
  ASSERT_GE(p.size(), 10u);
  std::vector<uint64_t> duty;
  uint64_t rise = on + kLat + 1;  // period starts (the pin may stay low in one)
  size_t k = 0;
  for (size_t i = 0; rise < off; ++i, rise += kPeriod) {
    const uint64_t sample = (i == 0) ? on : rise - kLat - 1;
    const uint64_t v = ref.v.at(sample - on + 1);  // tick 1 is the laser's first clock
    const uint64_t qv = (static_cast<unsigned __int128>(v) << 16) / vc;
    const uint64_t want = power * qv >> 16;
    duty.push_back(want);
    if (want == 0) continue;
    ASSERT_LT(k, p.size()) << "no pulse in period " << i;
    EXPECT_EQ(p[k].rise, rise) << "period " << i;
    EXPECT_EQ(p[k].fall, std::min(rise + want * kDiv, off))
        << "duty of period " << i << " (V " << v << ", " << want << " counts)";
    ++k;
  }
  EXPECT_EQ(k, p.size()) << "a rise off the period grid";
  ASSERT_GE(duty.size(), 11u);
  EXPECT_LT(duty[0], power / 4u) << "the first period at about V_entry";
  for (size_t i = 1; i < 5; ++i) EXPECT_GT(duty[i], duty[i - 1]) << "accelerating, period " << i;
  EXPECT_EQ(duty[6], power) << "cruise";
  for (size_t i = 8; i < duty.size(); ++i) EXPECT_LE(duty[i], duty[i - 1]) << "decelerating " << i;
  EXPECT_LT(duty.back(), power / 3u);
}

// A feed hold during a long LINE: with M4 each period's duty follows the rate down (power * r /
// 2^32 within one count, r ramping linearly from the hold frame), to 0 before the laser falls at
// rate 0; with M3 every period keeps the full power until the laser falls. After the resume the
// PWM restarts kLat + 1 clocks after the laser (M4: on that grid once the rate gives a count).
TEST(LaserPwm, HoldRampsDynamicPowerDownConstantStays) {
  for (bool dyn : {true, false}) {
    PwmBench b;
    if (dyn) b.ack(m4(b.seq++, true));
    const uint8_t power = 200;
    b.ack(v2::line(b.seq++, 1, power, static_cast<uint32_t>(40 * kPeriod), {4000, 0}, false));
    ASSERT_TRUE(b.wait_laser_edges(1, 100'000));
    const uint64_t on = b.laser[0].cycle;
    while (b.cycle() < on + 2 * kPeriod + kPeriod / 2) b.tick();
    // 100 % to 0 in 1560 rate periods of 256 clocks: about 8 PWM periods
    const uint32_t ramp = static_cast<uint32_t>(((uint64_t{1} << 32) + 1559) / 1560);
    b.send(motion(spec::kMotionHold, ramp));
    const uint64_t hold = b.cycle();
    ASSERT_TRUE(b.wait_laser_edges(2, 12 * kPeriod)) << "laser low at rate 0";
    const uint64_t stop = b.laser[1].cycle;
    EXPECT_NEAR(static_cast<double>(stop - hold), 1560.0 * 256, 3 * 256.0) << "hold ramp";
    b.idle(2 * kPeriod);
    const auto p = b.pulses();
    ASSERT_FALSE(b.pwm.back().high);
    EXPECT_LE(b.pwm.back().cycle, stop) << "no PWM after the laser fell";
    size_t ramped = 0;
    for (size_t i = 0; i < p.size(); ++i) {
      const uint64_t sample = p[i].rise - kLat - 1;
      if (p[i].fall == stop) break;  // cut by the laser
      const uint64_t got = (p[i].fall - p[i].rise) / kDiv;
      if (!dyn || sample < hold) {
        EXPECT_EQ(got, power) << "period " << i << (dyn ? " before the hold" : " (M3)");
        continue;
      }
      ++ramped;
      const double r = 1.0 - static_cast<double>(sample - hold) / (1560.0 * 256);
      EXPECT_NEAR(static_cast<double>(got), power * r, 1.5) << "period " << i << " in the ramp";
      if (i > 0) {
        EXPECT_LE(got, (p[i - 1].fall - p[i - 1].rise) / kDiv) << "period " << i;
      }
    }
    if (dyn) {
      EXPECT_GE(ramped, 6u) << "periods in the ramp";
    }
    // resume: the laser rises again and the PWM kLat + 1 clocks after it
    b.send(motion(spec::kMotionResume, ramp));
    ASSERT_TRUE(b.wait_laser_edges(3, 100'000)) << "laser after the resume";
    b.idle(3 * kPeriod);
    const auto q = b.pulses();
    ASSERT_GT(q.size(), p.size()) << (dyn ? "M4" : "M3");
    // M3 at once; M4 from the first period whose rate gives a count (the grid from the laser)
    const uint64_t first = b.laser[2].cycle + kLat + 1;
    if (dyn) {
      EXPECT_EQ((q[p.size()].rise - first) % kPeriod, 0u);
    } else {
      EXPECT_EQ(q[p.size()].rise, first);
    }
  }
}

}  // namespace
