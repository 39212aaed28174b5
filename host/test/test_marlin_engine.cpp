// Marlin front end (fpgacnc/marlin/engine.h) with the simulated board behind it, driven in-process
// as a printer host drives it, every wait paced by the board's clock (link time). Expected
// answers come from Marlin's G-code reference (M105, M114, M110, Resend) and positions from the
// machine's steps/mm (160 steps/mm on X and Y by default).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "fpgacnc/marlin/engine.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace marlin = fpgacnc::marlin;
using fpgacnc::config::MachineConfig;
using std::chrono::milliseconds;

extern "C" int sc_main(int, char*[]) {
  return 0;
}

namespace {

std::string numbered(long n, const std::string& cmd) {
  const std::string body = "N" + std::to_string(n) + " " + cmd;
  unsigned x = 0;
  for (unsigned char c : body) x ^= c;
  return body + "*" + std::to_string(x);
}

class Rig {
 public:
  explicit Rig(bool rtl = false, MachineConfig cfg = {})
      : link_(rtl ? fpgacnc::simboard::make_default_link(cfg, {})
                  : fpgacnc::simboard::make_board_link(
                        std::make_unique<fpgacnc::twins::TwinBoard>(
                            fpgacnc::twins::TwinBoard::options_from_config(cfg)),
                        cfg.baud, {})) {
    marlin::EngineOptions o;
    o.v2 = fpgacnc::link::stream_v2_options(cfg);
    if (rtl) {
      o.v2.plant_time = fpgacnc::simboard::plant_clock(*link_);
      o.v2.heater_poll = milliseconds(5);
      auto* bl = dynamic_cast<fpgacnc::simboard::BoardLink*>(link_.get());
      o.estop_press = [bl] { bl->board().set_estop(true); };
    }
    o.limit_switches = fpgacnc::simboard::any_board_of(*link_)->limit_switches();
    engine_ = std::make_unique<marlin::Engine>(*link_, cfg, o);
    engine_->connect();
    pump();
    banner_.assign(lines_.begin(), lines_.end());
    lines_.clear();
  }
  marlin::Engine& engine() { return *engine_; }

  void pump() {
    engine_->step(milliseconds(5));
    if (!engine_->busy()) link_->wait_until(link_->now() + milliseconds(5));
    partial_ += engine_->take_output();
    for (size_t nl; (nl = partial_.find('\n')) != std::string::npos;) {
      std::string l = partial_.substr(0, nl);
      partial_.erase(0, nl + 1);
      if (!l.empty()) lines_.push_back(l), all_.push_back(l);
    }
  }
  std::string next_line(milliseconds limit = milliseconds(600'000)) {
    const auto end = link_->now() + limit;
    while (lines_.empty() && link_->now() < end) pump();
    if (lines_.empty()) return "";
    std::string l = lines_.front();
    lines_.pop_front();
    return l;
  }
  // Sends a line; every answer line up to and including the one starting with "ok".
  std::vector<std::string> command(const std::string& line) {
    engine_->receive(line + "\n");
    std::vector<std::string> out;
    for (;;) {
      out.push_back(next_line());
      if (out.back().empty() || out.back().rfind("ok", 0) == 0) return out;
    }
  }
  const std::vector<std::string>& all() const { return all_; }
  const std::vector<std::string>& banner() const { return banner_; }
  fpgacnc::link::Link& link() { return *link_; }

 private:
  std::unique_ptr<fpgacnc::link::Link> link_;
  std::unique_ptr<marlin::Engine> engine_;
  std::string partial_;
  std::deque<std::string> lines_;
  std::vector<std::string> all_;
  std::vector<std::string> banner_;
};

const std::regex kTemps(
    R"(T:(-?\d+\.\d\d) /(-?\d+\.\d\d) B:(-?\d+\.\d\d) /(-?\d+\.\d\d) @:(\d+) B@:(\d+))");

}  // namespace

// M105: "ok T:<t> /<target> B:<t> /<target> @:<p> B@:<p>" (Marlin's M105 answer).
TEST(MarlinEngine, M105Format) {
  Rig rig;
  const auto ans = rig.command("M105");
  ASSERT_EQ(ans.size(), 1u);
  std::smatch m;
  const std::string body = ans[0].substr(3);
  ASSERT_EQ(ans[0].rfind("ok ", 0), 0u) << ans[0];
  ASSERT_TRUE(std::regex_match(body, m, kTemps)) << ans[0];
  EXPECT_EQ(m[2], "0.00");  // no target set
  EXPECT_EQ(m[4], "0.00");
}

// M114 after a move: the FPGA's step counters, X 10 mm = 1600 steps, Y 5 mm = 800 steps.
TEST(MarlinEngine, M114AfterMove) {
  Rig rig;
  EXPECT_EQ(rig.command("G1 X10 Y5 F3000").back(), "ok");
  EXPECT_EQ(rig.command("M400").back(), "ok");
  const auto ans = rig.command("M114");
  ASSERT_EQ(ans.size(), 2u);
  EXPECT_EQ(ans[0], "X:10.00 Y:5.00 Z:0.00 E:0.00 Count X:1600 Y:800 Z:0");
  EXPECT_EQ(ans[1], "ok");
}

// A host streaming numbered, checksummed lines; two lines corrupted on the way (a character
// changed after the checksum was computed) are refused with Resend and sent again by the host,
// and the machine ends where the uncorrupted program puts it.
TEST(MarlinEngine, ResendsAfterCorruption) {
  Rig rig;
  std::vector<std::string> prog = {"M110 N0",  "G21",      "G90",      "G1 X1 F3000", "G1 X2 Y1",
                                   "G1 X3 Y2", "G1 X4 Y3", "G1 X5 Y4", "M400"};
  std::vector<std::string> wire;
  for (size_t i = 0; i < prog.size(); ++i) wire.push_back(numbered(static_cast<long>(i), prog[i]));
  // Line 0 is M110 N0 itself (numbered 0), then lines 1.. follow.
  size_t next = 0, resends = 0;
  std::set<size_t> corrupt = {4, 6};  // each corrupted once
  while (next < wire.size()) {
    std::string l = wire[next];
    if (corrupt.erase(next) > 0) {
      l[l.find('X') + 1] ^= 0x01;  // X2 -> X3 / X4 -> X5 on the wire
    }
    const auto ans = rig.command(l);
    bool resent = false;
    for (const auto& a : ans) {
      if (a.rfind("Resend: ", 0) == 0) {
        next = std::stoul(a.substr(8));
        resent = true;
        ++resends;
      }
    }
    ASSERT_EQ(ans.back(), "ok");
    if (!resent) ++next;
  }
  EXPECT_EQ(resends, 2u);
  EXPECT_EQ(rig.engine().stats().resends, 2u);
  const auto ans = rig.command("M114");
  EXPECT_EQ(ans.at(0), "X:5.00 Y:4.00 Z:0.00 E:0.00 Count X:800 Y:640 Z:0");
}

// M109 on the Verilated board: the hot end heats on the simulated plant until the session's
// wait ends (in band for wait_settle_s of plant time); the host sees busy: processing and
// temperature lines meanwhile, then ok, and M105 shows the temperature near the target.
TEST(MarlinEngine, TemperatureWaitCompletesOnThePlant) {
  MachineConfig cfg;
  Rig rig(true, cfg);
  const double target = 60.0;
  const auto ans = rig.command("M109 S60");
  ASSERT_FALSE(ans.empty());
  EXPECT_EQ(ans.back(), "ok");
  size_t temp_lines = 0;
  double first_c = 0.0, last_c = 0.0;
  std::string last_target;
  for (const auto& l : ans) {
    std::smatch m;
    if (!std::regex_match(l, m, kTemps)) continue;
    ++temp_lines;
    if (temp_lines == 1) first_c = std::stod(m[1]);
    last_c = std::stod(m[1]);
    last_target = m[2];
  }
  EXPECT_GT(temp_lines, 3u) << "temperature lines during the wait";
  EXPECT_GT(rig.engine().stats().busy, 0u);
  EXPECT_EQ(last_target, "60.00");
  EXPECT_GT(last_c, first_c + 20.0) << "heated during the wait";
  const auto t = rig.command("M105");
  std::smatch m;
  const std::string body = t.at(0).substr(3);
  ASSERT_TRUE(std::regex_match(body, m, kTemps)) << t.at(0);
  EXPECT_NEAR(std::stod(m[1]), target, cfg.heaters.ch[0].wait_tolerance_c + 0.5);
  EXPECT_EQ(m[2], "60.00");
}

// The fan (M106/M107: OUTPUT frames), relative extrusion (M83) on the fourth step channel E
// (100 steps/mm by default) and G92 E (the interpreter's offset: the FPGA's counter is not reset).
TEST(MarlinEngine, FanAndExtruder) {
  Rig rig;
  EXPECT_EQ(rig.command("M106 S128").back(), "ok");
  EXPECT_EQ(rig.command("M83").back(), "ok");
  EXPECT_EQ(rig.command("G1 X1 E2 F600").back(), "ok");
  EXPECT_EQ(rig.command("G92 E0").back(), "ok");
  EXPECT_EQ(rig.command("G1 X2 E1").back(), "ok");
  EXPECT_EQ(rig.command("M107").back(), "ok");
  EXPECT_EQ(rig.command("M400").back(), "ok");
  const auto ans = rig.command("M114");
  EXPECT_EQ(ans.at(0), "X:2.00 Y:0.00 Z:0.00 E:3.00 Count X:320 Y:0 Z:0");
  EXPECT_GE(rig.engine().stats().frames, 4u);  // two moves, two outputs
}

// M155 S1: a temperature line (no ok) every second of link time; S0 stops them.
TEST(MarlinEngine, M155AutoReport) {
  Rig rig;
  EXPECT_EQ(rig.command("M155 S1").back(), "ok");
  std::vector<std::string> got;
  const auto t0 = rig.link().now();
  while (rig.link().now() - t0 < milliseconds(2500)) {
    const std::string l = rig.next_line(milliseconds(100));
    if (!l.empty()) got.push_back(l);
  }
  size_t reports = 0;
  for (const auto& l : got) {
    std::smatch m;
    EXPECT_TRUE(std::regex_match(l, m, kTemps)) << l;
    ++reports;
  }
  EXPECT_GE(reports, 2u);
  EXPECT_LE(reports, 3u);
  EXPECT_EQ(rig.command("M155 S0").back(), "ok");
  const auto t1 = rig.link().now();
  size_t after = 0;
  while (rig.link().now() - t1 < milliseconds(2500))
    if (!rig.next_line(milliseconds(100)).empty()) ++after;
  EXPECT_EQ(after, 0u);
}

// M112 mid-move on the Verilated board: taken at once (ahead of the queued lines), the e-stop
// pressed: the machine stops far short of the move's end and nothing more is answered.
TEST(MarlinEngine, M112StopsTheBoard) {
  MachineConfig cfg;
  Rig rig(true, cfg);
  EXPECT_EQ(rig.command("G1 X50 F3000").back(), "ok");  // 1 s of motion
  auto* bl = dynamic_cast<fpgacnc::simboard::BoardLink*>(&rig.link());
  ASSERT_NE(bl, nullptr);
  const auto t0 = rig.link().now();
  while (bl->board().stats().position[0] < 160 && rig.link().now() - t0 < milliseconds(500))
    rig.pump();
  ASSERT_GE(bl->board().stats().position[0], 160) << "moving";
  rig.engine().receive("G1 X0\nM112\n");  // M112 behind a queued move
  EXPECT_EQ(rig.next_line(), "Error:Printer halted. kill() called!");
  EXPECT_TRUE(rig.engine().killed());
  auto run_for = [&](milliseconds d) {
    const auto t = rig.link().now();
    while (rig.link().now() - t < d) rig.pump();
    return bl->board().stats().position[0];
  };
  const auto x1 = run_for(milliseconds(20));
  const auto x2 = run_for(milliseconds(50));  // over 1 mm more (160 steps) if it still moved
  EXPECT_EQ(x1, x2) << "still moving after M112";
  EXPECT_LT(x2, 50 * 160) << "stopped before the move's end";
  rig.engine().receive("M105\n");
  EXPECT_EQ(rig.next_line(milliseconds(50)), "");  // halted: no answer
}

// M115 as Marlin's G-code reference gives it: one FIRMWARE_NAME line (PROTOCOL_VERSION,
// MACHINE_TYPE, EXTRUDER_COUNT, UUID), then "Cap:NAME:0|1" lines, then ok. The capabilities this
// front end has are announced (hosts switch features on them): AUTOREPORT_TEMP (M155),
// EMERGENCY_PARSER (M108/M112 out of band), THERMAL_PROTECTION (the FPGA's heater safety), ARCS.
TEST(MarlinEngine, M115FirmwareAndCapabilities) {
  Rig rig;
  const auto ans = rig.command("M115");
  ASSERT_GE(ans.size(), 3u);
  EXPECT_TRUE(
      std::regex_match(ans[0], std::regex(R"(FIRMWARE_NAME:Marlin[^:]* PROTOCOL_VERSION:1\.0 )"
                                          R"(MACHINE_TYPE:\S+ EXTRUDER_COUNT:1 )"
                                          R"(UUID:[0-9a-f]{8}(-[0-9a-f]{4}){3}-[0-9a-f]{12})")))
      << ans[0];
  std::map<std::string, int> caps;
  const std::regex cap(R"(Cap:([A-Z_]+):([01]))");
  for (size_t i = 1; i + 1 < ans.size(); ++i) {
    std::smatch m;
    ASSERT_TRUE(std::regex_match(ans[i], m, cap)) << ans[i];
    EXPECT_TRUE(caps.emplace(m[1], std::stoi(m[2])).second) << "twice: " << ans[i];
  }
  EXPECT_EQ(ans.back(), "ok");
  EXPECT_EQ(caps["AUTOREPORT_TEMP"], 1);
  EXPECT_EQ(caps["EMERGENCY_PARSER"], 1);
  EXPECT_EQ(caps["THERMAL_PROTECTION"], 1);
  EXPECT_EQ(caps["ARCS"], 1);
  EXPECT_EQ(caps.count("SDCARD"), 1u);  // features it lacks are listed as 0
  EXPECT_EQ(caps["SDCARD"], 0);
  EXPECT_EQ(caps["EEPROM"], 0);
}

// M108 while M109 waits on the Verilated board's hot-end plant: the wait ends at the next STATUS
// (the M109 line gets its ok far below the target), the setpoint stays (M105 shows it, the hot
// end keeps heating), and the M108 line itself is answered ok in its turn.
TEST(MarlinEngine, M108EndsTheHeatingWait) {
  MachineConfig cfg;
  Rig rig(true, cfg);
  rig.engine().receive("M109 S200\n");
  size_t temp_lines = 0;
  double before_c = 0.0;
  while (temp_lines < 2) {  // the wait has begun and reports (one line a plant second)
    const std::string l = rig.next_line();
    ASSERT_FALSE(l.empty());
    ASSERT_NE(l.rfind("ok", 0), 0u) << "M109 ended before M108";
    std::smatch m;
    if (std::regex_match(l, m, kTemps)) ++temp_lines, before_c = std::stod(m[1]);
  }
  ASSERT_LT(before_c, 150.0);
  const auto t0 = rig.link().now();
  rig.engine().receive("M108\n");
  std::string l;
  do {
    l = rig.next_line(milliseconds(1000));
  } while (std::regex_match(l, kTemps) || l == "echo:busy: processing");
  EXPECT_EQ(l, "ok") << "M109's ok";
  EXPECT_LT(rig.link().now() - t0, milliseconds(50)) << "link time from M108 to M109's ok";
  EXPECT_EQ(rig.next_line(milliseconds(1000)), "ok") << "M108's own ok";
  const auto t = rig.command("M105");
  std::smatch m;
  const std::string body = t.at(0).substr(3);
  ASSERT_TRUE(std::regex_match(body, m, kTemps)) << t.at(0);
  EXPECT_EQ(m[2], "200.00") << "the setpoint stays";
  EXPECT_LT(std::stod(m[1]), 200.0 - cfg.heaters.ch[0].wait_tolerance_c);
}

// `fpgacnc marlin --no-pty --listen tcp:127.0.0.1:0` (the twin board behind it): a host on TCP
// waits for "start" and streams a short job as numbered, checksummed lines (send-response);
// M114 then gives the FPGA's step counters for the job's end (160 steps/mm on X and Y). The wall
// limits only stop a hung front end; the figures are the board's.
TEST(MarlinTcp, ClientStreamsAShortJob) {
  int out[2];
  ASSERT_EQ(::pipe(out), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(out[1], 1);
    ::close(out[0]);
    ::close(out[1]);
    ::execl(FPGACNC_EXE, FPGACNC_EXE, "marlin", "--no-pty", "--listen", "tcp:127.0.0.1:0",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(out[1]);
  struct Child {
    pid_t pid;
    int fd;
    ~Child() {
      ::kill(pid, SIGTERM);
      int st = 0;
      ::waitpid(pid, &st, 0);
      ::close(fd);
    }
  } child{pid, out[0]};
  // Reads one line from `fd` (hang guard: 60 s of wall time).
  auto read_line = [](int fd, std::string& buf) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    for (;;) {
      if (const auto nl = buf.find('\n'); nl != std::string::npos) {
        std::string l = buf.substr(0, nl);
        buf.erase(0, nl + 1);
        if (!l.empty() && l.back() == '\r') l.pop_back();
        return l;
      }
      if (std::chrono::steady_clock::now() > give_up) return std::string("<hung>");
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char b[4096];
      const ssize_t n = ::read(fd, b, sizeof b);
      if (n <= 0) return std::string("<closed>");
      buf.append(b, static_cast<size_t>(n));
    }
  };
  std::string obuf;
  EXPECT_EQ(read_line(child.fd, obuf), "-");  // no pty
  const std::string where = read_line(child.fd, obuf);
  std::smatch m;
  ASSERT_TRUE(std::regex_match(where, m, std::regex(R"(marlin on tcp 127\.0\.0\.1:(\d+))")))
      << where;
  const int port = std::stoi(m[1]);
  ASSERT_GT(port, 0);

  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(s, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a), 0) << std::strerror(errno);
  std::string sbuf;
  std::vector<std::string> got;
  for (std::string l; (l = read_line(s, sbuf)) != "start";) {
    ASSERT_NE(l.front(), '<') << l;  // hung or closed before the banner
  }
  const std::vector<std::string> prog = {"M110 N0",  "G21",      "G90", "G1 X1 F3000",
                                         "G1 X2 Y1", "G1 X3 Y2", "M400"};
  for (size_t i = 0; i < prog.size(); ++i) {
    const std::string line = numbered(static_cast<long>(i), prog[i]) + "\n";
    ASSERT_EQ(::write(s, line.data(), line.size()), static_cast<ssize_t>(line.size()));
    for (std::string l;;) {
      l = read_line(s, sbuf);
      ASSERT_NE(l.front(), '<') << prog[i] << ": " << l;
      ASSERT_EQ(l.rfind("Resend", 0), std::string::npos) << prog[i] << ": " << l;
      if (l.rfind("ok", 0) == 0) break;
    }
  }
  const std::string m114 = numbered(static_cast<long>(prog.size()), "M114") + "\n";
  ASSERT_EQ(::write(s, m114.data(), m114.size()), static_cast<ssize_t>(m114.size()));
  EXPECT_EQ(read_line(s, sbuf), "X:3.00 Y:2.00 Z:0.00 E:0.00 Count X:480 Y:320 Z:0");
  EXPECT_EQ(read_line(s, sbuf), "ok");
  ::close(s);
}

// M119 on the Verilated board (X, Y, Z min and max wired): Marlin's "Reporting endstop status"
// with one line per switch, TRIGGERED for the one held (after its 1 ms debounce, board time).
TEST(MarlinEngine, M119ReportsTheHeldSwitch) {
  Rig rig(true);
  auto& board = *fpgacnc::simboard::board_of(rig.link());
  board.set_limit(2, true, true);  // Z max
  rig.link().wait_until(rig.link().now() + milliseconds(5));
  const auto r = rig.command("M119");
  const std::vector<std::string> want = {"Reporting endstop status",
                                         "x_min: open",
                                         "x_max: open",
                                         "y_min: open",
                                         "y_max: open",
                                         "z_min: open",
                                         "z_max: TRIGGERED",
                                         "ok"};
  EXPECT_EQ(r, want);
}

// A limit switch hit while moving on the Verilated board: the FPGA stops every axis; the front
// end reports Marlin's endstop hit with the axis at the board's position, then halts.
TEST(MarlinEngine, EndstopHitWhileMovingHalts) {
  MachineConfig cfg;
  Rig rig(true, cfg);
  EXPECT_EQ(rig.command("G1 X50 F3000").back(), "ok");  // 1 s of motion
  auto& board = *fpgacnc::simboard::board_of(rig.link());
  const auto t0 = rig.link().now();
  while (board.stats().position[0] < 160 && rig.link().now() - t0 < milliseconds(500)) rig.pump();
  ASSERT_GE(board.stats().position[0], 160) << "moving";
  board.set_limit(0, true, true);  // X max
  const std::string hit = rig.next_line(milliseconds(1000));
  const auto x = board.stats().position[0];
  EXPECT_EQ(hit, fmt::format("echo:endstops hit:  X:{:.2f}", static_cast<double>(x) / 160.0));
  const std::string halt = rig.next_line(milliseconds(100));
  EXPECT_EQ(halt.rfind("Error:Printer halted. kill() called! (LIMIT alarm: X max", 0), 0u) << halt;
  EXPECT_TRUE(rig.engine().killed());
  EXPECT_LT(x, 50 * 160) << "stopped before the move's end";
  const auto t1 = rig.link().now();
  while (rig.link().now() - t1 < milliseconds(50)) rig.pump();
  EXPECT_EQ(board.stats().position[0], x) << "still moving after the trip";
}
