// The probe input of the simulated board (label system): the Verilated cnc_core with the probe
// wired (SimBoard::kProbeEnable, spec/protocol.toml sim.simboard_probe_enable), touched by
// set_probe() or the control protocol's `probe on|off`, or by a probe plate that follows the
// step count at the pins; STATUS state bit 7 (PROBE) is the filtered level. Every verdict counts
// board clocks, never wall time.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace sb = fpgacnc::simboard;
namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
using namespace std::chrono_literals;

namespace {

v2::Status probe_status(lk::Link& link, lk::FrameIo& io, lk::StreamV2Report& rep,
                        const lk::StreamV2Options& o) {
  return lk::query_status(link, io, rep, 4, o, "in the test");
}

}  // namespace

// set_probe and `probe on|off`: the pin from the next edge (recorded), the filtered level in
// STATUS after the filter; the board's clock runs through the filter without host traffic.
TEST(ProbeBoard, TouchAndLiftShowInStatus) {
  const fpgacnc::config::MachineConfig cfg;
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  auto& board = link.board();
  const lk::StreamV2Options o = lk::stream_v2_options(cfg);
  lk::StreamV2Report rep;
  lk::FrameIo io(link, rep);
  EXPECT_EQ(probe_status(link, io, rep, o).state & v2::kStateProbe, 0) << "released at reset";
  const uint64_t p = board.set_probe(true);
  link.wait_until(link.now() + 2ms);
  EXPECT_GT(board.cycle(), p + sb::SimBoard::kProbeFilterClks);
  EXPECT_NE(probe_status(link, io, rep, o).state & v2::kStateProbe, 0) << "touching";
  EXPECT_TRUE(board.probe_state());
  const std::string off = sb::board_control_command(board, "probe off");
  EXPECT_EQ(off.rfind("ok probe lifted from clock edge ", 0), 0u) << off;
  link.wait_until(link.now() + 2ms);
  EXPECT_EQ(probe_status(link, io, rep, o).state & v2::kStateProbe, 0) << "lifted";
  const std::string state = sb::board_control_command(board, "state");
  EXPECT_NE(state.find("probe_pin=off probe_filtered=off"), std::string::npos) << state;
  EXPECT_EQ(sb::board_control_command(board, "probe maybe"),
            "error: probe: 'maybe' is not on or off");
  const auto ev = board.probe_events();
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].cycle, p);
  EXPECT_TRUE(ev[0].contact);
  EXPECT_FALSE(ev[0].plate);
  EXPECT_FALSE(ev[1].contact);
}

// A plate the tool rests on (Z at or below step 0) touches from reset (edge 1); a plate on an
// axis the board does not have is refused.
TEST(ProbeBoard, PlateAtRestTouchesFromReset) {
  const fpgacnc::config::MachineConfig cfg;
  sb::BoardOptions bo = sb::SimBoard::options_from_config(cfg);
  bo.probe_plate = sb::ProbePlate{2, true, 0};
  sb::BoardLink link(bo);
  const lk::StreamV2Options o = lk::stream_v2_options(cfg);
  lk::StreamV2Report rep;
  lk::FrameIo io(link, rep);
  link.wait_until(link.now() + 2ms);
  EXPECT_NE(probe_status(link, io, rep, o).state & v2::kStateProbe, 0);
  const auto ev = link.board().probe_events();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].cycle, 1u);
  EXPECT_TRUE(ev[0].contact);
  EXPECT_TRUE(ev[0].plate);
  sb::BoardOptions bad = sb::SimBoard::options_from_config(cfg);
  bad.probe_plate = sb::ProbePlate{4, true, 0};
  EXPECT_THROW(sb::SimBoard{bad}, sb::BoardError);
}
