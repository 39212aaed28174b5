// Runs a whole job on the Verilated cnc_core (C++ model `vcore`: 50 MHz, 115200 baud, 100 ms
// watchdog) with the same host schedule as the virtual board: `fpgacnc sim --model rtl`, the
// benchmark, and the reference for the virtual platform's speed figure.
#pragma once

#include "fpgacnc/twins/host_schedule.h"
#include "fpgacnc/twins/run_result.h"

namespace fpgacnc::twins {

// Throws std::invalid_argument when `p` is not what the Verilated model was built with.
RunResult run_on_rtl(const CoreParams& p, const HostScript& script, bool record_tx = false);

}  // namespace fpgacnc::twins
