#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"

namespace pl = fpgacnc::plan;
using fpgacnc::config::MachineConfig;

namespace {

pl::Plan plan_text(const std::string& text, MachineConfig cfg = {}, double override_pct = 100) {
  pl::PlanOptions o;
  o.feed_override_pct = override_pct;
  return pl::plan_program(fpgacnc::gcode::parse_string(text), cfg, o);
}

std::vector<pl::Segment> segments(const pl::Plan& p) {
  std::vector<pl::Segment> s;
  for (const auto& it : p.items) {
    if (const auto* seg = std::get_if<pl::Segment>(&it)) s.push_back(*seg);
  }
  return s;
}

MachineConfig laser_always() {
  MachineConfig c;
  c.laser_requires_m3 = false;
  return c;
}

}  // namespace

TEST(Planner, InitNumerators) {
  EXPECT_EQ(pl::v1_numerator(50'000'000, 160), 18'750'000u);
  EXPECT_EQ(pl::v1_numerator(50'000'000, 400), 7'500'000u);
  EXPECT_THROW(pl::v1_numerator(50'000'000, 0.1), std::invalid_argument);
  EXPECT_EQ(plan_text("G0 X1").numerator[0], 18'750'000u);
}

TEST(Planner, AbsoluteRoundingDoesNotAccumulate) {
  std::string text = "G91 G1 F100\n";
  for (int i = 0; i < 1000; ++i) text += "X0.0031\n";
  const auto p = plan_text(text);
  EXPECT_EQ(p.final_steps[0], std::llround(3.1 * 160));  // 496; truncating each move gives 0
  int64_t sum = 0;
  for (const auto& s : segments(p)) sum += s.steps[0];
  EXPECT_EQ(sum, 496);
  EXPECT_NEAR(p.final_mm[0], 3.1, 1e-12);
}

TEST(Planner, LongMoveIsSplitNeverClamped) {
  MachineConfig c = laser_always();
  c.steps_per_mm[0] = 10000;  // 600 000 mm = 6e9 steps > INT32_MAX
  c.max_feed_mm_min[0] = 1e6;
  const auto p = plan_text("G1 X600000 Y-1 F1000", c);
  const auto segs = segments(p);
  ASSERT_EQ(segs.size(), 3u);
  int64_t sx = 0, sy = 0;
  for (const auto& s : segs) {
    EXPECT_LE(std::llabs(s.steps[0]), std::numeric_limits<int32_t>::max());
    sx += s.steps[0];
    sy += s.steps[1];
  }
  EXPECT_EQ(sx, 6'000'000'000);
  EXPECT_EQ(sy, -160);
  EXPECT_EQ(p.stats.split_moves, 1u);
  EXPECT_EQ(segs.back().target[0], 6'000'000'000);
  EXPECT_NO_THROW(fpgacnc::protocol::v1::pack_job(p));
}

TEST(Planner, V1FeedMakesTheResultantSpeedF) {
  const auto s = segments(plan_text("G1 X30 Y40 F1000", laser_always()));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].code, 1);
  EXPECT_EQ(s[0].steps[0], 4800);
  EXPECT_EQ(s[0].steps[1], 6400);
  EXPECT_EQ(s[0].feed_v1, 800);  // Y dominant: 1000 * 40 / 50
  // Device: dominant axis at feed_v1, the other in proportion -> resultant = F.
  const double resultant = s[0].feed_v1 * s[0].length_mm / 40.0;
  EXPECT_NEAR(resultant, 1000.0, 1.0);
  // Odd diagonal: rounding only.
  const auto d = segments(plan_text("G1 X7.3 Y-2.9 F1234", laser_always()));
  const double dx = d[0].steps[0] / 160.0, dy = d[0].steps[1] / 160.0;
  EXPECT_NEAR(d[0].feed_v1 * std::hypot(dx, dy) / std::fabs(dx), 1234.0,
              0.5 * std::hypot(dx, dy) / std::fabs(dx) + 1e-9);
  // X wins ties.
  const auto t = segments(plan_text("G1 X10 Y-10 F1000", laser_always()));
  EXPECT_EQ(t[0].feed_v1, static_cast<uint16_t>(std::llround(1000 / std::sqrt(2.0))));
}

TEST(Planner, FeedOverrideAndRapids) {
  auto s = segments(plan_text("G1 X30 Y40 F1000", laser_always(), 50));
  EXPECT_EQ(s[0].feed_v1, 400);
  EXPECT_EQ(s[0].feed_mm_min, 1000.0);
  s = segments(plan_text("G1 X30 Y40 F1000", laser_always(), 150));
  EXPECT_EQ(s[0].feed_v1, 1200);
  // Rapids: configured rapid feed, no override.
  s = segments(plan_text("G0 X10 F100", laser_always(), 50));
  EXPECT_EQ(s[0].code, 0);
  EXPECT_EQ(s[0].feed_v1, 3000);
}

TEST(Planner, FeedClampIsCounted) {
  const auto p = plan_text("G1 X100 Y0.01 F0.2\nG1 X200 Y0 F100000", [] {
    auto c = laser_always();
    c.max_feed_mm_min = {1e6, 1e6, 1e6, 1e6};
    return c;
  }());
  const auto s = segments(p);
  EXPECT_EQ(s[0].feed_v1, 1);
  EXPECT_EQ(s[1].feed_v1, 65535);
  EXPECT_EQ(p.stats.feed_clamped, 2u);
}

TEST(Planner, LaserRequiresM3) {
  MachineConfig c;  // laser_requires_m3 = true
  auto s =
      segments(plan_text("G1 X1 F500\nM3 S100\nG1 X2\nM3 S0\nG1 X3\nM5\nG1 X4\nM4\nG2 X5 Y1 "
                         "I0 J1",
                         c));
  ASSERT_GE(s.size(), 5u);
  EXPECT_EQ(s[0].code, 0);
  EXPECT_EQ(s[0].feed_v1, 500);  // a non-cutting G1 keeps its feed
  EXPECT_EQ(s[1].code, 1);
  EXPECT_EQ(s[2].code, 0);
  EXPECT_EQ(s[3].code, 0);
  EXPECT_EQ(s[4].code, 0);  // M4 but the last S is 0: laser off
  c.laser_requires_m3 = false;
  s = segments(plan_text("G1 X1 F500\nG3 X2 Y1 I0 J1", c));
  EXPECT_EQ(s[0].code, 1);
  EXPECT_EQ(s.back().code, 3);
}

TEST(Planner, ZEOnlyMovesAndDwellAndHeater) {
  const auto p =
      plan_text("G1 Z-1 F100\nG4 S0.25\nM104 S200\nG1 X1 E2", laser_always());  // Marlin: S in s
  EXPECT_EQ(p.stats.ze_only_moves, 1u);
  EXPECT_EQ(p.stats.dwells, 1u);
  EXPECT_EQ(p.stats.heater_commands, 1u);
  ASSERT_EQ(p.items.size(), 4u);
  EXPECT_EQ(std::get<pl::Segment>(p.items[0]).steps[2], -400);
  EXPECT_DOUBLE_EQ(std::get<pl::Dwell>(p.items[1]).seconds, 0.25);
  EXPECT_EQ(std::get<pl::HeaterCommand>(p.items[2]).mcode, 104);
  EXPECT_EQ(p.final_steps, (pl::Steps4{160, 0, -400, 200}));
  const auto job = fpgacnc::protocol::v1::pack_job(p);
  EXPECT_EQ(job.ze_only, 1u);
  EXPECT_EQ(job.steps[0].packet, fpgacnc::protocol::v1::pack_motion(1, 0, 0, 100));
}

// dwell_time scales G4 (a test configuration's compressed job); feeds are the feed override's.
TEST(Planner, DwellTimeScalesDwellsOnly) {
  MachineConfig c = laser_always();
  c.dwell_time_pct = 4.0;
  const auto p = plan_text("G1 X1 F100\nG4 P0.5\nG1 X2", c);
  ASSERT_EQ(p.items.size(), 3u);
  EXPECT_DOUBLE_EQ(std::get<pl::Dwell>(p.items[1]).seconds, 0.02);
  EXPECT_EQ(std::get<pl::Segment>(p.items[0]).feed_mm_min,
            std::get<pl::Segment>(plan_text("G1 X1 F100").items[0]).feed_mm_min);
  EXPECT_NEAR(p.stats.estimated_time_s, 2 * 60.0 / 100.0 + 0.02, 1e-9);
}

TEST(Planner, StreamingFilePlanEqualsProgramPlan) {
  const std::string path = std::string(FPGACNC_CORPUS_DIR) + "/jsdc-laser.gcode";
  MachineConfig c;
  const auto a = pl::plan_gcode_file(path, c, {});
  const auto b = pl::plan_program(fpgacnc::gcode::parse_file(path), c, {});
  EXPECT_EQ(fpgacnc::protocol::v1::job_bytes(a), fpgacnc::protocol::v1::job_bytes(b));
  EXPECT_EQ(a.final_steps, b.final_steps);
}

// Measured, not asserted: planning throughput on the 2 MB printer job.
TEST(Planner, ThroughputOnPartGcode) {
  const std::string path = std::string(FPGACNC_CORPUS_DIR) + "/part.gcode";
  const auto t0 = std::chrono::steady_clock::now();
  const auto p = pl::plan_gcode_file(path, {}, {});
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(p.stats.segments, 40000u);
  std::printf("plan throughput: %.0f lines/s (%llu lines in %.3f s)\n",
              static_cast<double>(p.input.lines) / s,
              static_cast<unsigned long long>(p.input.lines), s);
}
