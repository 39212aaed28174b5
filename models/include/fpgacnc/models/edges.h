// The board's pins as an edge list, shared by the simulated board (the Verilated core), the twins
// and the co-simulations: every change of STEP[n], DIR[n], LASER, the machine outputs (and, when
// asked, TX, RX) with the clock cycle at which the board drove it (RX: at which the line drove the
// core's rx pin).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace fpgacnc::models {

inline constexpr int kBoardAxes = 4;  // cnc_core N_AXES (X, Y, Z, E); v1 drives X and Y

// Signal numbers: STEP[n] = n, DIR[n] = 4 + n, LASER = 8, TX = 9, RX = 10, the machine outputs
// (OUTPUT frames; recorded by the co-simulation) COOLANT_FLOOD = 11, COOLANT_MIST = 12, FAN = 13,
// DOUT[n] = 14 + n, and the laser / spindle PWM SPINDLE_PWM = 18.
enum Signal : uint8_t {
  kStep0 = 0,
  kDir0 = 4,
  kLaser = 8,
  kTx = 9,
  kRx = 10,
  kFlood = 11,
  kMist = 12,
  kFan = 13,
  kDout0 = 14,
  kSpindlePwm = 18,
  kSignalCount = 19,
};
inline constexpr uint8_t step_signal(int axis) {
  return static_cast<uint8_t>(kStep0 + axis);
}
inline constexpr uint8_t dir_signal(int axis) {
  return static_cast<uint8_t>(kDir0 + axis);
}
// "step_x", "dir_y", "laser", "tx", "rx", "coolant_flood", "coolant_mist", "fan", "dout0",
// "spindle_pwm".
std::string signal_name(uint8_t signal);

// 16 bytes: (cycle, signal, new value). `cycle` counts rising clock edges since reset release.
struct Edge {
  uint64_t cycle;
  uint8_t signal;
  uint8_t value;
};

// A half-open interval of cycles [begin, end) where a signal was high.
struct Interval {
  uint64_t begin;
  uint64_t end;
};

// Net steps per axis: each STEP rise counts +1 when DIR of that axis is high at that cycle
// (DIR is set up before the STEP edge), -1 when low.
std::array<int64_t, kBoardAxes> net_steps(std::span<const Edge> edges);
// Number of rising edges of STEP per axis.
std::array<uint64_t, kBoardAxes> step_pulses(std::span<const Edge> edges);
// High intervals of `signal`; one still open at the end gets end = `end_cycle`.
std::vector<Interval> high_intervals(std::span<const Edge> edges, uint8_t signal,
                                     uint64_t end_cycle);
// CSV: "cycle,time_s,signal,value" (time = cycle / clk_hz). Throws std::runtime_error naming
// the file when it cannot be written.
void write_edges_csv(const std::string& path, std::span<const Edge> edges, double clk_hz);

// Growing edge list (reserve up front; push_back only on a change, so the hot loop pays one
// compare per clock).
class EdgeRecorder {
 public:
  explicit EdgeRecorder(size_t reserve = 1u << 20) { edges_.reserve(reserve); }
  void add(uint64_t cycle, uint8_t signal, uint8_t value) {
    edges_.push_back(Edge{cycle, signal, value});
  }
  void add_move_done(uint64_t cycle) { move_done_.push_back(cycle); }
  const std::vector<Edge>& edges() const { return edges_; }
  // Cycles of the core's seg_done strobes (one per completed move, in order).
  const std::vector<uint64_t>& move_done_cycles() const { return move_done_; }
  std::array<int64_t, kBoardAxes> net_steps() const { return models::net_steps(edges_); }
  void write_csv(const std::string& path, double clk_hz) const {
    write_edges_csv(path, edges_, clk_hz);
  }
  void clear() {
    edges_.clear();
    move_done_.clear();
  }

 private:
  std::vector<Edge> edges_;
  std::vector<uint64_t> move_done_;
};

}  // namespace fpgacnc::models
