// Simulated board tests (label system): the host's SerialLink and v1 streamer talk to the
// Verilated cnc_core through the board's pseudo-terminal, exactly as to a real port. Every wait
// on the board runs on its clock (BoardLink, link time: link.h), so no verdict depends on how
// fast or loaded the machine is.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <variant>

#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/plot.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace sb = fpgacnc::simboard;
namespace models = fpgacnc::models;
namespace lk = fpgacnc::link;
namespace cfgns = fpgacnc::config;
namespace plan = fpgacnc::plan;
using namespace std::chrono_literals;

namespace {

// The original controller's worked examples (docs/protocol.md, "v1").
const std::vector<uint8_t> kInit = {0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30};
const std::vector<uint8_t> kMotion = {0x01, 0x00, 0x00, 0x01, 0x40, 0xFF,
                                      0xFF, 0xFF, 0x60, 0x04, 0xB0};

size_t count_edges(const std::vector<models::Edge>& e, uint8_t signal, uint8_t value) {
  return static_cast<size_t>(std::count_if(e.begin(), e.end(), [&](const models::Edge& x) {
    return x.signal == signal && x.value == value;
  }));
}

TEST(SimBoard, RejectsOtherClockAndBaud) {
  sb::BoardOptions o;
  o.baud = 9600;
  EXPECT_THROW({ sb::SimBoard b(o); }, sb::BoardError);
  o.baud = 115200;
  o.clk_hz = 100e6;
  EXPECT_THROW({ sb::SimBoard b(o); }, sb::BoardError);
}

TEST(SimBoard, PtyRoundTripOriginalExample) {
  sb::BoardLink link(sb::BoardOptions{});
  auto& board = link.board();
  ASSERT_EQ(board.path().rfind("/dev/pts/", 0), 0u) << board.path();
  link.flush_input();
  link.write(kInit);
  link.write(kMotion);
  const auto t0 = std::chrono::steady_clock::now();
  // The move is ~5 M clocks (0.1 s of board time).
  const auto b = link.read_byte(1000ms);
  ASSERT_TRUE(b.has_value()) << "no ACK within 1 s of board time: " << board.stats_line();
  EXPECT_EQ(*b, 0xAA);
  ASSERT_TRUE(link.wait_idle(100ms)) << board.stats_line();
  board.stop();
  const auto e = board.edges();
  // 320 X steps with DIR X high, 160 Y steps with DIR Y low.
  EXPECT_EQ(count_edges(e, models::step_signal(0), 1), 320u);
  EXPECT_EQ(count_edges(e, models::step_signal(1), 1), 160u);
  EXPECT_EQ(count_edges(e, models::dir_signal(0), 1), 1u);
  EXPECT_EQ(count_edges(e, models::dir_signal(1), 1), 0u);
  const auto n = board.net_steps();
  EXPECT_EQ(n[0], 320);
  EXPECT_EQ(n[1], -160);
  // G1: the laser was on for exactly one interval, during the move.
  const auto st = board.stats();
  const auto laser = models::high_intervals(e, models::kLaser, st.cycles);
  ASSERT_EQ(laser.size(), 1u);
  for (const auto& x : e) {
    if (x.signal < 2 && x.value) {
      EXPECT_GE(x.cycle, laser[0].begin);
      EXPECT_LE(x.cycle, laser[0].end);  // the laser falls on the last STEP rise
    }
  }
  EXPECT_EQ(st.bytes_in, 20u);
  EXPECT_EQ(st.bytes_out, 1u);
  EXPECT_EQ(st.moves_done, 1u);
  EXPECT_EQ(st.position[0], 320);
  EXPECT_EQ(st.position[1], -160);
  fmt::print("round trip: {} (ACK after {:.3f} s wall)\n", board.stats_line(),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

// ---- Host timers on the board's clock (BoardLink, link.h) ----

// An idle board: a wait ends at once, link time jumps by exactly the wait, the board's clock
// stays where it was.
TEST(BoardLinkClock, IdleBoardSkipsTheWait) {
  sb::BoardLink link(sb::BoardOptions{});
  const auto clk = link.board_clock();
  ASSERT_TRUE(clk.has_value());
  EXPECT_EQ(clk->clk_hz, 50e6);
  EXPECT_TRUE(clk->idle_for_host);
  const uint64_t c0 = link.board().cycle();
  const lk::Link::Time t0 = link.now();
  EXPECT_FALSE(link.read_byte(300ms).has_value());
  EXPECT_EQ(link.now() - t0, std::chrono::nanoseconds(300ms));
  EXPECT_EQ(link.skipped(), std::chrono::nanoseconds(300ms));
  link.wait_until(link.now() + 150ms);
  EXPECT_EQ(link.now() - t0, std::chrono::nanoseconds(450ms));
  EXPECT_EQ(link.board().cycle(), c0);
}

// A busy board: a wait of T ends after T of the board's own clocks (the move's ACK comes after
// ~5 M clocks, 0.1 s), not after T of wall time; nothing is skipped while the board runs.
TEST(BoardLinkClock, BusyBoardTimesOutOnItsOwnClocks) {
  sb::BoardLink link(sb::BoardOptions{});
  link.write(kInit);
  link.write(kMotion);
  const uint64_t c0 = link.board().cycle();
  const lk::Link::Time t0 = link.now();
  EXPECT_FALSE(link.read_byte(20ms).has_value()) << "an ACK within 20 ms of board time";
  EXPECT_GE(link.board().cycle() - c0, 1'000'000u) << "the wait ended before 20 ms of clocks";
  EXPECT_GE(link.now() - t0, std::chrono::nanoseconds(20ms));
  EXPECT_EQ(link.skipped(), lk::Link::Time::zero()) << "skipped while the board was busy";
  EXPECT_FALSE(link.board_clock()->idle_for_host);
  const auto b = link.read_byte(1000ms);
  ASSERT_TRUE(b.has_value()) << "no ACK within 1 s of board time: " << link.board().stats_line();
  EXPECT_EQ(*b, 0xAA);
  EXPECT_LT(link.now() - t0, std::chrono::nanoseconds(200ms));
  EXPECT_EQ(link.skipped(), lk::Link::Time::zero());
}

// Bytes the host has just written and the board has not read yet: the board is quiet, but it is
// not idle for the host; a short wait must see the answer. HELLO -> IDENT takes ~2.3 ms of board
// time (6 + 20 bytes on the line); each probe waits 50 ms of board time, 30 times.
TEST(BoardLinkClock, JustWrittenBytesAreNotMistakenForIdle) {
  sb::BoardLink link(sb::BoardOptions{});
  for (int i = 0; i < 30; ++i) {
    const lk::Link::Time t0 = link.now();
    const auto id = lk::probe_v2(link, 50ms);
    ASSERT_TRUE(id.has_value()) << "probe " << i << ": no IDENT within 50 ms of board time";
    EXPECT_LT(link.now() - t0, std::chrono::nanoseconds(10ms)) << "probe " << i;
  }
  EXPECT_EQ(link.skipped(), lk::Link::Time::zero());
  EXPECT_EQ(link.board().bytes_from_host(), 30u * 6u);
}

// Time policy: clocks do not advance while the board waits for the host, so the same job gives
// the same edge list, cycle for cycle, run after run; the traced model (FST) gives the same
// edges as the untraced one. The streamer writes the init packet and the first move without
// waiting: whether the move's bytes arrive before the line went idle (back to back) or just
// after (start after the 32-clock quiet tail) depends on the host's speed, so the lists are
// compared relative to their first edge; from then on the stop-and-wait job is exact.
TEST(SimBoard, EdgesReproducibleAndFstSameAsUntraced) {
  plan::Plan p;
  plan::Steps4 pos{};
  const int64_t moves[][3] = {{1, 320, -160}, {0, -100, 40}, {3, 7, 250}, {0, 0, 0}, {2, -50, -3}};
  int line = 1;
  for (const auto& m : moves) {
    plan::Segment s;
    s.code = static_cast<uint8_t>(m[0]);
    s.steps = {m[1], m[2], 0, 0};
    s.feed_v1 = 20000;
    s.source_line = line++;
    pos[0] += m[1];
    pos[1] += m[2];
    s.target = pos;
    p.items.push_back(s);
  }
  p.final_steps = pos;
  sb::BoardRunOptions ro;
  ro.stream.ack_timeout = 5000ms;  // board time
  sb::BoardOptions o;
  const auto a = sb::run_plan_on_board(p, o, ro);
  const auto b = sb::run_plan_on_board(p, o, ro);
  const std::string fst = (std::filesystem::temp_directory_path() / "simboard_test.fst").string();
  o.fst_path = fst;
  const auto c = sb::run_plan_on_board(p, o, ro);
  ASSERT_EQ(a.edges.size(), b.edges.size());
  ASSERT_EQ(a.edges.size(), c.edges.size());
  ASSERT_FALSE(a.edges.empty());
  const uint64_t a0 = a.edges[0].cycle, b0 = b.edges[0].cycle, c0 = c.edges[0].cycle;
  for (const uint64_t x0 : {b0, c0}) {
    EXPECT_TRUE(x0 == a0 || x0 == a0 + sb::SimBoard::kQuietCycles ||
                a0 == x0 + sb::SimBoard::kQuietCycles)
        << a0 << " " << x0;
  }
  for (size_t i = 0; i < a.edges.size(); ++i) {
    ASSERT_EQ(a.edges[i].cycle - a0, b.edges[i].cycle - b0) << i;
    ASSERT_EQ(a.edges[i].signal, b.edges[i].signal) << i;
    ASSERT_EQ(a.edges[i].cycle - a0, c.edges[i].cycle - c0) << i;
    ASSERT_EQ(a.edges[i].signal, c.edges[i].signal) << i;
    ASSERT_EQ(a.edges[i].value, c.edges[i].value) << i;
  }
  EXPECT_EQ(a.net_steps[0], pos[0]);
  EXPECT_EQ(a.net_steps[1], pos[1]);
  ASSERT_EQ(a.move_done_cycles.size(), c.move_done_cycles.size());
  for (size_t i = 0; i < a.move_done_cycles.size(); ++i) {
    EXPECT_EQ(a.move_done_cycles[i] - a0, c.move_done_cycles[i] - c0);
  }
  EXPECT_GT(std::filesystem::file_size(fst), 1000u);
  fmt::print("reproducible: {} edges, {} cycles; traced run {:.2f} M clocks/s, untraced {:.2f}\n",
             a.edges.size(), a.stats.cycles, c.stats.clocks_per_s / 1e6,
             a.stats.clocks_per_s / 1e6);
}

// The board in the caller's thread: a raw client on the pty writes the example, run_until()
// simulates until the ACK has been sent, and the client reads it.
TEST(SimBoard, RunUntilInCallerThread) {
  sb::SimBoard board;
  const int fd = ::open(board.path().c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(fd, 0);
  std::vector<uint8_t> bytes = kInit;
  bytes.insert(bytes.end(), kMotion.begin(), kMotion.end());
  ASSERT_EQ(::write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  // ~5 M clocks to the ACK (see PtyRoundTripOriginalExample); decided on board clocks (50 M at
  // most), the wall-time limit is a safety net for a hung simulation only.
  board.run_until(
      [](const sb::SimBoard& b) { return b.stats().bytes_out >= 1 || b.cycle() >= 50'000'000; },
      600s);
  ASSERT_EQ(board.stats().bytes_out, 1u) << board.stats_line();
  pollfd p{fd, POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 2000), 1);
  uint8_t ack = 0;
  ASSERT_EQ(::read(fd, &ack, 1), 1);
  EXPECT_EQ(ack, 0xAA);
  const auto n = board.net_steps();
  EXPECT_EQ(n[0], 320);
  EXPECT_EQ(n[1], -160);
  // Nothing in flight: the board blocks instead of advancing clocks.
  board.run_cycles_until_quiet(100000);
  const uint64_t c = board.cycle();
  EXPECT_FALSE(board.run_until([](const sb::SimBoard&) { return false; }, 50ms));
  EXPECT_EQ(board.cycle(), c);
  ::close(fd);
}

// STEP rises of one axis, in order, with the DIR level at that cycle.
struct Rise {
  uint64_t cycle;
  int dir;
};
std::vector<Rise> rises(const std::vector<models::Edge>& e, int axis) {
  std::vector<Rise> r;
  int dir = 0;
  for (const auto& x : e) {
    if (x.signal == models::dir_signal(axis)) dir = x.value;
    if (x.signal == models::step_signal(axis) && x.value) r.push_back(Rise{x.cycle, dir ? 1 : -1});
  }
  return r;
}

// The first FPGACNC_CORPUS_MOVES segments of a plan (with what lies between them); the whole plan
// when the variable is unset or 0. CTest sets 100 (the Verilated core runs at 1-3 M clocks/s on
// a 2-core CI machine); `make soak` runs the whole files.
// `divisor` shortens a job whose moves are long (a third of the figure for the milling job).
plan::Plan first_moves(plan::Plan p, long divisor) {
  const char* e = std::getenv("FPGACNC_CORPUS_MOVES");
  const long n = e ? std::atol(e) / divisor : 0;
  if (n <= 0) return p;
  long kept = 0;
  size_t end = p.items.size();
  for (size_t i = 0; i < p.items.size(); ++i) {
    if (const auto* s = std::get_if<plan::Segment>(&p.items[i])) {
      p.final_steps = s->target;
      if (++kept == n) {
        end = i + 1;
        break;
      }
    }
  }
  p.items.resize(end);
  std::printf("first %ld segments of the plan (FPGACNC_CORPUS_MOVES)\n", kept);
  return p;
}

// Runs a corpus job host -> SerialLink -> pty -> Verilated cnc_core and checks it against the
// plan.
void run_corpus_job(const std::string& name, const cfgns::MachineConfig& cfg, long divisor = 1) {
  const std::string path = std::string(FPGACNC_CORPUS_DIR) + "/" + name;
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const plan::Plan p = first_moves(plan::plan_input_file(path, cfg, po), divisor);
  std::vector<plan::Segment> segs;
  for (const auto& it : p.items) {
    if (const auto* s = std::get_if<plan::Segment>(&it)) segs.push_back(*s);
  }
  sb::BoardRunOptions ro;
  ro.stream.ack_timeout = 10s;  // board time: no move of these jobs takes a second
  const auto t0 = std::chrono::steady_clock::now();
  const sb::BoardRunResult r = sb::run_plan_on_board(p, sb::SimBoard::options_from_config(cfg), ro);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Every move acknowledged.
  EXPECT_EQ(r.report.moves, segs.size());
  EXPECT_EQ(r.report.acks, segs.size());
  EXPECT_EQ(r.report.warnings, 0u);
  EXPECT_EQ(r.stats.frame_errors, 0u);
  EXPECT_EQ(r.stats.timeouts, 0u);
  // Net steps from the recorded STEP/DIR edges equal the interpreter's final target, exactly.
  // v1 carries X and Y only: Z (and E) are not driven by the board, so they are not compared
  // (the plan's Z target is not zero for the milling job).
  EXPECT_EQ(r.net_steps[0], p.final_steps[0]) << "X";
  EXPECT_EQ(r.net_steps[1], p.final_steps[1]) << "Y";
  EXPECT_EQ(r.net_steps[2], 0);
  EXPECT_EQ(r.net_steps[3], 0);
  EXPECT_EQ(r.stats.position[0], p.final_steps[0]);
  EXPECT_EQ(r.stats.position[1], p.final_steps[1]);

  // Laser high exactly during cutting moves. The moves run one at a time (stop-and-wait), so
  // the k-th segment owns the next |steps_x| X rises and |steps_y| Y rises, in order.
  const auto laser = models::high_intervals(r.edges, models::kLaser, r.stats.cycles);
  const auto rx = rises(r.edges, 0), ry = rises(r.edges, 1);
  size_t ix = 0, iy = 0, il = 0, cutting_with_steps = 0, bad_dir = 0, steps_outside = 0,
         rapid_steps_lit = 0;
  auto lit = [&](uint64_t c) {
    auto it = std::upper_bound(laser.begin(), laser.end(), c,
                               [](uint64_t v, const models::Interval& i) { return v < i.begin; });
    if (it == laser.begin()) return false;
    --it;
    return c >= it->begin && c < it->end;
  };
  for (const auto& s : segs) {
    const uint64_t nx = static_cast<uint64_t>(std::llabs(s.steps[0]));
    const uint64_t ny = static_cast<uint64_t>(std::llabs(s.steps[1]));
    ASSERT_LE(ix + nx, rx.size());
    ASSERT_LE(iy + ny, ry.size());
    const bool cutting = s.code != 0 && nx + ny > 0;
    std::vector<uint64_t> cycles;
    for (uint64_t k = 0; k < nx; ++k, ++ix) {
      if (rx[ix].dir != (s.steps[0] > 0 ? 1 : -1)) ++bad_dir;
      cycles.push_back(rx[ix].cycle);
    }
    for (uint64_t k = 0; k < ny; ++k, ++iy) {
      if (ry[iy].dir != (s.steps[1] > 0 ? 1 : -1)) ++bad_dir;
      cycles.push_back(ry[iy].cycle);
    }
    if (cutting) {
      ASSERT_LT(il, laser.size()) << "cutting move at line " << s.source_line << " has no laser";
      // The laser rises before the first STEP of the move and falls on its last STEP rise.
      for (uint64_t c : cycles) {
        if (c < laser[il].begin || c > laser[il].end) ++steps_outside;
      }
      ++il;
      ++cutting_with_steps;
    } else {
      for (uint64_t c : cycles) {
        if (lit(c)) ++rapid_steps_lit;
      }
    }
  }
  EXPECT_EQ(ix, rx.size());
  EXPECT_EQ(iy, ry.size());
  EXPECT_EQ(bad_dir, 0u);
  EXPECT_EQ(laser.size(), cutting_with_steps);
  EXPECT_EQ(steps_outside, 0u);
  EXPECT_EQ(rapid_steps_lit, 0u);
  EXPECT_EQ(r.stats.violations, 0u);

  fmt::print(
      "{}: {} moves ({} cutting with steps, {} laser intervals), {} edges; board {} cycles "
      "({:.2f} s simulated), {:.2f} M clocks/s, {:.1f} s of simulation; job wall {:.1f} s; "
      "net steps X {} Y {} (planned X {} Y {})\n",
      name, segs.size(), cutting_with_steps, laser.size(), r.edges.size(), r.stats.cycles,
      static_cast<double>(r.stats.cycles) / 50e6, r.stats.clocks_per_s / 1e6, r.stats.sim_wall_s,
      wall, r.net_steps[0], r.net_steps[1], p.final_steps[0], p.final_steps[1]);
  if (const char* out = std::getenv("SIMBOARD_PLOT_DIR")) {
    sb::PlotOptions o;
    o.steps_per_mm = {cfg.steps_per_mm[0], cfg.steps_per_mm[1]};
    o.title = name + " on the simulated board";
    sb::write_plot_svg(std::string(out) + "/" + name + ".svg", r.edges, sb::commanded_path(p, cfg),
                       o);
  }
}

// Test machine: the original 160 steps/mm, 115200 baud and DRV8825 step timing, with the
// motion sped up so that each job is simulated cycle by cycle in about a minute on one core:
// the scaled figures are the feed override (dwells shortened by the same factor), the rapid feed
// and the axis max feeds (the UART, packets, ACKs and pulse timing rules stay those of the real
// machine).
cfgns::MachineConfig fast_config(double override_pct, double rapid) {
  cfgns::MachineConfig c;
  c.feed_override_pct = override_pct;
  c.dwell_time_pct = 100.0 * 100.0 / override_pct;
  c.rapid_feed_mm_min = rapid;
  c.max_feed_mm_min = {60000.0, 60000.0, 60000.0, 60000.0};
  return c;
}

// Laser job, 2361 segments: F100 engraving x25 (2500 mm/min), rapids 20000 mm/min
// (about 15 s of machine time instead of 304 s).
TEST(SimBoardCorpus, JsdcLaser) {
  run_corpus_job("jsdc-laser.gcode", fast_config(2500.0, 20000.0));
}

// Milling calibration job, 1893 segments (all code 0: no M3, so no laser): F355 x100
// (35500 mm/min), rapids 40000 mm/min, Z max feed raised so Z moves do not slow X/Y
// (about 20 s of machine time instead of 1931 s). Its moves are long (the first 100 are 104 M
// clocks, 2.1 s of machine time): CTest runs the first third of FPGACNC_CORPUS_MOVES.
TEST(SimBoardCorpus, CircleDiamondSquare) {
  run_corpus_job("Circle_Diamond_Square_Calibration.gcode", fast_config(10000.0, 40000.0), 3);
}

// A board that stops answering in the middle of a job (paused: no clocks, nothing read): the
// streamer fails with its ACK timeout, naming the last acknowledged move. The frozen board ends
// the wait at once, with link time advanced by exactly the timeout.
TEST(SimBoardFailure, PausedBoardTimesOut) {
  cfgns::MachineConfig cfg = fast_config(2500.0, 20000.0);
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const plan::Plan p =
      plan::plan_input_file(std::string(FPGACNC_CORPUS_DIR) + "/jsdc-laser.gcode", cfg, po);
  sb::BoardLink link(sb::SimBoard::options_from_config(cfg));
  lk::StreamOptions so;
  so.ack_timeout = 8000ms;
  lk::Link::Time paused_at{};
  uint64_t paused_cycle = 0;
  so.progress = [&](size_t done, size_t) {
    if (done == 5) {
      link.board().pause();
      EXPECT_TRUE(link.board().idle_for_host()) << "a paused board is frozen";
      paused_at = link.now();
      paused_cycle = link.board().cycle();
    }
  };
  std::string what;
  try {
    lk::stream_v1(link, p, so);
  } catch (const lk::Error& e) {
    what = e.what();
  }
  ASSERT_FALSE(what.empty()) << "the stream did not fail";
  const auto waited = link.now() - paused_at;
  fmt::print("failure after {:.3f} s of link time: {}\n", lk::seconds(waited), what);
  // Moves 0..4 acknowledged; move 5 never is.
  std::vector<const plan::Segment*> segs;
  for (const auto& it : p.items) {
    if (const auto* s = std::get_if<plan::Segment>(&it)) segs.push_back(s);
  }
  EXPECT_NE(
      what.find(fmt::format("last acknowledged move: segment 4 (line {})", segs[4]->source_line)),
      std::string::npos)
      << what;
  EXPECT_NE(what.find("no ACK (0xAA) within 8 s of board time"), std::string::npos) << what;
  EXPECT_EQ(link.board().cycle(), paused_cycle) << "the paused board advanced";
  EXPECT_EQ(waited, std::chrono::nanoseconds(8000ms)) << "the ACK timeout, from the pause";
}

// Same with stop(): the board thread ends (the pty stays open), the host times out.
TEST(SimBoardFailure, StoppedBoardTimesOut) {
  plan::Plan p;
  plan::Steps4 pos{};
  for (int i = 0; i < 4; ++i) {
    plan::Segment s;
    s.code = 1;
    s.steps = {800, 0, 0, 0};  // 5 mm at 6000 mm/min: 50 ms of machine time each
    s.feed_v1 = 6000;
    s.source_line = 10 + i;
    for (int a = 0; a < 4; ++a) pos[static_cast<size_t>(a)] += s.steps[static_cast<size_t>(a)];
    s.target = pos;
    p.items.push_back(s);
  }
  p.final_steps = pos;
  sb::BoardRunOptions ro;
  ro.stream.ack_timeout = 8000ms;  // > a move's wall time on a slow, loaded simulation
  ro.on_ack = [&](sb::SimBoard& b, size_t done, size_t) {
    if (done == 2) b.stop();
  };
  try {
    sb::run_plan_on_board(p, sb::BoardOptions{}, ro);
    FAIL() << "the stream did not fail";
  } catch (const lk::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("segment 2 (line 12)"), std::string::npos) << what;
    EXPECT_NE(what.find("last acknowledged move: segment 1 (line 11)"), std::string::npos) << what;
  }
}

TEST(SimBoardPlot, WritesSvgWithLegend) {
  models::EdgeRecorder rec;
  // Two X steps forward with DIR high, laser on.
  rec.add(1, models::dir_signal(0), 1);
  rec.add(5, models::kLaser, 1);
  rec.add(10, models::step_signal(0), 1);
  rec.add(12, models::step_signal(0), 0);
  rec.add(20, models::step_signal(0), 1);
  rec.add(22, models::step_signal(0), 0);
  rec.add(22, models::kLaser, 0);
  EXPECT_EQ(rec.net_steps()[0], 2);
  std::vector<sb::CommandedSegment> cmd = {{0, 0, 2.0 / 160, 0, true}};
  const auto dir = std::filesystem::temp_directory_path();
  const std::string svg = (dir / "simboard_plot_test.svg").string();
  sb::write_plot_svg(svg, rec.edges(), cmd, sb::PlotOptions{});
  std::ifstream f(svg);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<svg"), std::string::npos);
  EXPECT_NE(text.find("executed (STEP/DIR), laser on"), std::string::npos);
  EXPECT_NE(text.find("X (mm)"), std::string::npos);
  const std::string csv = (dir / "simboard_edges_test.csv").string();
  rec.write_csv(csv, 50e6);
  std::ifstream c(csv);
  std::string header, first;
  std::getline(c, header);
  std::getline(c, first);
  EXPECT_EQ(header, "cycle,time_s,signal,value");
  EXPECT_EQ(first, "1,0.000000020,dir_x,1");
  EXPECT_THROW(sb::write_plot_svg("/nonexistent-dir/x.svg", rec.edges(), cmd, sb::PlotOptions{}),
               std::runtime_error);
}

}  // namespace

// The device's own soft limits (docs/machine.md "Soft limits"): a job planned without a [travel]
// but packed with X in [0, 5] mm (as a host whose planner does not check would send it) reaches
// the Verilated core, which refuses the first LINE_PROFILE ending beyond 5 mm (line 3, X 8):
// NAK TRAVEL, never retried: the stream stops at once naming that line, and the machine ends at
// the last move inside (X 4 mm = 640 steps), the refused and later lines never run.
TEST(SimBoardTravel, DeviceRefusesALineLeavingItsTravel) {
  cfgns::MachineConfig cfg;
  const auto p = plan::plan_program(
      fpgacnc::gcode::parse_string("G1 X2 F3000\nG1 X4\nG1 X8\nG1 X3\n"), cfg, {});
  cfgns::MachineConfig device = cfg;
  device.travel[cfgns::kX] = {true, 0.0, 5.0};
  const auto job =
      fpgacnc::protocol::v2::pack_job(plan::plan_motion(p, cfg), device, {.heaters = false});
  ASSERT_EQ(job.travel.size(), 1u);
  auto link = sb::make_default_link(cfg, {});
  try {
    lk::stream_v2_job(*link, job, lk::stream_v2_options(cfg));
    FAIL() << "the stream did not fail";
  } catch (const lk::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(line 3)"), std::string::npos) << what;
    EXPECT_NE(what.find("NAK TRAVEL"), std::string::npos) << what;
  }
  sb::Board* board = sb::any_board_of(*link);
  ASSERT_NE(board, nullptr);
  // The accepted moves run out on the board's clock (2 mm at 3000 mm/min: 40 ms each).
  link->wait_until(link->now() + 500ms);
  EXPECT_EQ(board->stats().position[0], 640);
}
