// A deterministic host for boards behind a pseudo-terminal (simboard::Board: the Verilated
// SimBoard or the twins' TwinBoard), and the comparison of two such runs.
//
// The host of host_schedule.h (v1 stop-and-wait packets or a v2 session: HELLO, CONFIG_AXIS,
// NUMERATORS, LINE / LINE_PROFILE / ARC / DWELL frames under the credit window, RELEASE), but
// paced by the board instead of by clocks: it writes everything it may send (a batch: v1 the init
// packet and the first move, then one move; v2 every frame the credit allows) in one write, waits
// until the board has read it and is idle for the host (Board::idle_for_host: nothing in flight,
// every answer written), reads every answer byte, lets the host decide, and repeats. By the
// boards' time policy every batch then starts on the clock after the board went quiet, so the
// same job gives the same bytes at the same clocks on any board that keeps the policy exactly.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/simboard/sim_board.h"
#include "fpgacnc/twins/host_schedule.h"

namespace fpgacnc::twins {

struct LockstepRun {
  std::string model;                // Board::model()
  std::vector<uint8_t> received;    // answer bytes as the host read them from the pty
  std::vector<models::Edge> edges;  // the board's edges (with TX when it records them)
  simboard::BoardStats stats;
  size_t batches = 0;
  size_t packets = 0;
  double wall_s = 0.0;
  std::string error;  // "" when the session ended normally
};

// Streams `script` through `board` (started here, stopped at the end). `timeout`: wall time the
// host waits for the board to become idle after a batch before it gives up (error set).
LockstepRun run_lockstep(simboard::Board& board, const HostScript& script, uint64_t clk_hz,
                         uint32_t baud, std::chrono::milliseconds timeout);

// Answer bytes decoded from the TX edges: (start cycle, byte) (8N1 at `clk_hz / baud`).
std::vector<std::pair<uint64_t, uint8_t>> tx_bytes_from_edges(
    const std::vector<models::Edge>& edges, double clk_hz, double baud);

// "" when both runs have identical edge lists (STEP/DIR/LASER and TX: every answer bit at its
// clock), identical answer bytes at identical start clocks and identical bytes read by the host;
// otherwise where they first differ, e.g. "edge #533: rtl cycle 44105 step_y -> 0, tlm cycle
// 44105 step_e -> 0" or "answer byte #12: rtl 0xAA at cycle 91234, tlm 0xAA at cycle 91235".
std::string compare_lockstep(const LockstepRun& a, const LockstepRun& b, double clk_hz,
                             double baud);

}  // namespace fpgacnc::twins
