// Heaters on the simulated board (label system): the Verilated cnc_core with its heater block,
// the LTC2308 pin model on its ADC pins and the plant models of
// models/include/fpgacnc/models/thermal_plant.h on its heater pins, with the scaled thermal time
// base (one plant second per SimBoard::kSampleClks = 102 400 clocks, docs/heater.md "Simulated
// board"). Host side: the v2 streamer with heaters and the relay autotune, over the board's pty.
//  - autotune of the bed through the board: critical period within 15 % of the reference 53 s;
//  - the start of part.gcode with a printer start sequence (M140/M104/M190/M109): waits, then the
//    first moves; the figures (warm-up times) are printed;
//  - a sensor-open fault injected during the bed warm-up stops the job with an error naming the
//    G-code line and the fault.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "../../test/stream_plan.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/heat/autotune_link.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace sb = fpgacnc::simboard;
namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
namespace heat = fpgacnc::heat;
namespace plan = fpgacnc::plan;
using namespace std::chrono_literals;

namespace {

// Printer start sequence put in front of the corpus file (part.gcode has no heater commands).
constexpr const char* kStart =
    "M140 S60 ; bed\n"
    "M104 S200 ; hot end, heats while the bed does\n"
    "M190 S60\n"
    "M109 S200\n";
constexpr int kStartLines = 4;

// The first `lines` lines of part.gcode (0: all).
std::string part_lines(size_t lines) {
  std::ifstream in(FPGACNC_CORPUS_DIR "/part.gcode");
  EXPECT_TRUE(in.good()) << "cannot open part.gcode";
  std::string out, l;
  for (size_t n = 0; std::getline(in, l) && (lines == 0 || n < lines); ++n) out += l + "\n";
  return out;
}

// Timers in board time (BoardLink, link.h): a heater poll every 5 ms of board time is one every
// 2.4 plant seconds.
lk::StreamV2Options board_options(sb::SimBoard& b) {
  lk::StreamV2Options o;
  o.retransmit_timeout = 1000ms;
  o.heater_poll = 5ms;
  o.plant_time = [&b] { return b.plant_seconds(); };
  return o;
}

fpgacnc::config::MachineConfig board_config() {
  fpgacnc::config::MachineConfig c;
  c.heaters.watchdog_s = 60.0;  // plant seconds; the host polls every 2.4 (board_options)
  return c;
}

}  // namespace

TEST(HeaterBoard, AutotuneBedCriticalPeriodNear53s) {
  sb::BoardOptions bo;
  bo.initial_c = {20.0, 58.0};  // bed near the relay setpoint: no 7-minute warm-up
  sb::BoardLink link(bo);
  auto& board = link.board();
  const auto cfg = board_config();
  heat::AutotuneLinkOptions o;
  o.channel = heat::kBed;
  o.relay.setpoint_c = 60.0;
  o.relay.u_high = 12.0;  // the reference relay test: 0/12 V
  o.relay.skip_cycles = 1;
  o.relay.cycles = 2;  // the simulated cycles are alike (58.0 s each with 2, 3 or more)
  o.max_plant_s = 1200.0;
  o.poll = 2ms;  // board time: about one plant second
  o.plant_time = [&board] { return board.plant_seconds(); };
  const auto r = heat::run_relay_test(link, cfg, o);
  fmt::print("{}", heat::format_autotune(r.result, o.relay));
  fmt::print("{} STATUS samples over {:.0f} plant s ({:.1f} s wall); board: {}\n", r.samples.size(),
             r.plant_s, r.wall_s, board.stats_line());
  ASSERT_TRUE(r.result.ok) << r.result.message;
  EXPECT_NEAR(r.result.period_s, 53.0, 53.0 * 0.15)
      << "critical period on the simulated bed, expected 53 s +-15 %";
  EXPECT_GT(r.result.ku, 0.0);
  const auto t = board.thermal();
  EXPECT_EQ(t.adc_violations, 0u) << t.adc_first_violation;
}

TEST(HeaterBoard, PartGcodeStartWithHeaters) {
  // Start sequence + the first 11 lines of part.gcode: N = 3 moves (Z up, the travel to the start
  // point, the prime: 1.5 s of machine time at the file's feeds), then heaters off. The moves are
  // not what is tested here, and each second of machine time is 50 M board clocks: a 1000 % feed
  // override on a fast machine (X/Y 120 000 mm/min at 40 000 mm/s^2, Z 3 000 mm/min, Z and E at
  // 10 000 mm/s^2) runs them in about 0.1 s. The whole file runs behind `make soak`
  // (soak_part_heaters).
  const size_t kPartLines = 11;
  const std::string g = std::string(kStart) + part_lines(kPartLines) + "M104 S0\nM140 S0\n";
  auto cfg = board_config();
  cfg.max_feed_mm_min[0] = cfg.max_feed_mm_min[1] = 120000.0;
  cfg.max_accel_mm_s2[0] = cfg.max_accel_mm_s2[1] = 40000.0;
  cfg.max_feed_mm_min[2] = 3000.0;
  cfg.max_accel_mm_s2[2] = cfg.max_accel_mm_s2[3] = 10000.0;
  plan::PlanOptions po;
  po.feed_override_pct = 1000.0;
  const auto p = plan::plan_program(fpgacnc::gcode::parse_string(g, "part-start.gcode"), cfg, po);
  sb::BoardLink link(sb::BoardOptions{});
  auto& board = link.board();
  auto o = board_options(board);
  size_t statuses = 0;
  o.on_status = [&](const v2::Status&) { ++statuses; };
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = fpgacnc::test::stream_plan(link, p, cfg, o);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  fmt::print("{}", lk::format_report(r));
  fmt::print(
      "part.gcode start ({} lines, {} moves) with heaters: {:.1f} s wall, {:.0f} plant s; "
      "board: {}\n",
      kPartLines, p.stats.segments, wall, board.plant_seconds(), board.stats_line());
  EXPECT_TRUE(r.position_ok);
  EXPECT_EQ(p.stats.segments, 3u);
  ASSERT_EQ(r.heater_waits.size(), 2u);
  EXPECT_EQ(r.heater_waits[0].mcode, 190);
  EXPECT_EQ(r.heater_waits[0].source_line, 3);
  EXPECT_FALSE(r.heater_waits[0].skipped);
  EXPECT_GT(r.heater_waits[0].plant_s, 60.0) << "the bed cannot reach 60 degC that fast";
  EXPECT_LT(r.heater_waits[0].plant_s, 900.0) << "bed warm-up over 15 minutes";
  EXPECT_EQ(r.heater_waits[1].mcode, 109);
  EXPECT_GT(statuses, 10u);
  EXPECT_NEAR(r.heater_waits[0].end_c, 60.0, cfg.heaters.bed().wait_tolerance_c);
  EXPECT_NEAR(r.heater_waits[1].end_c, 200.0, cfg.heaters.hotend().wait_tolerance_c);
  // No move before the waits ended: the first STEP edge comes after the M109 wait (plant time).
  const auto edges = board.edges();
  ASSERT_FALSE(edges.empty());
  const double first_step_plant =
      static_cast<double>(edges.front().cycle) / static_cast<double>(sb::SimBoard::kSampleClks);
  EXPECT_GT(first_step_plant, r.heater_waits[1].end_plant_s)
      << "a move ran before the M109 wait ended";
  fmt::print("bed 20 -> 60 degC (M190): {:.0f} plant s; first STEP at plant {:.0f} s\n",
             r.heater_waits[0].plant_s, first_step_plant);
  // Heaters off at the end (M104 S0, M140 S0): STATUS says disabled.
  ASSERT_EQ(r.status_end.heaters.size(), 2u);
  EXPECT_FALSE(r.status_end.heaters[0].enabled());
  EXPECT_FALSE(r.status_end.heaters[1].enabled());
  EXPECT_EQ(r.status_end.faults, 0);
  const auto t = board.thermal();
  EXPECT_EQ(t.adc_violations, 0u) << t.adc_first_violation;
}

TEST(HeaterBoard, SensorOpenDuringWarmUpStopsTheJob) {
  const std::string g = "M140 S60\nM190 S60\nG1 X2 F600\n";
  const auto cfg = board_config();
  const auto p = plan::plan_program(fpgacnc::gcode::parse_string(g, "fault.gcode"), cfg, {});
  sb::BoardLink link(sb::BoardOptions{});
  auto& board = link.board();
  auto o = board_options(board);
  double injected_at = -1.0;
  o.on_status = [&](const v2::Status&) {
    if (injected_at < 0 && board.plant_seconds() > 30.0) {
      injected_at = board.plant_seconds();
      board.inject_sensor(heat::kBed, sb::SensorFault::kOpen);
    }
  };
  try {
    fpgacnc::test::stream_plan(link, p, cfg, o);
    FAIL() << "an open bed sensor did not stop the job";
  } catch (const lk::Error& e) {
    const std::string w = e.what();
    fmt::print("sensor open at {:.1f} plant s -> {}\n", injected_at, w);
    EXPECT_NE(w.find("line fault.gcode:2 (M190 S60, waiting)"), std::string::npos) << w;
    EXPECT_NE(w.find("bed heater fault MINTEMP"), std::string::npos) << w;
  }
  EXPECT_GT(injected_at, 0.0);
  // The heater pin is off: the bed cools from here on.
  const auto t = board.thermal();
  EXPECT_EQ(t.last_duty[1], 0.0) << "bed heater still driven after the fault";
}
