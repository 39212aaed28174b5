// Twin of rtl/segment_executor.v: DIR hold/setup sequencing, the run of a segment, the laser
// (docs/timing.md "STEP/DIR per move").
//
// Target `segments`: a Segment valid from the delay's edge V; accepted on the first edge after
// V on which the executor is idle (returned in the delay). Then, with A the accept edge:
//   T = 0: done at once (seg_done after edge A).
//   no moving axis changes direction: the run starts at R = A.
//   otherwise: DIR is written at D = the first edge after A on which every reversing axis's
//   DIR hold has elapsed since its last STEP rise (asked from its step_pulse), and the run
//   starts at R = D + max(largest DIR setup of the reversing axes, 1).
//   Laser high from edge R to edge R + T for codes 1..3. Each axis's dda_linear is loaded with
//   (n, T) at R; seg_done after edge R + T, sent to initiator `done` (the status/ACK block).
// Target `status` (read): ExecIdle, the edge after which the executor and every pulse are idle.
#pragma once

#include <memory>

#include "fpgacnc/twins/dda_linear.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/step_pulse.h"

namespace fpgacnc::twins {

class SegmentExecutorTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<SegmentExecutorTwin> segments;
  tlm_utils::simple_target_socket<SegmentExecutorTwin> status;
  tlm_utils::simple_initiator_socket<SegmentExecutorTwin> done;
  // One DDA load socket and one step_pulse socket (DIR write, state read) per axis.
  std::array<std::unique_ptr<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>, kAxes> dda,
      pulse;

  SegmentExecutorTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p,
                      PinRecorder& pins)
      : sc_module(name),
        segments("segments"),
        status("status"),
        done("done"),
        clk_(clk),
        p_(p),
        pins_(pins) {
    segments.register_b_transport(this, &SegmentExecutorTwin::on_segment);
    status.register_b_transport(this, &SegmentExecutorTwin::on_status);
    for (int a = 0; a < kAxes; ++a) {
      dda[a] = std::make_unique<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>(
          sc_core::sc_gen_unique_name("dda"));
      pulse[a] = std::make_unique<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>(
          sc_core::sc_gen_unique_name("pulse"));
    }
  }

  void reset() {
    idle_after_ = -1;
    segments_run = 0;
    seg_start_cycles.clear();
  }
  uint64_t segments_run = 0;
  std::vector<Cycle> seg_start_cycles;  // edges after which seg_start is high

 private:
  PulseState pulse_state(int a, Cycle now) {
    PulseState s{};
    transport(*pulse[a], gp_, clk_, s, now, tlm::TLM_READ_COMMAND);
    return s;
  }

  void on_status(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    Cycle e = idle_after_;
    for (int a = 0; a < kAxes; ++a) e = std::max(e, pulse_state(a, clk_.at(delay)).idle_from);
    payload<ExecIdle>(gp).edge = e;
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }

  void on_segment(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Segment s = payload<Segment>(gp);
    const Cycle accept = std::max(clk_.at(delay) + 1, idle_after_ + 1);
    delay = clk_.delay_to(accept);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    ++segments_run;
    Cycle end = accept;
    if (s.total != 0) {
      Cycle run = accept;
      Cycle dir_edge = accept + 1;
      uint32_t setup = 0;
      bool change = false;
      std::array<bool, kAxes> flip{};
      for (int a = 0; a < kAxes; ++a) {
        if (s.steps[a] == 0) continue;
        const PulseState st = pulse_state(a, accept);
        if (st.dir == s.dir[a]) continue;
        flip[a] = change = true;
        dir_edge = std::max(dir_edge, st.last_rise + p_.timing[a].hold);
        setup = std::max(setup, p_.timing[a].setup);
      }
      if (change) {
        for (int a = 0; a < kAxes; ++a) {
          if (!flip[a]) continue;
          PulseCmd c{s.dir[a]};
          transport(*pulse[a], gp_, clk_, c, dir_edge, tlm::TLM_WRITE_COMMAND, kDirWrite);
        }
        run = dir_edge + std::max<uint32_t>(setup, 1);
      }
      seg_start_cycles.push_back(run);
      if (s.code != 0) {
        pins_.add(run, simboard::kLaser, 1);
        pins_.add(run + static_cast<Cycle>(s.total), simboard::kLaser, 0);
      }
      for (int a = 0; a < kAxes; ++a) {
        if (s.steps[a] == 0) continue;
        DdaLoad l{s.steps[a], s.total};
        transport(*dda[a], gp_, clk_, l, run);
      }
      end = run + static_cast<Cycle>(s.total);
    }
    idle_after_ = end;
    SegDone d{};
    transport(done, gp_, clk_, d, end);
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  PinRecorder& pins_;
  Cycle idle_after_ = -1;  // state IDLE after this edge
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
