// Twin of rtl/protocol/response_encoder.v: the device's answers on tx (docs/protocol.md "Device to
// host").
//
// Inputs are strobes after an edge e; each is sampled on edge e + 1 (a pending flag or a counter),
// so a frame can be decided (its fields snapshotted) on edge e + kRespStart = e + 2 at the
// earliest and its first byte taken by an idle uart_tx on the edge after:
//   target `req` (frame_decoder): IDENT, STATUS, NAK (seq, reason; a newer NAK replaces a
//     pending one), ACK requests, FAULT_CLEAR;
//   target `done` (segment_executor seg_done): a v2 segment counts in `segments done` and sets
//     DONE pending; a v1 motion owes one 0xAA byte; SegDone::outputs OUTPUT entries applied on the
//     edge (out_done) count like as many v2 segments (no seg_done strobe);
//   target `applied` (segment_prep): a v2 NUMERATORS entry applied counts like a v2 segment.
// A frame is decided on the first edge d on which the encoder is free (the edge after the last
// byte of the previous frame was taken by uart_tx) and something is pending: a v1 0xAA first (it
// only goes out between frames), then IDENT, STATUS, NAK, ACK, DONE. Its fields are the live
// state as it is after edge d - 1 (initiator `state`: StatusSnapshot, read in time order); an
// ACK also clears a pending DONE; a request sampled on d itself stays pending. The bytes go to
// uart_tx (initiator `tx`) back to back: byte 0 offered for edge d + 1, byte k for the edge
// after byte k-1 was taken, the CRC high byte for the second edge after the last payload byte
// was taken (the CRC folds that byte first). The device SEQ counts the frames sent.
//
// No wait(): the twin computes frames lazily, in time order, when the board calls step(limit)
// with a limit before which every input is known (the host's next byte cannot act earlier).
#pragma once

#include <functional>
#include <queue>

#include "fpgacnc/twins/frame_decoder.h"
#include "fpgacnc/twins/segment_prep.h"

namespace fpgacnc::twins {

inline constexpr Cycle kRespStart = 2;  // input strobe after edge e -> decision on e + 2

struct StatusSnapshot {  // the live state a frame is filled in from (cnc_core status)
  DecoderState dec;
  uint32_t fifo_level = 0;
  bool busy = false;
  bool fault = false;  // STEP timing violation latched (faults bit 0)
  uint8_t faults = 0;  // other latched fault bits (bit 1: arc error); OR-ed with `fault`
  std::array<int32_t, kAxes> position{};
  uint16_t frame_errors = 0, clamped = 0;
  bool hold = false;     // the motion rate's hold register (state bit 5 HOLD)
  bool stopped = false;  // the motion rate is 0 (state bit 6 STOPPED)
};

struct EncoderParams {
  uint32_t fifo_depth = v2::kFifoDepth;
  uint64_t clk_hz = 50'000'000, baud = 115'200;
  uint32_t build_id = v2::kBuildId;
  // cnc_core appends its 16-byte heater block to STATUS (rtl/protocol/response_encoder.v HEAT_BYTES
  // 16; the block-level encoder bench uses 0). The twins model idle heaters (no frames, ADC at 0):
  // per channel temperature 0 until the first sample's eval, then -2048 degC (0x8000, no table),
  // setpoint, duty, mode and faults 0. The first eval is on edge SAMPLE_CLKS (= clk_hz) + 635
  // after reset release (docs/heater.md), i.e. cycle clk_hz + 635 + kResetHoldRef here.
  bool heater_block = false;
};

class ResponseEncoderTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<ResponseEncoderTwin> req;
  tlm_utils::simple_target_socket<ResponseEncoderTwin> done;
  tlm_utils::simple_target_socket<ResponseEncoderTwin> applied;
  tlm_utils::simple_initiator_socket<ResponseEncoderTwin> tx;
  tlm_utils::simple_initiator_socket<ResponseEncoderTwin> state;
  // Called with edge d before a frame is decided on d (the board fires watchdogs up to d).
  std::function<void(Cycle)> before_decide;

  ResponseEncoderTwin(sc_core::sc_module_name name, const CycleClock& clk, EncoderParams p)
      : sc_module(name),
        req("req"),
        done("done"),
        applied("applied"),
        tx("tx"),
        state("state"),
        clk_(clk),
        p_(p) {
    req.register_b_transport(this, &ResponseEncoderTwin::on_req);
    done.register_b_transport(this, &ResponseEncoderTwin::on_done);
    applied.register_b_transport(this, &ResponseEncoderTwin::on_applied);
  }

  void reset() {
    events_ = {};
    order_ = 0;
    free_at_ = 0;
    pend_ = Pending{};
    device_seq_ = 0;
    segments_done = 0;
    v1_acks_owed_ = 0;
    fault_clear_at = -1;
    moves_done = 0;
    seg_done_cycles.clear();
    ack_cycles.clear();
    frames.clear();
  }

  // Decides and sends the next frame (or 0xAA) if it starts before edge `limit`; false when
  // nothing can start before it.
  bool step(Cycle limit) {
    Cycle d;
    if (any_pending()) {
      d = free_at_;
    } else {
      if (events_.empty()) return false;
      d = std::max(free_at_, events_.top().edge + kRespStart);
    }
    if (d >= limit) return false;
    while (!events_.empty() && events_.top().edge + kRespStart <= d) {
      apply(events_.top());
      events_.pop();
    }
    if (before_decide) before_decide(d);
    send(d);
    return true;
  }
  bool idle() const { return !any_pending() && events_.empty(); }
  // The edge step() would decide the next frame on if no input arrives before it; -1 when
  // nothing is pending or queued.
  Cycle next_decision() const {
    if (any_pending()) return free_at_;
    if (events_.empty()) return -1;
    return std::max(free_at_, events_.top().edge + kRespStart);
  }

  uint64_t segments_done = 0;  // v2 FIFO entries completed (the ACK / DONE field)
  uint64_t moves_done = 0;     // seg_done strobes (v1 and v2)
  Cycle fault_clear_at = -1;   // last FAULT_CLEAR edge
  std::vector<Cycle> seg_done_cycles;
  std::vector<Cycle> ack_cycles;  // v1: start edges of the 0xAA bytes
  struct SentFrame {
    Cycle start;
    std::vector<uint8_t> bytes;
  };
  std::vector<SentFrame> frames;  // v2 frames sent

 private:
  struct Event {
    Cycle edge;
    uint64_t order;
    uint8_t what;  // 0 request, 1 v1 done, 2 v2 done
    RespReq r;
    bool operator>(const Event& o) const {
      return edge != o.edge ? edge > o.edge : order > o.order;
    }
  };
  struct Pending {
    bool ident = false, status = false, nak = false, ack = false, done = false;
    uint8_t nak_seq = 0, nak_reason = 0;
  };
  bool any_pending() const {
    return v1_acks_owed_ > 0 || pend_.ident || pend_.status || pend_.nak || pend_.ack || pend_.done;
  }

  void push(Cycle e, uint8_t what, RespReq r = {}) { events_.push(Event{e, order_++, what, r}); }
  void on_req(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    push(clk_.at(delay), 0, payload<RespReq>(gp));
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_done(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Cycle e = clk_.at(delay);
    const SegDone& d = payload<SegDone>(gp);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (d.outputs > 0) {
      for (uint32_t i = 0; i < d.outputs; ++i) push(e, 2);
      return;
    }
    seg_done_cycles.push_back(e);
    ++moves_done;
    push(e, d.v2 ? 2 : 1);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_applied(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    if (payload<Applied>(gp).v2) push(clk_.at(delay), 2);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }

  void apply(const Event& e) {
    if (e.what == 1) {
      ++v1_acks_owed_;
      return;
    }
    if (e.what == 2) {
      ++segments_done;
      pend_.done = true;
      return;
    }
    switch (e.r.kind) {
      case kReqIdent:
        pend_.ident = true;
        break;
      case kReqStatus:
        pend_.status = true;
        break;
      case kReqNak:
        pend_.nak = true;
        pend_.nak_seq = e.r.seq;
        pend_.nak_reason = e.r.reason;
        break;
      case kReqAck:
        pend_.ack = true;
        break;
      case kReqFaultClear:
        fault_clear_at = e.edge;
        break;
      default:
        break;
    }
  }

  static void put16(std::vector<uint8_t>& b, uint32_t v) {
    b.push_back(static_cast<uint8_t>(v >> 8));
    b.push_back(static_cast<uint8_t>(v));
  }
  static void put32(std::vector<uint8_t>& b, uint32_t v) {
    put16(b, v >> 16);
    put16(b, v & 0xffff);
  }

  void send(Cycle d) {
    std::vector<uint8_t> out;
    if (v1_acks_owed_ > 0) {
      --v1_acks_owed_;
      out.push_back(spec::kV1Ack);
    } else {
      StatusSnapshot s{};
      transport(state, gp_, clk_, s, d, tlm::TLM_READ_COMMAND);
      const uint32_t free = p_.fifo_depth - s.fifo_level;
      uint8_t type;
      std::vector<uint8_t> pl;
      if (pend_.ident) {
        pend_.ident = false;
        type = v2::kIdent;
        pl.push_back(2);
        pl.push_back(kAxes);
        put16(pl, p_.fifo_depth);
        put32(pl, static_cast<uint32_t>(p_.clk_hz));
        put32(pl, static_cast<uint32_t>(p_.baud));
        put32(pl, p_.build_id);
        pl.push_back(s.dec.next_seq);
        pl.push_back(v2::kMaxPayload);
      } else if (pend_.status) {
        pend_.status = false;
        type = v2::kStatus;
        const uint8_t faults = static_cast<uint8_t>(s.faults | (s.fault ? 1 : 0));
        pl.push_back(static_cast<uint8_t>(
            (s.busy ? spec::kStateBusy : 0) | (s.dec.v2_mode ? spec::kStateV2 : 0) |
            (faults != 0 ? spec::kStateFault : 0) | (s.hold ? spec::kStateHold : 0) |
            (s.stopped ? spec::kStateStopped : 0)));
        pl.push_back(faults);
        put16(pl, s.fifo_level);
        pl.push_back(s.dec.next_seq);
        put32(pl, static_cast<uint32_t>(segments_done));
        for (int32_t v : s.position) put32(pl, static_cast<uint32_t>(v));
        for (uint16_t c :
             {s.dec.frames_ok, s.dec.crc_errors, s.dec.length_errors, s.dec.unknown_types,
              s.dec.timeouts, s.frame_errors, s.dec.overruns, s.dec.noise, s.clamped})
          put16(pl, c);
        // Limit byte and switch states: the twins have no limit switches (inputs inactive, as
        // cnc_core's with its pins low or LIMIT_ENABLE 0), so never a trip.
        pl.push_back(0);
        put16(pl, 0);
        if (p_.heater_block) {
          // State after edge d - 1 (the snapshot's convention).
          const bool evaluated =
              d - 1 >= static_cast<Cycle>(p_.clk_hz) + 635 - 20;  // kResetHoldRef = -20
          for (int ch = 0; ch < 2; ++ch) {
            put16(pl, evaluated ? 0x8000 : 0);
            for (int i = 0; i < 6; ++i) pl.push_back(0);
          }
        }
      } else if (pend_.nak) {
        pend_.nak = false;
        type = v2::kNak;
        pl = {pend_.nak_seq, pend_.nak_reason, s.dec.next_seq};
        put16(pl, free);
      } else {
        type = pend_.ack ? v2::kAck : v2::kDone;
        pend_.ack = pend_.done = false;
        pl.push_back(s.dec.next_seq);
        put16(pl, free);
        put32(pl, static_cast<uint32_t>(segments_done));
      }
      out = {v2::kSync, static_cast<uint8_t>(pl.size()), device_seq_++, type};
      out.insert(out.end(), pl.begin(), pl.end());
      const uint16_t crc = crc16_ccitt(out.data() + 1, out.size() - 1);
      put16(out, crc);
      frames.push_back(SentFrame{d, out});
    }
    Cycle offer = d + 1, taken = d;
    for (size_t i = 0; i < out.size(); ++i) {
      TxByte t{out[i]};
      taken = transport(tx, gp_, clk_, t, offer);
      if (out.size() == 1) ack_cycles.push_back(taken);
      // The CRC high byte is ready one clock after the last byte it covers was taken.
      offer = taken + (out.size() > 1 && i + 3 == out.size() ? 2 : 1);
    }
    free_at_ = taken + 1;
  }

  const CycleClock& clk_;
  EncoderParams p_;
  std::priority_queue<Event, std::vector<Event>, std::greater<Event>> events_;
  uint64_t order_ = 0;
  Cycle free_at_ = 0;
  Pending pend_;
  uint8_t device_seq_ = 0;
  uint64_t v1_acks_owed_ = 0;
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
