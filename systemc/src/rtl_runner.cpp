#include "fpgacnc/twins/rtl_runner.h"

#include <chrono>
#include <memory>
#include <stdexcept>

#include "Vcnc_core.h"
#include "fpgacnc/twins/rtl_driver.h"
#include "verilated.h"

namespace fpgacnc::twins {

namespace {
void clock_once(Vcnc_core& m) {
  m.clk = 1;
  m.eval();
  m.clk = 0;
  m.eval();
}
}  // namespace

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
  m->rst = 1;
  m->rx = 1;
  m->cfg_wr = 0;
  m->clk = 0;
  m->eval();
  for (int i = 0; i < kResetEdges; ++i) clock_once(*m);
  m->rst = 0;
  clock_once(*m);
  for (const CfgWrite& w : cfg_writes(p.timing)) {
    m->cfg_wr = 1;
    m->cfg_addr = w.addr;
    m->cfg_wdata = w.data;
    clock_once(*m);
  }
  m->cfg_wr = 0;
  for (int i = 0; i < kSettleEdges; ++i) clock_once(*m);
  Cycle c = 0;
  while (!drv.finished()) {
    ++c;
    m->rx = static_cast<uint8_t>(drv.rx_for(c));
    clock_once(*m);
    drv.after_edge(c, RtlDriver::Outputs{m->step, m->dir, m->laser != 0, m->tx != 0, m->busy != 0,
                                         m->seg_start != 0, m->seg_done != 0, m->packet_count});
    if ((c & 1023) == 0) drv.check_stall();
  }
  std::array<int64_t, kAxes> pos{};
  for (int a = 0; a < kAxes; ++a) pos[a] = static_cast<int32_t>(m->position[a]);
  RunResult r = drv.take_result(pos, m->timeouts, m->overruns, m->frame_errors, m->violations);
  m->final();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace fpgacnc::twins
