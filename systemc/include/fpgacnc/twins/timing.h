// Cycle arithmetic of the cnc_core blocks, from docs/timing.md, docs/protocol.md and the block
// contracts in docs/architecture.md. Pure integer functions, shared by the twins and their unit
// tests; nothing here is clocked. A "cycle" is a rising clock edge numbered from the end of
// reset and configuration (cycle 0); an event "at cycle c" is a register that changes on edge c.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>

namespace fpgacnc::twins {

using Cycle = int64_t;
inline constexpr int kAxes = 4;  // cnc_core N_AXES

// ceil(a / b) for a >= 0 (or small negative a), b > 0, in 128 bits.
inline constexpr int64_t ceil_div(__int128 a, __int128 b) {
  if (a <= 0) return static_cast<int64_t>(-((-a) / b));
  return static_cast<int64_t>((a + b - 1) / b);
}

// Step timing of one axis, in clocks (cfg port fields 0..3).
struct AxisTiming {
  uint32_t high = 100, low = 100, setup = 200, hold = 200;
};

// cnc_core parameters (docs/architecture.md "Parameters") plus the runtime step timing.
struct CoreParams {
  uint64_t clk_hz = 50'000'000;
  uint64_t baud = 115'200;
  uint64_t watchdog_clks = 5'000'000;
  uint32_t feed0_period = 62'500;
  uint32_t default_numerator = 18'750'000;
  std::array<AxisTiming, kAxes> timing{};

  // The executor's minimum period: max over axes of STEP high + STEP low, a setting of 0 counting
  // as 1 clock as in the pulse generator (docs/timing.md "Segment length").
  uint32_t min_period() const {
    uint32_t m = 0;
    for (const auto& t : timing)
      m = std::max(
          m, std::max<uint32_t>(t.high & 0xffffu, 1) + std::max<uint32_t>(t.low & 0xffffu, 1));
    return std::max<uint32_t>(m, 2);
  }
};

// The fractional bit timer of uart_rx / uart_tx (docs/protocol.md "Physical"): an accumulator
// that adds INC = BAUD/g per clock modulo MOD = CLK_HZ/g, g = gcd; a bit tick is a wrap.
struct BitTimer {
  int64_t mod, inc;
  BitTimer(uint64_t clk_hz, uint64_t baud) {
    const uint64_t g = std::gcd(clk_hz, baud);
    mod = static_cast<int64_t>(clk_hz / g);
    inc = static_cast<int64_t>(baud / g);
  }
  // Receiver: the accumulator is preloaded with (MOD + INC) / 2 on the start-detection edge;
  // tick m (m = 1 checks the start bit, m = 10 samples the stop bit) falls this many clocks
  // later.
  int64_t rx_tick(int m) const {
    const int64_t half = (mod + inc) / 2;
    return ceil_div(static_cast<__int128>(m) * mod - half, inc);
  }
  // Transmitter: boundary m of a stream (m = 10 k + i is bit i of its k-th back-to-back frame)
  // lies ceil(m * MOD / INC) clocks after the stream's first start edge.
  int64_t tx_boundary(int64_t m) const { return ceil_div(static_cast<__int128>(m) * mod, inc); }
};

// The host-side UART sender used by every harness (tb/common/uart_bits.h UartDriver in integer
// form): bit i of a frame starts round(i * CLK_HZ / BAUD) clocks (halves down) after the start
// edge; a frame is 10 bits and frames of a packet follow back to back.
struct SenderTiming {
  uint64_t clk_hz, baud;
  int64_t boundary(int i) const {
    if (i <= 0) return 0;
    return ceil_div(static_cast<__int128>(2) * i * clk_hz - baud, 2 * static_cast<int64_t>(baud));
  }
  int64_t frame() const { return boundary(10); }
  // Level of the line `offset` clocks after the start edge of a frame carrying `byte`
  // (start 0, data LSB first, stop 1; 1 after the frame).
  int level(uint8_t byte, int64_t offset) const {
    int bit = 0;
    while (bit < 10 && boundary(bit + 1) <= offset) ++bit;
    if (bit == 0) return 0;
    if (bit <= 8) return (byte >> (bit - 1)) & 1;
    return 1;
  }
};

// segment_prep (docs/timing.md "Segment length"): dominant period and length.
struct PreparedTiming {
  bool x_dominant;
  uint32_t period;  // P
  uint64_t total;   // T = P * N
};
inline PreparedTiming prepare_timing(uint32_t abs_x, uint32_t abs_y, uint32_t num_x, uint32_t num_y,
                                     uint16_t feed, uint32_t feed0_period, uint32_t min_period) {
  PreparedTiming r{};
  r.x_dominant = abs_x >= abs_y;
  const uint32_t num = r.x_dominant ? num_x : num_y;
  const uint32_t n = r.x_dominant ? abs_x : abs_y;
  const uint32_t p = feed == 0 ? feed0_period : num / feed;
  r.period = std::max(p, min_period);
  r.total = static_cast<uint64_t>(r.period) * n;
  return r;
}

// dda_linear (docs/timing.md "Steps"): the k-th step (k = 1..n) of an axis with n steps over
// T ticks falls on tick ceil(k * T / n).
inline int64_t dda_tick(uint64_t k, uint64_t n, uint64_t total) {
  return ceil_div(static_cast<__int128>(k) * total, n);
}

}  // namespace fpgacnc::twins
