// Jobs of the segment_executor block co-simulation (cosim_executor.cpp), shared by its RTL side
// (cosim_executor_rtl.cpp, Verilated C++ model, no SystemC headers) and its twin side.
#pragma once

#include <array>
#include <vector>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/twins/run_result.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

struct ExecSegment {
  uint8_t code;
  std::array<bool, kAxes> dir;
  std::array<uint32_t, kAxes> steps;
  std::array<uint64_t, kAxes> tmn;
  uint64_t total;
  uint32_t period;
  uint8_t power = 0xFF;
  bool v2 = false;
  bool dir_fast = false;
  bool prof = false;  // kind PROFILE: total, tmn, period 0 and dir_fast 0, as segment_prep sends
  ProfileParams profile{};
  bool arc = false;  // kind ARC: steps X = Y = 1, Z = |DZ|, the start directions, as prep sends
  models::arc::Frame arc_frame{};
};
struct ExecOffer {
  ExecSegment seg;
  int64_t gap;  // valid from `gap` edges after the previous accept (first: after cycle 0)
};

// The abort (e-stop) input is high in the clocks before edges first..last (in time order, not
// overlapping). An offer waiting during an abort is held (taken once the executor is ready).
struct ExecAbort {
  Cycle first, last;
};

// A request to the motion rate (feed_rate.v: an accepted MOTION frame's values, from clock
// `from` on), in time order. The rate's period counter and accumulator start at the reset
// release, kExecRatePhase clocks before cycle 0 (as in cnc_core's harness).
struct ExecRate {
  Cycle from;
  bool hold = false, resume = false;
  uint16_t feed = 0x8000, rapid = 0x8000;
  uint32_t ramp = 1;
};
inline constexpr Cycle kExecRatePhase = 21;

struct ExecJob {
  std::array<AxisTiming, kAxes> timing;
  std::vector<ExecOffer> offers;
  std::vector<ExecAbort> aborts;
  std::vector<ExecRate> rate;
};

RunResult run_executor_rtl(const ExecJob& j);

}  // namespace fpgacnc::twins
