// Twin of rtl/protocol/uart_rx.v: 8N1 receiver with a fractional bit timer (docs/protocol.md
// "Physical", docs/timing.md "Packet to motion").
//
// Target `pin`: one RxFrame per 8N1 frame the host puts on the rx pin, the delay naming the
// clock whose edge first sees the start bit's low level. The twin does not look at the line
// clock by clock: the two-flop synchronizer puts the start detection 2 edges later (or on the
// edge after the receiver is idle again, if later), the fractional timer gives every sample
// edge (BitTimer::rx_tick), each sample reads the sender's line (SenderTiming::level) two
// clocks earlier (the synchronizer), and the byte is valid on m_axis from the stop-bit sample
// edge. A stop bit sampled low is a framing error (counted, byte dropped); a start bit found
// high at its centre starts no byte.
// Initiator `bytes`: RxByte to the decoder, delay = the valid edge.
#pragma once

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

class UartRxTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<UartRxTwin> pin;
  tlm_utils::simple_initiator_socket<UartRxTwin> bytes;

  UartRxTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p)
      : sc_module(name),
        pin("pin"),
        bytes("bytes"),
        clk_(clk),
        timer_(p.clk_hz, p.baud),
        sender_{p.clk_hz, p.baud} {
    pin.register_b_transport(this, &UartRxTwin::b_transport);
    for (int m = 1; m <= 10; ++m) tick_[m] = timer_.rx_tick(m);
  }

  void reset() {
    idle_after_ = -1;
    frame_errors = 0;
  }
  uint64_t frame_errors = 0;

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const uint8_t byte = payload<RxFrame>(gp).byte;
    const Cycle start = clk_.at(delay);  // first edge that sees the start bit on the pin
    // Synchronizer: rxd_sync low 2 edges later; detected on an edge where the receiver idles.
    const Cycle detect = std::max(start + 2, idle_after_ + 1);
    // Sample m (bit m-1) on edge detect + tick_[m] reads the pin level of edge - 2.
    auto sample = [&](int m) { return sender_.level(byte, detect + tick_[m] - 2 - start); };
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (sample(1) != 0) {  // glitch: back to idle at the start-bit centre
      idle_after_ = detect + tick_[1];
      return;
    }
    uint8_t value = 0;
    for (int m = 2; m <= 9; ++m) value |= static_cast<uint8_t>(sample(m) << (m - 2));
    const Cycle valid = detect + tick_[10];
    idle_after_ = valid;
    if (sample(10) == 0) {
      ++frame_errors;
      return;  // (the RTL then waits for a high line; frames here always end high)
    }
    RxByte out{value};
    transport(bytes, gp_, clk_, out, valid);
  }

  const CycleClock& clk_;
  BitTimer timer_;
  SenderTiming sender_;
  std::array<int64_t, 11> tick_{};
  Cycle idle_after_ = -1;  // receiver idle after this edge
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
