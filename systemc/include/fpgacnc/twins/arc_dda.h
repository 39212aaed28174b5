// Twin of rtl/motion/arc_dda.v: the circular / helical DDA of one ARC segment (docs/motion.md
// "Arcs").
//
// Target `load`: an ArcLoad (the frame fields; prep's products are derived with arc::derive), the
// delay naming the load edge L (the edge on which the RTL takes `load`); clock c of the arc is
// the cycle after edge L + c, and its event is registered on edge L + c + 1. The twin runs the
// integer reference (arc_walk.h, arc::Dda) from event to event and sends one step request per axis
// step on initiators x_step, y_step, z_step (PulseCmd{dir}), delay = edge L + c + 1; the answer
// fills in the edge of the last move's register edge (`end_edge`: a next arc loaded on
// end_edge starts with zero gap, as the RTL's `ending`) and err / late.
#pragma once

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

struct ArcLoad {
  models::arc::Frame frame;
  Cycle end_edge = 0;  // out
  bool err = false;    // out
  bool late = false;   // out
};

class ArcDdaTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<ArcDdaTwin> load;
  tlm_utils::simple_initiator_socket<ArcDdaTwin> x_step, y_step, z_step;

  ArcDdaTwin(sc_core::sc_module_name name, const CycleClock& clk)
      : sc_module(name),
        load("load"),
        x_step("x_step"),
        y_step("y_step"),
        z_step("z_step"),
        clk_(clk) {
    load.register_b_transport(this, &ArcDdaTwin::b_transport);
  }

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    ArcLoad& l = payload<ArcLoad>(gp);
    const Cycle edge_l = clk_.at(delay);
    models::arc::Dda dda(l.frame);
    Cycle last = edge_l;
    while (!dda.done()) {
      dda.skip_quiet(~uint64_t{0});
      const models::arc::Event ev = dda.clock();
      const Cycle e = edge_l + static_cast<Cycle>(ev.clock) + 1;
      if (ev.dx) send(x_step, ev.dx > 0, e);
      if (ev.dy) send(y_step, ev.dy > 0, e);
      if (ev.dz) send(z_step, ev.dz > 0, e);
      last = e;
    }
    l.end_edge = last;
    l.err = dda.err();
    l.late = dda.late();
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }

  void send(tlm_utils::simple_initiator_socket<ArcDdaTwin>& s, bool dir, Cycle e) {
    PulseCmd cmd{dir};
    transport(s, gp_, clk_, cmd, e);
  }

  const CycleClock& clk_;
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
