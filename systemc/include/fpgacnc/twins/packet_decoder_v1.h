// Twin of rtl/packet_decoder_v1.v: byte-exact v1 packets (docs/protocol.md "Packets"), the
// 100 ms inter-byte watchdog and the one-command output register.
//
// Target `bytes`: RxByte valid from the delay's edge b; the decoder takes it on edge b + 1.
// A started packet whose next byte is taken more than WATCHDOG_CLKS edges after the previous
// one was dropped by the watchdog (timeout) and the byte starts a new packet. A complete packet
// is a Command valid from its last take edge; it is offered on initiator `commands`, whose
// target returns the accept edge. A packet completing while the previous command is still
// waiting (accept edge later than this take edge) is dropped (overrun).
#pragma once

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

class PacketDecoderTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<PacketDecoderTwin> bytes;
  tlm_utils::simple_initiator_socket<PacketDecoderTwin> commands;

  PacketDecoderTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p)
      : sc_module(name), bytes("bytes"), commands("commands"), clk_(clk), wd_(p.watchdog_clks) {
    bytes.register_b_transport(this, &PacketDecoderTwin::b_transport);
  }

  void reset() {
    count_ = 0;
    last_take_ = 0;
    out_accept_ = -1;
    packets = timeouts = overruns = 0;
    packet_done_cycles.clear();
  }
  uint64_t packets = 0, timeouts = 0, overruns = 0;
  std::vector<Cycle> packet_done_cycles;  // edges where packet_done is high (status counter)

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const uint8_t byte = payload<RxByte>(gp).byte;
    const Cycle take = clk_.at(delay) + 1;
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (count_ > 0 && take - last_take_ > static_cast<Cycle>(wd_)) {
      ++timeouts;
      count_ = 0;
    }
    last_take_ = take;
    if (count_ == 0) {
      init_ = byte == 0xFF;
      code_ = byte & 3;
    } else {
      buf_[count_ - 1] = byte;
    }
    ++count_;
    if (count_ < (init_ ? 9 : 11)) return;
    count_ = 0;
    if (out_accept_ > take) {
      ++overruns;
      return;
    }
    ++packets;
    packet_done_cycles.push_back(take);
    auto be32 = [&](int i) {
      return static_cast<uint32_t>(buf_[i]) << 24 | static_cast<uint32_t>(buf_[i + 1]) << 16 |
             static_cast<uint32_t>(buf_[i + 2]) << 8 | buf_[i + 3];
    };
    Command c{};
    c.init = init_;
    c.code = init_ ? 3 : code_;
    c.a = be32(0);
    c.b = be32(4);
    c.feed = init_ ? 0 : static_cast<uint16_t>(buf_[8] << 8 | buf_[9]);
    out_accept_ = transport(commands, gp_, clk_, c, take);
  }

  const CycleClock& clk_;
  uint64_t wd_;
  int count_ = 0;
  bool init_ = false;
  uint8_t code_ = 0;
  std::array<uint8_t, 10> buf_{};
  Cycle last_take_ = 0;
  Cycle out_accept_ = -1;  // accept edge of the command in the output register
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
