#include "fpgacnc/simboard/runner.h"

namespace fpgacnc::simboard {

BoardLink::BoardLink(BoardOptions options)
    : BoardLink(std::make_unique<SimBoard>(options), options.baud) {}

BoardLink::BoardLink(std::unique_ptr<Board> board, uint32_t baud) : board_(std::move(board)) {
  board_->start();
  serial_ = std::make_unique<link::SerialLink>(board_->path(), baud);
}

SimBoard& BoardLink::board() {
  auto* b = dynamic_cast<SimBoard*>(board_.get());
  if (!b) throw BoardError("BoardLink: the board is not the Verilated SimBoard");
  return *b;
}

const SimBoard& BoardLink::board() const {
  return const_cast<BoardLink*>(this)->board();
}

BoardLink::~BoardLink() {
  serial_.reset();
  board_->stop();
}

BoardRunResult run_plan_on_board(const plan::Plan& plan, const BoardOptions& board,
                                 const BoardRunOptions& options) {
  BoardLink lk(board);
  link::StreamOptions so = options.stream;
  if (options.on_ack) {
    so.progress = [&](size_t done, size_t total) {
      if (options.stream.progress) options.stream.progress(done, total);
      options.on_ack(lk.board(), done, total);
    };
  }
  BoardRunResult r;
  r.port = lk.name();
  r.report = link::stream_v1(lk, plan, so);
  // The last ACK has reached the host: every STEP edge is recorded by then. Let the board go
  // quiet (end of the ACK frame) before reading its figures.
  lk.board().wait_quiet(std::chrono::milliseconds(2000));
  lk.board().stop();
  r.stats = lk.board().stats();
  r.edges = lk.board().edges();
  r.move_done_cycles = lk.board().move_done_cycles();
  r.net_steps = net_steps(r.edges);
  return r;
}

}  // namespace fpgacnc::simboard
