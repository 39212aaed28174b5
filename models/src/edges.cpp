#include "fpgacnc/models/edges.h"

#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <stdexcept>

namespace fpgacnc::models {

std::string signal_name(uint8_t signal) {
  static constexpr char kAxis[] = {'x', 'y', 'z', 'e'};
  if (signal < 4) return fmt::format("step_{}", kAxis[signal]);
  if (signal < 8) return fmt::format("dir_{}", kAxis[signal - 4]);
  if (signal == kLaser) return "laser";
  if (signal == kTx) return "tx";
  if (signal == kRx) return "rx";
  if (signal == kFlood) return "coolant_flood";
  if (signal == kMist) return "coolant_mist";
  if (signal == kFan) return "fan";
  if (signal >= kDout0 && signal < kDout0 + 4) return fmt::format("dout{}", signal - kDout0);
  if (signal == kSpindlePwm) return "spindle_pwm";
  return fmt::format("signal{}", signal);
}

std::array<int64_t, kBoardAxes> net_steps(std::span<const Edge> edges) {
  std::array<int64_t, kBoardAxes> n{};
  uint32_t dir = 0;
  for (const Edge& e : edges) {
    if (e.signal >= kDir0 && e.signal < kDir0 + kBoardAxes) {
      const uint32_t bit = 1u << (e.signal - kDir0);
      dir = e.value ? (dir | bit) : (dir & ~bit);
    } else if (e.signal < kBoardAxes && e.value) {
      n[e.signal] += (dir >> e.signal) & 1u ? 1 : -1;
    }
  }
  return n;
}

std::array<uint64_t, kBoardAxes> step_pulses(std::span<const Edge> edges) {
  std::array<uint64_t, kBoardAxes> n{};
  for (const Edge& e : edges) {
    if (e.signal < kBoardAxes && e.value) ++n[e.signal];
  }
  return n;
}

std::vector<Interval> high_intervals(std::span<const Edge> edges, uint8_t signal,
                                     uint64_t end_cycle) {
  std::vector<Interval> out;
  bool high = false;
  uint64_t begin = 0;
  for (const Edge& e : edges) {
    if (e.signal != signal) continue;
    if (e.value && !high) {
      high = true;
      begin = e.cycle;
    } else if (!e.value && high) {
      high = false;
      out.push_back(Interval{begin, e.cycle});
    }
  }
  if (high) out.push_back(Interval{begin, end_cycle});
  return out;
}

void write_edges_csv(const std::string& path, std::span<const Edge> edges, double clk_hz) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "w"), &std::fclose);
  if (!f) throw std::runtime_error(fmt::format("{}: error: cannot create file", path));
  std::string buf = "cycle,time_s,signal,value\n";
  for (const Edge& e : edges) {
    fmt::format_to(std::back_inserter(buf), "{},{:.9f},{},{}\n", e.cycle,
                   static_cast<double>(e.cycle) / clk_hz, signal_name(e.signal), e.value);
    if (buf.size() > (1u << 16)) {
      std::fwrite(buf.data(), 1, buf.size(), f.get());
      buf.clear();
    }
  }
  std::fwrite(buf.data(), 1, buf.size(), f.get());
  if (std::ferror(f.get())) throw std::runtime_error(fmt::format("{}: error: write error", path));
}

}  // namespace fpgacnc::models
