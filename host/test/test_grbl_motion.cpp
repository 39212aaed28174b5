// The grbl front end's feed hold and overrides (docs/grbl.md "Feed hold and overrides") against
// the in-process fake device (fake_v2_device.h), which takes MOTION and freezes its queue at once
// on a hold (STATUS HOLD and STOPPED together): the MOTION frames the engine sends for '!', '~'
// and 0x90-0x9D, the states and Ov it reports, a feed override above 100 % planned by the host,
// and a reset during a hold. The Verilated board's own tests are in test_grbl.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fake_v2_device.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/link/stream_v2.h"

namespace {

namespace grbl = fpgacnc::grbl;
namespace v2 = fpgacnc::protocol::v2;
using fpgacnc::config::MachineConfig;
using fpgacnc::test::FakeV2Device;
using std::chrono::milliseconds;

class FakeRig {
 public:
  explicit FakeRig(FakeV2Device::Options o = options()) : dev_(o) {
    grbl::EngineOptions eo;
    eo.v2 = fpgacnc::link::stream_v2_options(cfg_);
    engine_ = std::make_unique<grbl::Engine>(dev_, cfg_, grbl::settings_from_config(cfg_), eo);
    engine_->connect();
    engine_->take_output();
  }
  static FakeV2Device::Options options() {
    FakeV2Device::Options o;
    o.fifo_depth = 16;
    o.exec_period = std::chrono::microseconds(50'000);  // 50 ms a frame: the job outlasts the keys
    return o;
  }
  void pump() {
    engine_->step(milliseconds(5));
    partial_ += engine_->take_output();
    for (size_t nl; (nl = partial_.find('\n')) != std::string::npos;) {
      std::string l = partial_.substr(0, nl);
      partial_.erase(0, nl + 1);
      if (!l.empty() && l.back() == '\r') l.pop_back();
      if (l.empty()) continue;
      (l[0] == '<' ? reports_ : lines_).push_back(l);
    }
  }
  template <typename P>
  bool pump_until(P pred, int rounds = 20'000) {
    for (int i = 0; i < rounds; ++i) {
      if (pred()) return true;
      pump();
    }
    return pred();
  }
  std::string next_line() {
    EXPECT_TRUE(pump_until([&] { return !lines_.empty(); })) << "no answer";
    if (lines_.empty()) return "";
    std::string l = lines_.front();
    lines_.erase(lines_.begin());
    return l;
  }
  std::string command(const std::string& line) {
    engine_->receive(line + "\n");
    std::string l;
    do {
      l = next_line();
    } while (!l.empty() && l != "ok" && l.rfind("error:", 0) != 0);
    return l;
  }
  std::string report() {
    const size_t n = reports_.size();
    engine_->receive("?");
    EXPECT_TRUE(pump_until([&] { return reports_.size() > n; })) << "no report";
    return reports_.empty() ? "" : reports_.back();
  }
  static std::string state(const std::string& r) { return r.substr(1, r.find('|') - 1); }

  MachineConfig cfg_;
  FakeV2Device dev_;
  std::unique_ptr<grbl::Engine> engine_;
  std::string partial_;
  std::vector<std::string> lines_, reports_;
};

}  // namespace

TEST(GrblMotion, HoldResumeAndOverridesAsMotionFrames) {
  FakeRig rig;
  ASSERT_TRUE(rig.engine_->motion_available());
  ASSERT_EQ(rig.dev_.motions().size(), 1u);  // the session's start: the machine's ramp, 100 %
  EXPECT_EQ(rig.dev_.motions()[0], fpgacnc::link::machine_motion(rig.cfg_));
  EXPECT_EQ(rig.command("G21 G90 F1200"), "ok");
  for (int i = 1; i <= 12; ++i) EXPECT_EQ(rig.command(fmt::format("G1 X{}", i)), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return rig.dev_.executed().size() >= 2; }));
  rig.engine_->receive("!");
  std::string r;
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(r = rig.report()) == "Hold:0"; }, 200))
      << r;
  ASSERT_EQ(rig.dev_.motions().size(), 2u);
  EXPECT_TRUE(rig.dev_.motions()[1].hold);
  // Held: nothing completes while the reports come.
  const size_t done = rig.dev_.executed().size();
  for (int i = 0; i < 5; ++i) EXPECT_EQ(FakeRig::state(rig.report()), "Hold:0");
  EXPECT_EQ(rig.dev_.executed().size(), done);
  // Feed 50 % (five -10 %), rapid 25 %, spindle +10 %: the board's rates, Ov in the next report.
  rig.engine_->receive("\x92\x92\x92\x92\x92\x97\x9A");
  r = rig.report();
  EXPECT_NE(r.find("|Ov:50,25,110"), std::string::npos) << r;
  const auto& m = rig.dev_.motions().back();
  EXPECT_EQ(m.feed, 0x4000);
  EXPECT_EQ(m.rapid, 0x2000);
  EXPECT_FALSE(m.hold || m.resume);
  // Above 100 %: the board stays at 100 %.
  rig.engine_->receive(std::string(10, '\x91'));
  r = rig.report();
  EXPECT_NE(r.find("|Ov:150,25,110"), std::string::npos) << r;
  EXPECT_EQ(rig.dev_.motions().back().feed, 0x8000);
  EXPECT_EQ(rig.engine_->overrides().feed, 150);
  rig.engine_->receive("~");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  EXPECT_TRUE(rig.dev_.motions().back().resume);
  EXPECT_FALSE(rig.dev_.held());
  EXPECT_EQ(rig.dev_.position()[0], 12 * 160);
  EXPECT_EQ(rig.engine_->stats().holds, 1u);
  EXPECT_EQ(rig.engine_->stats().resumes, 1u);
  // '!' at rest does nothing (grbl holds a cycle in progress only).
  const size_t motions = rig.dev_.motions().size();
  rig.engine_->receive("!");
  EXPECT_EQ(FakeRig::state(rig.report()), "Idle");
  EXPECT_EQ(rig.dev_.motions().size(), motions);
}

// Above 100 % the host plans faster: a G1 F600 after 150 % cruises at 900 mm/min (15 mm/s:
// V_cruise in dominant-axis steps per clock, 2^48 scale: 15 * 160 / 5e7 * 2^48).
TEST(GrblMotion, FeedOverrideAbove100PlansTheNextLinesFaster) {
  FakeRig rig;
  rig.engine_->receive(std::string(5, '\x91'));
  rig.report();
  EXPECT_EQ(rig.command("G21 G90 G1 X20 F600"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  ASSERT_EQ(rig.dev_.executed().size(), 1u);
  const auto p = v2::decode_line_profile(rig.dev_.executed()[0], 4);
  const double v_mm_min = static_cast<double>(p.v_cruise) / std::ldexp(1.0, 48) * 5e7 / 160.0 * 60;
  EXPECT_NEAR(v_mm_min, 900.0, 1.0);
}

// 0x18 during a hold: ALARM:3 (grbl); MOTION CANCEL drops the board's queue at rest (nothing more
// runs, the position kept), then the banner; the overrides are back at 100 %.
TEST(GrblMotion, ResetDuringAHoldAlarmsAndCancelsTheQueue) {
  FakeRig rig;
  EXPECT_EQ(rig.command("G21 G90 F1200"), "ok");
  for (int i = 1; i <= 12; ++i) EXPECT_EQ(rig.command(fmt::format("G1 X{}", i)), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return rig.dev_.executed().size() >= 1; }));
  rig.engine_->receive("\x92!");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Hold:0"; }, 200));
  const size_t done = rig.dev_.executed().size();
  const auto at = rig.dev_.position();
  rig.engine_->receive("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:3");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  EXPECT_FALSE(rig.dev_.held());
  EXPECT_GT(rig.dev_.cancelled(), 0u);
  EXPECT_EQ(rig.dev_.executed().size(), done) << "a frame ran after the reset";
  EXPECT_EQ(rig.dev_.position(), at);
  bool cancel = false;
  for (const auto& m : rig.dev_.motions()) cancel |= m.cancel;
  EXPECT_TRUE(cancel);
  EXPECT_EQ(rig.engine_->overrides(), grbl::Overrides{});
  // The new session's MOTION: 100 %.
  EXPECT_EQ(rig.dev_.motions().back().feed, 0x8000);
  EXPECT_EQ(FakeRig::state(rig.report()), "Alarm");
}

// $J= (docs/grbl.md "Jogging"): one straight move, laser off, state Jog while it runs; the
// parser's modes are not changed by it and follow the machine to the jog's end.
TEST(GrblMotion, JogMovesWithoutChangingTheParserState) {
  FakeRig rig;
  EXPECT_EQ(rig.command("G21 G90 G1 F300"), "ok");
  EXPECT_EQ(rig.command("G10 L20 P1 X5"), "ok");  // work X = machine X - (-5): WCO X -5
  EXPECT_EQ(rig.command("$J=G91 X2 F600"), "ok");
  EXPECT_EQ(FakeRig::state(rig.report()), "Jog");
  EXPECT_EQ(rig.command("$J=G91 Y-1 F600"), "ok") << "a jog is taken while jogging";
  EXPECT_EQ(rig.command("G1 X1"), "error:9") << "G-code is locked out while jogging";
  EXPECT_EQ(rig.command("$$"), "error:8");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  ASSERT_EQ(rig.dev_.executed().size(), 2u);
  for (const auto& f : rig.dev_.executed()) {
    const auto p = v2::decode_line_profile(f, 4);
    EXPECT_EQ(p.power, 0) << "a jog fires the laser";
  }
  EXPECT_EQ(rig.dev_.position()[0], 2 * 160);
  EXPECT_EQ(rig.dev_.position()[1], -160);
  // Work coordinates (G90, no G53): X3 work = X-2 machine; inches: Y0.1 in = 2.54 mm machine
  // (work Y offset 0).
  EXPECT_EQ(rig.command("$J=X3 F600"), "ok");
  EXPECT_EQ(rig.command("$J=G20 G53 Y0.1 F20"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  EXPECT_EQ(rig.dev_.position()[0], -2 * 160);
  EXPECT_EQ(rig.dev_.position()[1], static_cast<int32_t>(std::lround(2.54 * 160)));
  // The parser kept G1, G90, G21 and F300 and starts from the jog's end: G91 X1 from -2.
  rig.engine_->receive("$G\n");
  std::string gc;
  while ((gc = rig.next_line()).rfind("[GC:", 0) != 0 && !gc.empty()) {
  }
  EXPECT_NE(gc.find("G1 G54 G17 G21 G90"), std::string::npos) << gc;
  EXPECT_NE(gc.find("F300"), std::string::npos) << gc;
  EXPECT_EQ(rig.next_line(), "ok");
  EXPECT_EQ(rig.command("G91 X1"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  EXPECT_EQ(rig.dev_.position()[0], -1 * 160);
}

TEST(GrblMotion, JogErrorsAsGrbl) {
  FakeRig rig;
  EXPECT_EQ(rig.command("$J=G91 X1"), "error:22");  // no feed
  EXPECT_EQ(rig.command("$J=G91 X1 F0"), "error:22");
  EXPECT_EQ(rig.command("$J=G1 X1 F100"), "error:16");      // a motion mode
  EXPECT_EQ(rig.command("$J=G91 X1 M3 F100"), "error:16");  // an M word
  EXPECT_EQ(rig.command("$J=G91 F100"), "error:16");        // no axis
  EXPECT_EQ(rig.command("$J G91 X1 F100"), "error:3");
  EXPECT_EQ(rig.command("$J=G91 X1 F100 X2"), "error:25");  // a repeated word
  EXPECT_TRUE(rig.dev_.executed().empty());
  // Soft limits on: a target beyond the travel is error:15 and nothing moves (no alarm).
  EXPECT_EQ(rig.command("$20=1"), "ok");
  EXPECT_EQ(rig.command("$J=G53 X1 F600"), "error:15");  // grbl's travel is [-$130, 0]
  EXPECT_EQ(FakeRig::state(rig.report()), "Idle");
  EXPECT_TRUE(rig.dev_.executed().empty());
  // A reset while jogging is ALARM:3; $J is refused in Alarm until $X.
  EXPECT_EQ(rig.command("$J=G91 X-5 F600"), "ok");
  rig.engine_->receive("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:3");
  EXPECT_EQ(rig.command("$J=G91 X-1 F600"), "error:8");
  EXPECT_EQ(rig.command("$X"), "ok");
  EXPECT_EQ(rig.command("$J=G91 X-1 F600"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
}

// 0x85 while jogging: MOTION CANCEL, the board's queue dropped at rest, Idle at the machine's
// position, and the next jog starts there; 0x85 when not jogging does nothing.
TEST(GrblMotion, JogCancelStopsAndFlushes) {
  FakeRig rig;
  for (int i = 0; i < 6; ++i) EXPECT_EQ(rig.command("$J=G91 X1 F600"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return rig.dev_.executed().size() >= 1; }));
  rig.engine_->receive("\x85");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  EXPECT_FALSE(rig.dev_.held());
  bool cancel = false;
  for (const auto& m : rig.dev_.motions()) cancel |= m.cancel;
  EXPECT_TRUE(cancel);
  const size_t done = rig.dev_.executed().size();
  EXPECT_LT(done, 6u) << "the jog was not cancelled";
  const int32_t at = rig.dev_.position()[0];
  EXPECT_EQ(at, static_cast<int32_t>(done) * 160);
  EXPECT_EQ(rig.command("$J=G91 X0.5 F600"), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  EXPECT_EQ(rig.dev_.position()[0], at + 80);
  const size_t motions = rig.dev_.motions().size();
  rig.engine_->receive("\x85");
  EXPECT_EQ(FakeRig::state(rig.report()), "Idle");
  EXPECT_EQ(rig.dev_.motions().size(), motions);
  EXPECT_EQ(rig.command("G0 X0"), "ok");
}

// The motion code the board chooses its rate by: G0 is code 0 (the rapid rate), a G1 with the
// laser off code 1 with power 0 (the feed rate, the laser dark), a G1 under M3 code 1 with power
// (after the OUTPUT of the M3 mode: constant power).
TEST(GrblMotion, FeedMovesWithTheLaserOffAreCode1WithPower0) {
  FakeRig rig;
  for (const char* l : {"G21 G90 G0 X1", "G1 X2 F600", "M3 S1000", "G1 X3", "M5"})
    EXPECT_EQ(rig.command(l), "ok") << l;
  ASSERT_TRUE(rig.pump_until([&] { return FakeRig::state(rig.report()) == "Idle"; }, 2'000));
  ASSERT_EQ(rig.dev_.executed().size(), 4u);
  const auto g0 = v2::decode_line_profile(rig.dev_.executed()[0], 4);
  const auto dark = v2::decode_line_profile(rig.dev_.executed()[1], 4);
  const auto m3 = v2::decode_output(rig.dev_.executed()[2]);
  ASSERT_TRUE(m3.laser_dyn.has_value());
  EXPECT_FALSE(*m3.laser_dyn);
  const auto lit = v2::decode_line_profile(rig.dev_.executed()[3], 4);
  EXPECT_EQ(g0.code, 0);
  EXPECT_EQ(g0.power, 0);
  EXPECT_EQ(dark.code, 1);
  EXPECT_EQ(dark.power, 0);
  EXPECT_EQ(lit.code, 1);
  EXPECT_EQ(lit.power, 255);
}
