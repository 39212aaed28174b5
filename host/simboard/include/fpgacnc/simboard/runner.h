// Running jobs on the simulated board through the same code path as a real port: a Board
// (SimBoard or twins::TwinBoard) in its own thread, the host's SerialLink opened on the board's
// pty, the host's streamers.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace fpgacnc::simboard {

// A Link to a simulated board it owns: starts the board (its own thread) and opens a
// SerialLink on the board's pty. board() / any_board() give the figures after (or during) a
// stream.
//
// Link time runs on the board's clock (link.h): now() is the board's cycle / clk_hz plus the
// time skipped while the board was idle for the host, and every timeout given to read_byte(),
// read_byte_until() and wait_until() is board time. A wait ends when a byte arrives, when the
// board has run past the deadline (answer bytes it wrote by then are read first), or at once
// (now() jumping to the deadline) when the board is idle for the host: Board::idle_for_host()
// (quiet with its output written, or frozen), every byte this link wrote taken by the board
// (Board::bytes_from_host()) unless it is frozen, and every byte it wrote to the pty read here
// (bytes_to_host()). So no wait depends on how fast or loaded the machine is: a paused or
// stopped board (a board that stopped answering) ends every wait at once, as its deadline.
// flush_input() discards exactly the bytes the board has written to the pty so far. The board
// side is used through the Board interface (cycle(), clk_hz(), idle_for_host(),
// bytes_from_host(), bytes_to_host(), frozen()) only. One host thread uses the link.
class BoardLink : public link::Link {
 public:
  explicit BoardLink(BoardOptions options);
  // Any board behind a pty (SimBoard, twins::TwinBoard); the SerialLink is opened at `baud`.
  BoardLink(std::unique_ptr<Board> board, uint32_t baud);
  ~BoardLink() override;
  void write(std::span<const uint8_t> bytes) override;
  // `timeout` is board time (see above).
  std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) override {
    return read_byte_until(now() + timeout);
  }
  void flush_input() override;
  std::string name() const override { return serial_->name(); }
  std::optional<link::BoardClock> board_clock() const override;
  Time now() const override;
  std::optional<uint8_t> read_byte_until(Time deadline) override;
  // Tells the board the host waits until `deadline` (Board::set_host_deadline).
  void hold_board_at(Time deadline) const;
  void wait_until(Time deadline) override;
  // Waits until the board is idle for the host (true) or `timeout` of board time has passed
  // (false): after the last answer, before reading the board's figures.
  bool wait_idle(std::chrono::milliseconds timeout);
  // Board time skipped so far because the board was idle for the host.
  Time skipped() const { return skipped_; }
  // The SimBoard (BoardError when the board is another model: use any_board()).
  SimBoard& board();
  const SimBoard& board() const;
  Board& any_board() { return *board_; }
  const Board& any_board() const { return *board_; }

 private:
  Time board_time(uint64_t cycle) const;
  // Idle for the host (see above); reads the board in the order that makes the answer safe.
  bool idle() const;
  std::optional<uint8_t> take(std::chrono::milliseconds wall);
  // Clears the board's progress signal (Board::progress_fd); then waits (wall time, bounded)
  // until it is signalled again or, with `or_byte`, a byte is readable on the pty. Every wait
  // clears first, looks at the board, then waits: a signal after the look is never lost.
  void clear_progress();
  void await_progress(bool or_byte);
  // The next byte while fewer than `upto` bytes have been taken: waits (wall time, bounded) for
  // bytes the board has written but the pty has not delivered yet; nullopt once `upto` are
  // taken; throws link::Error naming the port if they never come.
  std::optional<uint8_t> take_in_flight(uint64_t upto);

  std::unique_ptr<Board> board_;
  std::unique_ptr<link::SerialLink> serial_;
  int serial_fd_ = -1;     // the SerialLink's descriptor (polled beside progress_fd)
  uint64_t written_ = 0;   // bytes written to the pty by this link
  uint64_t consumed_ = 0;  // bytes read (or discarded) from the pty by this link
  Time skipped_{0};
};

struct BoardRunOptions {
  link::StreamOptions stream;  // ack timeout, progress (called before on_ack)
  // Called after each acknowledged move (moves done, total), with the board: a test can
  // pause() or stop() it here to model a board that stops answering.
  std::function<void(SimBoard&, size_t, size_t)> on_ack;
};

struct BoardRunResult {
  link::StreamReport report;
  BoardStats stats;
  std::vector<models::Edge> edges;
  std::vector<uint64_t> move_done_cycles;
  std::array<int64_t, models::kBoardAxes> net_steps{};
  std::string port;
};

// Streams `plan` to a fresh simulated board (options from `board`) and collects its edges.
// Errors of the streamer (link::Error on an ACK timeout) propagate.
BoardRunResult run_plan_on_board(const plan::Plan& plan, const BoardOptions& board,
                                 const BoardRunOptions& options);

}  // namespace fpgacnc::simboard
