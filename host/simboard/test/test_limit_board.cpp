// Limit switches on the simulated board (label system): the Verilated cnc_core with the X, Y and
// Z switches wired (SimBoard::kLimitEnable) and a simulated endstop, a v2 job streamed through the
// pty into it. Bounds from docs/machine.md "Timing": for a pin that first reaches the
// synchronizer on edge p, with F = LIMIT_FILTER_CLKS, the alarm latches on p + 2 + F and no STEP
// rises after that edge. Every verdict counts board clocks (edges, STATUS), never wall time.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "../../test/stream_plan.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"
#include "fpgacnc/spec.h"

namespace sb = fpgacnc::simboard;
namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
namespace plan = fpgacnc::plan;
using namespace std::chrono_literals;

namespace {

constexpr uint64_t kF = fpgacnc::spec::kDefaultLimitFilterClks;

// STATUS now, through the pty.
v2::Status status(lk::Link& link, lk::FrameIo& io, lk::StreamV2Report& rep,
                  const lk::StreamV2Options& o) {
  return lk::query_status(link, io, rep, 4, o, "in the test");
}

// FAULT_CLEAR (sequenced at the device's next_seq), its ACK, then a fresh STATUS.
v2::Status fault_clear(lk::Link& link, lk::FrameIo& io, lk::StreamV2Report& rep,
                       const lk::StreamV2Options& o) {
  const v2::Status before = status(link, io, rep, o);
  io.send(v2::fault_clear(before.next_seq));
  EXPECT_TRUE(io.await_type(v2::Type::Ack, link.now() + 1000ms)) << "FAULT_CLEAR not acknowledged";
  return status(link, io, rep, o);
}

}  // namespace

TEST(LimitBoard, NoSwitchPressedReadsZero) {
  sb::SimBoard b{sb::BoardOptions{}};
  EXPECT_EQ(b.limit_switches(), 0x0707) << "X, Y, Z min and max wired";
  EXPECT_EQ(b.limit_state(), 0);
  EXPECT_THROW(b.set_limit(3, false, true), sb::BoardError) << "axis A has no switch";
}

TEST(LimitBoard, PressedAtRestShowsInStatusWithoutAlarm) {
  const fpgacnc::config::MachineConfig cfg;
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  auto& board = link.board();
  lk::StreamV2Options o = lk::stream_v2_options(cfg);
  lk::StreamV2Report rep;
  lk::FrameIo io(link, rep);
  const uint64_t p = board.set_limit(1, false, true);  // Y min
  // The board's clock runs through the filter on its own; the STATUS after it shows the switch.
  link.wait_until(link.now() + 5ms);
  const v2::Status st = status(link, io, rep, o);
  EXPECT_GT(board.cycle(), p + kF);
  EXPECT_EQ(st.switches, 0x0002) << "Y min asserted";
  EXPECT_EQ(st.faults & v2::kFaultLimit, 0) << "a switch pressed at rest is no alarm";
  EXPECT_EQ(st.state & v2::kStatePosUntrusted, 0);
  board.set_limit(1, false, false);
  link.wait_until(link.now() + 5ms);
  EXPECT_EQ(status(link, io, rep, o).switches, 0);
}

// A job along X runs into an endstop at X = 5 mm: the alarm names X max, no STEP rises after the
// documented bound, the positions are the STEP edges at the pins and are not trusted;
// FAULT_CLEAR changes nothing while the carriage stands on the switch and clears the alarm once
// it is pulled off.
TEST(LimitBoard, JobRunsIntoEndstop) {
  const fpgacnc::config::MachineConfig cfg;
  const int64_t stop_steps = static_cast<int64_t>(5.0 * cfg.steps_per_mm[0]);
  sb::BoardOptions bo = sb::SimBoard::options_from_config(cfg);
  bo.endstops = {{0, true, stop_steps}};
  sb::BoardLink link(bo);
  auto& board = link.board();
  const auto p = plan::plan_program(
      fpgacnc::gcode::parse_string("G1 X20 F6000\nG1 X0\n", "overrun.gcode"), cfg, {});
  lk::StreamV2Options o = lk::stream_v2_options(cfg);
  try {
    fpgacnc::test::stream_plan(link, p, cfg, o);
    FAIL() << "the endstop did not stop the job";
  } catch (const lk::Error& e) {
    const std::string w = e.what();
    fmt::print("{}\n", w);
    EXPECT_NE(w.find("LIMIT alarm: X max"), std::string::npos) << w;
    EXPECT_NE(w.find("G-code line 1"), std::string::npos) << w;
  }
  const auto ev = board.limit_events();
  ASSERT_FALSE(ev.empty());
  EXPECT_TRUE(ev[0].pressed && ev[0].endstop && ev[0].axis == 0 && ev[0].max_side);
  const uint64_t pin = ev[0].cycle;
  uint64_t last_rise = 0, rises_after_pin = 0;
  for (const auto& e : board.edges()) {
    if (e.signal < 4 && e.value) {
      last_rise = e.cycle;
      if (e.cycle >= pin) ++rises_after_pin;
    }
  }
  fmt::print(
      "endstop pin at edge {}, last STEP rise at {} (bound p + F + 2 = {}), {} rises "
      "while the filter ran\n",
      pin, last_rise, pin + kF + 2, rises_after_pin);
  EXPECT_GT(rises_after_pin, 0u) << "the axis was moving when the switch was hit";
  EXPECT_LE(last_rise, pin + kF + 2) << "STEP after the documented bound";

  lk::StreamV2Report rep;
  lk::FrameIo io(link, rep);
  v2::Status st = status(link, io, rep, o);
  EXPECT_TRUE(st.faults & v2::kFaultLimit);
  EXPECT_EQ(st.limit, 0x10) << "axis 0, max";
  EXPECT_EQ(st.switches, 0x0100) << "X max held";
  EXPECT_TRUE(st.state & v2::kStatePosUntrusted);
  EXPECT_EQ(st.state & v2::kStateBusy, 0);
  const auto net = board.net_steps();
  EXPECT_EQ(st.position[0], net[0]) << "positions are the STEP edges at the pins";
  EXPECT_GE(st.position[0], stop_steps) << "stopped at or past the switch";
  EXPECT_LT(st.position[0], static_cast<int64_t>(20.0 * cfg.steps_per_mm[0]));

  st = fault_clear(link, io, rep, o);
  EXPECT_TRUE(st.faults & v2::kFaultLimit) << "FAULT_CLEAR accepted while the switch is held";
  EXPECT_EQ(board.pull_off_endstops(), 1);
  link.wait_until(link.now() + 5ms);  // the debounce filter (1 ms) passes
  st = status(link, io, rep, o);
  EXPECT_EQ(st.switches, 0) << "released";
  EXPECT_TRUE(st.faults & v2::kFaultLimit) << "the alarm stays until FAULT_CLEAR";
  st = fault_clear(link, io, rep, o);
  EXPECT_EQ(st.faults & v2::kFaultLimit, 0) << "FAULT_CLEAR refused after the release";
  EXPECT_TRUE(st.state & v2::kStatePosUntrusted) << "FAULT_CLEAR must not clear the flag";
  const uint64_t clocks = board.cycle();
  fmt::print("cleared at board cycle {}\n", clocks);
}
