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
std::vector<RunResult> run_cosim_rtl(const CoreParams& params, const std::vector<CosimJob>& jobs);

}  // namespace fpgacnc::twins
