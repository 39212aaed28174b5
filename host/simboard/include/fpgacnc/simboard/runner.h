// Running jobs on the simulated board through the same code path as a real port: SimBoard in
// its own thread, the host's SerialLink opened on the board's pty, the host's v1 streamer.
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
// SerialLink on the board's pty. board() gives the figures after (or during) a stream.
class BoardLink : public link::Link {
 public:
  explicit BoardLink(BoardOptions options);
  // Any board behind a pty (SimBoard, twins::TwinBoard); the SerialLink is opened at `baud`.
  BoardLink(std::unique_ptr<Board> board, uint32_t baud);
  ~BoardLink() override;
  void write(std::span<const uint8_t> bytes) override { serial_->write(bytes); }
  std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) override {
    return serial_->read_byte(timeout);
  }
  void flush_input() override { serial_->flush_input(); }
  std::string name() const override { return serial_->name(); }
  // The SimBoard (BoardError when the board is another model: use any_board()).
  SimBoard& board();
  const SimBoard& board() const;
  Board& any_board() { return *board_; }
  const Board& any_board() const { return *board_; }

 private:
  std::unique_ptr<Board> board_;
  std::unique_ptr<link::SerialLink> serial_;
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
  std::vector<Edge> edges;
  std::vector<uint64_t> move_done_cycles;
  std::array<int64_t, kBoardAxes> net_steps{};
  std::string port;
};

// Streams `plan` to a fresh simulated board (options from `board`) and collects its edges.
// Errors of the streamer (link::Error on an ACK timeout) propagate.
BoardRunResult run_plan_on_board(const plan::Plan& plan, const BoardOptions& board,
                                 const BoardRunOptions& options);

}  // namespace fpgacnc::simboard
