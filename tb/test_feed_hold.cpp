// Feed hold, resume and the feed / rapid rates through cnc_core's pins (docs/timing.md "Feed hold
// and overrides (the motion rate)", docs/machine.md "Feed hold and overrides").
//
// The motion rate stretches the time between a segment's ticks and changes nothing else, so each
// test runs a job twice, once plainly and once with holds or rates, and compares what the pins
// show:
//   - the same STEP events in the same order, with the same steps coinciding (the path is the
//     planned one, tick for tick) and the same final positions;
//   - never a shorter time between two consecutive events than in the plain run (the rate never
//     exceeds 100 %: no axis moves faster than planned);
//   - while held: no STEP rise once the rate is 0, STATUS HOLD and STOPPED, the laser low;
//   - the deceleration of the dominant axis during the hold, measured from its STEP intervals,
//     within the bound of docs/timing.md (the ramp's share plus the plan's own deceleration and
//     the one-clock quantisation of the edges); the figures are printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "Vcnc_core_heat.h"
#include "common/core_pins.h"
#include "common/pin_harness.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec.h"
#include "verilated.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
namespace spec = fpgacnc::spec;

constexpr int kAxes = 4;
constexpr uint64_t kOne = uint64_t{1} << 48;  // LINE_PROFILE speeds: UQ0.48 steps per clock
constexpr uint64_t kPeriod = uint64_t{1} << spec::kDefaultRatePeriodLog2;
constexpr double kClkHz = 50e6;

class Core : public fpgacnc::tb::PinHarness<Vcnc_core_heat> {
 public:
  Core() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_heat>(), true, 3'000'000.0) {
    fpgacnc::tb::reset_core(*this);
  }
  std::vector<v2::DeviceMsg> msgs;
  uint64_t laser_high_clocks = 0;  // clocks with the laser pin high (counted from reset)

  // Sends a frame and runs until its answer (the first message after it that is not a DONE).
  v2::DeviceMsg ask(const std::vector<uint8_t>& f) {
    const size_t n0 = msgs.size();
    send(f);
    for (uint64_t i = 0; i < 200'000; ++i) {
      for (size_t k = n0; k < msgs.size(); ++k)
        if (msgs[k].type != v2::kDone) return msgs[k];
      tick();
    }
    ADD_FAILURE() << "no answer by cycle " << cycle();
    return {};
  }
  uint8_t state() { return static_cast<uint8_t>(ask(v2::status_query()).u8(0)); }

 protected:
  void observe() override {
    if (tx_bytes().size() != tx_seen_) {
      tx_seen_ = tx_bytes().size();
      if (auto m = parser_.push(tx_bytes().back().value, tx_bytes().back().start_cycle))
        msgs.push_back(*m);
    }
    if (dut().laser) ++laser_high_clocks;
  }

 private:
  size_t tx_seen_ = 0;
  v2::DeviceParser parser_;
};

std::vector<uint8_t> motion(uint8_t flags, uint16_t feed, uint16_t rapid, uint32_t ramp,
                            size_t cut = 0) {
  std::vector<uint8_t> p{flags};
  v2::be16(p, feed);
  v2::be16(p, rapid);
  v2::be32(p, ramp);
  p.resize(p.size() - cut);
  return v2::frame(spec::kTypeMotion, 0, p);
}
constexpr uint8_t kHold = spec::kMotionHold, kResume = spec::kMotionResume,
                  kCancel = spec::kMotionCancel;
constexpr uint16_t kFull = spec::kRateOne;

// Every STEP rise of axes 0 and 1 in time order: (clock, axis bits rising in that clock).
struct Event {
  uint64_t clock;
  unsigned axes;
};
std::vector<Event> events(Core& c) {
  std::vector<Event> ev;
  for (int a = 0; a < 2; ++a)
    for (uint64_t t : c.mon().axis(a).rises) ev.push_back({t, 1u << a});
  std::sort(ev.begin(), ev.end(), [](const Event& x, const Event& y) { return x.clock < y.clock; });
  std::vector<Event> merged;
  for (const Event& e : ev) {
    if (!merged.empty() && merged.back().clock == e.clock)
      merged.back().axes |= e.axes;
    else
      merged.push_back(e);
  }
  return merged;
}

// The same STEP events in the same order and grouping, never closer together than planned.
void expect_same_path(const std::vector<Event>& plain, const std::vector<Event>& held) {
  ASSERT_EQ(plain.size(), held.size()) << "step events";
  for (size_t k = 0; k < plain.size(); ++k) {
    ASSERT_EQ(plain[k].axes, held[k].axes) << "event " << k << " (clock " << held[k].clock << ")";
    if (k > 0) {
      ASSERT_GE(held[k].clock - held[k - 1].clock, plain[k].clock - plain[k - 1].clock)
          << "event " << k << " came faster than planned (clock " << held[k].clock << ")";
    }
  }
}

// A long profiled move on X and Y (negative: no DIR change after reset): accelerates from V_entry
// to V_cruise over about 100 000 clocks, cruises, decelerates at the stopping point.
struct Job {
  int32_t nx = -4000, ny = -3000;
  uint64_t vc = kOne / 500, ve = kOne / 20000, vx = kOne / 20000;
  uint32_t a = 5'629'500;  // V_cruise / 100 000 clocks, in 2^-48 steps per clock^2
  std::vector<uint8_t> frame(uint8_t seq, uint8_t power) const {
    const double dist = (std::pow(double(vc), 2) - std::pow(double(vx), 2)) / (2.0 * a) / kOne;
    const auto d = static_cast<uint32_t>(-nx - static_cast<int32_t>(std::ceil(dist)) - 1);
    return v2::line_profile(seq, 1, power, ve, vc, vx, a, d, {nx, ny, 0, 0}, false);
  }
};

void run_until_done(Core& c, uint32_t segments, uint64_t limit) {
  for (uint64_t i = 0; i < limit && c.dut().segments_done < segments; ++i) c.tick();
  ASSERT_EQ(c.dut().segments_done, segments) << "by cycle " << c.cycle();
  c.idle(400);
}

TEST(FeedHold, HoldDuringAccelerationStopsOnThePathAndResumes) {
  const Job job;
  Core plain;
  plain.ask(v2::hello());
  plain.send(job.frame(0, 200));
  run_until_done(plain, 1, 10'000'000);

  Core held;
  held.ask(v2::hello());
  held.send(job.frame(0, 200));
  // wait for the move to start, then hold 50 000 clocks into its acceleration
  for (int i = 0; i < 100'000 && !held.dut().running; ++i) held.tick();
  ASSERT_TRUE(held.dut().running);
  held.idle(50'000);
  const uint32_t ramp = static_cast<uint32_t>((uint64_t{1} << 32) / 200);  // 0 in 200 periods
  const uint64_t hold_clock = held.cycle();
  const v2::DeviceMsg ans = held.ask(motion(kHold, kFull, kFull, ramp));
  ASSERT_EQ(ans.type, v2::kStatus) << "MOTION is answered by STATUS";
  EXPECT_TRUE(ans.u8(0) & spec::kStateHold) << "STATUS HOLD right after the frame";
  const size_t x_before = held.mon().axis(0).rises.size();
  // the rate reaches 0 within 200 periods of the frame; wait for that and well beyond
  held.idle(210 * kPeriod);
  const size_t x_stopped = held.mon().axis(0).rises.size();
  const uint64_t laser_before = held.laser_high_clocks;
  held.idle(300'000);
  EXPECT_EQ(held.mon().axis(0).rises.size(), x_stopped) << "a STEP while the rate is 0";
  EXPECT_EQ(held.laser_high_clocks, laser_before) << "the laser is low while motion is stopped";
  const uint8_t st = held.state();
  EXPECT_EQ(st & (spec::kStateHold | spec::kStateStopped), spec::kStateHold | spec::kStateStopped)
      << "state " << int(st);
  EXPECT_TRUE(st & spec::kStateBusy) << "the segment stays in progress during the hold";
  EXPECT_EQ(held.dut().segments_done, 0u);

  // deceleration at the pins: X's STEP intervals from the hold frame to the stop
  const auto& xr = held.mon().axis(0).rises;
  double peak = 0;  // steps per clock^2
  const double v_hold = 1.0 / double(xr[x_before] - xr[x_before - 1]);
  for (size_t k = x_before + 1; k + 1 < x_stopped; ++k) {
    const double d1 = double(xr[k] - xr[k - 1]), d2 = double(xr[k + 1] - xr[k]);
    peak = std::max(peak, (1.0 / d1 - 1.0 / d2) / ((d1 + d2) / 2.0));
  }
  const double t_stop = double(xr[x_stopped - 1] - hold_clock);
  const double vc = double(job.vc) / kOne;
  const double ramp_share = vc * double(ramp) / 4294967296.0 / double(kPeriod);
  const double plan_share = double(job.a) / kOne;
  const double spc = kClkHz * kClkHz;  // steps per clock^2 -> steps per s^2
  std::printf(
      "hold at %.0f steps/s: %zu X steps to rest over %.0f clocks (%.2f ms); average deceleration "
      "%.4g steps/s^2, peak over one step pair %.4g steps/s^2; bound: ramp %.4g + plan %.4g\n",
      v_hold * kClkHz, x_stopped - x_before, t_stop, t_stop / kClkHz * 1e3, v_hold / t_stop * spc,
      peak * spc, ramp_share * spc, plan_share * spc);
  EXPECT_LE(peak, 1.25 * (ramp_share + plan_share)) << "hold deceleration above the bound";

  EXPECT_EQ(held.ask(motion(kResume, kFull, kFull, ramp)).u8(0) & spec::kStateHold, 0);
  run_until_done(held, 1, 10'000'000);
  EXPECT_EQ(held.state() & spec::kStateStopped, 0);
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(held.dut().position[a], plain.dut().position[a]) << "axis " << a;
  EXPECT_EQ(int32_t(held.dut().position[0]), job.nx);
  expect_same_path(events(plain), events(held));
  for (int a = 0; a < kAxes; ++a)
    for (auto& v : held.mon().check_pulses(a, fpgacnc::tb::AxisTiming{})) ADD_FAILURE() << v;
}

TEST(FeedHold, FeedAndRapidRatesStretchTheJobExactly) {
  // LINE segments: code 0 (rapid) then code 1 (feed), X only, T clocks each
  auto job = [](Core& c) {
    c.send(v2::line(0, 0, 0, 40'000, {-80, 0, 0, 0}, true));
    c.send(v2::line(1, 1, 0, 40'000, {-80, -40, 0, 0}, true));
  };
  Core plain;
  plain.ask(v2::hello());
  job(plain);
  run_until_done(plain, 2, 1'000'000);

  Core slow;
  slow.ask(v2::hello());
  // rapid 25 %, feed 50 %, reached within one period (the largest ramp)
  ASSERT_EQ(slow.ask(motion(0, kFull / 2, kFull / 4, 0xFFFF'FFFFu)).type, v2::kStatus);
  slow.idle(2 * kPeriod);
  job(slow);
  run_until_done(slow, 2, 2'000'000);
  const auto p = events(plain), s = events(slow);
  expect_same_path(p, s);
  // 80 rapid X steps at 25 % (a tick every 4th clock), then 80 at 50 %: the first rapid step comes
  // 4x as late, the first feed step after the change of rate; overall between 2x and 4x
  const double rapid_ratio = double(s[79].clock - s[0].clock) / double(p[79].clock - p[0].clock);
  const double feed_ratio =
      double(s.back().clock - s[90].clock) / double(p.back().clock - p[90].clock);
  std::printf("rapid 25 %%: %.4fx the plain time; feed 50 %%: %.4fx\n", rapid_ratio, feed_ratio);
  EXPECT_NEAR(rapid_ratio, 4.0, 0.01);
  EXPECT_NEAR(feed_ratio, 2.0, 0.01);
  for (int a = 0; a < kAxes; ++a)
    EXPECT_EQ(slow.dut().position[a], plain.dut().position[a]) << "axis " << a;
}

TEST(FeedHold, CancelStopsOnThePathThenDropsTheQueueKeepingThePosition) {
  const Job job;
  Core c;
  c.ask(v2::hello());
  c.send(job.frame(0, 200));
  c.send(job.frame(1, 200));
  c.send(v2::line(2, 1, 0, 10'000, {-20, 0, 0, 0}, true));
  for (int i = 0; i < 100'000 && !c.dut().running; ++i) c.tick();
  c.idle(200'000);  // cruising in the first move, the other two queued
  const uint32_t ramp = static_cast<uint32_t>((uint64_t{1} << 32) / 200);
  const v2::DeviceMsg ans = c.ask(motion(kCancel, kFull, kFull, ramp));
  ASSERT_EQ(ans.type, v2::kStatus);
  EXPECT_TRUE(ans.u8(0) & spec::kStateHold) << "a cancel holds first";
  c.idle(210 * kPeriod + 1000);
  const uint8_t st = c.state();
  EXPECT_EQ(st & (spec::kStateBusy | spec::kStateHold | spec::kStateFault), 0)
      << "after a cancel: idle, no hold, no fault (state " << int(st) << ")";
  EXPECT_EQ(st & spec::kStatePosUntrusted, 0) << "a cancel keeps the positions trusted";
  EXPECT_EQ(c.dut().segments_done, 0u) << "the dropped segments are not done";
  EXPECT_EQ(c.dut().fifo_level, 0u);
  EXPECT_EQ(c.dut().faults, 0u);
  // the position counters are the steps the pins made, and the motion stopped short of the end
  for (int a = 0; a < 2; ++a)
    EXPECT_EQ(int32_t(c.dut().position[a]), -int32_t(c.mon().axis(a).rises.size())) << "axis " << a;
  const int32_t x = int32_t(c.dut().position[0]);
  EXPECT_GT(x, job.nx);
  EXPECT_LT(x, 0);
  // a new move runs from there (the rate comes back from 0 with the ramp)
  c.send(v2::line(3, 1, 0, 10'000, {-20, 0, 0, 0}, true));
  run_until_done(c, 1, 1'000'000);
  EXPECT_EQ(int32_t(c.dut().position[0]), x - 20);
  for (int a = 0; a < kAxes; ++a)
    for (auto& v : c.mon().check_pulses(a, fpgacnc::tb::AxisTiming{})) ADD_FAILURE() << v;
}

TEST(FeedHold, BadMotionFramesAreRefusedAndChangeNothing) {
  Core c;
  c.ask(v2::hello());
  struct Bad {
    const char* what;
    std::vector<uint8_t> f;
    uint8_t reason;
  };
  const std::vector<Bad> bad = {
      {"HOLD and RESUME", motion(kHold | kResume, kFull, kFull, 1000), spec::kNakBadField},
      {"CANCEL and RESUME", motion(kCancel | kResume, kFull, kFull, 1000), spec::kNakBadField},
      {"reserved flag bit 3", motion(0x08, kFull, kFull, 1000), spec::kNakBadField},
      {"feed 0", motion(kHold, 0, kFull, 1000), spec::kNakBadField},
      {"feed above 100 %", motion(kHold, kFull + 1, kFull, 1000), spec::kNakBadField},
      {"rapid 0", motion(kHold, kFull, 0, 1000), spec::kNakBadField},
      {"rapid above 100 %", motion(kHold, kFull, 0xFFFF, 1000), spec::kNakBadField},
      {"ramp 0", motion(kHold, kFull, kFull, 0), spec::kNakBadField},
      {"8 bytes", motion(kHold, kFull, kFull, 1000, 1), spec::kNakBadLength},
  };
  for (const Bad& b : bad) {
    const v2::DeviceMsg m = c.ask(b.f);
    EXPECT_EQ(m.type, v2::kNak) << b.what;
    if (m.type == v2::kNak) {
      EXPECT_EQ(m.u8(1), b.reason) << b.what;
    }
  }
  EXPECT_EQ(c.state() & (spec::kStateHold | spec::kStateStopped), 0) << "a refused frame held";
  // a job still runs at full rate
  c.send(v2::line(0, 1, 0, 10'000, {-20, 0, 0, 0}, true));
  run_until_done(c, 1, 200'000);
  const auto& xr = c.mon().axis(0).rises;
  ASSERT_EQ(xr.size(), 20u);
  EXPECT_EQ(xr.back() - xr.front(), 19u * 500u) << "full rate: a step every 500 clocks";
}

TEST(FeedHold, HoldAndCycleStartButtons) {
  const Job job;
  Core c;
  c.ask(v2::hello());
  const uint32_t ramp = static_cast<uint32_t>((uint64_t{1} << 32) / 200);  // 0 in 200 periods
  ASSERT_EQ(c.ask(motion(0, kFull, kFull, ramp)).type, v2::kStatus);
  c.send(job.frame(0, 0));
  for (int i = 0; i < 100'000 && !c.dut().running; ++i) c.tick();
  c.idle(150'000);  // cruising
  // a bounce shorter than the filter (LIMIT_FILTER_CLKS, 50 000 clocks) is ignored
  c.dut().hold_in = 1;
  c.idle(20'000);
  c.dut().hold_in = 0;
  c.idle(60'000);
  EXPECT_EQ(c.state() & spec::kStateHold, 0) << "a 20 000-clock press held";
  c.dut().hold_in = 1;
  c.idle(60'000);
  c.dut().hold_in = 0;
  EXPECT_TRUE(c.state() & spec::kStateHold);
  c.idle(210 * kPeriod);
  const size_t n = c.mon().axis(0).rises.size();
  c.idle(100'000);
  EXPECT_EQ(c.mon().axis(0).rises.size(), n) << "steps after the hold completed";
  EXPECT_TRUE(c.state() & spec::kStateStopped);
  c.dut().start_in = 1;
  c.idle(60'000);
  c.dut().start_in = 0;
  EXPECT_EQ(c.state() & spec::kStateHold, 0) << "cycle start ends the hold";
  run_until_done(c, 1, 20'000'000);
  EXPECT_EQ(int32_t(c.dut().position[0]), job.nx);
  EXPECT_EQ(int32_t(c.dut().position[1]), job.ny);
}

}  // namespace
