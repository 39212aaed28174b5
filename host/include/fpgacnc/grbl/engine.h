// grbl 1.1's line protocol in front of the FPGA (docs/grbl.md): what a grbl sender (CNCjs, UGS,
// bCNC, Candle, LaserGRBL, LightBurn) sees, with protocol v2 behind it. Bytes in from the sender
// (receive), bytes out to it (take_output); step() moves everything on. The engine owns no file
// descriptor: `fpgacnc grbl` (host/cli/grbl_cmd.cpp) serves it on a pty or TCP, tests drive it
// in-process.
//
// Lines: taken from the 128-byte receive buffer while the pipeline has room (frames planned but
// not yet sent below one look-ahead window), so send-response and character-counting streaming
// both work; each G-code line goes through the interpreter (grbl dialect) and the planner into
// the look-ahead (plan::Lookahead, window W = lookahead_segments), whose finished profiles go to
// the v2 session (link/v2_session.h) as LINE_PROFILE frames at once; `ok` when the line is
// planned, `error:N` (grbl's codes) when refused; a line whose motion leaves the travel with soft
// limits on ($20=1) raises ALARM:2 (docs/grbl.md, "Soft limits").
// Flush rule: the look-ahead is planned to a stop and sent when no complete line waits in the
// receive buffer and the board has at most kLowWater FIFO frames left to run (the sender went
// quiet or is slower than the machine), and always at G4, M0/M1/M6, M2/M30, coolant/fan outputs
// and before a '$' command.
// Status reports (`?`): a STATUS_QUERY to the board; the report is written when its answer
// arrives: MPos (or WPos per $10) from the FPGA's step counters, Bf, FS, Ov and WCO.
// Feed hold and overrides (docs/grbl.md "Feed hold and overrides"), on a board that takes the
// MOTION frame (sent with the machine's hold ramp at every session start): `!` while running ->
// MOTION HOLD (Hold:1 until STATUS says STOPPED, then Hold:0; the hold pin gives the same states),
// `~` -> MOTION RESUME; 0x90-0x94 feed override 10..200 % (up to 100 % the board's feed rate at
// once on the running job; above, the board stays at 100 % and the lines planned from then on
// are planned faster, capped by the max rates), 0x95-0x97 rapid override 100 / 50 / 25 % (the
// board's rapid rate), 0x99-0x9D spindle override (kept and reported, no hardware). On a board
// without MOTION (NAK UNKNOWN_TYPE) `!` and the feed / rapid overrides are ignored as by a grbl
// built without them. A soft reset during a hold sends MOTION CANCEL: the board drops its queue
// at rest, positions kept.
// Jogging (docs/grbl.md "Jogging"): `$J=` in Idle or Jog, on a board that takes MOTION, plans one
// straight move (laser off) after the jogs already queued; the state is Jog until they have run.
// 0x85 (and `!` while jogging) is the jog cancel: MOTION CANCEL (the board decelerates with the
// hold ramp and drops its queue at rest), then a new session from the board's STATUS, the parser
// and planner moved to where the machine stopped with their modal state kept; Idle again.
// Probing (docs/grbl.md "Probing"): G38.2 .. G38.5 on a board with a probe input run
// link::ProbeCycle once the motion before them has run (state Run), then [PRB:x,y,z:1|0] in
// machine coordinates (kept for `$#`), ALARM:4 / ALARM:5 as grbl, the line's ok; the parser and
// planner continue from where the board stopped (its STATUS), past the contact.
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
#include "fpgacnc/gcode/reader.h"
#include "fpgacnc/grbl/settings.h"
#include "fpgacnc/link/homing.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/link/probe.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::grbl {

inline constexpr size_t kRxBuffer = 128;  // grbl's serial receive buffer (bytes)
inline constexpr size_t kLineMax = 80;    // grbl's line buffer: longer lines are error:11
inline constexpr size_t kLowWater = 2;    // board FIFO frames left that trigger a flush
inline constexpr const char* kBanner = "Grbl 1.1h ['$' for help]";
inline constexpr const char* kVersion = "1.1h.20190825";

// kHold: Hold:0 (at rest), kHolding: Hold:1 (decelerating).
enum class State { kIdle, kRun, kHold, kHolding, kJog, kAlarm, kCheck, kHome, kSleep };
const char* state_name(State s);

struct EngineOptions {
  link::StreamV2Options v2;   // session timers (link time)
  std::string settings_path;  // "" = settings not persisted
  // Soft reset mid-job on a board with an e-stop input (the Verilated simulated board): press
  // drops the board's queue (docs/protocol.md, E-stop); release once STATUS shows it latched.
  // Unset: the frames already on the board run out (at most its FIFO depth) before the reset
  // completes.
  std::function<void()> estop_press, estop_release;
  // The board's limit switches (bits as STATUS's switch u16: bit a min of axis a, bit 8 + a
  // max), from the board model (simboard::Board::limit_switches): 0 = none. With switches, `$21=1`
  // is accepted; a hard-limit alarm is reported whatever it says (docs/grbl.md).
  uint16_t limit_switches = 0;
  // The board has a probe input and TRIGGER (the Verilated board, a real port): G38.2 .. G38.5
  // run; else they are error:20 with a message (the twin board models no trigger).
  bool probe = false;
};

// Counters for tests and the exit summary.
struct EngineStats {
  uint64_t lines = 0;  // lines answered (ok or error)
  uint64_t oks = 0;
  uint64_t errors = 0;
  uint64_t reports = 0;  // status reports written
  uint64_t flushes = 0;  // look-ahead planned to a stop
  uint64_t frames = 0;   // FIFO frames pushed to the session
  uint64_t resets = 0;   // soft resets
  uint64_t aborted = 0;  // frames given up by a soft reset (never sent)
  uint64_t holds = 0;    // MOTION HOLD sent ('!')
  uint64_t resumes = 0;  // MOTION RESUME sent ('~')
  uint64_t motions = 0;  // MOTION frames sent in all (holds, resumes, overrides)
};

// grbl's override values, percent.
struct Overrides {
  int feed = 100;     // 10..200
  int rapid = 100;    // 100, 50, 25
  int spindle = 100;  // 10..200
  bool operator==(const Overrides&) const = default;
};

class Engine {
 public:
  // `base`: the machine configuration; `settings` over it (settings_from_config for none).
  Engine(link::Link& link, config::MachineConfig base, Settings settings, EngineOptions opt = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // IDENT handshake and the first session (throws link::Error); then the welcome banner, as
  // when a sender opens the port.
  void connect();
  // A sender (re)opened the port: the banner again (and the startup lines).
  void opened();
  // Bytes from the sender (real-time commands are taken out at once, wherever they are).
  void receive(std::string_view bytes);
  // Everything written to the sender since the last call.
  std::string take_output();
  // Takes lines, plans, runs the session; waits up to `wait` of link time for a board answer
  // when there is something in flight.
  void step(std::chrono::milliseconds wait = std::chrono::milliseconds(0));
  // Something is in flight or pending (motion, a report, a reset): call step() again soon.
  bool busy() const;

  State state() const;
  const Settings& settings() const { return settings_; }
  const config::MachineConfig& config() const { return cfg_; }
  const EngineStats& stats() const { return stats_; }
  // Machine position from the last STATUS (mm) and the planner's position (steps).
  std::array<double, 4> mpos() const;
  const plan::Steps4& planned_steps() const { return planner_->position(); }
  size_t rx_pending() const { return rx_.size(); }
  const Overrides& overrides() const { return ov_; }
  // The board took MOTION at the session start: feed hold and overrides work.
  bool motion_available() const { return motion_ok_; }

 private:
  void new_session();
  // A new session from the board's STATUS, the pipeline at its step position, the banner.
  void restart();
  void rebuild_pipeline(const plan::Steps4& steps);
  void banner();
  bool line_ready() const;
  bool can_take_line() const;
  void take_line();
  void process_line(const std::string& raw);
  int system_command(const std::string& cmd);
  // 0, grbl's error code, or kSoftLimit (a move leaves the travel: nothing of the line queued).
  int gcode_line(const std::string& raw, bool check_only);
  static constexpr int kSoftLimit = -2;
  static constexpr int kHomingStarted = -3;  // `$H` runs: its answer comes at the end
  // `$H` (docs/grbl.md "Homing"): 0 when started (kHomingStarted), else grbl's error code.
  int start_homing();
  void continue_homing(std::chrono::milliseconds wait);
  void finish_homing();
  static constexpr int kProbeStarted = -4;  // G38.x runs: the line's answer comes at the end
  // The line's G38.x: the probing cycle starts once the motion before it has run.
  int start_probe(const gcode::Probe& p);
  void continue_probe(std::chrono::milliseconds wait);
  void finish_probe();
  std::string prb_line() const;  // [PRB:x,y,z:s] of the last probe
  void push_items(std::vector<plan::PlanItem> items);
  void flush_lookahead();
  void emit_profiles();
  void push_fifo(const protocol::v2::Frame& f, int line, double feed, double s);
  // Real-time commands other than '?' and 0x18 (acted on in step(), in their order).
  void realtime(unsigned char c);
  // MOTION with the override rates and the machine's ramp (and HOLD / RESUME / CANCEL).
  protocol::v2::Motion motion_frame(bool hold, bool resume, bool cancel = false) const;
  void send_motion(bool hold, bool resume, bool cancel = false);
  bool board_held() const;  // a hold in effect: ours ('!') or the board's (its hold pin)
  void soft_reset();
  void continue_reset();
  // `$J=...`: 0 or grbl's error code (docs/grbl.md "Jogging").
  int jog_line(const std::string& cmd);
  void start_jog_cancel();
  void continue_jog_cancel();
  // The parser and the planner moved to `steps` (machine position), the parser's units, distance
  // and G0/G1 motion modes kept.
  void resync_parser(const plan::Steps4& steps);
  // The session threw: a hard-limit alarm on the board (ALARM:1 while running; quietly while
  // already in alarm) is handled, anything else rethrown.
  void on_session_error();
  // `$X` while the board's limit alarm may be latched: FAULT_CLEAR through a new session;
  // 0 when it cleared, 9 while the switch is still held.
  int clear_limit_alarm();
  void write_report();
  void track_modal(const gcode::Block& b);
  std::array<double, 3> wco() const;
  bool motion_pending() const;
  void say(std::string_view line);
  void save();

  link::Link& link_;
  config::MachineConfig base_;
  config::MachineConfig cfg_;
  Settings settings_;
  EngineOptions opt_;
  link::StreamV2Report rep_;
  protocol::v2::Ident ident_;
  std::unique_ptr<link::V2Session> session_;
  std::unique_ptr<gcode::Params> params_;
  std::unique_ptr<gcode::Interpreter> interp_;
  std::unique_ptr<plan::Planner> planner_;
  std::unique_ptr<plan::Lookahead> la_;
  size_t seg_index_ = 0;
  protocol::v2::OutputSet outputs_;
  std::string rx_;
  std::string out_;
  EngineStats stats_;

  bool alarm_ = false;
  // Soft-limit alarm (ALARM:2): no line is taken until a soft reset, which answers the refused
  // line's `ok` before the banner (grbl's critical event).
  bool critical_ = false;
  bool limit_alarm_ =
      false;  // ALARM:1 given: lines wait until a soft reset (grbl's critical alarm)
  bool check_ = false;
  bool sleep_ = false;
  std::unique_ptr<link::HomingCycle> homing_;  // `$H` in progress (state Home)
  bool homing_started_ = false;  // the cycle's first session is open (the one before settled)
  bool disarm_next_ = false;     // a homing or probe was cut short: the next session sends DISARM
  std::unique_ptr<link::ProbeCycle> probe_;  // G38.x in progress (state Run)
  bool probe_started_ = false;      // the cycle's first session is open (the motion before has run)
  std::array<double, 3> prb_mm_{};  // the last probe's position (machine mm) and success
  bool prb_ok_ = false;
  bool pause_pending_ = false;  // M0/M1/M6 planned: Hold:0 once the board is at rest
  bool held_ = false;           // at rest after M0 until '~'
  bool resetting_ = false;
  bool estop_pressed_ = false;
  bool motion_ok_ = false;   // the board took MOTION (session start)
  bool hold_ = false;        // '!' sent MOTION HOLD; '~' ends it
  bool jog_ = false;         // jog motion queued (state Jog while it runs)
  bool jog_cancel_ = false;  // MOTION CANCEL sent for a jog cancel: waiting for the board at rest
  size_t jog_answers_ = 0;   // the status answer count the jog cancel waits beyond
  Overrides ov_;
  bool ov_report_ = false;  // Ov in the next report (an override changed)
  std::string realtime_;    // real-time commands received, acted on in step()
  bool report_pending_ = false;
  size_t report_answers_ = 0;  // the session status answer count the report waits for
  bool report_asked_ = false;
  bool reset_asked_ = false;
  size_t reset_answers_ = 0;
  uint64_t report_count_ = 0;
  bool wco_changed_ = true;
  // Per FIFO frame pushed (index from fifo_base_): programmed feed (mm/min) and S, for FS.
  std::deque<std::pair<double, double>> fifo_info_;
  size_t fifo_base_ = 0;
  struct Modal {
    std::string motion = "G0", wcs = "G54", plane = "G17", units = "G21", distance = "G90",
                feed_mode = "G94", spindle = "M5", coolant = "M9";
    int tool = 0;
    double feed = 0.0, s = 0.0;
  } modal_;
};

}  // namespace fpgacnc::grbl
