// cnc_core's pins for PinHarness: 4-bit STEP/DIR buses, rst active high, cfg port idle.
#pragma once

#include <cstdint>

#include "Vcnc_core.h"
#include "common/pin_harness.h"

namespace fpgacnc::tb {

inline constexpr int kCoreAxes = 4;

inline constexpr PinAccess<Vcnc_core> kCorePins{
    [](Vcnc_core& m, bool asserted) { m.rst = asserted ? 1 : 0; },
    [](const Vcnc_core& m) { return static_cast<uint32_t>(m.step); },
    [](const Vcnc_core& m) { return static_cast<uint32_t>(m.dir); },
    [](Vcnc_core& m) { m.cfg_wr = 0; },
};

// The benches' reset: rst high for two clocks, one clock after the release.
inline void reset_core(PinHarness<Vcnc_core>& h) {
  h.reset(2, 1);
}

}  // namespace fpgacnc::tb
