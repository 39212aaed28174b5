// Cycle arithmetic of the cnc_core blocks, from docs/timing.md, docs/protocol.md and the block
// contracts in docs/architecture.md. Pure integer functions, shared by the twins and their unit
// tests; nothing here is clocked. A "cycle" is a rising clock edge numbered from the end of
// reset and configuration (cycle 0); an event "at cycle c" is a register that changes on edge c.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "fpgacnc/models/ramp.h"
#include "fpgacnc/spec.h"

namespace fpgacnc::twins {

using Cycle = int64_t;
inline constexpr int kAxes = static_cast<int>(spec::kDefaultNAxes);  // cnc_core N_AXES

// ceil(a / b) for a >= 0 (or small negative a), b > 0, in 128 bits.
inline constexpr int64_t ceil_div(__int128 a, __int128 b) {
  constexpr __int128 k63 = static_cast<__int128>(1) << 63;
  if (a > 0 && a < k63 && b < k63) {  // 64-bit division (the usual operands)
    const auto ua = static_cast<uint64_t>(a), ub = static_cast<uint64_t>(b);
    return static_cast<int64_t>(ua / ub + (ua % ub != 0));
  }
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
  // Fan PWM (cnc_core FAN_PWM_HZ): 256 counts of fan_div() clocks; the PWM counts from the reset
  // release, fan_phase clocks before cycle 0 (the RTL harness: release edge, 16 cfg writes, 4
  // settle edges).
  uint32_t fan_pwm_hz = 1000;
  int64_t fan_phase = 21;
  // The motion rate (rtl/motion/feed_rate.v, feed_rate.h) starts its period counter p and its
  // phase accumulator at the reset release, rate_phase clocks before cycle 0 (as the fan's PWM).
  int64_t rate_phase = 21;
  // The hold and cycle-start inputs' filter (cnc_core LIMIT_FILTER_CLKS, input_filter.v).
  uint32_t button_filter_clks = spec::kDefaultLimitFilterClks;
  uint32_t fan_div() const {
    return static_cast<uint32_t>((clk_hz + 128 * fan_pwm_hz) / (256 * fan_pwm_hz));
  }
  // Laser / spindle PWM (cnc_core LASER_PWM_HZ, rtl/machine/laser_pwm.v): 256 counts of
  // laser_div() clocks, periods started laser_lat + 1 clocks after the laser pin rises.
  uint32_t laser_pwm_hz = spec::kDefaultLaserPwmHz;
  uint32_t laser_lat = spec::kDefaultLaserScaleClks;
  uint32_t laser_div() const {
    return static_cast<uint32_t>((clk_hz + 128 * laser_pwm_hz) / (256 * laser_pwm_hz));
  }

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

// The host-side UART sender used by every harness (models/include/fpgacnc/models/uart_bits.h
// UartDriver in integer form): bit i of a frame starts round(i * CLK_HZ / BAUD) clocks (halves
// down) after the start edge; a frame is 10 bits and frames of a packet follow back to back.
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
// The same ticks for k = 1, 2, ..., n in turn, without a division per step: k T = q n + r.
class DdaTicks {
 public:
  DdaTicks(uint64_t n, uint64_t total)
      : n_(n), qt_(n == 0 ? 0 : total / n), rt_(n == 0 ? 0 : total % n) {}
  uint64_t next() {
    q_ += qt_;
    r_ += rt_;
    if (r_ >= n_) {
      r_ -= n_;
      ++q_;
    }
    return q_ + (r_ != 0);
  }

 private:
  uint64_t n_, qt_, rt_, q_ = 0, r_ = 0;
};

// ---- protocol v2 (docs/protocol.md "v2") -------------------------------------------------------

// CRC-16/CCITT-FALSE: polynomial 0x1021, initial 0xFFFF, no reflection, no final XOR ("123456789"
// gives 0x29B1). Bitwise, MSB first.
inline uint16_t crc16_ccitt(const uint8_t* data, size_t n, uint16_t crc = 0xFFFF) {
  for (size_t i = 0; i < n; ++i) {
    crc = static_cast<uint16_t>(crc ^ (static_cast<uint16_t>(data[i]) << 8));
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint16_t>((crc & 0x8000u) ? (crc << 1) ^ 0x1021u : crc << 1);
  }
  return crc;
}

namespace v2 {
// The numbers come from spec/protocol.toml (fpgacnc/spec.h, generated).
inline constexpr uint8_t kSync = spec::kSync;
inline constexpr int kMaxPayload = static_cast<int>(spec::kMaxPayload);
inline constexpr int kFifoDepth = static_cast<int>(spec::kDefaultFifoDepth);
inline constexpr uint32_t kBuildId = spec::kBuildId;
// Host -> device types.
inline constexpr uint8_t kHello = spec::kTypeHello, kStatusQuery = spec::kTypeStatusQuery,
                         kFaultClear = spec::kTypeFaultClear, kConfigAxis = spec::kTypeConfigAxis,
                         kConfigTravel = spec::kTypeConfigTravel,
                         kNumerators = spec::kTypeNumerators, kRelease = spec::kTypeRelease,
                         kLine = spec::kTypeLine, kDwell = spec::kTypeDwell,
                         kLineProfile = spec::kTypeLineProfile, kArc = spec::kTypeArc,
                         kOutput = spec::kTypeOutput;
inline constexpr uint8_t kHeaterConfig = spec::kTypeHeaterConfig,
                         kHeaterSetpoint = spec::kTypeHeaterSetpoint,
                         kThermistorTable = spec::kTypeThermistorTable,
                         kHeaterSafety = spec::kTypeHeaterSafety,
                         kHeaterWatchdog = spec::kTypeHeaterWatchdog;
// Device -> host types.
inline constexpr uint8_t kAck = spec::kTypeAck, kNak = spec::kTypeNak, kDone = spec::kTypeDone,
                         kStatus = spec::kTypeStatus, kIdent = spec::kTypeIdent;
// NAK reasons.
inline constexpr uint8_t kBadCrc = spec::kNakBadCrc, kBadLength = spec::kNakBadLength,
                         kUnknownType = spec::kNakUnknownType, kTimeout = spec::kNakTimeout,
                         kOutOfOrder = spec::kNakOutOfOrder, kFifoFull = spec::kNakFifoFull,
                         kBadField = spec::kNakBadField, kTravel = spec::kNakTravel;
// STATUS counters (payload order).
enum Counter : int {
  kFramesOk = spec::kCounterFramesOk,
  kCrcErrors = spec::kCounterCrcErrors,
  kLengthErrors = spec::kCounterLengthErrors,
  kUnknownTypes = spec::kCounterUnknownTypes,
  kTimeouts = spec::kCounterTimeouts,
  kFramingErrors = spec::kCounterUartFramingErrors,
  kOverruns = spec::kCounterOverruns,
  kNoiseBytes = spec::kCounterNoiseBytes,
  kClamped = spec::kCounterClamped,
  kCounters = spec::kCounters
};
inline constexpr int kStatusPayload =
    static_cast<int>(spec::kLenStatusHeader + spec::kLenStatusPerAxis * kAxes);
}  // namespace v2

// SEQ relative to the device's next_seq (docs/protocol.md "Sequence numbers").
enum class SeqClass { Accept, Duplicate, Ahead };
inline SeqClass classify_seq(uint8_t seq, uint8_t next_seq) {
  const uint8_t d = static_cast<uint8_t>(seq - next_seq);
  if (d == 0) return SeqClass::Accept;
  if (d >= 128) return SeqClass::Duplicate;  // next_seq - 1 .. next_seq - 128
  return SeqClass::Ahead;
}

// segment_prep for a v2 LINE (docs/protocol.md "LINE"): the segment lasts T clocks; the dominant
// axis has n_dom = max |steps|; T is raised to n_dom * min_period when T / n_dom is smaller.
struct V2Timing {
  uint32_t n_dom;
  uint32_t period;  // floor(T / n_dom) after the clamp (0 without steps)
  uint64_t total;
  bool clamped;
};
inline V2Timing prepare_v2(const std::array<uint32_t, kAxes>& abs_steps, uint32_t t,
                           uint32_t min_period) {
  V2Timing r{0, 0, t, false};
  for (uint32_t n : abs_steps) r.n_dom = std::max(r.n_dom, n);
  if (r.n_dom == 0) return r;
  r.period = t / r.n_dom;
  if (r.period < min_period) {
    r.total = static_cast<uint64_t>(r.n_dom) * min_period;
    r.period = min_period;
    r.clamped = true;
  }
  return r;
}

// "dir_fast": a reversing axis can change DIR during the previous segment's run when the
// segment's first step of every reversing axis comes at least DIR hold + DIR setup after its
// start. Every ceil(k T / n_a) >= floor(T / n_dom) = period, so period >= hold + setup (0
// settings counting as 1) for every reversing moving axis is enough.
inline bool dir_fast(const std::array<bool, kAxes>& reversing,
                     const std::array<AxisTiming, kAxes>& timing, uint64_t period) {
  for (int a = 0; a < kAxes; ++a) {
    if (!reversing[a]) continue;
    const uint64_t need = std::max<uint32_t>(timing[a].hold & 0xffffu, 1) +
                          std::max<uint32_t>(timing[a].setup & 0xffffu, 1);
    if (period < need) return false;
  }
  return true;
}

// ---- LINE_PROFILE (docs/timing.md "Profiled segments", docs/protocol.md "LINE_PROFILE") --------

// The frame's profile fields: V in 2^-48 dominant steps per clock (< 2^47), A in 2^-48 steps per
// clock^2, D the dominant step count at which deceleration starts.
struct ProfileParams {
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;
  uint32_t accel = 0, decel_at = 0;
};
inline constexpr uint8_t kOpInc = 0, kOpDec = 1, kOpCru = 2, kOpExit = 3;

// One master update (profile_gen): the velocity of the next clock from V and whether the path
// position after this clock has reached D (decelerating). Returns the op.
inline uint8_t profile_update(const ProfileParams& p, bool decel, uint64_t& v) {
  if (decel) {
    if (v >= p.v_exit + p.accel) {
      v -= p.accel;
      return kOpDec;
    }
    v = p.v_exit;
    return kOpExit;
  }
  if (v + p.accel <= p.v_cruise) {
    v += p.accel;
    return kOpInc;
  }
  v = p.v_cruise;
  return kOpCru;
}

// segment_prep's PROFILE outputs (the Verilated executor's s_axis_prof_* inputs): the first master
// update U(1) = V_entry, V(1), op(1) (decelerating iff D == 0: U(1) < 1 step), V_cruise - A and
// V_exit + A, and per axis the exact products V_entry*n, V_cruise*n, V_exit*n (71 bits), A*n.
struct ProfilePrepared {
  uint64_t u1, v1;
  uint8_t op1;
  uint64_t vcma;  // 48-bit two's complement
  uint64_t vxpa;
  uint32_t n_dom;
  std::array<unsigned __int128, kAxes> v0{}, vc{}, vx{};
  std::array<uint64_t, kAxes> acc{};
};
inline ProfilePrepared prepare_profile(const ProfileParams& p,
                                       const std::array<uint32_t, kAxes>& abs_steps) {
  ProfilePrepared r{};
  for (uint32_t n : abs_steps) r.n_dom = std::max(r.n_dom, n);
  r.u1 = p.v_entry;
  r.v1 = p.v_entry;
  r.op1 = profile_update(p, p.decel_at == 0, r.v1);
  r.vcma = (p.v_cruise - p.accel) & ((1ull << 48) - 1);
  r.vxpa = p.v_exit + p.accel;
  for (int a = 0; a < kAxes; ++a) {
    const unsigned __int128 n = abs_steps[a] & 0xffffffu;
    r.v0[a] = p.v_entry * n;
    r.vc[a] = p.v_cruise * n;
    r.vx[a] = p.v_exit * n;
    r.acc[a] = static_cast<uint64_t>(p.accel * n);
  }
  return r;
}

// The run of a profiled segment in exact integers: U(0) = 0, V(0) = V_entry; per clock c
// U(c+1) = U(c) + V(c), V(c+1) = profile_update(V(c), U(c+1) >= D*2^48). The segment lasts J ticks,
// J = the first j with U(j) >= n_dom*2^48. Axis a (n_a steps) has made floor(U(j)*n_a / M) steps
// after tick j (M = n_dom*2^48, products < 2^96): its k-th step is in the first tick j with
// U(j)*n_a >= k*M, and at most one per tick (V < 2^47). `ticks[a]` lists the tick of every step.
// Inputs as the decoder accepts them (V_cruise < 2^47, V_entry and V_exit <= V_cruise, V_exit >= 1,
// A >= 1 or V_entry >= 1). The cost grows with the steps, not with J: the clocks between two events
// (a step of any axis, the start of deceleration, V reaching V_cruise or V_exit, the end) form a
// ramp (V changes by +A, -A or 0 per clock) whose U follows in closed form; the run jumps over
// them and takes each event clock with the per-clock update.
struct ProfileRun {
  uint64_t ticks_total = 0;  // J
  bool cruised = false;  // V reached V_cruise (false: a triangle, or a ramp that never gets there)
  std::array<std::vector<uint64_t>, kAxes> ticks;
  // (j, V(j)) at j = 0 and around every event; V is linear in j between two of them
  // (profile_v_at).
  std::vector<std::pair<uint64_t, uint64_t>> v_points;
};
// V(j) from ProfileRun::v_points, 0 <= j <= J (the last point's V beyond it).
inline uint64_t profile_v_at(const std::vector<std::pair<uint64_t, uint64_t>>& pts, uint64_t j) {
  auto it = std::upper_bound(pts.begin(), pts.end(), j,
                             [](uint64_t x, const auto& p) { return x < p.first; });
  if (it == pts.begin()) return pts.empty() ? 0 : pts.front().second;
  const auto& a = *(it - 1);
  if (it == pts.end() || a.first == j) return a.second;
  const auto& b = *it;
  const __int128 dv = static_cast<__int128>(b.second) - static_cast<__int128>(a.second);
  return static_cast<uint64_t>(static_cast<__int128>(a.second) +
                               dv * static_cast<__int128>(j - a.first) /
                                   static_cast<__int128>(b.first - a.first));
}

inline ProfileRun run_profile(const ProfileParams& p,
                              const std::array<uint32_t, kAxes>& abs_steps) {
  ProfileRun r;
  uint32_t n_dom = 0;
  for (uint32_t n : abs_steps) n_dom = std::max(n_dom, n);
  if (n_dom == 0) return r;
  using u128 = unsigned __int128;
  const u128 m = static_cast<u128>(n_dom) << 48;
  const u128 d = static_cast<u128>(p.decel_at) << 48;
  // Next step threshold of each axis: the k-th step when U*n_a >= k*M, i.e. U >= ceil(k*M/n_a);
  // k*M = quo[a]*n_a + rem[a] kept without dividing (M = step_q[a]*n_a + step_r[a]).
  std::array<u128, kAxes> next{}, quo{}, step_q{};
  std::array<uint64_t, kAxes> rem{}, step_r{};
  std::array<uint32_t, kAxes> k{};
  for (int a = 0; a < kAxes; ++a) {
    r.ticks[a].reserve(abs_steps[a]);
    if (abs_steps[a] == 0) continue;
    quo[a] = m / abs_steps[a];
    rem[a] = static_cast<uint64_t>(m % abs_steps[a]);
    step_q[a] = quo[a];
    step_r[a] = rem[a];
    next[a] = quo[a] + (rem[a] != 0);
  }
  const uint64_t acc = p.accel;
  constexpr uint64_t kNoLimit = uint64_t{1} << 62;
  u128 u = 0;
  uint64_t v = p.v_entry;
  r.cruised = v == p.v_cruise;
  uint64_t j = 0;
  r.v_points.emplace_back(0, v);
  while (u < m) {
    // The ramp from here: V changes by `step` per clock (rising or falling) for at most `limit`
    // clocks before profile_update saturates it; no ramp (limit 0) when the next clock saturates.
    const bool decel = u >= d;
    uint64_t step = acc, limit = 0;
    bool falling = decel;
    if (!decel && v + acc <= p.v_cruise) {
      limit = acc == 0 ? kNoLimit : std::min(kNoLimit, (p.v_cruise - v) / acc);
    } else if (decel && v >= p.v_exit + acc) {
      limit = acc == 0 ? kNoLimit : std::min(kNoLimit, (v - p.v_exit) / acc);
    } else if (v == (decel ? p.v_exit : p.v_cruise)) {  // saturated: constant velocity
      step = 0;
      falling = false;
      limit = kNoLimit;
    }
    u128 target = m;  // the clocks skipped end with U below every event threshold
    if (!decel) target = std::min(target, d);
    for (int a = 0; a < kAxes; ++a)
      if (k[a] < abs_steps[a]) target = std::min(target, next[a]);
    if (limit != 0 && (step != 0 || v != 0) && u < target) {
      const uint64_t i = models::ramp::last_below(u, v, step, falling, target, limit);
      if (i != 0) {
        u = models::ramp::sum(u, v, step, falling, i);
        const uint64_t v_end = falling ? v - step * i : v + step * i;
        // V passed V_cruise on one of the skipped clocks (only a start above V_cruise can do that
        // while falling)
        if (step == 0
                ? v == p.v_cruise
                : (falling ? p.v_cruise < v && p.v_cruise >= v_end && (v - p.v_cruise) % step == 0
                           : p.v_cruise > v && p.v_cruise <= v_end && (p.v_cruise - v) % step == 0))
          r.cruised = true;
        v = v_end;
        j += i;
        r.v_points.emplace_back(j, v);
      }
    }
    ++j;
    u += v;
    profile_update(p, u >= d, v);
    r.v_points.emplace_back(j, v);
    r.cruised = r.cruised || v == p.v_cruise;
    for (int a = 0; a < kAxes; ++a) {
      if (k[a] < abs_steps[a] && u >= next[a]) {
        r.ticks[a].push_back(j);
        ++k[a];
        quo[a] += step_q[a];
        rem[a] += step_r[a];
        if (rem[a] >= abs_steps[a]) {
          rem[a] -= abs_steps[a];
          quo[a] += 1;
        }
        next[a] = quo[a] + (rem[a] != 0);
      }
    }
  }
  r.ticks_total = j;
  return r;
}

}  // namespace fpgacnc::twins
