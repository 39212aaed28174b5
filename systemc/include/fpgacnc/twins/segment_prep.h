// Twin of rtl/segment_prep.v: v1 timing semantics (docs/protocol.md "Timing semantics",
// docs/timing.md "Segment length").
//
// Target `commands`: a Command valid from the delay's edge V. It is accepted on the first edge
// after V on which the block is idle (its previous segment taken by the executor) and, for an
// init, the executor is idle (asked on initiator `exec_status`); the delay returned names the
// accept edge. An init sets NUMERATOR_X/Y. A motion becomes a Segment (dominant axis,
// P = NUMERATOR_dom / feed or FEED0_PERIOD, raised to min_period, T = P * N, tmn = T - |steps|)
// valid PREP_LATENCY = 68 edges after acceptance, offered on initiator `segments`; the block
// is idle again from the edge after the executor takes it.
#pragma once

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

inline constexpr Cycle kPrepLatency = 68;

struct ExecIdle {  // segment_executor status read: idle (and every STEP pulse done) after `edge`
  Cycle edge;
};

class SegmentPrepTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<SegmentPrepTwin> commands;
  tlm_utils::simple_initiator_socket<SegmentPrepTwin> segments;
  tlm_utils::simple_initiator_socket<SegmentPrepTwin> exec_status;

  SegmentPrepTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p)
      : sc_module(name),
        commands("commands"),
        segments("segments"),
        exec_status("exec_status"),
        clk_(clk),
        p_(p) {
    commands.register_b_transport(this, &SegmentPrepTwin::b_transport);
  }

  void reset() {
    free_from_ = 0;
    num_x = num_y = p_.default_numerator;
    last_period = 0;
    last_feed = 0;
    last_code = 0;
  }
  uint32_t num_x = 18'750'000, num_y = 18'750'000;
  uint32_t last_period = 0;
  uint16_t last_feed = 0;
  uint8_t last_code = 0;

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Command c = payload<Command>(gp);
    Cycle accept = std::max(clk_.at(delay) + 1, free_from_);
    if (c.init) {
      ExecIdle idle{0};
      transport(exec_status, gp_, clk_, idle, clk_.at(delay), tlm::TLM_READ_COMMAND);
      accept = std::max(accept, idle.edge + 1);
      num_x = c.a;
      num_y = c.b;
      free_from_ = accept + 1;
    } else {
      const auto sx = static_cast<int32_t>(c.a), sy = static_cast<int32_t>(c.b);
      const uint32_t ax = sx < 0 ? 0u - c.a : c.a, ay = sy < 0 ? 0u - c.b : c.b;
      const PreparedTiming t =
          prepare_timing(ax, ay, num_x, num_y, c.feed, p_.feed0_period, p_.min_period());
      Segment s{};
      s.code = c.code;
      s.dir = {sx >= 0, sy >= 0, false, false};
      s.steps = {ax, ay, 0, 0};
      for (int a = 0; a < kAxes; ++a) s.tmn[a] = t.total - s.steps[a];
      s.total = t.total;
      s.period = t.period;
      s.feed = c.feed;
      const Cycle taken = transport(segments, gp_, clk_, s, accept + kPrepLatency);
      free_from_ = taken + 1;
      last_period = t.period;
      last_feed = c.feed;
      last_code = c.code;
    }
    delay = clk_.delay_to(accept);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  Cycle free_from_ = 0;  // first edge on which a command can be accepted
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
