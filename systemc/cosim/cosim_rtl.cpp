// The RTL side of the co-simulation (cosim_rtl.h).
#include "cosim_rtl.h"

#include <chrono>
#include <memory>

#include "Vcnc_core_cosim.h"
#include "fpgacnc/twins/rtl_driver.h"

namespace fpgacnc::twins {
namespace {

// The Verilated cnc_core (the C++ model Vcnc_core_cosim, this program's parameters) clocked by
// a loop through an RtlDriver: each clock, the inputs are set, then the rising and the falling
// edge are evaluated and the outputs read (they show the rising edge). No SystemC scheduler
// between the clocks (docs/systemc.md, "Co-simulation").
class RtlHarness {
 public:
  explicit RtlHarness(const CoreParams& params) : params_(params) {}

  std::vector<RunResult> run(const std::vector<CosimJob>& jobs, const std::vector<Cycle>& ends) {
    std::vector<RunResult> results;
    for (size_t i = 0; i < jobs.size(); ++i)
      results.push_back(run_job(jobs[i], i < ends.size() ? 2 * ends[i] + 1'000'000 : 0));
    return results;
  }

 private:
  void edge() {
    m_.clk = 1;
    m_.eval();
    m_.clk = 0;
    m_.eval();
  }

  RunResult run_job(const CosimJob& job, Cycle limit) {
    const auto t0 = std::chrono::steady_clock::now();
    CoreParams p = params_;
    p.timing = job.timing;
    RtlDriver drv(p, job.script, true, true);
    // The pins the twins do not model, held: e-stop released, no limit switch or probe wired
    // (cnc_core's defaults LIMIT_ENABLE and PROBE_ENABLE are 0 anyway), ADC SDO low.
    m_.estop = 0;
    m_.limit_min = 0;
    m_.limit_max = 0;
    m_.probe_in = 0;
    m_.adc_sdo = 0;
    m_.rst = 1;
    m_.rx = 1;
    m_.cfg_wr = 0;
    for (int i = 0; i < kResetEdges; ++i) edge();
    m_.rst = 0;
    edge();
    for (const CfgWrite& w : cfg_writes(p.timing)) {
      m_.cfg_wr = 1;
      m_.cfg_addr = w.addr;
      m_.cfg_wdata = w.data;
      edge();
    }
    m_.cfg_wr = 0;
    m_.hold_in = 0;
    m_.start_in = 0;
    for (int i = 0; i < kSettleEdges; ++i) edge();
    Cycle c = 0;
    size_t press = 0;  // the first button press not over
    const auto& bp = job.script.buttons;
    bool over = false;
    while (!drv.finished()) {
      if (limit > 0 && c >= limit) {
        over = true;
        break;
      }
      ++c;
      m_.rx = drv.rx_for(c) != 0;
      // The buttons' levels for edge c.
      while (press < bp.size() && bp[press].from + bp[press].clocks <= c) ++press;
      bool level[2] = {false, false};
      for (size_t k = press; k < bp.size() && bp[k].from <= c; ++k)
        if (c < bp[k].from + bp[k].clocks) level[bp[k].button & 1] = true;
      m_.hold_in = level[0];
      m_.start_in = level[1];
      edge();
      drv.after_edge(
          c, RtlDriver::Outputs{
                 m_.step, m_.dir, m_.laser != 0, m_.tx != 0, m_.busy != 0, m_.seg_start != 0,
                 m_.seg_done != 0, static_cast<uint16_t>(m_.packet_count),
                 (m_.coolant_flood ? 1u : 0u) | (m_.coolant_mist ? 2u : 0u) | (m_.fan ? 4u : 0u) |
                     (static_cast<uint32_t>(m_.dout) << 3) | (m_.spindle_pwm ? 128u : 0u)});
      if ((c & 1023) == 0) drv.check_stall();
    }
    std::array<int64_t, kAxes> pos{};
    for (int a = 0; a < kAxes; ++a) pos[a] = static_cast<int32_t>(m_.position[a]);
    RunResult r = drv.take_result(pos, m_.timeouts, m_.overruns, m_.frame_errors, m_.violations);
    if (over)
      r.error = "RTL job not finished at clock " + std::to_string(c) +
                " (the twins' end: " + std::to_string((limit - 1'000'000) / 2) + ")";
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  }

  CoreParams params_;
  std::unique_ptr<Vcnc_core_cosim> model_ = std::make_unique<Vcnc_core_cosim>();
  Vcnc_core_cosim& m_ = *model_;
};

}  // namespace

std::vector<RunResult> run_cosim_rtl(const CoreParams& params, const std::vector<CosimJob>& jobs,
                                     const std::vector<Cycle>& twin_ends) {
  return RtlHarness(params).run(jobs, twin_ends);
}

}  // namespace fpgacnc::twins
