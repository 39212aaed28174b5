// Fault injection on the simulated serial line (host <-> simulated board), for testing the
// host's v2 streamer (retransmission, resynchronisation) against a real RTL decoder.
//
// Faults (all off by default; every random decision comes from a seeded generator, one
// independent stream per fault kind, so a run is reproducible and changing one rate does not
// change the pattern of another):
//   - host -> board, per host byte, in this order: dropped (`drop`: the byte never reaches the
//     line); duplicated (`dup`: the byte goes on the line twice); each copy then has each of its
//     10 UART bits (start, 8 data, stop) flipped with probability `ber_to_board` before it
//     reaches the core's rx pin. A flipped start bit leaves the line high (the receiver then
//     takes the next 0 bit as a start bit), a flipped stop bit is a framing error, a flipped
//     data bit gives a different byte.
//   - board -> host, per byte decoded from the core's tx pin: device frames are delimited by
//     the v2 framing (0xA5, LEN, then 4 + LEN more bytes; LEN > 64 ends the frame at the LEN
//     byte; any other byte between frames, e.g. v1's 0xAA, is a one-byte frame). A whole frame
//     is lost (every byte of it dropped: "lost ACKs") with probability `lose_frames`, decided at
//     its first byte. The bytes that are delivered then have each of their 8 data bits flipped
//     with probability `ber_to_host`.
//   - stalls of the host -> board line: the line stays idle (high) for `clocks` simulated clocks
//     while the board keeps running. Trigger kCycle: the line is held during [at, at + clocks);
//     a byte that would start in that window starts at at + clocks (the ones queued behind it
//     follow back to back); a byte that starts later is not delayed. Trigger kBytes: the frame
//     with index `at` on the line (0-based, counting frames after drops and duplicates, i.e.
//     after `at` frames have been sent) starts exactly `clocks` later than it would have.
//     A held line counts as activity, so simulated time keeps advancing during a stall.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace fpgacnc::simboard {

struct LineStall {
  enum class Trigger : uint8_t { kCycle, kBytes };
  Trigger trigger = Trigger::kCycle;
  uint64_t at = 0;      // cycle (kCycle) or frame index on the line (kBytes)
  uint64_t clocks = 0;  // hold duration, simulated clocks (> 0); 200 ms = 10 000 000 at 50 MHz
};

struct LineFaults {
  uint64_t seed = 1;
  double ber_to_board = 0.0;  // per UART bit (10 per byte), host -> board
  double ber_to_host = 0.0;   // per data bit (8 per byte), board -> host
  double drop = 0.0;          // per host byte
  double dup = 0.0;           // per host byte (not dropped)
  double lose_frames = 0.0;   // per device frame
  std::vector<LineStall> stalls;
  // Keep a record of every frame put on the rx line and every byte decoded from tx (tests;
  // grows with the traffic).
  bool log = false;

  bool any() const {
    return ber_to_board > 0 || ber_to_host > 0 || drop > 0 || dup > 0 || lose_frames > 0 ||
           !stalls.empty();
  }
  // Throws std::invalid_argument for a probability outside [0, 1] or a stall of 0 clocks.
  void validate() const;
  // One line, e.g. "seed 1, BER to board 1e-04, drop 0.001, stall at cycle 5000 for 10000000
  // clocks"; "none" when no fault is enabled.
  std::string describe() const;
};

// Counters of every injected fault (BoardStats::line).
struct LineFaultStats {
  uint64_t bytes_to_board = 0;           // host bytes offered to the line
  uint64_t frames_to_board = 0;          // UART frames started on rx (after drops, duplicates)
  uint64_t bytes_dropped = 0;            // host -> board
  uint64_t bytes_duplicated = 0;         // host -> board
  uint64_t bits_flipped_to_board = 0;    // UART bits flipped on rx
  uint64_t frames_flipped_to_board = 0;  // rx frames with at least one flipped bit
  uint64_t bytes_from_board = 0;         // bytes decoded from tx
  uint64_t device_frames = 0;            // device frames seen on tx (v2 frames, single bytes)
  uint64_t device_frames_lost = 0;
  uint64_t device_bytes_lost = 0;
  uint64_t bits_flipped_to_host = 0;   // data bits flipped in delivered bytes
  uint64_t bytes_flipped_to_host = 0;  // delivered bytes with at least one flipped bit
  uint64_t stalls = 0;                 // stalls that held at least one byte back
  uint64_t stall_clocks = 0;           // clocks bytes were held back, total
  uint64_t injected() const {
    return bytes_dropped + bytes_duplicated + frames_flipped_to_board + device_frames_lost +
           bytes_flipped_to_host + stalls;
  }
};
// "dropped 3, duplicated 2, rx frames corrupted 5 (6 bits), device frames lost 1/40 (13 bytes),
// tx bytes corrupted 2 (2 bits), stalls 1 (10000000 clocks)".
std::string describe(const LineFaultStats& s);

// One UART frame for the rx line: the byte, the bits to invert (bit 0 start, bits 1..8 data
// LSB first, bit 9 stop) and whether it is the duplicate copy of the previous host byte.
struct LineFrame {
  uint8_t byte = 0;
  uint16_t flip = 0;
  bool duplicate = false;
};

// Log entries (LineFaults::log).
struct RxFrameRecord {
  uint64_t start_cycle = 0;  // cycle at which the start bit (or the flipped start bit) is driven
  uint64_t held = 0;         // clocks this frame was held back by a stall
  LineFrame frame;
};
struct TxByteRecord {
  uint64_t cycle = 0;  // cycle at which the stop bit was sampled
  uint8_t byte = 0;    // as sent by the core
  uint8_t delivered = 0;
  bool lost = false;
};

// The random part of the injection, independent of the model (unit-testable).
class LineFaultInjector {
 public:
  explicit LineFaultInjector(const LineFaults& faults);
  const LineFaults& faults() const { return f_; }
  // Host -> board: appends the frames that go on the line for `byte` (none, one or two).
  void to_board(uint8_t byte, std::vector<LineFrame>& out);
  // Board -> host: appends the byte to deliver to the host (nothing when its frame is lost).
  void to_host(uint8_t byte, uint64_t cycle, std::vector<uint8_t>& out);
  // Called by the rx line when a frame is about to start at `cycle` (it is the
  // `frame_index`-th frame): clocks to hold the line first (0: none).
  uint64_t hold_before_frame(uint64_t cycle, uint64_t frame_index);
  // Called by the rx line when a frame starts.
  void frame_started(const LineFrame& frame, uint64_t cycle, uint64_t held);

  const LineFaultStats& stats() const { return st_; }
  const std::vector<RxFrameRecord>& rx_log() const { return rx_log_; }
  const std::vector<TxByteRecord>& tx_log() const { return tx_log_; }

 private:
  class Rng {
   public:
    explicit Rng(uint64_t seed) : s_(seed) {}
    uint64_t next();
    bool chance(double p);

   private:
    uint64_t s_;
  };
  LineFaults f_;
  Rng r_drop_, r_dup_, r_ber_board_, r_ber_host_, r_lose_;
  std::vector<bool> stall_done_;
  // Device frame tracker on tx.
  enum class TxState : uint8_t { kIdle, kLen, kBody } tx_state_ = TxState::kIdle;
  uint32_t tx_remaining_ = 0;
  bool tx_losing_ = false;
  LineFaultStats st_;
  std::vector<RxFrameRecord> rx_log_;
  std::vector<TxByteRecord> tx_log_;
};

// The host -> board line: UART frames (8N1, LSB first, idle high) with the bit timing of
// models::UartDriver (bit i starts round(i * clk_hz / baud) clocks after the start bit), the
// injector's bit flips and stalls. tick(cycle) gives the rx level for `cycle`.
class RxLine {
 public:
  RxLine(double clk_hz, double baud, LineFaultInjector* injector)
      : clocks_per_bit_(clk_hz / baud), inj_(injector) {}
  void push(const LineFrame& f) { queue_.push_back(f); }
  void push(uint8_t byte) { queue_.push_back(LineFrame{byte, 0, false}); }
  bool idle() const { return !active_ && !holding_ && queue_.empty(); }
  size_t pending() const { return queue_.size() + (active_ ? 1 : 0); }
  uint64_t frames_started() const { return frames_; }

  int tick(uint64_t cycle) {
    if (!active_) {
      if (queue_.empty()) return 1;
      if (!holding_) {
        hold_until_ = cycle;
        if (inj_) {
          const uint64_t h = inj_->hold_before_frame(cycle, frames_);
          hold_until_ = cycle + h;
          held_ = h;
        }
        holding_ = true;
      }
      if (cycle < hold_until_) return 1;
      holding_ = false;
      cur_ = queue_.front();
      queue_.pop_front();
      active_ = true;
      clock_in_frame_ = 0;
      if (inj_) inj_->frame_started(cur_, cycle, held_);
      held_ = 0;
      ++frames_;
    }
    const uint64_t c = clock_in_frame_++;
    const int bit = static_cast<int>((static_cast<double>(c) + 0.5) / clocks_per_bit_);
    int level;
    if (bit == 0) {
      level = 0;
    } else if (bit <= 8) {
      level = (cur_.byte >> (bit - 1)) & 1;
    } else {
      level = 1;
    }
    if (bit <= 9) level ^= (cur_.flip >> bit) & 1;
    if (static_cast<double>(clock_in_frame_) + 0.5 >= 10.0 * clocks_per_bit_) active_ = false;
    return level;
  }

 private:
  double clocks_per_bit_;
  LineFaultInjector* inj_;
  std::deque<LineFrame> queue_;
  LineFrame cur_{};
  bool active_ = false;
  bool holding_ = false;
  uint64_t hold_until_ = 0;
  uint64_t held_ = 0;
  uint64_t clock_in_frame_ = 0;
  uint64_t frames_ = 0;
};

}  // namespace fpgacnc::simboard
