// Jobs of the block-level co-simulation of uart_rx, uart_tx, packet_decoder_v1 and
// segment_prep (cosim_blocks.cpp): the stimulus, and the events both sides report. The RTL side
// (cosim_blocks_rtl.cpp) uses the Verilated C++ block models of tb/ and no SystemC header.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "fpgacnc/models/edges.h"
#include "fpgacnc/spec.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

// One output event of a block: its edge and up to four values (meaning per block).
struct BlockEvent {
  Cycle cycle;
  std::array<uint64_t, 6> v;
  bool operator==(const BlockEvent&) const = default;
};
struct BlockRun {
  std::vector<BlockEvent> events;
  std::vector<models::Edge> edges;     // uart_tx: tx edges
  std::array<uint64_t, 2> counters{};  // decoder: timeouts, overruns; prep: numerators x, y
};

// uart_rx: frames (start edge on the pin, byte) at `baud`; events (valid edge, byte).
struct UartRxJob {
  uint64_t baud;
  std::vector<std::pair<Cycle, uint8_t>> frames;
};
// uart_tx (3 Mbaud): byte k offered from edge (previous accept, or 0) + gap; events (accept, byte).
struct UartTxJob {
  std::vector<std::pair<uint8_t, int64_t>> offers;
};
// frame_decoder (100 ms watchdog): bytes valid after their edge (one clock each); the FIFO has
// no room in the clocks after the edges of `full` ([first, last] intervals). Events: FIFO writes
// (write edge, 1 << 60 | v2 << 12 | kind << 10 | code << 8 | power, t, steps X | Y << 32,
// steps Z | E << 32), requests (strobe edge, 2 << 60 | kind | seq << 8 | reason << 16), CONFIG
// writes (edge, 4 << 60 | axis, high | low << 16 | setup << 32 | hold << 48), v1 packets queued
// (edge, 5 << 60) and the decoder state when it changes (edge after which it holds, 3 << 60 |
// next_seq | v2 mode << 8, frames ok | CRC errors << 16 | length errors << 32 | unknown types
// << 48, timeouts | overruns << 16 | noise << 32): the counters as cnc_core counts the strobes.
struct FrameJob {
  std::vector<std::pair<Cycle, uint8_t>> bytes;
  std::vector<std::pair<Cycle, Cycle>> full;
  bool full_at(Cycle c) const {
    for (const auto& [a, b] : full)
      if (c >= a && c <= b) return true;
    return false;
  }
};
inline constexpr uint64_t kEvWrite = 1ull << 60, kEvReq = 2ull << 60, kEvState = 3ull << 60,
                          kEvCfg = 4ull << 60, kEvV1 = 5ull << 60;

// A wide bit vector (LSB first) in 64-bit words: the FIFO entry above its first 173 bits (the
// LINE_PROFILE and ARC fields) and segment_prep's m_axis_arc are compared whole.
struct Bits {
  std::vector<uint64_t> w;
  explicit Bits(int width) : w(static_cast<size_t>((width + 63) / 64), 0) {}
  void put(int lsb, unsigned __int128 v, int width) {
    for (int b = 0; b < width; ++b)
      if ((v >> b) & 1u) w[static_cast<size_t>((lsb + b) / 64)] |= 1ull << ((lsb + b) % 64);
  }
  bool bit(int i) const { return (w[static_cast<size_t>(i / 64)] >> (i % 64)) & 1u; }
  // bits [from, from + width) as words (LSB first)
  std::vector<uint64_t> slice(int from, int width) const {
    Bits o(width);
    for (int i = 0; i < width; ++i)
      if (bit(from + i)) o.w[static_cast<size_t>(i / 64)] |= 1ull << (i % 64);
    return o.w;
  }
};
// Verilator's wide port (32-bit words) as Bits.
template <class W>
Bits bits_of(const W& words, int width) {
  Bits b(width);
  for (int i = 0; i < width; ++i)
    if ((words[static_cast<size_t>(i / 32)] >> (i % 32)) & 1u)
      b.w[static_cast<size_t>(i / 64)] |= 1ull << (i % 64);
  return b;
}
// Words as events at edge c: (kEvWide | tag << 8 | k, five words each).
inline constexpr uint64_t kEvWide = 7ull << 60;
inline void wide_events(std::vector<BlockEvent>& out, Cycle c, uint64_t tag,
                        const std::vector<uint64_t>& w) {
  for (size_t k = 0; k * 5 < w.size(); ++k) {
    BlockEvent e{c, {kEvWide | tag << 8 | k, 0, 0, 0, 0, 0}};
    for (size_t i = 0; i < 5 && k * 5 + i < w.size(); ++i) e.v[1 + i] = w[k * 5 + i];
    out.push_back(e);
  }
}
inline constexpr int kEntryBits = spec::entry_width(kAxes);       // 839: the FIFO entry
inline constexpr int kEntryLow = spec::kEntryBaseW + 32 * kAxes;  // 173: the kEvWrite fields
inline constexpr int kArcBits = 945;                              // segment_prep's m_axis_arc

// segment_prep: FIFO entry k valid from (previous accept, or 0) + gap; segment j taken
// `accept_delay[j]` edges late; exec_idle low from its accept edge A_j until after edge
// A_j + busy[j] (the executor running it), so a numerators entry waits. Events: accepts (edge,
// k), segments (valid edge, period | code << 32 | dir << 40 | dir_fast << 44 | v2 << 45 |
// power << 48, total, steps X | Y << 32, steps Z | E << 32, tmn X, tmn E), init_applied
// (edge, 1 << 62 | init_v2) and clamped (edge, 1 << 63) strobes.
struct PrepCommand {
  bool v2;
  uint8_t kind, code, power;
  uint32_t t;
  std::array<uint32_t, kAxes> steps;
  int64_t gap;
  bool prof = false;  // LINE_PROFILE (kind 0, v2, t = A) with these fields
  ProfileParams profile{};
  bool arc = false;  // ARC (kind 0, v2, code 2 / 3): payload bytes 2..62
  std::array<uint8_t, 61> arc_raw{};
};
// A PROFILE segment's outputs (m_axis_prof_*) as events at its valid edge, after its segment
// event: (kEvProf | op1 | n_dom << 8, U(1), V(1), V_cruise - A, V_exit + A, A | D << 32),
// (kEvProf | 1, V_cruise, V_exit) and per axis a (kEvProf | 2 + a, V_entry*n_a mod 2^64,
// the three products' bits 64..70, V_cruise*n_a mod 2^64, V_exit*n_a mod 2^64, A*n_a).
inline constexpr uint64_t kEvProf = 6ull << 60;
inline void profile_events(std::vector<BlockEvent>& out, Cycle c, const ProfilePrepared& pp,
                           const ProfileParams& p) {
  out.push_back(BlockEvent{c,
                           {kEvProf | pp.op1 | static_cast<uint64_t>(pp.n_dom) << 8, pp.u1, pp.v1,
                            pp.vcma, pp.vxpa, p.accel | static_cast<uint64_t>(p.decel_at) << 32}});
  out.push_back(BlockEvent{c, {kEvProf | 1ull << 40, p.v_cruise, p.v_exit, 0, 0, 0}});
  for (int a = 0; a < kAxes; ++a) {
    const auto hi = [](unsigned __int128 v) { return static_cast<uint64_t>(v >> 64); };
    out.push_back(
        BlockEvent{c,
                   {kEvProf | static_cast<uint64_t>(2 + a) << 40, static_cast<uint64_t>(pp.v0[a]),
                    hi(pp.v0[a]) | hi(pp.vc[a]) << 8 | hi(pp.vx[a]) << 16,
                    static_cast<uint64_t>(pp.vc[a]), static_cast<uint64_t>(pp.vx[a]), pp.acc[a]}});
  }
}
struct PrepJob {
  uint32_t min_half;  // min_period = 2 * min_half via STEP high = low = min_half on X
  std::array<uint16_t, kAxes> setup{}, hold{};
  std::vector<PrepCommand> commands;
  std::vector<int64_t> accept_delay;
  std::vector<int64_t> busy;
};

// response_encoder (N_AXES 4, 50 MHz, 115 200 baud): request strobes high after their edge (kind
// 0 IDENT, 1 STATUS, 2 NAK with seq and reason, 3 ACK, 5 done (a v2 entry completed), 6 v1 move
// done; segments_done counts the done strobes as cnc_core does, on the edge after); the live
// inputs as they are after the listed edges; the transmitter takes a byte when ready and is busy
// `busy[k]` edges after taking byte k. Events: (take edge, byte).
struct EncoderJob {
  struct Strobe {
    Cycle edge;
    uint8_t kind, seq, reason;
  };
  struct Live {
    Cycle edge;
    uint8_t next_seq, state;
    uint16_t level;
    std::array<int32_t, kAxes> position;
    std::array<uint16_t, 9> counters;
  };
  std::vector<Strobe> strobes;  // by edge
  std::vector<Live> live;       // by edge, the first at edge 0
  std::vector<int64_t> busy;
  const Live& live_after(Cycle c) const {
    size_t k = 0;
    while (k + 1 < live.size() && live[k + 1].edge <= c) ++k;
    return live[k];
  }
  uint32_t done_after(Cycle c) const {  // segments_done register after edge c
    uint32_t n = 0;
    for (const auto& s : strobes) n += s.kind == 5 && s.edge + 1 <= c ? 1 : 0;
    return n;
  }
};

BlockRun rtl_uart_rx(const UartRxJob& j);
BlockRun rtl_uart_tx(const UartTxJob& j);
BlockRun rtl_frame_decoder(const FrameJob& j);
BlockRun rtl_prep(const PrepJob& j);
BlockRun rtl_encoder(const EncoderJob& j);

}  // namespace fpgacnc::twins
