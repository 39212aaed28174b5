#include "fpgacnc/twins/rtl_runner.h"

#include <chrono>
#include <memory>
#include <stdexcept>

#include "Vcnc_core.h"
#include "fpgacnc/twins/rtl_driver.h"
#include "verilated.h"

namespace fpgacnc::twins {

RunResult run_on_rtl(const CoreParams& p, const HostScript& script, bool record_tx) {
  const CoreParams built;
  if (p.clk_hz != built.clk_hz || p.baud != built.baud || p.watchdog_clks != built.watchdog_clks ||
      p.feed0_period != built.feed0_period || p.default_numerator != built.default_numerator)
    throw std::invalid_argument(
        "rtl model: the Verilated cnc_core is built for 50 MHz, 115200 baud and the default "
        "parameters");
  const auto t0 = std::chrono::steady_clock::now();
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vcnc_core>(ctx.get(), "cnc_core");
  RtlDriver drv(p, script, record_tx);
  drv.reserve(1u << 20);
  RunResult r = run_core(*m, drv, p.timing, script.buttons);
  m->final();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace fpgacnc::twins
