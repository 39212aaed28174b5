// StepMonitor: records STEP/DIR pin activity of N axes, one sample per clock, and checks the
// pulse rules (STEP high exactly `high` clocks, low at least `low`, DIR stable `setup` clocks
// before and `hold` clocks after every STEP rising edge).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace fpgacnc::tb {

struct AxisTiming {
  uint32_t high = 100, low = 100, setup = 200, hold = 200;
};

struct AxisTrace {
  std::vector<uint64_t> rises;      // cycles at which STEP was first seen high
  std::vector<uint64_t> falls;      // cycles at which STEP was first seen low again
  std::vector<int> rise_dir;        // DIR level at each rise
  std::vector<uint64_t> dir_edges;  // cycles at which DIR was first seen at a new level
  int64_t position = 0;             // +1 per rise with DIR high, -1 with DIR low
};

class StepMonitor {
 public:
  explicit StepMonitor(int axes) : axes_(axes), trace_(static_cast<size_t>(axes)) {}

  // Pin levels seen after the clock edge numbered `cycle`.
  void sample(uint64_t cycle, uint32_t step_bits, uint32_t dir_bits) {
    if (first_) {
      prev_step_ = step_bits;
      prev_dir_ = dir_bits;
      first_ = false;
      return;
    }
    const uint32_t step_changed = step_bits ^ prev_step_;
    const uint32_t dir_changed = dir_bits ^ prev_dir_;
    if (step_changed | dir_changed) {
      for (int a = 0; a < axes_; ++a) {
        AxisTrace& t = trace_[static_cast<size_t>(a)];
        const uint32_t m = 1u << a;
        if (dir_changed & m) t.dir_edges.push_back(cycle);
        if (step_changed & m) {
          if (step_bits & m) {
            t.rises.push_back(cycle);
            const int d = (dir_bits & m) ? 1 : 0;
            t.rise_dir.push_back(d);
            t.position += d ? 1 : -1;
          } else {
            t.falls.push_back(cycle);
          }
        }
      }
    }
    prev_step_ = step_bits;
    prev_dir_ = dir_bits;
  }

  const AxisTrace& axis(int a) const { return trace_[static_cast<size_t>(a)]; }
  AxisTrace& axis(int a) { return trace_[static_cast<size_t>(a)]; }
  int axes() const { return axes_; }

  // Checks the pulse rules for one axis on the rising edges in cycles [from, to); returns
  // human-readable violations (empty = pass).
  std::vector<std::string> check_pulses(int a, const AxisTiming& t, uint64_t from = 0,
                                        uint64_t to = UINT64_MAX) const {
    std::vector<std::string> bad;
    const AxisTrace& tr = axis(a);
    for (size_t i = 0; i < tr.rises.size(); ++i) {
      if (tr.rises[i] < from || tr.rises[i] >= to) continue;
      if (i < tr.falls.size()) {
        const uint64_t h = tr.falls[i] - tr.rises[i];
        if (h != t.high)
          bad.push_back(fmt::format("axis {}: STEP high {} clocks at cycle {}, expected {}", a, h,
                                    tr.rises[i], t.high));
      }
      if (i > 0 && i - 1 < tr.falls.size()) {
        const uint64_t l = tr.rises[i] - tr.falls[i - 1];
        if (l < t.low)
          bad.push_back(fmt::format("axis {}: STEP low {} clocks before cycle {}, expected >= {}",
                                    a, l, tr.rises[i], t.low));
      }
    }
    // DIR setup/hold around every rising edge: no DIR edge in (rise - setup, rise + hold).
    size_t d = 0;
    for (uint64_t r : tr.rises) {
      if (r < from || r >= to) continue;
      while (d < tr.dir_edges.size() && tr.dir_edges[d] + t.setup <= r) ++d;
      // dir_edges[d] > r - setup (or none)
      if (d < tr.dir_edges.size() && tr.dir_edges[d] < r + t.hold)
        bad.push_back(fmt::format(
            "axis {}: DIR edge at cycle {} within setup {} / hold {} of STEP rise at {}", a,
            tr.dir_edges[d], t.setup, t.hold, r));
    }
    return bad;
  }

 private:
  int axes_;
  std::vector<AxisTrace> trace_;
  uint32_t prev_step_ = 0, prev_dir_ = 0;
  bool first_ = true;
};

}  // namespace fpgacnc::tb
