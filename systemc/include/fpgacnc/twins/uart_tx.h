// Twin of rtl/protocol/uart_tx.v: 8N1 transmitter with a fractional bit timer (docs/timing.md
// "ACK").
//
// Target `bytes`: a TxByte offered from the delay's edge; accepted on that edge if the line is
// idle, or on the last-stop-bit edge of the frame on the line (the next frame then follows back
// to back and keeps the timer's fraction). The start bit goes on the pin on the accept edge;
// boundary m of a stream (10 per frame) lies BitTimer::tx_boundary(m) edges after the stream's
// first start edge. The accept edge is returned in the delay; each frame is also sent on
// initiator `line` (to whoever listens on tx: the host), delay = its start edge.
#pragma once

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

class UartTxTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<UartTxTwin> bytes;
  tlm_utils::simple_initiator_socket<UartTxTwin> line;

  UartTxTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p,
             PinRecorder& pins)
      : sc_module(name),
        bytes("bytes"),
        line("line"),
        clk_(clk),
        timer_(p.clk_hz, p.baud),
        pins_(pins) {
    bytes.register_b_transport(this, &UartTxTwin::b_transport);
  }

  void reset() {
    frame_end_ = -1;
    frames = 0;
  }
  uint64_t frames = 0;
  // Length of one frame from idle, in clocks.
  int64_t frame_clocks() const { return timer_.tx_boundary(10); }

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const uint8_t byte = payload<TxByte>(gp).byte;
    const Cycle offer = clk_.at(delay);
    Cycle accept;
    if (frame_end_ >= offer) {  // back to back: taken on the last stop-bit edge
      accept = frame_end_;
      ++index_;
    } else {
      accept = offer;
      stream_ = offer;
      index_ = 0;
    }
    const uint16_t bits = static_cast<uint16_t>(0x200u | (static_cast<uint16_t>(byte) << 1));
    int level = 1;
    for (int i = 0; i < 10; ++i) {
      const int b = (bits >> i) & 1;
      if (b != level) {
        pins_.add(stream_ + timer_.tx_boundary(10 * index_ + i), models::kTx,
                  static_cast<uint8_t>(b));
        level = b;
      }
    }
    frame_end_ = stream_ + timer_.tx_boundary(10 * index_ + 10);
    ++frames;
    delay = clk_.delay_to(accept);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    LineFrame f{byte};
    transport(line, gp_, clk_, f, accept);
  }

  const CycleClock& clk_;
  BitTimer timer_;
  PinRecorder& pins_;
  Cycle frame_end_ = -1;  // edge of the current frame's end (its last stop-bit clock)
  Cycle stream_ = 0;      // start edge of the current back-to-back stream
  int64_t index_ = 0;     // frame index in the stream
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
