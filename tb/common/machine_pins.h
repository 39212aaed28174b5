// The pins of vcore_machine (tb/limits.cmake: cnc_core with X min active low and the probe
// wired), shared by test_limits and test_trigger: idle with every switch and the probe released.
#pragma once

#include <cstdint>

#include "Vcnc_core_machine.h"
#include "common/pin_harness.h"

namespace fpgacnc::tb {

inline constexpr PinAccess<Vcnc_core_machine> kMachinePins{
    [](Vcnc_core_machine& m, bool asserted) { m.rst = asserted ? 1 : 0; },
    [](const Vcnc_core_machine& m) { return static_cast<uint32_t>(m.step); },
    [](const Vcnc_core_machine& m) { return static_cast<uint32_t>(m.dir); },
    [](Vcnc_core_machine& m) {
      m.cfg_wr = 0;
      m.limit_min = 1;  // X min is active low: released = high
      m.limit_max = 0;
      m.probe_in = 0;  // the probe released
    },
};

}  // namespace fpgacnc::tb
