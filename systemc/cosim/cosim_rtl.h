// The RTL side of the co-simulation (cosim_main.cpp): its jobs, and the Verilated cnc_core
// that runs them (cosim_rtl.cpp; its own translation unit, as Verilator's C++ headers and
// SystemC's do not mix).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "fpgacnc/twins/host_schedule.h"
#include "fpgacnc/twins/run_result.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

struct CosimJob {
  std::string name;
  HostScript script;
  std::array<AxisTiming, kAxes> timing;
  size_t segments = 0;
};

// Runs every job on the Verilated cnc_core, each from reset, and returns their results in order.
// twin_ends[i] (when given) is job i's end cycle on the twins: the RTL's run of it stops at twice
// that plus 1 000 000 clocks with the error "RTL job not finished at clock N (limit L)", which the
// comparison then reports, instead of running for ever.
std::vector<RunResult> run_cosim_rtl(const CoreParams& params, const std::vector<CosimJob>& jobs,
                                     const std::vector<Cycle>& twin_ends = {});

}  // namespace fpgacnc::twins
