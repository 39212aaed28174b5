// Marlin's host protocol in front of the FPGA (docs/marlin.md): what a printer host (OctoPrint,
// Pronterface, Repetier-Host) sees, with protocol v2 behind it. Bytes in (receive), bytes out
// (take_output), step() moves everything on; `fpgacnc marlin` serves it on a pty, tests drive it
// in-process.
//
// Lines: numbered and checksummed lines are checked (marlin/protocol.h: Error, Resend, ok); each
// command is answered `ok` once it is planned. G-code goes through the interpreter (Marlin
// dialect: E is the fourth step channel, M82/M83 and G92 E as the interpreter takes them) and the
// planner into the look-ahead, whose finished profiles go to the v2 session as LINE_PROFILE
// frames; the look-ahead is planned to a stop when no complete line waits and the board has at
// most 2 FIFO frames left, and before every command that waits. Handled here: M105 and M155
// (temperatures from a fresh STATUS), M114 (the FPGA's step counters), M400 (waits until the
// board has run every move), M104/M140 (setpoints: HEATER_SETPOINT frames, sequenced, ahead of
// the motion in the FIFO as in Marlin), M109/M190 (setpoint, then the session's heater wait:
// FIFO drained, temperature in band for wait_settle_s of plant time), M106/M107 (the fan output,
// an OUTPUT frame in the FIFO), M110, M112 (emergency stop), M108 (ends an M109/M190 wait; the
// setpoint stays), M115 (firmware name and capabilities). M112 and M108 act as soon as their line
// is in, ahead of the lines queued before them (Marlin's emergency parser). While M109/M190/M400
// wait the host gets "echo:busy: processing" every 2 s and a temperature line every second of the
// heaters' clock (the simulated plant's time on the Verilated board, link time otherwise).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/marlin/protocol.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::marlin {

inline constexpr size_t kLowWater = 2;  // board FIFO frames left that trigger a flush
// Seconds of the heaters' clock (plant time on the Verilated board, link time otherwise).
inline constexpr double kBusyInterval_s = 2.0;  // Marlin's host keepalive
inline constexpr double kWaitReport_s = 1.0;    // temperature line while M109/M190 wait

struct EngineOptions {
  link::StreamV2Options v2;  // session timers (link time), plant_time, heater_poll
  // M112 on a board with an e-stop input (the Verilated simulated board). Unset: the session is
  // abandoned and the frames already on the board run out (at most its FIFO depth).
  std::function<void()> estop_press;
  // The board's limit switches (bits as STATUS's switch u16: bit a min of axis a, bit 8 + a
  // max; simboard::Board::limit_switches), listed by M119; 0 = none.
  uint16_t limit_switches = 0;
};

struct EngineStats {
  uint64_t lines = 0;    // commands answered
  uint64_t resends = 0;  // lines refused (Resend asked)
  uint64_t frames = 0;   // FIFO frames pushed
  uint64_t busy = 0;     // "busy: processing" lines
  uint64_t reports = 0;  // temperature reports (M105, M155, during waits)
};

class Engine {
 public:
  Engine(link::Link& link, config::MachineConfig cfg, EngineOptions opt = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // IDENT handshake, the session, the heater setup frames; then "start" as Marlin prints at boot.
  void connect();
  void receive(std::string_view bytes);
  std::string take_output();
  void step(std::chrono::milliseconds wait = std::chrono::milliseconds(0));
  bool busy() const;
  // M112 was received: nothing more is taken (Marlin halts until reset).
  bool killed() const { return killed_; }
  const EngineStats& stats() const { return stats_; }
  const LineChecker& lines() const { return checker_; }
  // M115's answer lines before its `ok`: FIRMWARE_NAME... and the Cap: lines.
  std::vector<std::string> firmware_report() const;
  // The FPGA's position from the last STATUS (mm).
  std::array<double, 4> position_mm() const;

 private:
  enum class Wait { kNone, kStatus, kDrain, kHeat };
  enum class After { kNone, kTemps, kPosition, kEndstops };
  bool line_ready() const;
  bool can_take_line() const;
  void take_line();
  void run_command(const std::string& cmd);
  bool gcode(const std::string& cmd, std::string& error);
  void push_items(std::vector<plan::PlanItem> items);
  void emit_profiles();
  void flush_lookahead();
  void push_fifo(const protocol::v2::Frame& f, int line);
  void ask_status(After after);
  std::string temps() const;
  void halt();
  void cancel_heating();
  void say(std::string_view line);

  link::Link& link_;
  config::MachineConfig cfg_;
  EngineOptions opt_;
  link::StreamV2Report rep_;
  protocol::v2::Ident ident_;
  heat::HeaterJob heaters_;
  std::deque<heat::HeaterAction> actions_;  // kept for the session (pointers)
  std::unique_ptr<link::V2Session> session_;
  std::unique_ptr<gcode::Params> params_;
  std::unique_ptr<gcode::Interpreter> interp_;
  std::unique_ptr<plan::Planner> planner_;
  std::unique_ptr<plan::Lookahead> la_;
  size_t seg_index_ = 0;
  LineChecker checker_;
  std::string rx_, out_;
  EngineStats stats_;
  Wait wait_ = Wait::kNone;
  After after_ = After::kNone;
  size_t status_answers_ = 0;
  double clock_s() const;
  double busy_at_ = 0.0, report_at_ = 0.0;
  std::chrono::milliseconds auto_report_{0};  // M155 S<sec>; 0: off
  link::Link::Time auto_at_{};
  bool auto_pending_ = false;
  size_t auto_answers_ = 0;
  bool killed_ = false;
};

}  // namespace fpgacnc::marlin
