#include "fpgacnc/simboard/runner.h"

#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <cmath>

namespace fpgacnc::simboard {

namespace {
// Wall-time bound of one wait for the board's signal (Board::progress_fd) or a byte: the board
// signals every event that can end a wait, so this only bounds the cost of a signal lost to a
// race; no decision is taken on it (the deadline is decided on the board's cycle count).
constexpr std::chrono::milliseconds kRecheck{50};
// Safety net (wall time) for bytes the board has written to the pty that do not arrive: the
// kernel delivers them within microseconds; this only names a broken pty instead of hanging.
constexpr std::chrono::seconds kInFlightLimit{30};
}  // namespace

BoardLink::BoardLink(BoardOptions options)
    : BoardLink(std::make_unique<SimBoard>(options), options.baud) {}

BoardLink::BoardLink(std::unique_ptr<Board> board, uint32_t baud) : board_(std::move(board)) {
  board_->start();
  serial_ = std::make_unique<link::SerialLink>(board_->path(), baud);
  serial_fd_ = serial_->native_fd();
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

void BoardLink::write(std::span<const uint8_t> bytes) {
  serial_->write(bytes);
  written_ += bytes.size();
}

link::Link::Time BoardLink::board_time(uint64_t cycle) const {
  return Time(static_cast<int64_t>(static_cast<double>(cycle) * 1e9 / board_->clk_hz()));
}

link::Link::Time BoardLink::now() const {
  return board_time(board_->cycle()) + skipped_;
}

std::optional<link::BoardClock> BoardLink::board_clock() const {
  return link::BoardClock{board_->cycle(), board_->clk_hz(), idle()};
}

bool BoardLink::idle() const {
  // Order matters: the host's bytes taken by the board (before), then the board quiet (after
  // that), then every byte it wrote read here (nothing more is written while it is idle).
  const bool frozen = board_->frozen();
  const bool taken = frozen || board_->bytes_from_host() == written_;
  return taken && board_->idle_for_host() && board_->bytes_to_host() == consumed_;
}

std::optional<uint8_t> BoardLink::take(std::chrono::milliseconds wall) {
  auto b = serial_->read_byte(wall);
  if (b) ++consumed_;
  return b;
}

void BoardLink::clear_progress() {
  uint64_t v;
  [[maybe_unused]] ssize_t n = ::read(board_->progress_fd(), &v, sizeof v);
}

void BoardLink::await_progress(bool or_byte) {
  pollfd p[2] = {{board_->progress_fd(), POLLIN, 0}, {serial_fd_, POLLIN, 0}};
  ::poll(p, or_byte ? 2 : 1, static_cast<int>(kRecheck.count()));
}

std::optional<uint8_t> BoardLink::take_in_flight(uint64_t upto) {
  const auto give_up = std::chrono::steady_clock::now() + kInFlightLimit;
  while (upto > consumed_) {
    if (auto b = take(kRecheck)) return b;
    if (std::chrono::steady_clock::now() > give_up) {
      throw link::Error(fmt::format(
          "{}: {} bytes written by the simulated board did not arrive on the pty within {} s",
          name(), upto - consumed_, kInFlightLimit.count()));
    }
  }
  return std::nullopt;
}

void BoardLink::hold_board_at(Time deadline) const {
  // Only a deadline ahead of the board: a look without waiting (a deadline already passed) must
  // not release the hold at the host's real next timer.
  if (deadline <= now()) return;
  board_->set_host_deadline(static_cast<int64_t>(
      std::ceil(static_cast<double>((deadline - skipped_).count()) * board_->clk_hz() / 1e9)));
}

std::optional<uint8_t> BoardLink::read_byte_until(Time deadline) {
  // The board may not jump past the host's deadline (an event-driven board would otherwise run
  // a long move to its end before the host's poll).
  hold_board_at(deadline);
  for (;;) {
    clear_progress();  // before the looks: a signal after them ends await_progress() at once
    if (auto b = take(std::chrono::milliseconds(0))) return b;
    // The cycle first: every answer byte decoded up to it is counted in bytes_to_host() by now.
    const uint64_t cycle = board_->cycle();
    if (auto b = take_in_flight(board_->bytes_to_host())) return b;
    const Time t = board_time(cycle) + skipped_;
    if (t >= deadline) return std::nullopt;
    if (idle()) {
      skipped_ += deadline - t;  // nothing can arrive before the host writes: skip the rest
      return std::nullopt;
    }
    await_progress(true);
  }
}

void BoardLink::wait_until(Time deadline) {
  hold_board_at(deadline);
  for (;;) {
    clear_progress();
    const Time t = now();
    if (t >= deadline) return;
    // Bytes still on their way to the host do not make the board busy: only the board's own
    // state and the host's bytes count while nothing is read.
    const bool frozen = board_->frozen();
    if ((frozen || board_->bytes_from_host() == written_) && board_->idle_for_host()) {
      skipped_ += deadline - now();
      return;
    }
    await_progress(false);
  }
}

bool BoardLink::wait_idle(std::chrono::milliseconds timeout) {
  const Time deadline = now() + timeout;
  for (;;) {
    clear_progress();
    const bool frozen = board_->frozen();
    if ((frozen || board_->bytes_from_host() == written_) && board_->idle_for_host()) return true;
    if (now() >= deadline) return false;
    await_progress(false);
  }
}

void BoardLink::flush_input() {
  // Exactly what the board has written so far, wherever it is on its way: deterministic, where
  // tcflush() would race with bytes still inside the pty.
  const uint64_t upto = board_->bytes_to_host();
  while (take_in_flight(upto)) {
  }
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
  // quiet (end of the ACK frame: a few clocks) before reading its figures.
  if (!lk.wait_idle(std::chrono::milliseconds(1000))) {
    throw link::Error(
        fmt::format("{}: the simulated board is not idle 1 s of board time after "
                    "the last ACK: {}",
                    lk.name(), lk.board().stats_line()));
  }
  lk.board().stop();
  r.stats = lk.board().stats();
  r.edges = lk.board().edges();
  r.move_done_cycles = lk.board().move_done_cycles();
  r.net_steps = models::net_steps(r.edges);
  return r;
}

}  // namespace fpgacnc::simboard
