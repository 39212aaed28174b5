// Comparison of two runs (RTL vs twins), event by event: the first difference, with its cycle.
#pragma once

#include <string>

#include "fpgacnc/twins/run_result.h"

namespace fpgacnc::twins {

// "" when identical: pin edges (cycle, signal, value), ACK start edges, block events
// (decoder packet_done, executor seg_start / seg_done), counters, positions and duration.
// Otherwise one line naming the first differing event and its cycle.
std::string compare_runs(const RunResult& rtl, const RunResult& twin);

}  // namespace fpgacnc::twins
