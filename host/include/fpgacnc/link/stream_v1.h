// v1 streamer: the original stop-and-wait handshake. Flush input, send the init packet, then for
// each move send 11 bytes and wait for 0xAA (sent by the device when the move has completed).
// Other bytes are counted as warnings and it keeps waiting. The whole job is packed (and so
// validated) before the first byte is written.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "fpgacnc/link/link.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::link {

struct StreamOptions {
  // Link time (link.h): wall time on a serial port, board time on a simulated board. Dwells
  // (G4) wait in link time too.
  std::chrono::milliseconds ack_timeout{10'000};
  // Called after each acknowledged move: (moves done, moves total).
  std::function<void(size_t, size_t)> progress;
  // Called for each unexpected byte received while waiting for an ACK.
  std::function<void(uint8_t)> unexpected_byte;
};

struct StreamReport {
  size_t moves = 0;     // motion packets sent
  size_t acks = 0;      // 0xAA received
  size_t warnings = 0;  // unexpected bytes received
  size_t dwells = 0;
  size_t skipped_heater = 0;  // heater commands v1 cannot carry
  size_t ze_only = 0;         // Z/E-only moves sent as 0,0 steps (not driven by v1)
  size_t bytes_written = 0;
  std::chrono::duration<double> elapsed{0};  // wall time
  plan::Steps4 final_steps{};
  std::array<double, 4> final_mm{};
};

// Streams `plan` over `link`. Throws link::Error on timeout ("... last acknowledged move:
// segment N (line L)"), std::invalid_argument if the plan cannot be packed (nothing written).
StreamReport stream_v1(Link& link, const plan::Plan& plan, const StreamOptions& options);

// Plans a G-code file or step-file CSV with `cfg` (feed override from cfg), then streams it.
// Any input error throws before a single byte is written to `link`.
StreamReport stream_file_v1(Link& link, const std::string& path, const config::MachineConfig& cfg,
                            const StreamOptions& options);

}  // namespace fpgacnc::link
