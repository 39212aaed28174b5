// The corpus arc files through host -> pty -> simulated board (Verilated cnc_core with arc_dda):
// the planner's look-ahead with native arcs (motion = "profile", native_arcs) packs G2/G3 in XY as
// ARC frames, the v2 streamer sends them over the pty, the board runs them. Checked: every ARC
// frame passes the codec's decoder (the device's field rules), the job completes with DONE for
// every frame, the board's net steps and position registers equal the plan's final position on
// every axis, no STEP timing violation and no fault.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <string>

#include "../../test/stream_plan.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace sb = fpgacnc::simboard;
namespace models = fpgacnc::models;
namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
namespace cfgns = fpgacnc::config;
namespace plan = fpgacnc::plan;
using namespace std::chrono_literals;

namespace {

class CorpusArcs : public ::testing::TestWithParam<const char*> {};

TEST_P(CorpusArcs, EndPositionsThroughThePty) {
  const std::string path = std::string(FPGACNC_CORPUS_DIR) + "/" + GetParam();
  cfgns::MachineConfig cfg;
  cfg.motion = "profile";
  cfg.native_arcs = true;
  // a faster machine than the default so the simulation stays short (the arcs are the same)
  // (short STEP/DIR times, fast feeds: about 1/25 of the default job time; the arcs stay under the
  // protocol's 1/8 step per clock and the STEP rate under 1/(high + low))
  cfg.step_timing = {20, 20, 40, 40};
  cfg.max_feed_mm_min = {200000.0, 200000.0, 60000.0, 60000.0};
  cfg.rapid_feed_mm_min = 200000.0;
  cfg.max_accel_mm_s2 = {500000.0, 500000.0, 500000.0, 500000.0};
  plan::PlanOptions po;
  po.feed_override_pct = 50000.0;
  const plan::Plan p = plan::plan_program(fpgacnc::gcode::parse_file(path), cfg, po);
  const v2::Job job = fpgacnc::test::pack_motion(p, cfg);
  if (job.arcs == 0) GTEST_SKIP() << "no ARC frame (arc walk not built in?)";
  size_t arcs = 0;
  for (const auto& jf : job.frames) {
    if (jf.frame.type != static_cast<uint8_t>(v2::Type::Arc)) continue;
    ++arcs;
    EXPECT_NO_THROW((void)v2::decode_arc(jf.frame))
        << "ARC frame of line " << jf.source_line << " breaks the device's field rules";
    if (std::getenv("FPGACNC_ARC_DEBUG"))
      fmt::print("ARC line {}: {}\n", jf.source_line, v2::hex(jf.frame.payload));
  }
  ASSERT_EQ(arcs, job.arcs);
  fmt::print("{}: job {} clocks planned ({} ARC, {} LINE_PROFILE frames)\n", GetParam(),
             job.total_t, job.arcs, job.profiles);
  std::fflush(stdout);

  lk::StreamV2Options so;  // board time (BoardLink, link.h)
  so.retransmit_timeout = 5000ms;
  so.idle_poll = 1000ms;
  const auto w0 = std::chrono::steady_clock::now();
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  const auto choice = lk::select_protocol(link, "auto", so);
  ASSERT_EQ(choice.protocol, "v2");
  const lk::StreamV2Report rep = fpgacnc::test::stream_plan(link, p, cfg, so, choice.ident);
  EXPECT_TRUE(link.wait_idle(1000ms)) << "board still busy 1 s of board time after the job";
  link.board().stop();
  const sb::BoardStats st = link.board().stats();
  const auto net = models::net_steps(link.board().edges());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  EXPECT_TRUE(rep.position_ok);
  EXPECT_EQ(rep.status_end.done - rep.status_start.done, job.frames.size());
  EXPECT_EQ(st.violations, 0u) << "STEP/DIR timing violations";
  EXPECT_EQ(rep.status_end.faults, 0u) << "faults (bit 1: arc error)";
  for (size_t a = 0; a < 4; ++a) {
    EXPECT_EQ(net[a], p.final_steps[a]) << "net steps at the pins, axis " << a;
    EXPECT_EQ(st.position[a], p.final_steps[a]) << "position register, axis " << a;
  }
  fmt::print("{}: {} ARC frames of {} FIFO frames, final ({}, {}, {}) steps, {} clocks, {:.1f} s\n",
             GetParam(), arcs, job.frames.size(), p.final_steps[0], p.final_steps[1],
             p.final_steps[2], st.cycles, wall);
}

INSTANTIATE_TEST_SUITE_P(Corpus, CorpusArcs,
                         ::testing::Values("circle.gcode", "arc-ijk.gcode", "g2-arc.gcode",
                                           "full-circle-without-xyz.gcode", "arc-xy-plane.gcode"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (auto& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

}  // namespace
