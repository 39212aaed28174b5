// Jobs of the block-level co-simulation of uart_rx, uart_tx, packet_decoder_v1 and
// segment_prep (cosim_blocks.cpp): the stimulus, and the events both sides report. The RTL side
// (cosim_blocks_rtl.cpp) uses the Verilated C++ block models of tb/ and no SystemC header.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "fpgacnc/simboard/edges.h"
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
  std::vector<simboard::Edge> edges;   // uart_tx: tx edges
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
// packet_decoder_v1 (100 ms watchdog): bytes valid after their edge (one clock each); command
// k is taken `accept_delay[k]` edges after the first edge it could be; events (valid edge,
// code | init << 8, a, b | feed << 32).
struct DecoderJob {
  std::vector<std::pair<Cycle, uint8_t>> bytes;
  std::vector<int64_t> accept_delay;
};
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
};
struct PrepJob {
  uint32_t min_half;  // min_period = 2 * min_half via STEP high = low = min_half on X
  std::array<uint16_t, kAxes> setup{}, hold{};
  std::vector<PrepCommand> commands;
  std::vector<int64_t> accept_delay;
  std::vector<int64_t> busy;
};

BlockRun rtl_uart_rx(const UartRxJob& j);
BlockRun rtl_uart_tx(const UartTxJob& j);
BlockRun rtl_decoder(const DecoderJob& j);
BlockRun rtl_prep(const PrepJob& j);

}  // namespace fpgacnc::twins
