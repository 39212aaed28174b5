// Byte link to a controller: a serial port, or a simulated board behind a pseudo-terminal.
//
// Link time. Every host timer (ACK and answer timeouts, retransmission, IDENT after HELLO, the
// v1 settle, STATUS and heater polls, dwells) runs on the link's clock, now(), and waits through
// read_byte_until() / wait_until():
//  - a real serial port has no board clock (board_clock() is nullopt): link time is the wall
//    clock (std::chrono::steady_clock) and a wait of T ms blocks for T ms of wall time;
//  - a simulated board reports its clock: link time is the board's clock cycles / clk_hz plus the
//    time skipped while the board was idle for the host. A wait of T ms ends when the byte
//    arrives, when the board has run T ms worth of its own clocks since the wait started, or at
//    once when the board is idle for the host (nothing in flight, every byte the host wrote taken
//    by the board, every answer byte read by the host: nothing can arrive until the host writes
//    again, so the rest of the wait is skipped and now() jumps to its end). Waits then end at the
//    same board cycle however fast or loaded the machine is.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>

namespace fpgacnc::link {

// Link failures (open, configure, I/O, ACK timeout). what() names the port or the move.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The clock of a simulated board as its link sees it.
struct BoardClock {
  uint64_t cycle = 0;          // board clock cycles since reset
  double clk_hz = 0.0;         // board clock frequency
  bool idle_for_host = false;  // nothing can reach the host until it writes again
};

class Link {
 public:
  // A point in link time (nanoseconds from an origin of the link's choosing), or a span of it.
  using Time = std::chrono::nanoseconds;

  virtual ~Link() = default;
  // Writes all bytes (blocking until handed to the OS / device).
  virtual void write(std::span<const uint8_t> bytes) = 0;
  // One byte, or nullopt when none arrived within `timeout` of link time.
  virtual std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) = 0;
  // Discards bytes received but not yet read.
  virtual void flush_input() = 0;
  // Human-readable name (port path) for messages.
  virtual std::string name() const = 0;

  // The board's clock when the link leads to a simulated board; nullopt for a real port (host
  // timers then run on the wall clock).
  virtual std::optional<BoardClock> board_clock() const { return std::nullopt; }
  // Link time now. Default: the wall clock (steady_clock). Monotonic.
  virtual Time now() const;
  // One byte, or nullopt when none has arrived by `deadline` (link time). A deadline already
  // passed still returns a byte that is there. Default: read_byte() with the wall time left.
  virtual std::optional<uint8_t> read_byte_until(Time deadline);
  // Returns at `deadline` (link time) without reading. Default: sleeps (wall clock).
  virtual void wait_until(Time deadline);
};

inline Link::Time Link::now() const {
  return std::chrono::duration_cast<Time>(std::chrono::steady_clock::now().time_since_epoch());
}

inline std::optional<uint8_t> Link::read_byte_until(Time deadline) {
  for (;;) {
    const Time left = deadline - now();
    const auto ms = left <= Time::zero() ? std::chrono::milliseconds(0)
                                         : std::chrono::ceil<std::chrono::milliseconds>(left);
    if (auto b = read_byte(ms)) return b;
    if (now() >= deadline) return std::nullopt;
  }
}

inline void Link::wait_until(Time deadline) {
  const Time left = deadline - now();
  if (left > Time::zero()) std::this_thread::sleep_for(left);
}

// Link time as seconds (reports, plant-time fallbacks).
inline double seconds(Link::Time t) {
  return std::chrono::duration<double>(t).count();
}

}  // namespace fpgacnc::link
