// Twin of rtl/segment_executor.v: DIR hold/setup sequencing, the run of a segment, queued
// segments without idle clocks, the laser (docs/timing.md "STEP/DIR per move", "Queued segments").
//
// Target `segments`: a Segment valid from the delay's edge V. With E the edge of the last tick
// of the segment running (R + T), the segment is accepted on edge A (returned in the delay):
//   zero gap: a segment with T > 0 runs, V < E (valid while the last tick is issued), the new
//     segment has T > 0, and no moving axis reverses or the segment is dir_fast: A = R' = E.
//     A reversing axis's DIR changes on the first edge >= E + kFastDirDelay on which its DIR
//     hold since its last STEP rise has elapsed (its first step comes at least hold + setup
//     after R', the prep's dir_fast guarantee).
//   otherwise: A = E when V < E (the executor takes a segment during the last tick), else the
//     first edge after V on which the executor is idle (from E + 1, or A + 1 after a segment of
//     T = 0, A + 2 after one taken on a last tick). T = 0: done at once (seg_done after edge
//     A, or A + 1 when taken on a last tick: one clock in ZERO). No moving axis changes
//     direction: the run starts at R = A. Otherwise DIR is written at D = the first edge after
//     A on which every reversing axis's DIR hold has elapsed since its last STEP rise (asked
//     from its step_pulse), and the run starts at R = D + max(largest DIR setup of the
//     reversing axes, 1).
//   Tick c of the run is edge R + c; each axis's dda_linear is loaded with (n, T) at R; a
//   segment without steps (a dwell) just lasts T ticks. Laser high from edge R to edge R + T
//   for codes 1..3 with power > 0 (back-to-back cutting segments keep it high: the recorder
//   cancels a fall and a rise on the same edge). seg_done after edge R + T, sent to initiator
//   `done` with the segment's v2 bit.
//   Kind PROFILE (Segment::prof, from LINE_PROFILE): T is the J of run_profile (timing.h: the
//   U/V master and floor(U*n_a/M) per axis in exact integers, as profile_gen and dda_profile);
//   the k-th step of an axis in tick j is a step request on edge R + j, sent straight to the
//   axis's step_pulse. dir_fast is 0, so a reversing axis always takes HOLD/SETUP. Everything
//   else (accept edges, zero gap, laser, seg_done) as for a segment of T = J.
// Target `status` (read): ExecIdle, the edge after which the executor and every pulse are idle.
#pragma once

#include <array>
#include <memory>

#include "fpgacnc/twins/dda_linear.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/step_pulse.h"

namespace fpgacnc::twins {

inline constexpr Cycle kFastDirDelay = 1;  // earliest DIR change after a zero-gap accept edge

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
    run_end_ = -1;
    running_ = false;
    segments_run = 0;
    profiled = profiled_zero_gap = profiled_reversing = profiled_triangles = 0;
    zero_gap = fast_reversals = zero_len_on_last_tick = hold_on_last_tick = 0;
    seg_start_cycles.clear();
  }
  uint64_t segments_run = 0;
  uint64_t profiled = 0;                // PROFILE segments (LINE_PROFILE)
  uint64_t profiled_zero_gap = 0;       // of those, started on the previous one's last tick
  uint64_t profiled_reversing = 0;      // of those, with a reversing axis (HOLD/SETUP path)
  uint64_t profiled_triangles = 0;      // of those, never at V_cruise
  uint64_t zero_gap = 0;                // segments started on the previous one's last tick
  uint64_t fast_reversals = 0;          // of those, with a DIR write during the run (dir_fast)
  uint64_t zero_len_on_last_tick = 0;   // T = 0 taken on a last tick (one clock in ZERO)
  uint64_t hold_on_last_tick = 0;       // taken on a last tick, then HOLD / SETUP
  std::vector<Cycle> seg_start_cycles;  // edges after which seg_start is high
  // When set: the edge after which each segment stops keeping the executor busy (R + T; its
  // accept edge for T = 0, + 1 when taken on a last tick), in order (cnc_core busy).
  std::vector<Cycle>* entry_ends = nullptr;

 private:
  PulseState pulse_state(int a, Cycle now) {
    PulseState s{};
    transport(*pulse[a], gp_, clk_, s, now, tlm::TLM_READ_COMMAND);
    return s;
  }

  void on_status(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    payload<ExecIdle>(gp).edge = idle_edge(clk_.at(delay));
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }

 public:
  // The edge after which the executor and every STEP pulse are idle (exec_idle), asked at `now`.
  Cycle idle_edge(Cycle now) {
    Cycle e = idle_after_;
    for (int a = 0; a < kAxes; ++a) e = std::max(e, pulse_state(a, now).idle_from);
    return e;
  }

 private:
  void on_segment(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    Segment s = payload<Segment>(gp);
    const Cycle valid = clk_.at(delay);
    // PROFILE: the run in exact integers (profile_gen + dda_profile); the segment lasts J ticks
    // and is never zero-length (n_dom >= 1), so below it is handled as a segment of T = J.
    ProfileRun prof;
    if (s.prof) {
      prof = run_profile(s.profile, s.steps);
      s.total = prof.ticks_total;
      ++profiled;
      if (!prof.cruised) ++profiled_triangles;
    }
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    ++segments_run;
    // Which moving axes reverse (DIR as it will be: every earlier write is already recorded).
    std::array<bool, kAxes> flip{};
    std::array<PulseState, kAxes> st{};
    bool change = false;
    for (int a = 0; a < kAxes; ++a) {
      if (s.steps[a] == 0 || s.total == 0) continue;
      st[a] = pulse_state(a, valid);
      if (st[a].dir == s.dir[a]) continue;
      flip[a] = change = true;
    }
    // Offered while the last tick of a running segment is issued: accepted on its last edge.
    const bool on_last_tick = running_ && valid < run_end_;
    const bool queued = on_last_tick && s.total != 0 && (!change || s.dir_fast);
    Cycle accept, run;
    if (s.prof && change) ++profiled_reversing;
    if (queued) {
      accept = run = run_end_;
      ++zero_gap;
      if (s.prof) ++profiled_zero_gap;
      if (change) ++fast_reversals;
      for (int a = 0; a < kAxes; ++a) {
        if (!flip[a]) continue;
        PulseCmd c{s.dir[a]};
        const Cycle d =
            std::max<Cycle>(run_end_ + kFastDirDelay, st[a].last_rise + p_.timing[a].hold);
        transport(*pulse[a], gp_, clk_, c, d, tlm::TLM_WRITE_COMMAND, kDirWrite);
      }
    } else {
      accept = on_last_tick ? run_end_ : std::max(valid + 1, idle_after_ + 1);
      if (on_last_tick && s.total == 0) ++zero_len_on_last_tick;
      if (on_last_tick && s.total != 0) ++hold_on_last_tick;
      run = accept;
      if (change) {
        Cycle dir_edge = accept + 1;
        uint32_t setup = 0;
        for (int a = 0; a < kAxes; ++a) {
          if (!flip[a]) continue;
          const PulseState now = pulse_state(a, accept);
          dir_edge = std::max(dir_edge, now.last_rise + p_.timing[a].hold);
          setup = std::max(setup, p_.timing[a].setup);
        }
        for (int a = 0; a < kAxes; ++a) {
          if (!flip[a]) continue;
          PulseCmd c{s.dir[a]};
          transport(*pulse[a], gp_, clk_, c, dir_edge, tlm::TLM_WRITE_COMMAND, kDirWrite);
        }
        run = dir_edge + std::max<uint32_t>(setup, 1);
      }
    }
    delay = clk_.delay_to(accept);
    // T = 0 completes at once; accepted on a last tick it passes one clock in ZERO.
    Cycle end = on_last_tick ? accept + 1 : accept;
    running_ = s.total != 0;
    if (s.total != 0) {
      seg_start_cycles.push_back(run);
      if (s.code != 0 && s.power != 0) {
        pins_.add(run, simboard::kLaser, 1);
        pins_.add(run + static_cast<Cycle>(s.total), simboard::kLaser, 0);
      }
      for (int a = 0; a < kAxes; ++a) {
        if (s.steps[a] == 0) continue;
        if (s.prof) {  // a step in tick j: step request on edge R + j (STEP rises there)
          PulseCmd none{false};
          for (uint64_t j : prof.ticks[a])
            transport(*pulse[a], gp_, clk_, none, run + static_cast<Cycle>(j));
          continue;
        }
        DdaLoad l{s.steps[a], s.total};
        transport(*dda[a], gp_, clk_, l, run);
      }
      end = run + static_cast<Cycle>(s.total);
      run_end_ = end;
    }
    idle_after_ = end;
    if (entry_ends) entry_ends->push_back(end);
    SegDone d{s.v2};
    transport(done, gp_, clk_, d, end);
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  PinRecorder& pins_;
  Cycle idle_after_ = -1;  // state IDLE after this edge
  Cycle run_end_ = -1;     // edge of the last tick of the last segment with T > 0
  bool running_ = false;   // the last segment accepted has T > 0
  tlm::tlm_generic_payload gp_;
};

// Creates the per-axis DDA and step_pulse twins of `exec` and binds them: executor -> DDA load,
// executor -> step_pulse control, DDA step -> step_pulse request. Shared by the virtual board
// and the executor benches. Call from the enclosing module's constructor (names are generated
// in its scope).
inline void make_axis_twins(SegmentExecutorTwin& exec, const CycleClock& clk, const CoreParams& p,
                            PinRecorder& pins,
                            std::array<std::unique_ptr<DdaLinearTwin>, kAxes>& dda,
                            std::array<std::unique_ptr<StepPulseTwin>, kAxes>& pulse) {
  for (int a = 0; a < kAxes; ++a) {
    dda[a] = std::make_unique<DdaLinearTwin>(sc_core::sc_gen_unique_name("dda_linear"), clk);
    pulse[a] = std::make_unique<StepPulseTwin>(sc_core::sc_gen_unique_name("step_pulse"), clk,
                                               p.timing[a], a, pins);
    exec.dda[a]->bind(dda[a]->load);
    exec.pulse[a]->bind(pulse[a]->ctl);
    dda[a]->step.bind(pulse[a]->req);
  }
}

}  // namespace fpgacnc::twins
