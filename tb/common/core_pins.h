// cnc_core's pins for PinHarness: 4-bit STEP/DIR buses, rst active high, cfg port idle.
// core_pins<Model>() serves any Verilated cnc_core; kCorePins is the default Vcnc_core's.
#pragma once

#include <cstdint>

#include "common/pin_harness.h"
#if __has_include("Vcnc_core.h")
#include "Vcnc_core.h"
#define FPGACNC_TB_HAVE_VCNC_CORE 1
#endif

namespace fpgacnc::tb {

inline constexpr int kCoreAxes = 4;

// The same pins for any Verilated cnc_core (other parameters, other prefix).
template <class Model>
constexpr PinAccess<Model> core_pins() {
  return PinAccess<Model>{
      [](Model& m, bool asserted) { m.rst = asserted ? 1 : 0; },
      [](const Model& m) { return static_cast<uint32_t>(m.step); },
      [](const Model& m) { return static_cast<uint32_t>(m.dir); },
      [](Model& m) { m.cfg_wr = 0; },
  };
}

#ifdef FPGACNC_TB_HAVE_VCNC_CORE
inline constexpr PinAccess<Vcnc_core> kCorePins = core_pins<Vcnc_core>();
#endif

// The benches' reset: rst high for two clocks, one clock after the release.
template <class Model>
inline void reset_core(PinHarness<Model>& h) {
  h.reset(2, 1);
}

}  // namespace fpgacnc::tb
