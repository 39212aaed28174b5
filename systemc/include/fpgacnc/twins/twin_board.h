// TwinBoard: the SystemC twins of cnc_core (VirtualBoard) behind a pseudo-terminal, a drop-in for
// simboard::SimBoard (the Verilated core) that runs thousands of times faster.
//
// Serial side: any client opens path() (/dev/pts/N, raw). Bytes written to the pty enter the
// twin uart_rx as 8N1 frames at simulated clocks; every byte the twin uart_tx sends is written
// back to the pty. STEP/DIR/LASER edges (and TX when asked) are recorded with their clocks
// (models::Edge), with the same cycle numbering as SimBoard (cycle 0 = the last settle edge
// after the step timing writes; the first host byte starts on cycle 1).
//
// Time policy: SimBoard's (sim_board.h). A quiet board (nothing in flight: no rx bytes on the
// line, no entry queued, prepared or running, no STEP pulse high, no tx byte, no packet started,
// and 32 clocks past the last activity) does not advance; bytes arriving while quiet start on
// the next clock; bytes arriving during the 32-clock quiet tail start after it; bytes arriving
// while busy start on the next clock of the board's time (back to back after host bytes still
// on the line). Activity is counted exactly as SimBoard counts it (the rx line until its stop
// bit ends, cnc_core `busy`, STEP high, tx low or being decoded until the end of its stop bit),
// so a host that writes only when the board is idle_for_host() gets the same bytes at the same
// clocks from both boards. The answers are written to the pty when they are decoded: the middle
// of their stop bit, as SimBoard's UART monitor decodes them.
//
// Without realtime the board jumps from event to event (an answer's decision, a byte decoded, the
// end of activity) with no per-clock work. So that a host keeps up as with SimBoard (which needs
// about 2.7 ms of wall time per UART byte), it holds its time (a) before its time passes the end
// of the host's bytes on the line, until `host_grace` after the host's last write, (b) after
// the last byte of an answer, at the clock SimBoard would write it (the first inactive clock, at
// most one poll interval later), until the client has read every answer byte and then
// `host_grace` has passed without a write, and (c) at the host's next timer
// (set_host_deadline: a STATUS poll during a long move), for `host_grace`. With realtime, simulated
// time follows the wall clock (50 M clocks per second at 50 MHz, times realtime_speed) while the
// board is busy; no holds.
//
// MOTION (feed hold, resume, feed and rapid rates): the twins compute a segment's edges and its
// end when the executor accepts it, ahead of the board's time, so a MOTION frame changes edges
// already computed. The board keeps a log of every host byte with its start clock; at a MOTION
// frame the twins did not know up front, it runs the session again from the reset up to `now`
// with the requests of every MOTION frame so far known up front (VirtualBoard::run_job's way),
// in the same thread, without waiting: the answers already decided and the edges already
// released (up to the published cycle) come out the same (checked: a difference ends the
// session with error()), the edges after them are replaced. A replay costs the host bytes and
// the edges of the session so far, never its clocks (replays()). A board held for good (rate 0,
// nothing to end it) does not run its clock on its own: it moves on to the host's deadlines
// (set_host_deadline) or its next bytes. The host's timer stops the board at that clock also
// when an event falls on it (bytes written then start on the next clock, as with SimBoard).
//
// Buttons (press_button): as on SimBoard, the pin is high from the edge after the board's
// clock for SimBoard::kButtonPressClks edges (a press while the same button is held lengthens
// it) and the board counts as active until kFilterClks + 8 clocks after the release; the filtered
// rise requests a hold or a resume (input_filter.h). A press is a request the twins did not know
// up front: the board replays its session with it, as for a MOTION frame. A press while the
// board stands at the host's deadline keeps it there until the host writes or names another
// deadline, so that the press lands on the same edge as on SimBoard.
//
// No heaters (the twins model idle heaters: STATUS reports them so), no line fault injection, no
// e-stop input (set_estop throws BoardError), no limit switches (set_limit throws BoardError). The
// SystemC kernel runs in a thread of its own, one per process, elaborated by the first TwinBoard;
// later TwinBoards run as further sessions in it (one at a time, with the same clock, baud and
// watchdog).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/simboard/sim_board.h"

namespace fpgacnc::twins {

class VirtualBoard;

struct TwinBoardOptions {
  uint64_t clk_hz = 50'000'000;  // must divide 1e12 (whole ps per clock)
  uint32_t baud = 115200;
  // Step timing per axis; unset: the RTL defaults (100/100/200/200 clocks).
  std::optional<std::array<config::StepTiming, models::kBoardAxes>> step_timing;
  bool realtime = false;        // pace simulated time to the wall clock while busy
  double realtime_speed = 1.0;  // with realtime: simulated seconds per wall second (> 0)
  bool record_tx = false;       // also record TX pin edges
  std::chrono::microseconds host_grace{300};
  uint32_t poll_interval_cycles = 1024;  // SimBoard's: the latest clock an answer is written
};

class TwinBoard : public simboard::Board {
 public:
  // Clock, baud and step timing from a machine configuration (as SimBoard::options_from_config).
  static TwinBoardOptions options_from_config(const config::MachineConfig& cfg);
  // Creates the pty. Throws simboard::BoardError (pty failure, bad clock or step timing).
  explicit TwinBoard(TwinBoardOptions options = {});
  ~TwinBoard() override;
  TwinBoard(const TwinBoard&) = delete;
  TwinBoard& operator=(const TwinBoard&) = delete;

  const std::string& path() const override { return path_; }
  const TwinBoardOptions& options() const { return opt_; }
  // Starts a session in the process's SystemC thread (resetting the twins); throws BoardError
  // when running, when another TwinBoard's session runs, or for a clock/baud other than the
  // first TwinBoard's.
  void start() override;
  void stop() override;
  uint64_t cycle() const override;
  double clk_hz() const override { return static_cast<double>(opt_.clk_hz); }
  simboard::BoardStats stats() const override;
  std::vector<models::Edge> edges() const override;
  std::array<int64_t, models::kBoardAxes> net_steps() const override;
  void set_estop(bool pressed) override;
  // The feed hold and cycle-start buttons, pressed as on SimBoard (see above); throws BoardError
  // when no session runs.
  uint64_t press_button(simboard::Button b) override;
  // No limit switches are modelled: set_limit throws BoardError, limit_switches() is 0.
  uint64_t set_limit(int axis, bool max_side, bool pressed) override;
  uint16_t limit_switches() const override { return 0; }
  bool idle_for_host() const override;
  bool wait_quiet(std::chrono::milliseconds timeout) const override;
  // Published with the quiet state: while idle_for_host() is true they are current.
  uint64_t bytes_from_host() const override;
  uint64_t bytes_to_host() const override;
  bool frozen() const override;
  std::string model() const override { return "tlm"; }
  void set_host_deadline(int64_t cycle) override;
  // An error that ended the session (a twin's logic error), "" when none.
  std::string error() const;
  // Replays of this session so far (one per MOTION frame the twins did not know; see above).
  uint64_t replays() const { return replays_.load(); }

 private:
  void session(VirtualBoard& vb);
  void open_pty();
  void wake() const;

  TwinBoardOptions opt_;
  std::string path_;
  int master_ = -1, slave_ = -1, wake_ = -1;

  mutable std::mutex mu_;  // guards the published figures below
  simboard::BoardStats st_{};
  // Recorded so far, in drained batches (sorted on request and at the session's end); while the
  // board runs, stats().edges counts the batches (a laser pair split over two batches counts).
  std::vector<models::Edge> edges_;
  std::string error_;
  bool running_ = false;
  std::atomic<bool> stop_{false};
  std::atomic<bool> quiet_{true};
  std::atomic<uint64_t> replays_{0};
  // Button presses asked by the host, taken by the session (under mu_): requests, answers.
  std::vector<int> press_req_;
  uint64_t press_asked_ = 0, press_taken_ = 0;
  uint64_t press_edge_ = 0;  // the edge of the last press taken
  std::condition_variable press_cv_;
  std::atomic<int64_t> host_deadline_{-1};
  std::atomic<bool> session_done_{true};
  std::chrono::steady_clock::time_point t_start_{};
};

}  // namespace fpgacnc::twins
