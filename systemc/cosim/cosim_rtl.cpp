// The RTL side of the co-simulation (cosim_rtl.h).
#include "cosim_rtl.h"

#include <chrono>
#include <memory>

#include "Vcnc_core_cosim.h"
#include "fpgacnc/twins/rtl_driver.h"

namespace fpgacnc::twins {
namespace {

// The Verilated cnc_core (the C++ model Vcnc_core_cosim, this program's parameters), each job
// from reset through run_core (rtl_driver.h): no SystemC scheduler between the clocks
// (docs/systemc.md, "Co-simulation").
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
  // Each job from reset; `limit` as run_core's.
  RunResult run_job(const CosimJob& job, Cycle limit) {
    const auto t0 = std::chrono::steady_clock::now();
    CoreParams p = params_;
    p.timing = job.timing;
    RtlDriver drv(p, job.script, true, true);
    RunResult r = run_core(*model_, drv, p.timing, job.script.buttons, limit);
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  }

  CoreParams params_;
  std::unique_ptr<Vcnc_core_cosim> model_ = std::make_unique<Vcnc_core_cosim>();
};

}  // namespace

std::vector<RunResult> run_cosim_rtl(const CoreParams& params, const std::vector<CosimJob>& jobs,
                                     const std::vector<Cycle>& twin_ends) {
  return RtlHarness(params).run(jobs, twin_ends);
}

}  // namespace fpgacnc::twins
