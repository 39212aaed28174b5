// Twin of cnc_core's ACK queue and status counters (rtl/cnc_core.v, docs/timing.md "ACK").
//
// Target `done`: a seg_done strobe after the delay's edge Dn. The ACK counter increments on
// edge Dn + 1; one 0xAA is offered to uart_tx (initiator `tx`) from edge Dn + 2, in order.
#pragma once

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

class StatusAckTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<StatusAckTwin> done;
  tlm_utils::simple_initiator_socket<StatusAckTwin> tx;

  StatusAckTwin(sc_core::sc_module_name name, const CycleClock& clk)
      : sc_module(name), done("done"), tx("tx"), clk_(clk) {
    done.register_b_transport(this, &StatusAckTwin::b_transport);
  }

  void reset() {
    moves_done = 0;
    seg_done_cycles.clear();
    ack_cycles.clear();
    last_accept_ = -1;
  }
  uint64_t moves_done = 0;
  std::vector<Cycle> seg_done_cycles;  // edges after which seg_done is high
  std::vector<Cycle> ack_cycles;       // start edges of the ACK bytes on tx

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Cycle dn = clk_.at(delay);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    ++moves_done;
    seg_done_cycles.push_back(dn);
    TxByte ack{0xAA};
    // In order: an ACK is offered no earlier than the edge after the previous one was taken.
    last_accept_ = transport(tx, gp_, clk_, ack, std::max(dn + 2, last_accept_ + 1));
    ack_cycles.push_back(last_accept_);
  }

  const CycleClock& clk_;
  Cycle last_accept_ = -1;
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
