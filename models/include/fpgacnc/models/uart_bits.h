// UART bit-level driver and monitor for Verilated benches and the simulated board.
//
// UartDriver turns bytes into an rx pin level per clock (8N1, LSB first, idle high).
// Bit boundaries are placed at round(i * clk_hz / baud) clocks from the start bit, so the
// average bit time is exact even when clk_hz / baud is not an integer. A rate factor lets a
// bench model a sender that is a few percent fast or slow.
//
// UartMonitor samples a tx pin once per clock and reassembles bytes: it finds the falling
// start edge, samples each bit at its centre and checks the stop bit.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>

namespace fpgacnc::models {

class UartDriver {
 public:
  // rate > 1.0 means the sender is fast (shorter bits).
  UartDriver(double clk_hz, double baud, double rate = 1.0)
      : clocks_per_bit_(clk_hz / (baud * rate)) {}

  void push(uint8_t byte) { queue_.push_back(Frame{byte, true}); }
  // Queue a byte whose stop bit is driven low (framing error).
  void push_bad_stop(uint8_t byte) { queue_.push_back(Frame{byte, false}); }
  bool idle() const { return !active_ && queue_.empty(); }
  size_t pending() const { return queue_.size() + (active_ ? 1 : 0); }
  void set_rate(double clk_hz, double baud, double rate = 1.0) {
    clocks_per_bit_ = clk_hz / (baud * rate);
  }

  // Level of the line for the next clock; advances by one clock.
  int tick() {
    if (!active_) {
      if (queue_.empty()) return 1;
      cur_ = queue_.front();
      queue_.pop_front();
      active_ = true;
      clock_in_frame_ = 0;
    }
    const uint64_t c = clock_in_frame_++;
    // bit index = floor((c + 0.5) / clocks_per_bit) gives boundaries at round(i * cpb).
    const int bit = static_cast<int>((static_cast<double>(c) + 0.5) / clocks_per_bit_);
    int level;
    if (bit == 0) {
      level = 0;
    } else if (bit <= 8) {
      level = (cur_.byte >> (bit - 1)) & 1;
    } else {
      level = cur_.good_stop ? 1 : 0;
    }
    // Frame ends after 10 bits.
    if (static_cast<double>(clock_in_frame_) + 0.5 >= 10.0 * clocks_per_bit_) active_ = false;
    return level;
  }

 private:
  struct Frame {
    uint8_t byte;
    bool good_stop;
  };
  double clocks_per_bit_;
  std::deque<Frame> queue_;
  Frame cur_{0, true};
  bool active_ = false;
  uint64_t clock_in_frame_ = 0;
};

class UartMonitor {
 public:
  UartMonitor(double clk_hz, double baud) : clocks_per_bit_(clk_hz / baud) {}

  struct Byte {
    uint8_t value;
    uint64_t start_cycle;  // cycle of the falling start edge
    bool framing_ok;
  };

  // Feed the pin level sampled at `cycle`; returns a byte when its stop bit has been sampled.
  std::optional<Byte> sample(int level, uint64_t cycle) {
    if (!busy_) {
      if (prev_ == 1 && level == 0) {
        busy_ = true;
        start_ = cycle;
        bits_ = 0;
        next_bit_ = 0;
      }
      prev_ = level;
      return std::nullopt;
    }
    prev_ = level;
    const double centre = (next_bit_ + 0.5) * clocks_per_bit_;
    if (static_cast<double>(cycle - start_) >= centre) {
      if (next_bit_ == 0) {
        if (level != 0) {  // glitch, not a start bit
          busy_ = false;
          return std::nullopt;
        }
      } else if (next_bit_ <= 8) {
        bits_ |= static_cast<uint8_t>(level << (next_bit_ - 1));
      } else {
        busy_ = false;
        return Byte{bits_, start_, level == 1};
      }
      ++next_bit_;
    }
    return std::nullopt;
  }
  bool busy() const { return busy_; }

 private:
  double clocks_per_bit_;
  bool busy_ = false;
  int prev_ = 1;
  uint64_t start_ = 0;
  int next_bit_ = 0;
  uint8_t bits_ = 0;
};

}  // namespace fpgacnc::models
