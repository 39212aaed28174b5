// grbl 1.1 front end (fpgacnc/grbl/engine.h) against the twin board behind its pty, driven
// in-process as a sender would drive it, with every wait and poll paced by the board's clock
// (link time), never by wall time. Expected answers come from grbl's documents (interface,
// commands, settings: docs/grbl.md) and final positions from the host planner run on the same
// file, independently of the engine.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/grbl/settings.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace fs = std::filesystem;
namespace grbl = fpgacnc::grbl;
using fpgacnc::config::MachineConfig;
using std::chrono::milliseconds;

namespace {

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::string> lines;
  std::string l;
  while (std::getline(in, l)) {
    if (!l.empty() && l.back() == '\r') l.pop_back();
    lines.push_back(l);
  }
  return lines;
}

struct Report {
  std::string state;
  std::array<double, 3> mpos{};
};

// "<Idle|MPos:1.000,2.000,3.000|...>"
std::optional<Report> parse_report(const std::string& line) {
  static const std::regex re(
      R"(^<([A-Za-z]+(?::\d)?)\|MPos:(-?[\d.]+),(-?[\d.]+),(-?[\d.]+)(\|.*)?>$)");
  std::smatch m;
  if (!std::regex_match(line, m, re)) return std::nullopt;
  Report r;
  r.state = m[1];
  for (int i = 0; i < 3; ++i) r.mpos[static_cast<size_t>(i)] = std::stod(m[i + 2]);
  return r;
}

// The engine with the twin board behind it, and a sender's view of it.
class Rig {
 public:
  // `rtl`: the Verilated board (with its e-stop input and limit switches) instead of the twins;
  // `endstops`, `plate`: simulated endstops and a probe plate on it; `noise`: the endstops'
  // bounce and trigger jitter.
  explicit Rig(std::string settings_path = "", MachineConfig cfg = {}, bool rtl = false,
               std::vector<fpgacnc::simboard::Endstop> endstops = {},
               std::optional<fpgacnc::simboard::ProbePlate> plate = std::nullopt,
               fpgacnc::simboard::SwitchNoise noise = {})
      : cfg_(cfg),
        link_(rtl ? rtl_link(cfg, std::move(endstops), plate, noise)
                  : fpgacnc::simboard::make_board_link(
                        std::make_unique<fpgacnc::twins::TwinBoard>(
                            fpgacnc::twins::TwinBoard::options_from_config(cfg)),
                        cfg.baud, {})) {
    grbl::Settings s = grbl::settings_from_config(cfg);
    if (!settings_path.empty()) s = grbl::load_settings(settings_path, s).value_or(s);
    grbl::EngineOptions o;
    o.v2 = fpgacnc::link::stream_v2_options(cfg);
    o.settings_path = settings_path;
    if (rtl) {
      auto* bl = dynamic_cast<fpgacnc::simboard::BoardLink*>(link_.get());
      o.estop_press = [bl] { bl->board().set_estop(true); };
      o.estop_release = [bl] { bl->board().set_estop(false); };
    }
    o.limit_switches = fpgacnc::simboard::any_board_of(*link_)->limit_switches();
    o.probe = rtl;
    engine_ = std::make_unique<grbl::Engine>(*link_, cfg, s, o);
    engine_->connect();
    engine_->take_output();  // as fpgacnc grbl: the banner goes to a sender when it connects
  }

  static std::unique_ptr<fpgacnc::link::Link> rtl_link(
      const MachineConfig& cfg, std::vector<fpgacnc::simboard::Endstop> endstops,
      std::optional<fpgacnc::simboard::ProbePlate> plate, fpgacnc::simboard::SwitchNoise noise) {
    auto o = fpgacnc::simboard::SimBoard::options_from_config(cfg);
    o.endstops = std::move(endstops);
    o.probe_plate = plate;
    o.switch_noise = noise;
    return fpgacnc::simboard::make_board_link(std::make_unique<fpgacnc::simboard::SimBoard>(o),
                                              cfg.baud, {});
  }
  fpgacnc::simboard::SimBoard& board() { return *fpgacnc::simboard::board_of(*link_); }
  grbl::Engine& engine() { return *engine_; }
  fpgacnc::link::Link& link() { return *link_; }

  // One step of the engine; complete lines of its output are queued.
  void pump() { pump(step_wait); }
  void pump(milliseconds wait) {
    engine_->step(wait);
    // Nothing in flight: let board time pass as a sender's pause would.
    if (!engine_->busy()) link_->wait_until(link_->now() + wait);
    partial_ += engine_->take_output();
    for (size_t nl; (nl = partial_.find('\n')) != std::string::npos;) {
      std::string l = partial_.substr(0, nl);
      partial_.erase(0, nl + 1);
      if (!l.empty() && l.back() == '\r') l.pop_back();
      if (l.empty()) continue;
      all_.push_back(l);
      if (l[0] == '<') {
        reports_.push_back(l);
      } else {
        lines_.push_back(l);
      }
    }
  }
  // Pumps until `pred` or `limit` of board time; false on the limit.
  template <typename P>
  bool pump_until(P pred, milliseconds limit = milliseconds(600'000)) {
    const auto end = link_->now() + limit;
    while (!pred()) {
      if (link_->now() > end) return false;
      maybe_poll();
      pump();
    }
    return true;
  }
  // '?' every 100 ms of board time (10 Hz) while `polling`.
  void maybe_poll() {
    if (!polling) return;
    const auto now = link_->now();
    if (now - last_poll_ >= milliseconds(100)) {
      engine_->receive("?");
      last_poll_ = now;
    }
  }
  void send(const std::string& bytes) { engine_->receive(bytes); }
  // The next non-report line (ok, error:N, [..], ALARM:N, Grbl ...).
  std::string next_line() {
    EXPECT_TRUE(pump_until([&] { return !lines_.empty(); })) << "no answer";
    if (lines_.empty()) return "";
    std::string l = lines_.front();
    lines_.pop_front();
    return l;
  }
  // Sends one line and returns every line of its answer up to and including ok / error:N.
  std::vector<std::string> command(const std::string& line) {
    send(line + "\n");
    std::vector<std::string> out;
    for (;;) {
      out.push_back(next_line());
      const std::string& l = out.back();
      if (l.empty() || l == "ok" || l.rfind("error:", 0) == 0) return out;
    }
  }
  // A fresh status report (asked now, its answer awaited).
  Report status() {
    const size_t n = reports_.size();
    send("?");
    EXPECT_TRUE(pump_until([&] { return reports_.size() > n; })) << "no status report";
    const auto r = parse_report(reports_.back());
    EXPECT_TRUE(r.has_value()) << reports_.back();
    return r.value_or(Report{});
  }
  Report wait_idle() {
    Report r;
    const auto end = link_->now() + milliseconds(3'600'000);
    while (link_->now() < end) {
      r = status();
      if (r.state == "Idle") return r;
      const auto until = link_->now() + milliseconds(100);
      while (link_->now() < until) pump(milliseconds(20));
    }
    ADD_FAILURE() << "not idle: " << r.state;
    return r;
  }
  const std::vector<std::string>& reports() const { return reports_; }
  std::deque<std::string>& lines() { return lines_; }
  const std::vector<std::string>& all() const { return all_; }

  bool polling = false;
  // Board time one step of the engine may wait for an answer (it returns at the first answer):
  // long jobs take fewer, longer steps.
  milliseconds step_wait{5};

 private:
  MachineConfig cfg_;
  std::unique_ptr<fpgacnc::link::Link> link_;
  std::unique_ptr<grbl::Engine> engine_;
  std::string partial_;
  std::deque<std::string> lines_;
  std::vector<std::string> reports_;
  std::vector<std::string> all_;
  fpgacnc::link::Link::Time last_poll_{};
};

// The file's end position as the host planner computes it (grbl dialect, the same machine).
std::array<int64_t, 3> planned_end(const std::string& path, const MachineConfig& cfg) {
  auto go = fpgacnc::plan::gcode_options(cfg);
  go.dialect = fpgacnc::gcode::Dialect::kGrbl;
  go.tool_change_pause = false;
  const auto prog = fpgacnc::gcode::parse_file(path, go);
  const auto plan = fpgacnc::plan::plan_program(prog, cfg, {});
  return {plan.final_steps[0], plan.final_steps[1], plan.final_steps[2]};
}

void expect_at(const Report& r, const std::array<int64_t, 3>& steps, const MachineConfig& cfg) {
  for (size_t a = 0; a < 3; ++a) {
    const double want = static_cast<double>(steps[a]) / cfg.steps_per_mm[a];
    EXPECT_NEAR(r.mpos[a], want, 0.0006) << "axis " << a;
  }
}

// A soft reset (0x18) out of an alarm that left a line waiting: that line's ok, the banner, and
// the alarm's unlock message (grbl keeps the alarm over a reset).
void expect_reset_out_of_alarm(Rig& rig) {
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), "ok");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
}

struct StreamResult {
  size_t oks = 0, errors = 0;
  std::vector<std::string> error_lines;
};

// Send-response: one line, wait for its ok/error, the next.
StreamResult ping_pong(Rig& rig, const std::vector<std::string>& lines) {
  StreamResult r;
  for (const auto& l : lines) {
    const auto ans = rig.command(l);
    if (ans.back() == "ok") {
      ++r.oks;
    } else {
      ++r.errors;
      r.error_lines.push_back(l + " -> " + ans.back());
    }
  }
  return r;
}

// Character counting: lines go out while the bytes of unanswered lines fit the 128-byte buffer.
StreamResult char_counting(Rig& rig, const std::vector<std::string>& lines, size_t* max_in_flight) {
  StreamResult r;
  std::deque<size_t> in_flight;
  size_t bytes = 0, next = 0;
  *max_in_flight = 0;
  while (next < lines.size() || !in_flight.empty()) {
    while (next < lines.size() && bytes + lines[next].size() + 1 <= grbl::kRxBuffer) {
      rig.send(lines[next] + "\n");
      in_flight.push_back(lines[next].size() + 1);
      bytes += in_flight.back();
      ++next;
    }
    *max_in_flight = std::max(*max_in_flight, in_flight.size());
    // The engine never holds more than the sender put in flight.
    EXPECT_LE(rig.engine().rx_pending(), grbl::kRxBuffer);
    const std::string a = rig.next_line();
    if (a == "ok" || a.rfind("error:", 0) == 0) {
      (a == "ok" ? r.oks : r.errors)++;
      if (a != "ok") r.error_lines.push_back(a);
      bytes -= in_flight.front();
      in_flight.pop_front();
    } else if (a.empty()) {
      break;
    }
  }
  return r;
}

const std::string kCorpus = FPGACNC_CORPUS_ROOT;

}  // namespace

// libsystemc's main() calls sc_main(); gtest_main provides main(), so this only links.
extern "C" int sc_main(int, char*[]) {
  return 0;
}

namespace {

struct JobCase {
  const char* file;
  bool counting;
};

void PrintTo(const JobCase& c, std::ostream* os) {
  *os << c.file << (c.counting ? " (character counting)" : " (send-response)");
}

class GrblStream : public ::testing::TestWithParam<JobCase> {};

}  // namespace

// A corpus job streamed as a sender streams it, `?` at 10 Hz of board time throughout; every
// line is answered ok and the machine ends, at rest, where the planner puts the file's end.
TEST_P(GrblStream, CorpusJobEndsWhereThePlanEnds) {
  const JobCase c = GetParam();
  const std::string path = kCorpus + "/" + c.file;
  MachineConfig cfg;
  Rig rig;
  rig.polling = true;
  rig.step_wait = milliseconds(50);
  const auto lines = read_lines(path);
  StreamResult r;
  size_t max_in_flight = 0;
  if (c.counting) {
    r = char_counting(rig, lines, &max_in_flight);
    EXPECT_GT(max_in_flight, 2u) << "character counting kept more than one line in flight";
  } else {
    r = ping_pong(rig, lines);
  }
  EXPECT_EQ(r.errors, 0u) << (r.error_lines.empty() ? "" : r.error_lines.front());
  EXPECT_EQ(r.oks, lines.size());
  const Report end = rig.wait_idle();
  expect_at(end, planned_end(path, cfg), cfg);
  // The report's position is the FPGA's step counter, the engine's view of it the same.
  const auto mp = rig.engine().mpos();
  for (size_t a = 0; a < 3; ++a) EXPECT_NEAR(end.mpos[a], mp[a], 0.0005);
  // Polled throughout at 10 Hz of board time (while the lines went out, then by wait_idle() until
  // Idle): several reports said Run, each well formed. How many polls fall while the lines go
  // out is not counted: a short job's lines are all taken in a few steps of the engine, and how
  // much board time those steps cover depends on how far the board ran while the host worked.
  size_t runs = 0;
  for (const auto& rep : rig.reports()) {
    const auto p = parse_report(rep);
    ASSERT_TRUE(p.has_value()) << rep;
    runs += p->state == "Run" ? 1 : 0;
    EXPECT_NE(rep.find("|FS:"), std::string::npos) << rep;
  }
  EXPECT_GT(runs, 3u);
  EXPECT_GT(rig.engine().stats().frames, 0u);
}

INSTANTIATE_TEST_SUITE_P(Corpus, GrblStream,
                         ::testing::Values(JobCase{"cncjs/circle.gcode", false},
                                           JobCase{"cncjs/circle.gcode", true},
                                           JobCase{"cncjs/circle-inch.gcode", true},
                                           JobCase{"cncjs/arc-ijk.gcode", false},
                                           JobCase{"cncjs/g2-arc.gcode", true},
                                           JobCase{"cncjs/jsdc-laser.gcode", true}),
                         [](const ::testing::TestParamInfo<JobCase>& i) {
                           std::string n = fs::path(i.param.file).stem().string() +
                                           (i.param.counting ? "_counting" : "_ping_pong");
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

// Welcome message on connect (interface.md, "Welcome Message") and the queried messages.
TEST(Grbl, BannerAndQueries) {
  Rig rig;
  rig.engine().opened();
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  auto a = rig.command("$I");
  ASSERT_EQ(a.size(), 3u) << ::testing::PrintToString(a);
  EXPECT_EQ(a[0].rfind("[VER:1.1", 0), 0u);
  EXPECT_TRUE(std::regex_match(a[1], std::regex(R"(\[OPT:[A-Z]*,\d+,128\])"))) << a[1];
  a = rig.command("$G");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0], "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]");
  a = rig.command("$#");
  ASSERT_EQ(a.size(), 12u);
  EXPECT_EQ(a[0], "[G54:0.000,0.000,0.000]");
  EXPECT_EQ(a[10], "[PRB:0.000,0.000,0.000:0]");
  a = rig.command("$N");
  EXPECT_EQ(a[0], "$N0=");
  EXPECT_EQ(a[1], "$N1=");
  EXPECT_EQ(rig.command("")[0], "ok");  // an empty line is ok
  // Modal state follows the lines; offsets appear in $# and in the report's WCO.
  EXPECT_EQ(rig.command("G10 L2 P1 X5 Y-2")[0], "ok");
  EXPECT_EQ(rig.command("G91 G20 M8")[0], "ok");
  a = rig.command("$G");
  EXPECT_EQ(a[0], "[GC:G0 G54 G17 G20 G91 G94 M5 M8 T0 F0 S0]");
  EXPECT_EQ(rig.command("G21 G90")[0], "ok");
  a = rig.command("$#");
  EXPECT_EQ(a[0], "[G54:5.000,-2.000,0.000]");
  const size_t n = rig.reports().size();
  rig.send("?");
  ASSERT_TRUE(rig.pump_until([&] { return rig.reports().size() > n; }));
  EXPECT_NE(rig.reports().back().find("|WCO:5.000,-2.000,0.000"), std::string::npos)
      << rig.reports().back();
  // A reset at rest: no alarm, the banner, and the work offsets kept (grbl keeps them).
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.status().state, "Idle");
  EXPECT_EQ(rig.command("$#")[0], "[G54:5.000,-2.000,0.000]");
}

// Every error class the front end answers (interface.md's error table, docs/grbl.md).
TEST(Grbl, ErrorCodes) {
  Rig rig;
  const std::vector<std::pair<std::string, std::string>> cases{
      {"X", "error:2"},          // bad number format
      {"$Z", "error:3"},         // not a '$' command
      {"G1 F-5 X1", "error:4"},  // negative value
      {"$H", "error:5"},         // homing not enabled
      {"G1 X1" + std::string(80, ' ') + "Y" + std::string(80, '1'), "error:11"},  // too long
      {"G99", "error:20"},            // unsupported G code
      {"M104 S200", "error:20"},      // unsupported M code
      {"G1 X1 E2", "error:20"},       // a letter grbl does not have
      {"G38.2 Z-1 F10", "error:20"},  // the twin board: no probe input, no trigger
      {"G1 G0 X1", "error:21"},       // modal group violation
      {"G1 X1 X2", "error:25"},       // repeated word
      {"G4", "error:28"},             // missing P
      {"G59.1", "error:29"},          // G59.x
      {"G2 X10 Y0", "error:35"},      // arc without offsets
      {"$J G91 X1 F100", "error:3"},  // $J without '=' (the jog refusals: test_grbl_motion.cpp)
      {"$100=-1", "error:4"},
      {"$21=1", "error:3"},  // hard limits: not available
  };
  for (const auto& [line, want] : cases) {
    const auto a = rig.command(line);
    EXPECT_EQ(a.back(), want) << line;
  }
  // Nothing moved.
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Idle");
  expect_at(r, {0, 0, 0}, MachineConfig{});
  // A line numbered in error is not executed: the next good line still works from 0.
  EXPECT_EQ(rig.command("G0 X1")[0], "ok");
  expect_at(rig.wait_idle(), {160, 0, 0}, MachineConfig{});
}

// $$ lists the settings; $N=value changes the machine (steps/mm moves the same G-code a
// different number of steps), persists in the settings file, and a new engine reads it back.
TEST(Grbl, SettingsRoundTripThroughTheFile) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("grbl_settings_{}", ::getpid());
  fs::create_directories(dir);
  const std::string file = (dir / "settings.txt").string();
  {
    Rig rig(file);
    auto a = rig.command("$$");
    EXPECT_EQ(a.back(), "ok");
    EXPECT_NE(std::find(a.begin(), a.end(), "$100=160.000"), a.end());
    EXPECT_NE(std::find(a.begin(), a.end(), "$11=0.010"), a.end());
    EXPECT_EQ(rig.command("$100=80")[0], "ok");
    EXPECT_EQ(rig.command("$110=6000")[0], "ok");
    EXPECT_EQ(rig.command("$N0=G21 G90")[0], "ok");
    EXPECT_EQ(rig.command("$10=3")[0], "ok");  // MPos and Bf
    EXPECT_EQ(rig.command("G0 X10")[0], "ok");
    const Report r = rig.wait_idle();
    // 10 mm at 80 steps/mm: 800 FPGA steps, reported back as 10 mm.
    EXPECT_NEAR(r.mpos[0], 10.0, 1e-9);
    EXPECT_NE(rig.reports().back().find("|Bf:"), std::string::npos) << rig.reports().back();
  }
  ASSERT_TRUE(fs::exists(file));
  {
    // The board is a new one (at 0); the file's settings and startup line come back.
    Rig rig(file);
    rig.engine().opened();
    EXPECT_EQ(rig.next_line(), grbl::kBanner);
    // Stored as grbl's parser keeps a line: no spaces (interface.md: ">G54G20:ok").
    EXPECT_EQ(rig.next_line(), ">G21G90:ok");
    auto a = rig.command("$$");
    EXPECT_NE(std::find(a.begin(), a.end(), "$100=80.000"), a.end());
    EXPECT_NE(std::find(a.begin(), a.end(), "$110=6000.000"), a.end());
    EXPECT_NE(std::find(a.begin(), a.end(), "$10=3"), a.end());
    EXPECT_EQ(rig.engine().config().steps_per_mm[0], 80.0);
    // $RST=$ restores the machine's values and keeps the work offsets; $RST=# clears those.
    EXPECT_EQ(rig.command("G10 L2 P2 X1.5").back(), "ok");
    a = rig.command("$RST=$");
    EXPECT_EQ(a[0], "[MSG:Restoring defaults]");
    a = rig.command("$$");
    EXPECT_NE(std::find(a.begin(), a.end(), "$100=160.000"), a.end());
    EXPECT_EQ(rig.command("$#")[1], "[G55:1.500,0.000,0.000]");
    EXPECT_EQ(rig.command("$RST=#").back(), "ok");
    EXPECT_EQ(rig.command("$#")[1], "[G55:0.000,0.000,0.000]");
  }
  fs::remove_all(dir);
}

// $C: every line parsed and answered, nothing moves; $C again leaves it with a reset.
TEST(Grbl, CheckModeMovesNothing) {
  Rig rig;
  auto a = rig.command("$C");
  EXPECT_EQ(a[0], "[MSG:Enabled]");
  EXPECT_EQ(rig.status().state, "Check");
  EXPECT_EQ(rig.command("G0 X10 Y10")[0], "ok");
  EXPECT_EQ(rig.command("G1 X1 X2")[0], "error:25");
  EXPECT_EQ(rig.command("G2 X20 Y10 I5 J0 F100")[0], "ok");
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Check");
  expect_at(r, {0, 0, 0}, MachineConfig{});
  a = rig.command("$C");
  EXPECT_EQ(a[0], "[MSG:Disabled]");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.engine().stats().frames, 0u);
  // The parser restarts where the machine is: G0 X1 moves 1 mm from 0.
  EXPECT_EQ(rig.command("G0 X1")[0], "ok");
  expect_at(rig.wait_idle(), {160, 0, 0}, MachineConfig{});
}

// Soft reset mid-job: sending stops, ALARM:3 then the banner and the unlock hint; G-code is
// locked until $X; the position is the FPGA's and the parser starts there again.
TEST(Grbl, SoftResetMidJobAlarmsAndResyncs) {
  Rig rig;
  rig.polling = true;
  std::vector<std::string> lines{"G21 G90 F2000"};
  for (int i = 1; i <= 200; ++i)
    lines.push_back(fmt::format("G1 X{} Y{}", (i % 2) ? 20 : 0, i * 0.2));
  std::deque<size_t> in_flight;
  size_t bytes = 0, next = 0, oks = 0;
  while (oks < 60) {
    while (next < lines.size() && bytes + lines[next].size() + 1 <= grbl::kRxBuffer) {
      rig.send(lines[next] + "\n");
      in_flight.push_back(lines[next].size() + 1);
      bytes += in_flight.back();
      ++next;
    }
    const std::string a = rig.next_line();
    ASSERT_EQ(a, "ok");
    ++oks;
    bytes -= in_flight.front();
    in_flight.pop_front();
  }
  EXPECT_EQ(rig.status().state, "Run");
  rig.polling = false;
  rig.send("\x18");
  // Lines taken before the reset keep their ok.
  std::string l = rig.next_line();
  while (l == "ok") l = rig.next_line();
  EXPECT_EQ(l, "ALARM:3");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  // Lines that were in the receive buffer are gone: no answer for them.
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Alarm");
  EXPECT_TRUE(rig.lines().empty());
  // Far from the job's end (Y 40): the rest was never sent.
  EXPECT_LT(r.mpos[1], 30.0);
  EXPECT_GT(rig.engine().stats().aborted + (lines.size() - next), 0u);
  EXPECT_EQ(rig.command("G0 X0 Y0")[0], "error:9");
  auto a = rig.command("$X");
  EXPECT_EQ(a[0], "[MSG:Caution: Unlocked]");
  EXPECT_EQ(a[1], "ok");
  // Still where the FPGA stopped; then back to 0 exactly (the parser starts at the FPGA's
  // position after the reset).
  const Report after = rig.status();
  EXPECT_EQ(after.state, "Idle");
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(after.mpos[i], r.mpos[i], 1e-9);
  EXPECT_EQ(rig.command("G90 G0 X0 Y0")[0], "ok");
  expect_at(rig.wait_idle(), {0, 0, 0}, MachineConfig{});
}

// Soft limits (docs/grbl.md, "Soft limits"): $20=1 with $130 = 50 and no [travel] in the
// configuration is grbl's own travel, X in [-50, 0]. A line that leaves it raises ALARM:2 and
// [MSG:Reset to continue], sends nothing and takes no further line until a soft reset, which
// answers its ok, then the banner and the unlock hint; the machine stays where it was.
TEST(Grbl, SoftLimitLineRaisesAlarm2AndMovesNothing) {
  Rig rig;
  EXPECT_EQ(rig.command("$20=1")[0], "ok");
  EXPECT_EQ(rig.command("$130=50")[0], "ok");
  auto a = rig.command("$$");
  EXPECT_NE(std::find(a.begin(), a.end(), "$20=1"), a.end());
  EXPECT_NE(std::find(a.begin(), a.end(), "$130=50.000"), a.end());
  EXPECT_EQ(rig.command("G0 X-20")[0], "ok");
  expect_at(rig.wait_idle(), {-20 * 160, 0, 0}, MachineConfig{});
  const uint64_t frames = rig.engine().stats().frames;
  rig.send("G0 X-50.5\nG0 X-30\n");
  EXPECT_EQ(rig.next_line(), "ALARM:2");
  EXPECT_EQ(rig.next_line(), "[MSG:Reset to continue]");
  Report r = rig.status();
  EXPECT_EQ(r.state, "Alarm");
  expect_at(r, {-20 * 160, 0, 0}, MachineConfig{});
  // The next line waits unanswered (grbl blocks everything but reports and the reset).
  EXPECT_TRUE(rig.lines().empty());
  EXPECT_EQ(rig.engine().stats().frames, frames);
  expect_reset_out_of_alarm(rig);
  EXPECT_EQ(rig.command("G0 X-30")[0], "error:9");
  EXPECT_EQ(rig.command("$X")[0], "[MSG:Caution: Unlocked]");
  // The parser restarts at the machine's position: X-30 is 10 mm further, inside.
  EXPECT_EQ(rig.command("G0 X-30")[0], "ok");
  expect_at(rig.wait_idle(), {-30 * 160, 0, 0}, MachineConfig{});
  // Y's travel is [-200, 0] ($131 = 200). A clockwise half circle from (-30, 0) about
  // (-30, -10) passes X -20: inside.
  EXPECT_EQ(rig.command("G2 X-30 Y-20 I0 J-10 F1000")[0], "ok");
  expect_at(rig.wait_idle(), {-30 * 160, -20 * 160, 0}, MachineConfig{});
  // From (-30, -20) about (-30, -45), radius 25, counter-clockwise to (-30, -70): through
  // 180 deg at X -55, 5 mm beyond -50, while both ends are inside.
  rig.send("G3 X-30 Y-70 I0 J-25\n");
  EXPECT_EQ(rig.next_line(), "ALARM:2");
  EXPECT_EQ(rig.next_line(), "[MSG:Reset to continue]");
  expect_reset_out_of_alarm(rig);
  EXPECT_EQ(rig.command("$X")[1], "ok");
  // Check mode checks soft limits too; $20=0 turns them off.
  EXPECT_EQ(rig.command("$C")[0], "[MSG:Enabled]");
  rig.send("G0 X5\n");
  EXPECT_EQ(rig.next_line(), "ALARM:2");
  EXPECT_EQ(rig.next_line(), "[MSG:Reset to continue]");
  expect_reset_out_of_alarm(rig);
  EXPECT_EQ(rig.command("$X")[1], "ok");
  EXPECT_EQ(rig.command("$20=0")[0], "ok");
  EXPECT_EQ(rig.command("G0 X5")[0], "ok");
  expect_at(rig.wait_idle(), {5 * 160, -20 * 160, 0}, MachineConfig{});
}

// Features that need hardware not built yet answer as grbl does without them (docs/grbl.md):
// $H error:5, a jog cancel outside Jog ignored; the spindle override is kept and reported (Ov)
// with nothing to drive; M0 holds at rest until '~'.
TEST(Grbl, FeaturesNotAvailableAndProgramPause) {
  Rig rig;
  EXPECT_EQ(rig.command("$H")[0], "error:5");
  EXPECT_EQ(rig.command("G0 X5")[0], "ok");
  rig.send("\x9A\x85");  // spindle override +10 %, jog cancel (not jogging: nothing)
  const Report r = rig.wait_idle();
  expect_at(r, {800, 0, 0}, MachineConfig{});
  size_t ov = 0;
  for (const auto& rep : rig.reports()) {
    if (rep.find("|Ov:") != std::string::npos) {
      EXPECT_NE(rep.find("|Ov:100,100,110"), std::string::npos) << rep;
      ++ov;
    }
  }
  EXPECT_GE(ov, 1u) << "the report after an override change carries Ov";
  // M0: Hold:0 once at rest, then '~' runs the rest.
  EXPECT_EQ(rig.command("G0 X6")[0], "ok");
  EXPECT_EQ(rig.command("M0")[0], "ok");
  rig.send("G0 X7\n");
  Report h;
  ASSERT_TRUE(rig.pump_until([&] {
    h = rig.status();
    return h.state == "Hold:0";
  }));
  expect_at(h, {960, 0, 0}, MachineConfig{});
  rig.send("~");
  EXPECT_EQ(rig.next_line(), "ok");
  expect_at(rig.wait_idle(), {1120, 0, 0}, MachineConfig{});
}

// On the Verilated board the soft reset presses the e-stop: the board drops its queue at once, so
// the reset completes long before the queued moves could have run out, and after $X the parser
// starts at the FPGA's position (back to 0 exactly).
TEST(Grbl, SoftResetOnTheVerilatedBoardDropsItsQueue) {
  Rig rig("", MachineConfig{}, true);
  // Slow 2 mm zigzag moves (0.2 s each at F600): several queued on the board at the reset.
  std::vector<std::string> lines{"G21 G90 F600"};
  for (int i = 1; i <= 12; ++i)
    lines.push_back(fmt::format("G1 X{} Y{}", (i % 2) ? 2 : 0, i * 0.1));
  for (const auto& l : lines) EXPECT_EQ(rig.command(l).back(), "ok") << l;
  // Let the board take the frames (flush rule: the sender went quiet) and start moving.
  ASSERT_TRUE(rig.pump_until([&] { return rig.status().mpos[0] > 0.1; }, milliseconds(2000)));
  const auto t0 = rig.link().now();
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:3");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  const auto took = rig.link().now() - t0;
  // The 12 moves take 2.4 s of machine time; the reset took a small part of one.
  EXPECT_LT(took, milliseconds(150)) << std::chrono::duration<double>(took).count() << " s";
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Alarm");
  EXPECT_LT(r.mpos[1], 0.6);
  EXPECT_EQ(rig.command("$X").back(), "ok");
  EXPECT_EQ(rig.command("G0 X0 Y0").back(), "ok");
  expect_at(rig.wait_idle(), {0, 0, 0}, MachineConfig{});
}

// The Verilated board's limit switches (docs/grbl.md "Hard limits"): Pn shows a held switch, a
// job that runs into a simulated endstop at X = 2 mm gives ALARM:1 with the position where the
// board stopped (its STEP edges), a reset with the switch still held says Check Limits, $X is
// refused until the carriage is pulled off the switch and then returns to Idle. Every wait is
// board time.
TEST(Grbl, HardLimitOnTheVerilatedBoard) {
  const MachineConfig cfg;
  const double spm = cfg.steps_per_mm[0];
  Rig rig("", cfg, true, {{0, true, static_cast<int64_t>(2.0 * spm)}});
  EXPECT_EQ(rig.command("$21=1").back(), "ok") << "the board has switches";
  // Pn: a held switch, then none.
  rig.board().set_limit(1, false, true);  // Y min
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  rig.status();
  EXPECT_NE(rig.reports().back().find("|Pn:Y"), std::string::npos) << rig.reports().back();
  rig.board().set_limit(1, false, false);
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  rig.status();
  EXPECT_EQ(rig.reports().back().find("|Pn:"), std::string::npos) << rig.reports().back();

  EXPECT_EQ(rig.command("G1 X20 F3000").back(), "ok");
  EXPECT_EQ(rig.next_line(), "ALARM:1");
  EXPECT_EQ(rig.next_line(), "[MSG:Reset to continue]");
  const Report a = rig.status();
  EXPECT_EQ(a.state, "Alarm");
  const auto net = rig.board().net_steps();
  EXPECT_NEAR(a.mpos[0], static_cast<double>(net[0]) / spm, 0.0005) << "the board's position";
  EXPECT_GE(a.mpos[0], 2.0);
  EXPECT_LT(a.mpos[0], 20.0);
  EXPECT_NE(rig.reports().back().find("|Pn:X"), std::string::npos) << rig.reports().back();

  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:Check Limits]");
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  EXPECT_EQ(rig.status().state, "Alarm");
  const auto held = rig.command("$X");
  ASSERT_EQ(held.size(), 2u);
  EXPECT_EQ(held[0], "[MSG:Check Limits]");
  EXPECT_EQ(held[1], "error:9");
  EXPECT_EQ(rig.command("G1 X0").back(), "error:9");

  EXPECT_EQ(rig.board().pull_off_endstops(), 1);
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  const auto unlock = rig.command("$X");
  EXPECT_EQ(unlock.front(), "[MSG:Caution: Unlocked]");
  EXPECT_EQ(unlock.back(), "ok");
  const Report idle = rig.status();
  EXPECT_EQ(idle.state, "Idle");
  EXPECT_EQ(rig.reports().back().find("|Pn:"), std::string::npos) << rig.reports().back();
  EXPECT_EQ(rig.command("G1 X1").back(), "ok");
  const Report end = rig.wait_idle();
  EXPECT_NEAR(end.mpos[0], 1.0, 0.0005);
}

// ---- Feed hold and overrides on the Verilated board (docs/grbl.md "Feed hold and overrides").
// Every duration is counted in board clocks (SimBoard::cycle, move_done_cycles), never wall time.

std::array<int64_t, 3> board_xyz(Rig& rig) {
  const auto n = rig.board().net_steps();
  return {n[0], n[1], n[2]};
}

// Reports until `pred` holds for one of them (asked back to back: a few ms of board time each),
// every state seen kept in `states`; false after `limit` of board time.
template <typename P>
bool poll_reports(Rig& rig, std::vector<std::string>& states, P pred,
                  milliseconds limit = milliseconds(3000)) {
  const auto end = rig.link().now() + limit;
  while (rig.link().now() < end) {
    const Report r = rig.status();
    states.push_back(r.state);
    if (pred(r)) return true;
  }
  return false;
}

// '!' mid-job: Hold:1 while the board decelerates, then Hold:0 with the machine at rest (no STEP
// edge for a while of polling); '~' runs the rest and the job ends where the plan ends, on
// the board's own step counters.
TEST(Grbl, FeedHoldMidJobThenResumeEndsOnThePlan) {
  // The rate ramps from 100 % to rest in 40 ms (X: 5000 mm/s^2 at its 200 mm/s top feed), not the
  // default 200 ms: the same hold and resume in a fifth of the board time.
  MachineConfig cfg;
  cfg.hold_decel_mm_s2 = 5000.0;
  Rig rig("", cfg, true);
  ASSERT_TRUE(rig.engine().motion_available()) << "the Verilated board refuses MOTION";
  for (const char* l : {"G21 G90 F2400", "G1 X3 Y1", "G1 X6 Y0", "G1 X8 Y2"})
    EXPECT_EQ(rig.command(l).back(), "ok") << l;
  std::vector<std::string> states;
  ASSERT_TRUE(poll_reports(rig, states, [](const Report& r) { return r.mpos[0] > 1.0; }));
  EXPECT_EQ(states.back(), "Run");
  rig.send("!");
  states.clear();
  Report held;
  ASSERT_TRUE(poll_reports(rig, states, [&](const Report& r) {
    held = r;
    return r.state == "Hold:0";
  })) << "no Hold:0";
  EXPECT_NE(std::find(states.begin(), states.end(), "Hold:1"), states.end())
      << "no Hold:1 while decelerating (states polled: " << states.size() << ")";
  EXPECT_LT(held.mpos[0], 8.0) << "the hold came after the end of the job";
  // At rest: the board's step counters stay put while held, and the report says so.
  const auto at_rest = board_xyz(rig);
  std::vector<std::string> still;
  EXPECT_FALSE(poll_reports(
      rig, still, [](const Report& r) { return r.state != "Hold:0"; }, milliseconds(50)));
  EXPECT_EQ(board_xyz(rig), at_rest) << "STEP edges during Hold:0";
  for (size_t a = 0; a < 3; ++a) {
    EXPECT_NEAR(held.mpos[a], static_cast<double>(at_rest[a]) / cfg.steps_per_mm[a], 0.0005);
  }
  EXPECT_EQ(rig.engine().stats().holds, 1u);
  rig.send("~");
  const Report end = rig.wait_idle();
  const std::array<int64_t, 3> plan{8 * 160, 2 * 160, 0};
  expect_at(end, plan, cfg);
  EXPECT_EQ(board_xyz(rig), plan);
  EXPECT_EQ(rig.engine().stats().resumes, 1u);
}

// The rate settles at once in the override tests: a hold deceleration of 1e6 mm/s^2 makes the
// ramp 2^32 * 256 * 5000 / 5e7 per period, 100 % to 25 % in 30 periods (7 680 clocks), so the
// clocks measured are the rates', not the ramp's. The G1 moves run with M3 (laser on: code 1,
// the feed rate); G0 and moves with the laser off are code 0, the rapid rate (docs/timing.md).
MachineConfig override_cfg() {
  MachineConfig c;
  c.hold_decel_mm_s2 = 1e6;
  return c;
}

// Rapid override 25 %: a G0 takes four times the board clocks (the board's rapid rate); a G1
// (laser on) after it runs at 100 % (the feed rate is separate). Ov shows 100,25,100. On the twin
// board (its feed rate is checked clock for clock against the RTL's in cosim): the X STEP rises
// of the G0 (1.5 mm, the first 240) and of the G1 (the next 240), first to last.
TEST(Grbl, RapidOverrideScalesRapidsOnly) {
  const MachineConfig cfg = override_cfg();
  const size_t g0_steps = static_cast<size_t>(std::lround(1.5 * cfg.steps_per_mm[0]));
  auto run = [&](bool slow) -> std::pair<double, double> {
    Rig rig("", cfg);
    EXPECT_TRUE(rig.engine().motion_available());
    if (slow) {
      rig.send("\x97");
      rig.status();
      EXPECT_NE(rig.reports().back().find("|Ov:100,25,100"), std::string::npos)
          << rig.reports().back();
    }
    EXPECT_EQ(rig.command("G21 G90 M3 S1000").back(), "ok");
    EXPECT_EQ(rig.command("G0 X1.5").back(), "ok");
    EXPECT_EQ(rig.command("G4 P0.01").back(), "ok");  // the G0 ends at rest
    EXPECT_EQ(rig.command("G1 X3 F1200").back(), "ok");
    expect_at(rig.wait_idle(), {480, 0, 0}, cfg);
    std::vector<uint64_t> x;  // X STEP rises
    for (const auto& e : fpgacnc::simboard::any_board_of(rig.link())->edges())
      if (e.signal == fpgacnc::models::step_signal(0) && e.value) x.push_back(e.cycle);
    EXPECT_EQ(x.size(), 2 * g0_steps);
    if (x.size() != 2 * g0_steps) return {0.0, 0.0};
    return {static_cast<double>(x[g0_steps - 1] - x[0]),
            static_cast<double>(x.back() - x[g0_steps])};
  };
  const auto [g0_100, g1_100] = run(false);
  const auto [g0_25, g1_25] = run(true);
  ASSERT_GT(g0_100, 0.0);
  ASSERT_GT(g1_100, 0.0);
  fmt::print(
      "G0 X1.5: {:.0f} clocks at 100 %, {:.0f} at 25 % ({:.4f}x); the G1 after it {:.0f} and "
      "{:.0f} ({:.4f}x)\n",
      g0_100, g0_25, g0_25 / g0_100, g1_100, g1_25, g1_25 / g1_100);
  EXPECT_NEAR(g0_25 / g0_100, 4.0, 0.05) << g0_25 << " vs " << g0_100 << " clocks";
  EXPECT_NEAR(g1_25 / g1_100, 1.0, 0.01) << g1_25 << " vs " << g1_100 << " clocks";
}

std::array<int64_t, 3> board_xyz_of(Rig& rig) {
  const auto n = fpgacnc::simboard::any_board_of(rig.link())->net_steps();
  return {n[0], n[1], n[2]};
}

// ---- Feed hold and feed override on the twin board (the default model of `fpgacnc grbl`).
// Board clocks from the board's first edge to its last (Board::edges; the twin board releases
// edges up to its clock).
double twin_clocks_of_job(Rig& rig) {
  const auto e = fpgacnc::simboard::any_board_of(rig.link())->edges();
  EXPECT_FALSE(e.empty());
  return e.empty() ? 0.0 : static_cast<double>(e.back().cycle - e.front().cycle);
}

// '!' while the G1 runs, Hold:0, '~' some board time later: the move ends where the plan ends and
// took longer than without the hold by at least the board clocks it was seen at rest and at most
// those from '!' to '~' and the RESUME's way (the ramps of this machine are short: under 1 % of
// the move); at a 50 % feed override the move takes twice the clocks.
TEST(Grbl, TwinBoardFeedHoldResumeAndOverride) {
  const MachineConfig cfg = override_cfg();
  const std::array<int64_t, 3> plan{320, 0, 0};
  auto cycle = [](Rig& rig) {
    return static_cast<double>(fpgacnc::simboard::any_board_of(rig.link())->cycle());
  };
  auto start = [&](Rig& rig, const std::string& ov) {
    EXPECT_TRUE(rig.engine().motion_available()) << "the twin board refuses MOTION";
    if (!ov.empty()) {
      rig.send(ov);
      rig.status();
    }
    EXPECT_EQ(rig.command("G21 G90 M3 S1000").back(), "ok");
    EXPECT_EQ(rig.command("G1 X2 F1200").back(), "ok");
  };
  // held: clocks from the first Hold:0 report to '~'; between: from '!' to '~'
  double plain = 0.0, half = 0.0, held_job = 0.0, held = 0.0, between = 0.0;
  {
    Rig rig("", cfg);
    start(rig, "");
    expect_at(rig.wait_idle(), plan, cfg);
    EXPECT_EQ(board_xyz_of(rig), plan);
    plain = twin_clocks_of_job(rig);
  }
  {
    Rig rig("", cfg);
    start(rig, "\x92\x92\x92\x92\x92");
    EXPECT_NE(rig.reports().back().find("|Ov:50,100,100"), std::string::npos)
        << rig.reports().back();
    expect_at(rig.wait_idle(), plan, cfg);
    EXPECT_EQ(board_xyz_of(rig), plan);
    half = twin_clocks_of_job(rig);
  }
  {
    Rig rig("", cfg);
    start(rig, "");
    std::vector<std::string> states;
    ASSERT_TRUE(poll_reports(rig, states, [](const Report& r) { return r.mpos[0] > 0.5; }));
    const double h_send = cycle(rig);
    rig.send("!");
    Report at_rest;
    ASSERT_TRUE(poll_reports(rig, states, [&](const Report& r) {
      at_rest = r;
      return r.state == "Hold:0";
    })) << "no Hold:0";
    EXPECT_LT(at_rest.mpos[0], 2.0) << "the hold came after the end of the move";
    const double h0 = cycle(rig);
    const auto still = board_xyz_of(rig);
    rig.link().wait_until(rig.link().now() + milliseconds(200));  // held for 200 ms
    std::vector<std::string> more;
    EXPECT_FALSE(poll_reports(
        rig, more, [](const Report& r) { return r.state != "Hold:0"; }, milliseconds(20)));
    EXPECT_EQ(board_xyz_of(rig), still) << "STEP edges during Hold:0";
    held = cycle(rig) - h0;
    between = cycle(rig) - h_send;
    rig.send("~");
    expect_at(rig.wait_idle(), plan, cfg);
    EXPECT_EQ(board_xyz_of(rig), plan);
    held_job = twin_clocks_of_job(rig);
    EXPECT_EQ(rig.engine().stats().holds, 1u);
    EXPECT_EQ(rig.engine().stats().resumes, 1u);
  }
  ASSERT_GT(plain, 0.0);
  fmt::print(
      "twin board, G1 X2 F1200: {:.0f} clocks at 100 %, {:.0f} at 50 % ({:.4f}x); with a hold "
      "of {:.0f} clocks at rest ({:.0f} from '!' to '~') {:.0f} ({:.0f} more)\n",
      plain, half, half / plain, held, between, held_job, held_job - plain);
  EXPECT_NEAR(half / plain, 2.0, 0.02) << half << " vs " << plain << " clocks";
  EXPECT_GT(held, 0.2 * cfg.clk_hz);
  EXPECT_GE(held_job - plain, held);
  // at most the clocks from '!' to '~' and the RESUME frame's 15 bytes on the line (65 100
  // clocks) and its ramp
  EXPECT_LE(held_job - plain, between + 0.02 * plain);
}

// 0x18 during a hold on the twin board: MOTION CANCEL drops the queue at rest (the twins model
// the flush), so the alarm comes with the held position, and a new move ends on the plan.
TEST(Grbl, TwinBoardSoftResetDuringAHoldKeepsThePosition) {
  const MachineConfig cfg;
  Rig rig("", cfg);
  ASSERT_TRUE(rig.engine().motion_available()) << "the twin board refuses MOTION";
  EXPECT_EQ(rig.command("G21 G90 G1 X6 F2400").back(), "ok");
  std::vector<std::string> states;
  ASSERT_TRUE(poll_reports(rig, states, [](const Report& r) { return r.mpos[0] > 1.0; }));
  rig.send("!");
  ASSERT_TRUE(poll_reports(rig, states, [](const Report& r) { return r.state == "Hold:0"; }));
  const auto held = board_xyz_of(rig);
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:3");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  const Report a = rig.status();
  EXPECT_EQ(a.state, "Alarm");
  EXPECT_EQ(board_xyz_of(rig), held) << "the board moved after the reset";
  EXPECT_NEAR(a.mpos[0], static_cast<double>(held[0]) / cfg.steps_per_mm[0], 0.0005);
  EXPECT_LT(a.mpos[0], 6.0);
  EXPECT_EQ(rig.command("$X").back(), "ok");
  EXPECT_EQ(rig.command("G0 X1").back(), "ok");
  expect_at(rig.wait_idle(), {160, 0, 0}, cfg);
  EXPECT_EQ(board_xyz_of(rig), (std::array<int64_t, 3>{160, 0, 0}));
}

// $J= and the jog cancel on the twin board (the default model; cosim checks its MOTION CANCEL
// against the RTL's): Jog while it runs; 0x85 mid-jog decelerates it with the board's hold ramp
// and drops the queued jogs; Idle at rest with the
// report at the board's own step counters, short of the jogs' end; the next jog starts there
// and ends exactly one jog length on.
TEST(Grbl, JogAndJogCancelOnTheTwinBoard) {
  const MachineConfig cfg;
  Rig rig("", cfg);
  ASSERT_TRUE(rig.engine().motion_available());
  for (int i = 0; i < 4; ++i) EXPECT_EQ(rig.command("$J=G91 X1 F1200").back(), "ok");
  std::vector<std::string> states;
  ASSERT_TRUE(poll_reports(rig, states, [](const Report& r) { return r.mpos[0] > 0.2; }));
  EXPECT_EQ(states.back(), "Jog");
  rig.send("\x85");
  states.clear();
  Report idle;
  ASSERT_TRUE(poll_reports(rig, states, [&](const Report& r) {
    idle = r;
    return r.state == "Idle";
  })) << "no Idle after the jog cancel";
  const auto at = board_xyz_of(rig);
  EXPECT_GT(at[0], 32);
  EXPECT_LT(at[0], 4 * 160) << "the jog cancel did not stop the jogs";
  EXPECT_NEAR(idle.mpos[0], static_cast<double>(at[0]) / cfg.steps_per_mm[0], 0.0005);
  EXPECT_EQ(rig.command("$J=G91 X-0.1 F600").back(), "ok");
  expect_at(rig.wait_idle(), {at[0] - 16, 0, 0}, cfg);
  EXPECT_EQ(board_xyz_of(rig), (std::array<int64_t, 3>{at[0] - 16, 0, 0}));
  EXPECT_EQ(rig.command("G91 G1 Y0.1 F1200").back(), "ok") << "G-code after the jogs";
  expect_at(rig.wait_idle(), {at[0] - 16, 16, 0}, cfg);
}

namespace {

// ---- Homing on the Verilated board (docs/grbl.md "Homing", docs/machine.md "Homing and probing
// (host)"). Short travels and fast feeds keep each run to a fraction of a second of board time.

MachineConfig homing_config() {
  MachineConfig cfg;
  // A quick machine: the cycle's short moves are not spent accelerating.
  cfg.max_accel_mm_s2 = {10000.0, 10000.0, 10000.0, 1000.0};
  cfg.max_feed_mm_min[2] = 3000.0;
  cfg.homing.enabled = true;  // grbl's $22=1: the engine starts in alarm until $H
  cfg.homing.seek_feed_mm_min = 3000.0;
  cfg.homing.locate_feed_mm_min = 300.0;
  cfg.homing.pulloff_mm = 0.1;
  cfg.homing.max_travel_mm = {1.0, 1.0, 1.0};  // seek 1.5 mm at most
  return cfg;
}

// Status reports back to back until Idle (a few ms of board time each).
Report idle_soon(Rig& rig) {
  Report r;
  EXPECT_TRUE(rig.pump_until([&] {
    r = rig.status();
    return r.state == "Idle";
  })) << r.state;
  return r;
}

struct Homed {
  char axis = 0;
  int32_t step = 0;  // latched, machine steps after homing
};

// "[MSG:Homed X max: switch latched at 1.234 (step 197), set to -0.250]"
std::vector<Homed> homed_messages(const std::vector<std::string>& lines) {
  static const std::regex re(
      R"(^\[MSG:Homed ([XYZ]) max: switch latched at -?[\d.]+ \(step (-?\d+)\), set to -?[\d.]+\]$)");
  std::vector<Homed> out;
  for (const auto& l : lines) {
    std::smatch m;
    if (std::regex_match(l, m, re)) out.push_back({m[1].str()[0], std::stoi(m[2])});
  }
  return out;
}

// The filter (1 ms of board clocks) lets at most this many steps through after the pin, at the
// locate feed: the latched position is the endstop's step plus 0 .. this.
int64_t filter_steps(const MachineConfig& cfg, size_t a) {
  const double rate = cfg.homing.locate_feed_mm_min / 60.0 * cfg.steps_per_mm[a];
  return static_cast<int64_t>(std::ceil(rate * 50'002.0 / 50e6));
}

// One $H with reports asked at 10 Hz: the homed messages, the board step count of each latched
// position (machine steps minus the offset SET_POSITION gave, taken from where the board stands
// now), and checks: Home while it ran, ok, Idle at MPos = -pull-off on the homed axes.
std::map<char, int64_t> home_once(Rig& rig, const MachineConfig& cfg, size_t n_homed) {
  rig.polling = true;
  rig.send("$H\n");
  std::vector<std::string> ans;
  for (;;) {
    ans.push_back(rig.next_line());
    if (ans.back().empty() || ans.back() == "ok" || ans.back().rfind("ALARM", 0) == 0) break;
  }
  rig.polling = false;
  std::map<char, int64_t> out;
  EXPECT_EQ(ans.back(), "ok");
  bool saw_home = false;
  for (const auto& r : rig.reports()) saw_home |= r.rfind("<Home|", 0) == 0;
  EXPECT_TRUE(saw_home) << "status reports during $H say Home";
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Idle");
  const auto homed = homed_messages(ans);
  EXPECT_EQ(homed.size(), n_homed);
  const auto net = rig.board().net_steps();
  for (const auto& h : homed) {
    const size_t a = static_cast<size_t>(h.axis - 'X');
    EXPECT_NEAR(r.mpos[a], -cfg.homing.pulloff_mm, 1e-9) << h.axis;
    const int64_t offset = std::llround(r.mpos[a] * cfg.steps_per_mm[a]) - net[a];
    out[h.axis] = h.step - offset;
  }
  if (!homed.empty()) {
    EXPECT_EQ(homed[0].axis, n_homed == 3 ? 'Z' : 'X') << "Z first (grbl)";
  }
  return out;
}

// $H with X, Y and Z switches (all toward max, $23=0): starts in alarm ($22=1), Home while it
// runs, ok at the end, Idle at MPos = -pull-off on every axis (grbl 1.1 without
// HOMING_FORCE_SET_ORIGIN), each latched position the board's step count at its switch's edge
// (the endstop's step plus what the filter lets through); G-code then moves from machine zero.
TEST(Grbl, HomingOnTheVerilatedBoard) {
  const MachineConfig cfg = homing_config();
  const std::array<int64_t, 3> edge{80, 64, 100};  // x-max 0.5 mm, y-max 0.4 mm, z-max 0.25 mm
  Rig rig("", cfg, true, {{0, true, edge[0]}, {1, true, edge[1]}, {2, true, edge[2]}});
  EXPECT_EQ(rig.status().state, "Alarm") << "$22=1: alarm until $H";
  EXPECT_EQ(rig.command("G0 X1").back(), "error:9");
  const auto steps = home_once(rig, cfg, 3);
  ASSERT_EQ(steps.size(), 3u);
  for (const auto& [axis, st] : steps) {
    const size_t a = static_cast<size_t>(axis - 'X');
    EXPECT_GE(st, edge[a]) << axis;
    EXPECT_LE(st, edge[a] + filter_steps(cfg, a)) << axis;
  }
  EXPECT_EQ(rig.command("G0 X-0.3 Z-0.2").back(), "ok");
  const Report m = idle_soon(rig);
  EXPECT_NEAR(m.mpos[0], -0.3, 1e-9);
  EXPECT_NEAR(m.mpos[1], -0.1, 1e-9);
  EXPECT_NEAR(m.mpos[2], -0.2, 1e-9);
  expect_at(m, {-48, -16, -80}, cfg);
}

// Three $H of X and Y from different places, on switches that bounce (2 to 6 more toggles within
// 10 000 clocks of each change) and trip within +-2 steps of their place: the latched board
// steps stay within the jitter and what the bounce and the filter allow at the locate feed
// (printed: the spread in steps).
TEST(Grbl, HomingRepeatability) {
  MachineConfig cfg = homing_config();
  cfg.homing.cycles = {0b011};  // X and Y together
  const std::array<int64_t, 2> edge{80, 64};
  fpgacnc::simboard::SwitchNoise noise;
  noise.bounce_clks = 10'000;
  noise.jitter_steps = 2;
  noise.seed = 7;
  // The filtered rise comes at most bounce + filter clocks after the pin's first rise.
  auto late = [&](size_t a) {
    const double rate = cfg.homing.locate_feed_mm_min / 60.0 * cfg.steps_per_mm[a];
    return static_cast<int64_t>(
        std::ceil(rate * static_cast<double>(noise.bounce_clks + 50'002) / 50e6));
  };
  Rig rig("", cfg, true, {{0, true, edge[0]}, {1, true, edge[1]}}, std::nullopt, noise);
  std::array<int64_t, 2> lo{INT64_MAX, INT64_MAX}, hi{INT64_MIN, INT64_MIN};
  const char* away[] = {"G0 X-0.3 Y-0.2", "G0 X-0.15 Y-0.35"};
  // A setting right before $H: its frames (CONFIG_AXIS, MOTION) go out before the cycle's.
  EXPECT_EQ(rig.command("$24=300").back(), "ok");
  for (int run = 0; run < 3; ++run) {
    const auto steps = home_once(rig, cfg, 2);
    ASSERT_EQ(steps.size(), 2u) << "run " << run;
    for (size_t a = 0; a < 2; ++a) {
      const int64_t st = steps.at("XY"[a]);
      EXPECT_GE(st, edge[a] - noise.jitter_steps) << "run " << run;
      EXPECT_LE(st, edge[a] + noise.jitter_steps + late(a)) << "run " << run;
      lo[a] = std::min(lo[a], st);
      hi[a] = std::max(hi[a], st);
    }
    if (run < 2) {
      EXPECT_EQ(rig.command(away[run]).back(), "ok");
      idle_soon(rig);
    }
  }
  // The switches did bounce: more pin changes than the 24 presses and releases of 2 switches in 3
  // cycles of a seek and a locate.
  size_t changes = 0;
  for (const auto& e : rig.board().limit_events()) changes += e.endstop ? 1 : 0;
  EXPECT_GT(changes, 24u);
  for (size_t a = 0; a < 2; ++a) {
    std::printf(
        "homing repeatability %c (bounce %llu clocks, jitter +-%lld steps, %zu pin changes): "
        "latched board steps %lld..%lld (spread %lld steps)\n",
        "XY"[a], static_cast<unsigned long long>(noise.bounce_clks),
        static_cast<long long>(noise.jitter_steps), changes, static_cast<long long>(lo[a]),
        static_cast<long long>(hi[a]), static_cast<long long>(hi[a] - lo[a]));
    EXPECT_LE(hi[a] - lo[a], 2 * noise.jitter_steps + late(a));
  }
}

// A switch already pressed when $H starts (x-max at step 0: pressed from reset): the cycle
// pulls off it first, then homes as usual.
TEST(Grbl, HomingStartsOnAPressedSwitch) {
  MachineConfig cfg = homing_config();
  cfg.homing.cycles = {0b001};  // X only
  Rig rig("", cfg, true, {{0, true, 0}});
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  const Report before = rig.status();
  EXPECT_EQ(before.state, "Alarm");
  EXPECT_NE(rig.reports().back().find("|Pn:X"), std::string::npos) << rig.reports().back();
  const auto ans = rig.command("$H");
  ASSERT_EQ(ans.back(), "ok");
  const auto homed = homed_messages(ans);
  ASSERT_EQ(homed.size(), 1u);
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Idle");
  EXPECT_NEAR(r.mpos[0], -0.1, 1e-9);
  EXPECT_EQ(rig.reports().back().find("|Pn:"), std::string::npos) << rig.reports().back();
  const int64_t offset = std::llround(r.mpos[0] * 160.0) - rig.board().net_steps()[0];
  EXPECT_GE(homed[0].step - offset, 0);
  EXPECT_LE(homed[0].step - offset, 1);
}

// Z has a switch wired but no endstop on the simulated board: the seek ends without it,
// ALARM:9 naming Z max, the line's ok, a reset into the alarm; the trigger is disarmed.
TEST(Grbl, HomingMissingSwitchIsAlarm9) {
  const MachineConfig cfg = homing_config();
  Rig rig("", cfg, true, {{0, true, 80}, {1, true, 64}});
  const auto ans = rig.command("$H");
  ASSERT_GE(ans.size(), 3u);
  EXPECT_EQ(ans[0], "ALARM:9");
  EXPECT_NE(ans[1].find("Z max not found"), std::string::npos) << ans[1];
  EXPECT_EQ(ans.back(), "ok");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Alarm");
  EXPECT_NEAR(r.mpos[2], 1.5, 1e-9) << "the whole seek of 1.5 x 1 mm ran";
  EXPECT_EQ(rig.command("$X").back(), "ok");
  EXPECT_EQ(rig.command("G0 Z1").back(), "ok");
  expect_at(idle_soon(rig), {0, 0, 400}, cfg);
}

// A soft reset while $H runs: ALARM:6 (grbl), the board stopped by its e-stop, the banner
// into the alarm; the next session disarms the trigger, so after $X a move into the X switch's
// side trips the hard limit again (an armed HOME would suppress it) and a new $H homes.
TEST(Grbl, HomingSoftResetIsAlarm6) {
  MachineConfig cfg = homing_config();
  cfg.homing.cycles = {0b001};
  Rig rig("", cfg, true, {{0, true, 80}});
  rig.send("$H\n");
  ASSERT_TRUE(rig.pump_until([&] { return rig.status().state == "Home"; }));
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:6");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  EXPECT_EQ(rig.status().state, "Alarm");
  EXPECT_EQ(rig.command("$X").back(), "ok");
  const Report at = rig.status();
  EXPECT_EQ(rig.command("G91 G1 X1 F3000").back(), "ok");
  ASSERT_TRUE(rig.pump_until([&] { return !rig.lines().empty(); }, milliseconds(2000)))
      << "X from " << at.mpos[0] << " mm: no alarm; board X " << rig.board().net_steps()[0];
  EXPECT_EQ(rig.next_line(), "ALARM:1") << "the X max switch trips: the trigger is disarmed";
  EXPECT_EQ(rig.next_line(), "[MSG:Reset to continue]");
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:Check Limits]");
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  EXPECT_EQ(rig.board().pull_off_endstops(), 1);
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  EXPECT_EQ(rig.command("$X").back(), "ok");
  // (The pull-off by hand moved the carriage against the step count: the switch's step is no
  // longer 80, so only the cycle's end is checked.)
  EXPECT_EQ(home_once(rig, cfg, 1).size(), 1u);
}

// $22=0 (the default): $H is error:5 as in grbl; $22=1 is refused on a board without switches.
TEST(Grbl, HomingDisabledIsError5) {
  Rig rtl("", MachineConfig{}, true);
  EXPECT_EQ(rtl.command("$H").back(), "error:5");
  EXPECT_EQ(rtl.command("$22=1").back(), "ok") << "the Verilated board has switches";
  EXPECT_EQ(rtl.command("$22=0").back(), "ok");
  EXPECT_EQ(rtl.command("$H").back(), "error:5");
  Rig twin;
  EXPECT_EQ(twin.command("$22=1").back(), "error:3") << "the twin board has no switches";
}

}  // namespace

namespace {

// ---- Probing on the Verilated board (docs/grbl.md "Probing", docs/machine.md "Homing and
// probing (host)"): a probe plate under Z (the probe pin high while the Z step count at the pins
// is at or below the plate). The machine: fast accelerations, 3000 mm/min on X, Y, Z and E and a
// hold deceleration of 2000 mm/s^2, so that the stop after the contact (the board's CANCEL ramp,
// MOTION's ramp: the rate falls from 100 % to 0 in 1 / 40 s) is short and each probe takes a
// fraction of a second of board time.

MachineConfig probe_config() {
  MachineConfig cfg;
  cfg.max_accel_mm_s2 = {10000.0, 10000.0, 10000.0, 10000.0};
  cfg.max_feed_mm_min = {3000.0, 3000.0, 3000.0, 3000.0};
  cfg.hold_decel_mm_s2 = 2000.0;
  return cfg;
}

constexpr double kProbeFeed = 600.0;  // mm/min: Z 10 mm/s, 4000 steps/s

// "[PRB:0.000,0.000,-0.500:1]" -> the position (mm) and the flag.
struct Prb {
  std::array<double, 3> mm{};
  int ok = -1;
};
std::optional<Prb> parse_prb(const std::string& line) {
  static const std::regex re(R"(^\[PRB:(-?[\d.]+),(-?[\d.]+),(-?[\d.]+):([01])\]$)");
  std::smatch m;
  if (!std::regex_match(line, m, re)) return std::nullopt;
  Prb p;
  for (int i = 0; i < 3; ++i) p.mm[static_cast<size_t>(i)] = std::stod(m[i + 1]);
  p.ok = std::stoi(m[4]);
  return p;
}
std::optional<Prb> find_prb(const std::vector<std::string>& lines) {
  for (const auto& l : lines)
    if (auto p = parse_prb(l)) return p;
  return std::nullopt;
}

// Steps of Z a probe latch may lie beyond the plate: the pin changes on the STEP that reaches the
// plate, the filter passes it PROBE_FILTER_CLKS + 1 clocks later (+1 for the sampling edge), and
// the latch counts every STEP up to that clock: at v steps/s, ceil(v (F + 2) / clk) steps.
int64_t latch_bound(const MachineConfig& cfg) {
  const double v = kProbeFeed / 60.0 * cfg.steps_per_mm[2];
  return static_cast<int64_t>(
      std::ceil(v * static_cast<double>(fpgacnc::simboard::SimBoard::kProbeFilterClks + 2) /
                static_cast<double>(cfg.clk_hz)));
}

// The stop after the latch (steps of Z): the rate falls by ramp / 2^32 per 256 clocks from the
// end of the period after the edge, so from v it stops in T = 2^32 * 256 / (ramp * clk) over
// v T / 2, plus up to two periods at full speed (the period in progress and its quantization).
std::pair<double, double> stop_bounds(const MachineConfig& cfg) {
  const double v = kProbeFeed / 60.0 * cfg.steps_per_mm[2];
  const double clk = static_cast<double>(cfg.clk_hz);
  const double ramp = fpgacnc::link::machine_hold_ramp(cfg, 4);
  const double t = std::ldexp(1.0, 32) * 256.0 / (ramp * clk);
  return {v * t / 2.0 - 1.0, v * (t / 2.0 + 2.0 * 256.0 / clk) + 1.0};
}

// G38.2 Z- onto a plate at Z -0.5 mm (step -200): Run while it probes, [PRB:] with Z at the plate
// (within the latch bound), ok; the machine stops past the plate by the stopping distance and
// the report shows the board's position (its STATUS, not the target); $# keeps the PRB; the
// parser continues from there (G0 Z0 returns to step 0 exactly). The figures are printed.
TEST(Grbl, ProbeFindsThePlate) {
  const MachineConfig cfg = probe_config();
  const int64_t plate = -200;
  Rig rig("", cfg, true, {}, fpgacnc::simboard::ProbePlate{2, true, plate});
  rig.polling = true;
  const auto ans = rig.command("G38.2 Z-1 F600");
  rig.polling = false;
  ASSERT_EQ(ans.back(), "ok");
  ASSERT_EQ(ans.size(), 2u) << ans[0];
  const auto prb = parse_prb(ans[0]);
  ASSERT_TRUE(prb.has_value()) << ans[0];
  EXPECT_EQ(prb->ok, 1);
  bool saw_run = false;
  for (const auto& r : rig.reports()) saw_run |= r.rfind("<Run|", 0) == 0;
  EXPECT_TRUE(saw_run) << "status reports while probing say Run";
  const int64_t latched = std::llround(prb->mm[2] * cfg.steps_per_mm[2]);
  EXPECT_LE(plate - latched, latch_bound(cfg)) << "latched Z " << latched;
  EXPECT_GE(plate - latched, 0) << "latched Z " << latched;
  EXPECT_EQ(prb->mm[0], 0.0);
  EXPECT_EQ(prb->mm[1], 0.0);
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Idle");
  const int64_t board_z = rig.board().net_steps()[2];
  EXPECT_NEAR(r.mpos[2], static_cast<double>(board_z) / cfg.steps_per_mm[2], 0.0005 + 1e-9)
      << "the report shows the board's position (3 decimals)";
  const double past = static_cast<double>(latched - board_z);
  const auto [lo, hi] = stop_bounds(cfg);
  EXPECT_GE(past, lo);
  EXPECT_LE(past, hi);
  std::printf(
      "probe G38.2 Z- at %.0f mm/min: plate at step %lld, latched %lld (bound %lld), stopped at "
      "%lld: %.0f steps (%.4f mm) past the latch (bounds %.1f .. %.1f)\n",
      kProbeFeed, static_cast<long long>(plate), static_cast<long long>(latched),
      static_cast<long long>(latch_bound(cfg)), static_cast<long long>(board_z), past,
      past / cfg.steps_per_mm[2], lo, hi);
  const auto st = rig.board().stats();
  std::printf("board: %llu clocks at %.2f M clocks/s\n", static_cast<unsigned long long>(st.cycles),
              st.clocks_per_s / 1e6);
  const auto events = rig.board().probe_events();
  ASSERT_GE(events.size(), 1u);
  EXPECT_TRUE(events[0].contact);
  EXPECT_TRUE(events[0].plate);
  const auto hash = rig.command("$#");
  const auto kept = find_prb(hash);
  ASSERT_TRUE(kept.has_value());
  EXPECT_EQ(kept->mm, prb->mm);
  EXPECT_EQ(kept->ok, 1);
  EXPECT_EQ(rig.command("G0 Z0").back(), "ok");
  expect_at(idle_soon(rig), {0, 0, 0}, cfg);
  EXPECT_EQ(rig.board().net_steps()[2], 0) << "the parser went on from the board's position";
}

// G38.2 that ends before the plate: ALARM:5, [PRB:...:0] at the move's end, ok, Alarm; the
// trigger is disarmed after it: after $X, a G1 through the plate runs to its end.
TEST(Grbl, ProbeMissIsAlarm5) {
  const MachineConfig cfg = probe_config();
  Rig rig("", cfg, true, {}, fpgacnc::simboard::ProbePlate{2, true, -400});
  const auto ans = rig.command("G38.2 Z-0.5 F600");
  ASSERT_GE(ans.size(), 4u);
  EXPECT_EQ(ans[0], "ALARM:5");
  EXPECT_NE(ans[1].find("no contact"), std::string::npos) << ans[1];
  const auto prb = parse_prb(ans[2]);
  ASSERT_TRUE(prb.has_value()) << ans[2];
  EXPECT_EQ(prb->ok, 0);
  EXPECT_EQ(prb->mm[2], -0.5);
  EXPECT_EQ(ans.back(), "ok");
  EXPECT_EQ(rig.status().state, "Alarm");
  EXPECT_EQ(rig.command("G0 Z0").back(), "error:9");
  EXPECT_EQ(rig.command("$X").back(), "ok");
  EXPECT_EQ(rig.command("G1 Z-1.5 F600").back(), "ok");
  // An armed PROBE would end this move 50 steps past the plate (no DONE: never Idle).
  ASSERT_TRUE(
      rig.pump_until([&] { return rig.board().net_steps()[2] == -600; }, milliseconds(2000)))
      << "a trigger left armed: Z at " << rig.board().net_steps()[2];
  expect_at(idle_soon(rig), {0, 0, -600}, cfg);
}

// G38.3 that ends before the plate: [PRB:...:0], ok, no alarm (grbl's G38.3).
TEST(Grbl, ProbeMissWithG38_3IsNoAlarm) {
  const MachineConfig cfg = probe_config();
  Rig rig("", cfg, true, {}, fpgacnc::simboard::ProbePlate{2, true, -400});
  const auto ans = rig.command("G38.3 Z-0.5 F600");
  ASSERT_EQ(ans.size(), 2u) << ans[0];
  const auto prb = parse_prb(ans[0]);
  ASSERT_TRUE(prb.has_value()) << ans[0];
  EXPECT_EQ(prb->ok, 0);
  EXPECT_EQ(ans[1], "ok");
  const Report r = idle_soon(rig);
  EXPECT_NEAR(r.mpos[2], -0.5, 1e-9);
  EXPECT_EQ(rig.command("$G").front().find("G38.3"), 4u) << "the probe mode stays modal";
}

// The probe touches while Z is at or below step 0 (touching from reset); the tool goes down to
// Z -0.5 mm in contact: G38.2 there is ALARM:4 and nothing moves; after $X, G38.4 lifting off
// latches the release (the first step above the plate, at the probing speed) and G38.4 again,
// clear of the plate, is ALARM:4.
TEST(Grbl, ProbeTouchingIsAlarm4AndG38_4LatchesTheRelease) {
  const MachineConfig cfg = probe_config();
  Rig rig("", cfg, true, {}, fpgacnc::simboard::ProbePlate{2, true, 0});
  EXPECT_EQ(rig.command("G0 Z-0.5").back(), "ok");
  idle_soon(rig);
  const auto a4 = rig.command("G38.2 Z-1 F600");
  ASSERT_GE(a4.size(), 2u);
  EXPECT_EQ(a4[0], "ALARM:4");
  EXPECT_NE(a4[1].find("already touching"), std::string::npos) << a4[1];
  EXPECT_EQ(a4.back(), "ok");
  EXPECT_EQ(rig.board().net_steps()[2], -200) << "nothing moved";
  EXPECT_EQ(rig.status().state, "Alarm");
  EXPECT_EQ(rig.command("$X").back(), "ok");
  const auto ans = rig.command("G38.4 Z0.5 F600");
  ASSERT_EQ(ans.size(), 2u) << ans[0];
  const auto prb = parse_prb(ans[0]);
  ASSERT_TRUE(prb.has_value()) << ans[0];
  EXPECT_EQ(prb->ok, 1);
  const int64_t latched = std::llround(prb->mm[2] * cfg.steps_per_mm[2]);
  EXPECT_GE(latched, 1) << "released on the first step above the plate";
  EXPECT_LE(latched, 1 + latch_bound(cfg));
  const Report r = idle_soon(rig);
  const int64_t board_z = rig.board().net_steps()[2];
  EXPECT_NEAR(r.mpos[2], static_cast<double>(board_z) / cfg.steps_per_mm[2], 0.0005 + 1e-9);
  const auto [lo, hi] = stop_bounds(cfg);
  EXPECT_GE(static_cast<double>(board_z - latched), lo);
  EXPECT_LE(static_cast<double>(board_z - latched), hi);
  std::printf("probe G38.4 Z+ at %.0f mm/min: released at step %lld, stopped at %lld\n", kProbeFeed,
              static_cast<long long>(latched), static_cast<long long>(board_z));
  const auto again = rig.command("G38.4 Z1 F600");
  EXPECT_EQ(again[0], "ALARM:4");
  EXPECT_EQ(again.back(), "ok");
  EXPECT_EQ(rig.board().net_steps()[2], board_z) << "nothing moved";
}

// A soft reset while the probe moves: ALARM:3 (grbl), the board stopped by its e-stop, the
// banner into the alarm; the next session disarms the trigger, so after $X a G1 through the
// plate runs to its end.
TEST(Grbl, ProbeSoftResetIsAlarm3AndDisarms) {
  const MachineConfig cfg = probe_config();
  Rig rig("", cfg, true, {}, fpgacnc::simboard::ProbePlate{2, true, -400});
  rig.send("G38.2 Z-2 F600\n");
  ASSERT_TRUE(rig.pump_until([&] { return rig.board().net_steps()[2] < -40; }));
  EXPECT_EQ(rig.status().state, "Run");
  rig.send("\x18");
  EXPECT_EQ(rig.next_line(), "ALARM:3");
  EXPECT_EQ(rig.next_line(), grbl::kBanner);
  EXPECT_EQ(rig.next_line(), "[MSG:'$H'|'$X' to unlock]");
  const int64_t at = rig.board().net_steps()[2];
  EXPECT_GT(at, -400) << "stopped before the plate";
  EXPECT_EQ(rig.command("$X").back(), "ok");
  EXPECT_EQ(rig.command("G1 Z-1.5 F600").back(), "ok");
  // An armed PROBE would end this move 50 steps past the plate (no DONE: never Idle).
  ASSERT_TRUE(
      rig.pump_until([&] { return rig.board().net_steps()[2] == -600; }, milliseconds(2000)))
      << "a trigger left armed: Z at " << rig.board().net_steps()[2];
  expect_at(idle_soon(rig), {0, 0, -600}, cfg);
}

// The twin board models no trigger: G38.2 is error:20 with a message; on any board a probe
// target equal to the position is error:33 and G38.x with E is refused.
TEST(Grbl, ProbeNeedsTheTrigger) {
  Rig twin;
  const auto ans = twin.command("G38.2 Z-1 F100");
  ASSERT_EQ(ans.size(), 2u);
  EXPECT_NE(ans[0].find("probing needs"), std::string::npos) << ans[0];
  EXPECT_EQ(ans[1], "error:20");
  Rig rtl("", probe_config(), true);
  EXPECT_EQ(rtl.command("G38.2 Z0 F100").back(), "error:33");
  EXPECT_EQ(rtl.command("G38.2 Z-1 F100 M2").back(), "error:20");
  EXPECT_EQ(rtl.command("G0 Z0").back(), "ok") << "the parser is where the board is";
  expect_at(idle_soon(rtl), {0, 0, 0}, probe_config());
}

}  // namespace
