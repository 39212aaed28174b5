// What a whole-job run gives, for either model (twins or Verilated RTL): the pin edge list and
// the block-level event lists that the co-simulation compares, and the figures of the report.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/models/edges.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

struct RunResult {
  std::vector<models::Edge> edges;  // STEP/DIR/LASER (and TX) by (cycle, signal)
  // Net steps per axis from the STEP/DIR edges and the number of edges: from `edges`, or with
  // VirtualBoard::summary_only() (then `edges` is empty) from the recorder's summary.
  std::array<int64_t, 4> net_steps{};
  uint64_t edge_count = 0;
  std::vector<Cycle> acks;            // start edge of each ACK byte the host received
  std::vector<Cycle> packet_done;     // decoder: edge after which packet_done is high
  std::vector<Cycle> seg_start;       // executor: edge after which seg_start is high
  std::vector<Cycle> seg_done;        // executor: edge after which seg_done is high
  std::vector<Cycle> seg_done_v2;     // the same for v2 segments (seg_done_v2; block level)
  std::vector<Cycle> arc_err;         // executor: edge on which arc_err is latched (block level)
  Cycle end_cycle = 0;                // job duration: last ACK's end or last edge, the later
  std::array<int64_t, 4> position{};  // position counters of the core
  uint64_t moves_done = 0, packets = 0, timeouts = 0, overruns = 0, frame_errors = 0,
           violations = 0;
  uint64_t packets_sent = 0;
  // v2: what the host saw (device frames, NAKs, retransmitted frames, `segments done` of the
  // last ACK/DONE) and the device side (v2 frames with a good CRC, clamped segments, segments
  // started with zero idle clocks: seg_start in the clock of the previous seg_done).
  uint64_t device_frames = 0, naks = 0, retransmitted = 0, segments_done = 0;
  uint64_t frames_ok = 0, clamped = 0, zero_gap = 0;
  std::vector<std::vector<uint8_t>> statuses;  // payloads of the STATUS frames the host got
  // Twins: runs of the job (more than 1 with MOTION frames, virtual_board.h); the first clock of
  // the values of each accepted MOTION frame (L + 2); the segments their requests took effect
  // in, by the executor's kind: LINE (and dwell), PROFILE, ARC, none (idle, between segments).
  int runs = 1;
  uint64_t flushed =
      0;  // FIFO entries dropped by a CANCEL's flush (in the FIFO, prepared, running)
  std::vector<Cycle> motion_from;
  std::array<uint64_t, 4> motion_in{};
  double wall_s = 0.0;
  std::string error;  // "" = the host got every ACK it waited for
};

}  // namespace fpgacnc::twins
