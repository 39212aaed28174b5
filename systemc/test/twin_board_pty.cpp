// The twin board behind its pseudo-terminal (label system).
//
// Equivalence: the same jobs (v1 packets and v2 sessions of examples/jsdc-laser.gcode, and
// corpus/cncjs/circle.gcode as native ARC frames, planned and packed by the host) go through the
// pty into the Verilated SimBoard and into the TwinBoard with the lockstep host (pty_lockstep.h: a
// batch written when the board is idle for the host, so the time policy makes every start clock
// deterministic); the edge lists (STEP/DIR/LASER and TX, so every answer bit at its clock), the
// answer bytes with their start clocks and the bytes the host read must be identical; a difference
// names the first differing edge or byte and its cycle. The v2 sessions end without STATUS_QUERY:
// the twins report idle heaters in STATUS, the Verilated board its heater plants. No line faults:
// the twin board has no fault injector. FPGACNC_TWIN_PTY_MOVES sets the number of v2 motion frames
// (default 30) and twice the number of v1 moves (the Verilated side is the slow one: about 20 M
// clocks for both).
//
// Corpus: a whole corpus job (jsdc-laser.gcode, about 5 minutes of machine time) at its real feeds
// through the pty into the twin board with the host's own v2 streamer (protocol selection, sliding
// window); net steps from the edges equal the plan's final target, and every motion frame ran
// once.
//
// Any client: pyserial (python3-serial) drives the twin board with the original controller's
// example and gets the ACK.
#include <gtest/gtest.h>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <tuple>

#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/simboard/sim_board.h"
#include "fpgacnc/twins/pty_lockstep.h"
#include "fpgacnc/twins/twin_board.h"

extern char** environ;

namespace sb = fpgacnc::simboard;
namespace models = fpgacnc::models;
namespace tw = fpgacnc::twins;
namespace cfgns = fpgacnc::config;
namespace plan = fpgacnc::plan;
using namespace std::chrono_literals;

// libsystemc's main() calls sc_main(); gtest_main provides main(), so this only links.
extern "C" int sc_main(int, char*[]) {
  return 1;
}

namespace {

size_t moves() {
  const char* e = std::getenv("FPGACNC_TWIN_PTY_MOVES");
  return e ? static_cast<size_t>(std::strtoull(e, nullptr, 10)) : 30;
}

// The job's motion frames, planned then packed (the boards here have no heater plants).
fpgacnc::protocol::v2::Job pack_motion(const plan::Plan& p, const cfgns::MachineConfig& cfg) {
  return fpgacnc::protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg, {.heaters = false});
}

// The demo job 25 times faster than written (examples/demo-machine.toml: feed override 2500 %,
// dwells at 4 %, rapids at 20 000 mm/min, accelerations 625 times the defaults): short moves,
// many answers per second of board time, so that the Verilated side stays short.
cfgns::MachineConfig job_config() {
  cfgns::MachineConfig cfg;
  cfg.feed_override_pct = 2500.0;
  cfg.dwell_time_pct = 4.0;
  cfg.rapid_feed_mm_min = 20000.0;
  cfg.max_feed_mm_min[0] = cfg.max_feed_mm_min[1] = 60000.0;
  cfg.max_accel_mm_s2 = {625000.0, 625000.0, 62500.0, 625000.0};
  return cfg;
}

plan::Plan job_plan(const cfgns::MachineConfig& cfg) {
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  return plan::plan_input_file(std::string(FPGACNC_EXAMPLES_DIR) + "/jsdc-laser.gcode", cfg, po);
}

void expect_same(const tw::HostScript& script, const cfgns::MachineConfig& cfg,
                 size_t min_answers) {
  sb::BoardOptions ro = sb::SimBoard::options_from_config(cfg);
  ro.record_tx = true;
  sb::SimBoard rtl(ro);
  tw::TwinBoardOptions to = tw::TwinBoard::options_from_config(cfg);
  to.record_tx = true;
  tw::TwinBoard tlm(to);
  // Liveness only (a board that never goes idle): generous, the verdict counts board clocks.
  const auto b = tw::run_lockstep(tlm, script, cfg.clk_hz, cfg.baud, 600s);
  ASSERT_EQ(tlm.error(), "");
  ASSERT_EQ(b.error, "");
  const auto a = tw::run_lockstep(rtl, script, cfg.clk_hz, cfg.baud, 600s);
  ASSERT_EQ(a.error, "");
  ASSERT_EQ(b.error, "");
  ASSERT_EQ(tlm.error(), "");
  const std::string d = tw::compare_lockstep(a, b, static_cast<double>(cfg.clk_hz), cfg.baud);
  EXPECT_EQ(d, "") << "rtl and tlm boards differ behind the pty";
  // The comparison is not vacuous: answers and motion were there.
  EXPECT_GE(a.received.size(), min_answers);
  EXPECT_GT(models::step_pulses(a.edges)[0] + models::step_pulses(a.edges)[1], 1000u);
  EXPECT_EQ(a.stats.cycles, b.stats.cycles) << "board time at the end";
  EXPECT_EQ(a.stats.moves_done, b.stats.moves_done);
  std::printf(
      "%zu batches, %zu answer bytes, %zu edges, %llu cycles; wall: rtl %.2f s, tlm %.3f s\n",
      a.batches, a.received.size(), a.edges.size(), static_cast<unsigned long long>(a.stats.cycles),
      a.wall_s, b.wall_s);
}

TEST(TwinBoardPty, V1SameAsVerilatedBoard) {
  const auto cfg = job_config();
  const auto p = job_plan(cfg);
  tw::HostScript s;
  s.v1 = tw::job_packets(fpgacnc::protocol::v1::pack_job(p), cfg.clk_hz, moves() / 2);
  expect_same(s, cfg, moves() / 2);
}

TEST(TwinBoardPty, V2SameAsVerilatedBoard) {
  const auto cfg = job_config();
  const auto p = job_plan(cfg);
  tw::HostScript s;
  s.v2 = tw::job_script(pack_motion(p, cfg), moves());
  s.v2->status_at_end = false;
  expect_same(s, cfg, moves());
}

// Native arcs: corpus/cncjs/circle.gcode as ARC frames (systemc/cosim/circle-arcs.toml: four
// quarter circles, a Z move, a rapid; 100 times faster than written).
TEST(TwinBoardPty, V2ArcsSameAsVerilatedBoard) {
  const auto cfg = cfgns::load_machine_config(std::string(FPGACNC_COSIM_DIR) + "/circle-arcs.toml");
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const auto p = plan::plan_input_file(std::string(FPGACNC_CORPUS_DIR) + "/circle.gcode", cfg, po);
  const auto job = pack_motion(p, cfg);
  tw::HostScript s;
  s.v2 = tw::job_script(job);
  s.v2->status_at_end = false;
  size_t arcs = 0;
  for (const auto& f : job.frames) arcs += f.frame.type == tw::v2::kArc ? 1 : 0;
  EXPECT_EQ(arcs, 4u) << "the four quarter circles as ARC frames";
  expect_same(s, cfg, 4);
}

TEST(TwinBoardPty, CorpusJobNetStepsMatchPlan) {
  cfgns::MachineConfig cfg;
  plan::PlanOptions po;
  const auto p =
      plan::plan_input_file(std::string(FPGACNC_CORPUS_DIR) + "/jsdc-laser.gcode", cfg, po);
  tw::TwinBoard board(tw::TwinBoard::options_from_config(cfg));
  board.start();
  uint64_t motion_frames = 0;
  {
    fpgacnc::link::SerialLink lk(board.path(), cfg.baud);
    auto o2 = fpgacnc::link::stream_v2_options(cfg);
    const auto choice = fpgacnc::link::select_protocol(lk, "auto", o2);
    ASSERT_EQ(choice.protocol, "v2");
    const auto job = pack_motion(p, cfg);
    const auto rep = fpgacnc::link::stream_v2_job(lk, job, o2, choice.ident);
    EXPECT_TRUE(rep.position_ok);
    motion_frames = rep.lines + rep.profiles + rep.arcs + rep.dwells;
  }
  ASSERT_TRUE(board.wait_quiet(5000ms));
  board.stop();
  ASSERT_EQ(board.error(), "");
  const auto n = board.net_steps();
  for (int a = 0; a < models::kBoardAxes; ++a) {
    EXPECT_EQ(n[static_cast<size_t>(a)], p.final_steps[static_cast<size_t>(a)]) << "axis " << a;
  }
  const auto st = board.stats();
  EXPECT_GT(st.cycles, 10'000'000'000u) << "the job at its real feeds: about 300 s of board time";
  EXPECT_EQ(st.moves_done, motion_frames) << "every LINE/LINE_PROFILE/ARC/DWELL frame ran once";
  std::printf("%s: %llu cycles (%.1f s of machine time) in %.2f s wall, %.0f M clocks/s\n",
              p.source.c_str(), static_cast<unsigned long long>(st.cycles),
              static_cast<double>(st.cycles) / cfg.clk_hz, st.wall_s, st.clocks_per_s / 1e6);
}

// Any serial program: pyserial (Debian python3-serial) writes the original controller's example
// (init and one move, protocol v1) to the twin board's pty and must read the ACK; the board moved
// exactly the example's steps.
TEST(TwinBoardPty, PyserialClientGetsTheAck) {
  const char* python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  tw::TwinBoard board;
  board.start();
  std::string script = PYSERIAL_SCRIPT, path = board.path(), timeout = "60";
  char* argv[] = {const_cast<char*>(python), script.data(), path.data(), timeout.data(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawnp(&pid, python, nullptr, nullptr, argv, environ), 0) << python;
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "pyserial_drive.py on " << path;
  ASSERT_TRUE(board.wait_quiet(5000ms));
  board.stop();
  const auto n = board.net_steps();
  EXPECT_EQ(n[0], 320);  // the example's X +320, Y -160 steps (docs/protocol.md, "v1")
  EXPECT_EQ(n[1], -160);
  EXPECT_EQ(board.stats().moves_done, 1u);
}

// ---- MOTION through the pty at given board clocks ----
// A host that writes either when the board is idle for the host (as the lockstep host) or at a
// given board clock while the board is busy: the twin board stops at the host's deadline
// (set_host_deadline) and the Verilated board is run in this thread (not started) up to that
// clock, so the bytes start on the next clock on both, whatever the wall time.
class ClockedHost {
 public:
  virtual ~ClockedHost() = default;
  virtual void write(const std::vector<uint8_t>& b) = 0;
  // Runs the board to clock `c` (busy all the way); returns the clock reached.
  virtual uint64_t run_to(uint64_t c) = 0;
  // Runs the board until it is idle for the host (every answer read).
  virtual void run_idle() = 0;
  virtual uint64_t cycle() const = 0;
  virtual uint64_t press(sb::Button b) = 0;
  std::vector<uint8_t> received;
};

class TwinHost : public ClockedHost {
 public:
  explicit TwinHost(tw::TwinBoard& b) : b_(b) {
    b_.start();
    lk_ = std::make_unique<fpgacnc::link::SerialLink>(b_.path(), b_.options().baud);
  }
  void write(const std::vector<uint8_t>& b) override {
    lk_->write(b);
    written_ += b.size();
  }
  uint64_t run_to(uint64_t c) override {
    b_.set_host_deadline(static_cast<int64_t>(c));
    // Liveness only (the verdict counts board clocks).
    const auto give_up = std::chrono::steady_clock::now() + 60s;
    while (std::chrono::steady_clock::now() < give_up) {
      read();
      if (b_.cycle() >= c) break;
      if (b_.stats().bytes_in >= written_ && b_.idle_for_host()) break;  // quiet before c
      std::this_thread::sleep_for(50us);
    }
    return b_.cycle();
  }
  void run_idle() override {
    b_.set_host_deadline(-1);  // no timer: a board held at one goes on
    const auto give_up = std::chrono::steady_clock::now() + 60s;
    while (std::chrono::steady_clock::now() < give_up) {
      read();
      if (b_.stats().bytes_in >= written_ && b_.idle_for_host() &&
          received.size() >= b_.stats().bytes_out)
        return;
      std::this_thread::sleep_for(50us);
    }
    ADD_FAILURE() << "twin board not idle after 60 s";
  }
  uint64_t cycle() const override { return b_.cycle(); }
  uint64_t press(sb::Button b) override { return b_.press_button(b); }

 private:
  void read() {
    while (const auto b = lk_->read_byte(std::chrono::milliseconds(0))) received.push_back(*b);
  }
  tw::TwinBoard& b_;
  std::unique_ptr<fpgacnc::link::SerialLink> lk_;
  uint64_t written_ = 0;
};

class RtlHost : public ClockedHost {
 public:
  explicit RtlHost(sb::SimBoard& b) : b_(b) {
    lk_ = std::make_unique<fpgacnc::link::SerialLink>(b_.path(), b_.options().baud);
  }
  void write(const std::vector<uint8_t>& b) override { lk_->write(b); }
  uint64_t run_to(uint64_t c) override {
    if (c > b_.cycle()) b_.run_cycles_until_quiet(c - b_.cycle());
    read(false);
    return b_.cycle();
  }
  void run_idle() override {
    b_.run_cycles_until_quiet(uint64_t{1} << 40);
    read(true);
  }
  uint64_t cycle() const override { return b_.cycle(); }
  uint64_t press(sb::Button b) override { return b_.press_button(b); }

 private:
  void read(bool all) {
    const uint64_t out = b_.bytes_to_host();
    while (received.size() < out) {
      const auto b = lk_->read_byte(all ? std::chrono::milliseconds(2000) : 0ms);
      if (!b) break;
      received.push_back(*b);
    }
  }
  sb::SimBoard& b_;
  std::unique_ptr<fpgacnc::link::SerialLink> lk_;
};

// The session (both boards): HELLO; three LINE frames (X 2000 steps in 1 M clocks, X back 1500
// in 600 k, Y 800 in 400 k; code 1 without power: the feed rate), then at fixed clocks after
// they were written: a HOLD (ramp 1/40 of 100 % per 256 clocks) during the first, a STATUS_QUERY
// while held, a RESUME, a 50 % feed rate, a STATUS_QUERY, a CANCEL (back to 100 %) with the
// first LINE still running and the others queued; when idle a new LINE (X -300, Y -200), then a
// STATUS_QUERY. Returns the clock the first LINE frames were written at (0 on a failure).
uint64_t motion_session(ClockedHost& h) {
  namespace v2 = tw::v2;
  h.write(v2::frame(0, v2::kHello));
  h.run_idle();
  v2::FrameParser parser;
  uint8_t seq = 0;
  bool ident = false;
  for (uint8_t b : h.received)
    if (const auto f = parser.feed(b); f && f->type == v2::kIdent) {
      seq = f->u8(16);
      ident = true;
    }
  EXPECT_TRUE(ident) << "no IDENT";
  const uint64_t c0 = h.cycle();
  std::vector<uint8_t> lines;
  for (const auto& [t, x, y] : {std::tuple<uint32_t, int32_t, int32_t>{1'000'000, 2000, 0},
                                {600'000, -1500, 300},
                                {400'000, 0, 800}}) {
    const std::array<int32_t, 4> steps{x, y, 0, 0};
    const auto f = v2::frame(seq++, v2::kLine, v2::line_payload(1, 0, t, steps, false));
    lines.insert(lines.end(), f.begin(), f.end());
  }
  h.write(lines);
  const uint32_t ramp = static_cast<uint32_t>((uint64_t{1} << 32) / 40);
  auto motion = [&](uint8_t flags, uint16_t rate) {
    return v2::frame(0, fpgacnc::spec::kTypeMotion, v2::motion_payload(flags, rate, rate, ramp));
  };
  const std::vector<std::pair<uint64_t, std::vector<uint8_t>>> timed{
      {400'000, motion(static_cast<uint8_t>(fpgacnc::spec::kMotionHold), 0x8000)},
      {600'000, v2::frame(0, v2::kStatusQuery)},
      {900'000, motion(static_cast<uint8_t>(fpgacnc::spec::kMotionResume), 0x8000)},
      {1'100'000, motion(0, 0x4000)},
      {1'300'000, v2::frame(0, v2::kStatusQuery)},
      {1'500'000, motion(static_cast<uint8_t>(fpgacnc::spec::kMotionCancel), 0x8000)},
  };
  for (const auto& [dt, bytes] : timed) {
    const uint64_t at = c0 + dt;
    const uint64_t got = h.run_to(at);
    EXPECT_EQ(got, at) << "the board was not busy at clock " << at;
    if (got != at) return 0;
    h.write(bytes);
  }
  h.run_idle();
  // after the CANCEL: a new move from where the machine stopped
  const std::array<int32_t, 4> back{-300, -200, 0, 0};
  h.write(v2::frame(seq++, v2::kLine, v2::line_payload(1, 0, 150'000, back, false)));
  h.run_idle();
  h.write(v2::frame(0, v2::kStatusQuery));
  h.run_idle();
  return c0;
}

// Runs `session` on the twin board and on the Verilated board and compares them: the STEP/DIR
// edges identical; every answer byte starting on the same clock; the device frames identical but
// for the heater block of STATUS (the Verilated core samples its heaters every
// kSimboardSampleClks, the twins model cnc_core's SAMPLE_CLKS of one second: their first sample
// comes later).
struct BothRuns {
  tw::LockstepRun rtl, tlm;
  uint64_t replays = 0;
};
BothRuns run_both(const std::function<uint64_t(ClockedHost&)>& session) {
  const cfgns::MachineConfig cfg;
  BothRuns r;
  tw::LockstepRun &a = r.rtl, &b = r.tlm;
  sb::BoardOptions ro = sb::SimBoard::options_from_config(cfg);
  ro.record_tx = true;
  sb::SimBoard rtl(ro);
  tw::TwinBoardOptions to = tw::TwinBoard::options_from_config(cfg);
  to.record_tx = true;
  // The board does not pass the end of the bytes written at a timer until 50 ms after the write:
  // time for this thread to name its next timer first, also on a loaded machine.
  to.host_grace = std::chrono::milliseconds(50);
  tw::TwinBoard tlm(to);
  {
    TwinHost h(tlm);
    b.model = "tlm";
    EXPECT_NE(session(h), 0u);
    b.received = h.received;
  }
  tlm.stop();
  EXPECT_EQ(tlm.error(), "");
  b.edges = tlm.edges();
  b.stats = tlm.stats();
  r.replays = tlm.replays();
  {
    RtlHost h(rtl);
    a.model = "rtl";
    EXPECT_NE(session(h), 0u);
    a.received = h.received;
  }
  a.edges = rtl.edges();
  a.stats = rtl.stats();
  auto pins = [](const std::vector<models::Edge>& e) {
    std::vector<std::tuple<uint64_t, int, int>> v;
    for (const auto& x : e)
      if (x.signal != models::kTx) v.emplace_back(x.cycle, x.signal, x.value);
    return v;
  };
  auto starts = [&](const std::vector<models::Edge>& e) {
    std::vector<uint64_t> v;
    for (const auto& [c, byte] :
         tw::tx_bytes_from_edges(e, static_cast<double>(cfg.clk_hz), cfg.baud))
      v.push_back(c);
    return v;
  };
  auto frames = [](const std::vector<uint8_t>& rx) {
    std::vector<std::pair<uint8_t, std::vector<uint8_t>>> v;
    tw::v2::FrameParser fp;
    constexpr size_t kHeat = 30 + 4 * models::kBoardAxes;  // the heater block's first byte
    for (uint8_t x : rx)
      if (auto f = fp.feed(x)) {
        if (f->type == tw::v2::kStatus && f->payload.size() > kHeat)
          std::fill(f->payload.begin() + kHeat, f->payload.end(), uint8_t{0});
        v.emplace_back(f->type, f->payload);
      }
    return v;
  };
  EXPECT_TRUE(pins(a.edges) == pins(b.edges)) << "STEP/DIR edges differ";
  EXPECT_TRUE(starts(a.edges) == starts(b.edges)) << "answer byte clocks differ";
  EXPECT_EQ(a.received.size(), b.received.size());
  const auto fa = frames(a.received), fb = frames(b.received);
  EXPECT_EQ(fa.size(), fb.size());
  for (size_t k = 0; k < std::min(fa.size(), fb.size()); ++k) {
    EXPECT_EQ(fa[k].first, fb[k].first) << "device frame #" << k;
    EXPECT_EQ(fa[k].second, fb[k].second) << "device frame #" << k;
  }
  EXPECT_EQ(a.stats.cycles, b.stats.cycles);
  return r;
}

// The STATUS frames the host received, in order.
std::vector<std::vector<uint8_t>> statuses(const std::vector<uint8_t>& rx) {
  std::vector<std::vector<uint8_t>> v;
  tw::v2::FrameParser parser;
  for (uint8_t x : rx)
    if (const auto f = parser.feed(x); f && f->type == tw::v2::kStatus) v.push_back(f->payload);
  return v;
}

// The session above on the twin board and on the Verilated board (run_both).
TEST(TwinBoardPty, MotionAtBoardClocksSameAsVerilatedBoard) {
  const auto r = run_both(motion_session);
  const tw::LockstepRun &a = r.rtl, &b = r.tlm;
  // Not vacuous: the hold stopped the board (a STATUS with HOLD and STOPPED); the CANCEL came
  // with the first LINE still running (held, then at 50 %) and dropped it and the two queued:
  // X short of the first's 2000 steps, no Y but the new move's; no fault, the hold over, not
  // busy (the last STATUS); one move done (the one after the CANCEL); the twin board replayed
  // its session at each MOTION frame.
  const auto n = models::net_steps(a.edges);
  EXPECT_GT(n[0], 0);
  EXPECT_LT(n[0], 2000 - 300);
  EXPECT_EQ(n[1], -200) << "the third LINE (Y 800) was dropped";
  const auto st = statuses(a.received);
  int held = 0;
  for (const auto& f : st) {
    const uint8_t want = fpgacnc::spec::kStateHold | fpgacnc::spec::kStateStopped;
    if ((f.at(0) & want) == want) ++held;
  }
  EXPECT_GE(st.size(), 5u);
  EXPECT_GE(held, 1) << "no STATUS with HOLD and STOPPED";
  ASSERT_FALSE(st.empty());
  const std::vector<uint8_t>& last = st.back();
  ASSERT_GE(last.size(), 30u);
  EXPECT_EQ(last[0] & (fpgacnc::spec::kStateBusy | fpgacnc::spec::kStateHold |
                       fpgacnc::spec::kStateFault),
            0)
      << "busy, held or a fault after the CANCEL and the new move";
  EXPECT_EQ(r.replays, 4u);
  EXPECT_EQ(a.stats.moves_done, 1u);
  EXPECT_EQ(b.stats.moves_done, 1u);
  std::printf("%zu answer bytes, %zu edges, %llu cycles; %llu replays\n", a.received.size(),
              a.edges.size(), static_cast<unsigned long long>(a.stats.cycles),
              static_cast<unsigned long long>(r.replays));
}

// The buttons at board clocks: HELLO, a MOTION setting a short hold ramp, a LINE (X 3000 steps
// in 1.5 M clocks); the feed hold button
// pressed 300 000 clocks after it was written, a STATUS_QUERY 800 000 clocks after it, the
// cycle-start button at 1 000 000; when idle a STATUS_QUERY. Both boards press for
// SimBoard::kButtonPressClks from the next edge.
uint64_t button_session(ClockedHost& h) {
  namespace v2 = tw::v2;
  h.write(v2::frame(0, v2::kHello));
  h.run_idle();
  v2::FrameParser parser;
  uint8_t seq = 0;
  for (uint8_t b : h.received)
    if (const auto f = parser.feed(b); f && f->type == v2::kIdent) seq = f->u8(16);
  // the ramp of a hold: 1/40 of 100 % per 256 clocks (the default takes 0.1 s)
  h.write(v2::frame(
      0, fpgacnc::spec::kTypeMotion,
      v2::motion_payload(0, 0x8000, 0x8000, static_cast<uint32_t>((uint64_t{1} << 32) / 40))));
  h.run_idle();
  const uint64_t c0 = h.cycle();
  const std::array<int32_t, 4> steps{3000, 0, 0, 0};
  h.write(v2::frame(seq, v2::kLine, v2::line_payload(1, 0, 1'500'000, steps, false)));
  for (const auto& [dt, what] :
       {std::pair<uint64_t, int>{300'000, 0}, {800'000, 2}, {1'000'000, 1}}) {
    const uint64_t at = c0 + dt;
    const uint64_t got = h.run_to(at);
    EXPECT_EQ(got, at) << "the board was not busy at clock " << at;
    if (got != at) return 0;
    if (what == 2) {
      h.write(v2::frame(0, v2::kStatusQuery));
    } else {
      EXPECT_EQ(h.press(what == 0 ? sb::Button::kHold : sb::Button::kStart), at + 1);
    }
  }
  h.run_idle();
  h.write(v2::frame(0, v2::kStatusQuery));
  h.run_idle();
  return c0;
}

// The feed hold and cycle-start buttons of the twin board against the Verilated board's: identical
// edges and answers (run_both); the hold stopped the move (a STATUS with HOLD and STOPPED), the
// cycle start resumed it (the move done, X at 3000, HOLD clear at the end), and the board took
// longer than the move's 1.5 M clocks.
TEST(TwinBoardPty, ButtonsAtBoardClocksSameAsVerilatedBoard) {
  const auto r = run_both(button_session);
  const tw::LockstepRun& a = r.rtl;
  EXPECT_EQ(models::net_steps(a.edges)[0], 3000);
  EXPECT_EQ(a.stats.moves_done, 1u);
  EXPECT_EQ(r.tlm.stats.moves_done, 1u);
  const auto st = statuses(a.received);
  ASSERT_EQ(st.size(), 3u);  // the MOTION's, the two STATUS_QUERYs'
  const uint8_t both = fpgacnc::spec::kStateHold | fpgacnc::spec::kStateStopped;
  EXPECT_EQ(st[1].at(0) & both, both) << "not held at rest 500 000 clocks after the press";
  EXPECT_EQ(st[2].at(0) & (both | fpgacnc::spec::kStateBusy), 0);
  EXPECT_GT(a.stats.cycles, 1'500'000u + 500'000u) << "held for about 600 000 clocks";
  EXPECT_EQ(r.replays, 3u);  // the MOTION, the two presses
  std::printf("%zu answer bytes, %zu edges, %llu cycles; %llu replays\n", a.received.size(),
              a.edges.size(), static_cast<unsigned long long>(a.stats.cycles),
              static_cast<unsigned long long>(r.replays));
}

}  // namespace
