// Protocol v2 system tests (label system): the host's v2 streamer -> SerialLink -> pty -> the
// simulated board (Verilated cnc_core with the v2 frame decoder, command FIFO and zero-gap
// executor), measured at the pins (recorded STEP/DIR/LASER edges and seg_done cycles).
//
// Job: a square spiral of short segments, each 0.1 mm (16 steps) along X or Y at 3000 mm/min:
// T = 0.1 / 3000 * 60 * 50e6 = 100 000 clocks (2 ms) per segment; sides of 1, 1, 2, 2, 3, 3, ...
// segments (every corner turns 90 degrees; X and Y each reverse every other side), laser on
// (M3 S1000: power 255). FPGACNC_V2_SEGMENTS sets the number of segments: CTest runs 100
// (0.32 s of machine time, about 25 s of simulation for v2 and v1), `make soak` 10 000; run by hand
// the default is 1 000. Every host timer runs on the board's clock (BoardLink, link.h): the
// timeouts below are board time.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
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

size_t env_size(const char* name, size_t dflt) {
  const char* e = std::getenv(name);
  return e ? static_cast<size_t>(std::strtoull(e, nullptr, 10)) : dflt;
}

// Square spiral of `n` segments of 0.1 mm at 3000 mm/min (see the file comment); every
// `ze_every` segments (0: never) a Z and E move out and back.
std::string spiral_gcode(size_t n, size_t ze_every = 0) {
  std::string g = "G21 G90\nM3 S1000\nG1 F3000\n";
  long x = 0, y = 0;  // in 0.1 mm
  size_t side = 1, on_side = 0;
  int dir = 0;
  for (size_t i = 0; i < n; ++i) {
    if (dir == 0) ++x;
    if (dir == 1) ++y;
    if (dir == 2) --x;
    if (dir == 3) --y;
    g += fmt::format("G1 X{:.1f} Y{:.1f}\n", x * 0.1, y * 0.1);
    if (++on_side == side) {
      on_side = 0;
      if (dir == 1 || dir == 3) ++side;
      dir = (dir + 1) % 4;
    }
    if (ze_every && i % ze_every == ze_every / 2) {
      g += fmt::format("G1 Z0.5 E{:.2f}\nG1 Z0\n", 0.05 * static_cast<double>(i / ze_every + 1));
    }
  }
  g += "M5\n";
  return g;
}

plan::Plan plan_of(const std::string& g, const cfgns::MachineConfig& cfg) {
  return plan::plan_program(fpgacnc::gcode::parse_string(g, "spiral.gcode"), cfg, {});
}

struct V2Run {
  lk::StreamV2Report rep;
  sb::BoardStats stats;
  std::vector<models::Edge> edges;
  std::vector<uint64_t> move_done;
  std::string protocol;
};

// Streams with protocol selection "auto" (it must pick v2 on this board) and collects the pins.
V2Run run_v2(const plan::Plan& p, const cfgns::MachineConfig& cfg, const sb::BoardOptions& bo,
             const lk::StreamV2Options& so) {
  sb::BoardLink link(bo);
  V2Run r;
  const auto choice = lk::select_protocol(link, "auto", so);
  r.protocol = choice.protocol;
  if (choice.protocol != "v2") return r;
  r.rep = fpgacnc::test::stream_plan(link, p, cfg, so, choice.ident);
  EXPECT_TRUE(link.wait_idle(1000ms)) << "board still busy 1 s of board time after the job";
  link.board().stop();
  r.stats = link.board().stats();
  r.edges = link.board().edges();
  r.move_done = link.board().move_done_cycles();
  return r;
}

std::vector<uint64_t> rises(const std::vector<models::Edge>& e) {
  std::vector<uint64_t> c;
  for (const auto& x : e) {
    if (x.signal < models::kDir0 && x.value) c.push_back(x.cycle);
  }
  return c;
}

}  // namespace

TEST(V2System, HelloGetsIdent) {
  sb::BoardLink link(sb::BoardOptions{});
  const auto id = lk::probe_v2(link, 2000ms);
  ASSERT_TRUE(id.has_value()) << "no IDENT within 2 s of board time after HELLO";
  EXPECT_EQ(id->version, 2);
  EXPECT_EQ(id->n_axes, 4);
  EXPECT_EQ(id->fifo_depth, 64);
  EXPECT_EQ(id->clk_hz, 50'000'000u);
  EXPECT_EQ(id->baud, 115'200u);
  EXPECT_EQ(id->max_payload, 64);
  EXPECT_EQ(id->next_seq, 0);
}

// A frame cut short on an otherwise idle board: the board keeps its clock running while the
// decoder holds the partial frame, so the 100 ms watchdog drops it and NAKs it with TIMEOUT
// (as the real board does), instead of waiting for the next byte forever.
TEST(V2System, CutFrameOnIdleBoardIsNakedWithTimeout) {
  sb::BoardLink link(sb::BoardOptions{});
  const int32_t steps[2] = {16, 0};
  const auto full = v2::encode(v2::line(0, 1, 0, 100'000, steps));
  ASSERT_GT(full.size(), 8u);
  link.write(std::span<const uint8_t>(full.data(), 7));  // SYNC LEN SEQ TYPE and 3 payload bytes
  v2::FrameParser parser;
  std::optional<v2::Frame> nak;
  const auto give_up = link.now() + 1s;  // board time; the watchdog needs 100 ms
  while (!nak && link.now() < give_up) {
    if (auto b = link.read_byte(100ms)) parser.feed(std::span<const uint8_t>(&*b, 1));
    while (auto f = parser.next()) {
      if (f->type == static_cast<uint8_t>(v2::Type::Nak)) nak = f;
    }
  }
  ASSERT_TRUE(nak.has_value()) << "no NAK within 1 s of board time after a cut frame";
  const auto n = v2::decode_nak(*nak);
  EXPECT_EQ(n.reason, v2::NakReason::Timeout);
  EXPECT_EQ(n.seq, 0) << "SEQ of the cut frame";
  EXPECT_EQ(n.next_seq, 0) << "nothing accepted";
  EXPECT_GE(link.board().cycle(), 5'000'000u) << "the watchdog needs 100 ms of board time";
  // Nothing moved, and the board still takes a good frame afterwards.
  EXPECT_TRUE(link.board().edges().empty());
  const auto id = lk::probe_v2(link, 2000ms);
  ASSERT_TRUE(id.has_value()) << "no IDENT after the cut frame";
  EXPECT_EQ(id->next_seq, 0);
}

// (a) Zero gap through the pins, and the same job with v1 stop-and-wait for comparison.
TEST(V2System, ZeroGapThroughThePinsAndV1Comparison) {
  const size_t n = env_size("FPGACNC_V2_SEGMENTS", 1000);
  cfgns::MachineConfig cfg;
  cfg.motion = "constant";  // LINE frames: constant feed, the gap-free join at full speed
  const plan::Plan p = plan_of(spiral_gcode(n), cfg);
  const v2::Job job = fpgacnc::test::pack_motion(p, cfg);
  ASSERT_EQ(job.lines, n);
  uint64_t sum_t = 0;
  std::vector<uint64_t> t;
  std::array<uint64_t, 4> pulses_want{};
  for (const auto& jf : job.frames) {
    if (jf.frame.type != static_cast<uint8_t>(v2::Type::Line)) continue;
    const auto l = v2::decode_line(jf.frame);
    ASSERT_EQ(l.t, 100'000u) << "segment " << t.size() << ": 0.1 mm at 3000 mm/min";
    t.push_back(l.t);
    sum_t += l.t;
    for (size_t a = 0; a < l.steps.size(); ++a) pulses_want[a] += std::abs(l.steps[a]);
  }
  // A clean line: a retransmission timeout far above any frame -> ACK time (the longest queue
  // of frames on the line is about 0.1 s of board time), so nothing is resent.
  lk::StreamV2Options so;
  so.retransmit_timeout = 5000ms;
  so.idle_poll = 1000ms;
  const auto w0 = std::chrono::steady_clock::now();
  const V2Run r = run_v2(p, cfg, sb::SimBoard::options_from_config(cfg), so);
  const double v2_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  ASSERT_EQ(r.protocol, "v2") << "the board did not answer HELLO with IDENT";
  EXPECT_TRUE(r.rep.position_ok);
  EXPECT_TRUE(r.rep.released);
  EXPECT_EQ(r.rep.retransmissions, 0u);
  EXPECT_EQ(r.rep.status_end.done - r.rep.status_start.done, job.frames.size());
  EXPECT_EQ(r.rep.status_end.counters[v2::kClamped], 0u);

  const auto steps = models::step_pulses(r.edges);
  const auto net = models::net_steps(r.edges);
  for (size_t a = 0; a < 4; ++a) {
    EXPECT_EQ(steps[a], pulses_want[a]) << "STEP pulses, axis " << a;
    EXPECT_EQ(net[a], p.final_steps[a]) << "net steps, axis " << a;
  }
  // Zero gap: consecutive seg_done strobes are exactly one segment length apart.
  ASSERT_EQ(r.move_done.size(), n) << "seg_done strobes";
  size_t gaps = 0;
  for (size_t i = 1; i < n; ++i) {
    if (r.move_done[i] - r.move_done[i - 1] != t[i]) {
      if (++gaps <= 5) {
        ADD_FAILURE() << "segment " << i << ": seg_done at cycle " << r.move_done[i]
                      << ", previous at " << r.move_done[i - 1] << ": expected " << t[i]
                      << " clocks apart, got " << (r.move_done[i] - r.move_done[i - 1]);
      }
    }
  }
  EXPECT_EQ(gaps, 0u);
  // Job time through the pins: the first STEP rise is at R0 + ceil(T0 / 16) (16 steps per
  // segment), the last at R_last + T_last; so last - first + ceil(T0 / 16) = sum of T.
  const auto rv2 = rises(r.edges);
  ASSERT_FALSE(rv2.empty());
  const uint64_t first_offset = (t[0] + 15) / 16;
  const uint64_t v2_clocks = rv2.back() - rv2.front() + first_offset;
  EXPECT_EQ(v2_clocks, sum_t) << "job time at the pins (clocks) vs the sum of planned T";

  // The same job with v1 stop-and-wait (same board model, fresh).
  sb::BoardRunOptions ro;  // default ACK timeout: 10 s of board time
  const auto w1 = std::chrono::steady_clock::now();
  const sb::BoardRunResult r1 =
      sb::run_plan_on_board(p, sb::SimBoard::options_from_config(cfg), ro);
  const double v1_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - w1).count();
  const auto rv1 = rises(r1.edges);
  ASSERT_FALSE(rv1.empty());
  const uint64_t v1_clocks = rv1.back() - rv1.front() + first_offset;
  EXPECT_EQ(r1.net_steps[0], p.final_steps[0]);
  EXPECT_EQ(r1.net_steps[1], p.final_steps[1]);
  EXPECT_GT(v1_clocks, v2_clocks);
  const double clk = 50e6;
  fmt::print(
      "square spiral, {} segments of 0.1 mm at 3000 mm/min (T = 100000 clocks each)\n"
      "  planned sum of T : {} clocks ({:.4f} s)\n"
      "  v2 at the pins   : {} clocks ({:.4f} s), gaps 0, {} frames, {} bytes, "
      "simulated in {:.1f} s\n"
      "  v1 at the pins   : {} clocks ({:.4f} s), simulated in {:.1f} s\n"
      "  v1 overhead      : {} clocks ({:.4f} s, {:.1f} clocks = {:.1f} us per move), "
      "v1/v2 = {:.3f}\n",
      n, sum_t, sum_t / clk, v2_clocks, v2_clocks / clk, r.rep.frames_sent, r.rep.bytes_written,
      v2_wall, v1_clocks, v1_clocks / clk, v1_wall, v1_clocks - v2_clocks,
      (v1_clocks - v2_clocks) / clk, static_cast<double>(v1_clocks - v2_clocks) / (n - 1),
      static_cast<double>(v1_clocks - v2_clocks) / (n - 1) / 50.0,
      static_cast<double>(v1_clocks) / static_cast<double>(v2_clocks));
}

// (b) Line faults both ways: the job completes, no segment lost or run twice.
TEST(V2System, LineFaultsJobCompletesExactlyOnce) {
  const size_t n = env_size("FPGACNC_V2_FAULT_SEGMENTS", 60);
  const uint64_t seed = env_size("FPGACNC_SEED", 5);
  std::printf("seed %llu (FPGACNC_SEED)\n", static_cast<unsigned long long>(seed));
  cfgns::MachineConfig cfg;
  // LINE frames: the link layer under test does not depend on the frame type, and the
  // constant-feed job is the shorter one to simulate (planned trapezoids: about twice as long).
  cfg.motion = "constant";
  const plan::Plan p = plan_of(spiral_gcode(n, 50), cfg);
  const v2::Job job = fpgacnc::test::pack_motion(p, cfg);
  std::array<uint64_t, 4> pulses_want{};
  for (const auto& jf : job.frames) {
    if (jf.frame.type != static_cast<uint8_t>(v2::Type::Line)) continue;
    const auto l = v2::decode_line(jf.frame);
    for (size_t a = 0; a < l.steps.size(); ++a) pulses_want[a] += std::abs(l.steps[a]);
  }
  sb::BoardOptions bo = sb::SimBoard::options_from_config(cfg);
  bo.line_faults.seed = seed;
  bo.line_faults.ber_to_board = 1e-4;
  bo.line_faults.ber_to_host = 1e-4;
  bo.line_faults.drop = 5e-4;
  bo.line_faults.dup = 5e-4;
  bo.line_faults.lose_frames = 0.01;
  // One 50 ms stall (2 500 000 clocks) before the 1500th byte on the line: mid-job.
  bo.line_faults.stalls.push_back({sb::LineStall::Trigger::kBytes, 1500, 2'500'000});
  lk::StreamV2Options so;  // defaults: 300 ms retransmission timeout, 10 s answer timeout
  const V2Run r = run_v2(p, cfg, bo, so);
  ASSERT_EQ(r.protocol, "v2");
  const auto& ls = r.stats.line;
  fmt::print("injected: {}\n", sb::describe(ls));
  fmt::print("{}", lk::format_report(r.rep));
  EXPECT_EQ(ls.stalls, 1u);
  EXPECT_GT(ls.frames_flipped_to_board + ls.bytes_dropped + ls.bytes_duplicated, 0u);
  EXPECT_GT(ls.device_frames_lost + ls.bytes_flipped_to_host, 0u);
  // Exactly once: the device counted every FIFO frame once, STEP pulses and net steps match
  // the plan on every axis.
  EXPECT_EQ(r.rep.status_end.done - r.rep.status_start.done, job.frames.size());
  EXPECT_EQ(r.move_done.size(), job.lines);
  EXPECT_TRUE(r.rep.position_ok);
  const auto steps = models::step_pulses(r.edges);
  const auto net = models::net_steps(r.edges);
  for (size_t a = 0; a < 4; ++a) {
    EXPECT_EQ(steps[a], pulses_want[a]) << "STEP pulses, axis " << a;
    EXPECT_EQ(net[a], p.final_steps[a]) << "net steps, axis " << a;
  }
  EXPECT_GT(r.rep.retransmissions, 0u);
}

// RELEASE returns the board to auto mode: a v1 job runs after a v2 one on the same board.
TEST(V2System, V1AfterV2OnTheSameBoard) {
  cfgns::MachineConfig cfg;
  const plan::Plan p = plan_of(spiral_gcode(12), cfg);
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  lk::StreamV2Options so;
  const auto c = lk::select_protocol(link, "auto", so);
  ASSERT_EQ(c.protocol, "v2");
  const auto r2 = fpgacnc::test::stream_plan(link, p, cfg, so, c.ident);
  EXPECT_TRUE(r2.released);
  EXPECT_TRUE(r2.position_ok);
  lk::StreamOptions o1;
  const auto r1 = lk::stream_v1(link, p, o1);
  EXPECT_EQ(r1.acks, r1.moves);
  EXPECT_EQ(r1.warnings, 0u);
  EXPECT_TRUE(link.wait_idle(1000ms));
  link.board().stop();
  const auto net = link.board().net_steps();
  EXPECT_EQ(net[0], 2 * p.final_steps[0]);
  EXPECT_EQ(net[1], 2 * p.final_steps[1]);
}
