// Twin of rtl/motion/dda_linear.v: the exact DDA of one axis (docs/timing.md "Steps").
//
// Target `load`: a DdaLoad (n steps over T ticks), the delay naming the run-start edge R; tick
// c of the segment is edge R + c, or with DdaLoad::rate the edge after the c-th clock with the
// motion rate's `adv` high from the clock after R (feed_rate.h). The k-th step (k = 1..n) falls on
// tick ceil(k * T / n) (128-bit product): the twin computes each step time instead of ticking, and
// sends one step request per step on initiator `step` (to the axis's step_pulse), delay = R + tick.
// DdaLoad::cut (an abort edge, from the executor): requests on that edge or later are not sent.
#pragma once

#include <limits>

#include "fpgacnc/twins/feed_rate.h"
#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

struct DdaLoad {
  uint32_t steps;
  uint64_t total;
  Cycle cut = std::numeric_limits<Cycle>::max();  // abort: no step request on this edge or later
  FeedRate* rate = nullptr;  // ticks through the motion rate (null: every clock)
};

class DdaLinearTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<DdaLinearTwin> load;
  tlm_utils::simple_initiator_socket<DdaLinearTwin> step;

  DdaLinearTwin(sc_core::sc_module_name name, const CycleClock& clk)
      : sc_module(name), load("load"), step("step"), clk_(clk) {
    load.register_b_transport(this, &DdaLinearTwin::b_transport);
  }

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const DdaLoad l = payload<DdaLoad>(gp);
    const Cycle r = clk_.at(delay);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    PulseCmd none{false};
    DdaTicks ticks(l.steps, l.total);
    for (uint64_t k = 1; k <= l.steps; ++k) {
      const uint64_t j = ticks.next();
      const Cycle e = l.rate ? l.rate->tick_edge(r, j) : r + static_cast<Cycle>(j);
      if (e >= l.cut) break;  // the executor gates step_req from the abort edge on
      transport(step, gp_, clk_, none, e);
    }
  }

  const CycleClock& clk_;
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
