// The machine buttons of the simulated board (label system): SimBoard::press_button drives
// cnc_core's hold_in / start_in for kButtonPressClks board clocks (docs/machine.md "Simulated
// board"). The pin levels are checked clock-exactly against the documented press (edges E ..
// E + kButtonPressClks - 1 sample it pressed), and the core's answer through STATUS on the pty:
// each press is one rise of the filtered level, so hold, start, hold, start alternate HOLD on and
// off. Every verdict counts board clocks, never wall time.
#include <gtest/gtest.h>

#include <chrono>

#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"
#include "fpgacnc/spec.h"

namespace sb = fpgacnc::simboard;
namespace lk = fpgacnc::link;
using namespace std::chrono_literals;

namespace {

constexpr uint64_t kF = fpgacnc::spec::kDefaultLimitFilterClks;
constexpr uint64_t kPress = sb::SimBoard::kButtonPressClks;
constexpr uint8_t kHoldBit = fpgacnc::spec::kStateHold;  // STATUS state bit 5 HOLD

}  // namespace

TEST(ButtonBoard, PressHoldsThePinForItsClocksThenTheFilterSeesTheRelease) {
  static_assert(kPress >= 2 * kF, "a press must be comfortably longer than the input filter");
  sb::SimBoard b{sb::BoardOptions{}};
  b.run_cycles_until_quiet(1000);
  const uint64_t c0 = b.cycle();
  EXPECT_EQ(b.pins().buttons, 0);
  const uint64_t e = b.press_button(sb::Button::kStart);
  EXPECT_EQ(e, c0 + 1) << "the next clock edge samples the pin pressed";
  sb::BoardPins p = b.pins();
  EXPECT_EQ(p.buttons, 0b10) << "cycle start held, hold not";
  EXPECT_EQ(p.release_edge[1], e + kPress);
  // Edges e .. e + kPress - 1 sample it pressed: at cycle e + kPress - 1 it still is.
  b.run_cycles_until_quiet(e + kPress - 1 - b.cycle());
  ASSERT_EQ(b.cycle(), e + kPress - 1) << "the board's clock runs through the press by itself";
  EXPECT_EQ(b.pins().buttons, 0b10);
  b.run_cycles_until_quiet(1);
  EXPECT_EQ(b.pins().buttons, 0) << "released on edge e + kButtonPressClks";
  // Then the clock runs on until the filter has taken the release (its level falls F + 1 edges
  // after the pin reaches the synchronizer) and the board goes quiet soon after.
  b.run_cycles_until_quiet(100'000'000);
  EXPECT_GT(b.cycle(), e + kPress + kF + 1);
  EXPECT_LT(b.cycle(), e + kPress + kF + 1000) << "quiet once the filter has settled";
}

TEST(ButtonBoard, EachPressIsOneHoldOrResumeInStatus) {
  const fpgacnc::config::MachineConfig cfg;
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  auto& board = link.board();
  lk::StreamV2Options o = lk::stream_v2_options(cfg);
  lk::StreamV2Report rep;
  lk::FrameIo io(link, rep);
  const auto status = [&] { return lk::query_status(link, io, rep, 4, o, "in the test"); };
  EXPECT_EQ(status().state & kHoldBit, 0) << "no hold after reset";
  // The press (4 ms) and the filter's release (1 ms) run on the board's clock; 10 ms of board
  // time later each press has been taken whole.
  for (int round = 0; round < 2; ++round) {
    const uint64_t e = board.press_button(sb::Button::kHold);
    link.wait_until(link.now() + 10ms);
    EXPECT_GT(board.cycle(), e + kPress + kF) << "round " << round;
    EXPECT_NE(status().state & kHoldBit, 0) << "round " << round << ": the hold button holds";
    board.press_button(sb::Button::kStart);
    link.wait_until(link.now() + 10ms);
    EXPECT_EQ(status().state & kHoldBit, 0)
        << "round " << round << ": cycle start resumes (a new rise after the release)";
  }
}
