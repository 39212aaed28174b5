// Test-only reference: segment_executor's twin with its ARC run clock by clock (the form before
// arc::Dda::skip_quiet and the computed DIR-write clocks), on the clock-by-clock ref::arc::Dda.
// Everything else is SegmentExecutorTwin's code (segment_executor.h); twins_executor_arcs
// compares the two on random arc jobs.
#pragma once

#include <algorithm>
#include <array>
#include <deque>
#include <limits>
#include <memory>

#include "clockwise_ref.h"
#include "fpgacnc/twins/dda_linear.h"
#include "fpgacnc/twins/segment_executor.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/step_pulse.h"

namespace fpgacnc::twins::ref {

class ClockwiseExecutorTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<ClockwiseExecutorTwin> segments;
  tlm_utils::simple_target_socket<ClockwiseExecutorTwin> status;
  tlm_utils::simple_target_socket<ClockwiseExecutorTwin> abort;
  tlm_utils::simple_initiator_socket<ClockwiseExecutorTwin> done;
  // One DDA load socket and one step_pulse socket (DIR write, state read) per axis.
  std::array<std::unique_ptr<tlm_utils::simple_initiator_socket<ClockwiseExecutorTwin>>, kAxes> dda,
      pulse;

  ClockwiseExecutorTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p,
                        PinRecorder& pins)
      : sc_module(name),
        segments("segments"),
        status("status"),
        abort("abort"),
        done("done"),
        clk_(clk),
        p_(p),
        pins_(pins) {
    last_wr_.fill(kLongAgo);
    segments.register_b_transport(this, &ClockwiseExecutorTwin::on_segment);
    status.register_b_transport(this, &ClockwiseExecutorTwin::on_status);
    abort.register_b_transport(this, &ClockwiseExecutorTwin::on_abort);
    for (int a = 0; a < kAxes; ++a) {
      dda[a] = std::make_unique<tlm_utils::simple_initiator_socket<ClockwiseExecutorTwin>>(
          sc_core::sc_gen_unique_name("dda"));
      pulse[a] = std::make_unique<tlm_utils::simple_initiator_socket<ClockwiseExecutorTwin>>(
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
    arcs = arc_errors = arc_dir_writes = 0;
    seg_start_cycles.clear();
    arc_err_cycles.clear();
    arc_violation_cycles.clear();
    arc_step_edges.clear();
    last_wr_.fill(kLongAgo);
    aborts_.clear();
    trace.clear();
    aborted = 0;
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
  uint64_t arcs = 0;                    // ARC segments
  uint64_t arc_errors = 0;              // of those, ended inconsistently (arc error)
  uint64_t arc_dir_writes = 0;          // DIR writes of X / Y inside arcs (quadrant points)
  std::vector<Cycle> arc_err_cycles;    // edges on which `arc error` (faults bit 1) is latched
  // edges after which an arc's `violation` strobe (a step within DIR setup of its DIR change, or
  // before its DIR is on the pin) is high
  std::vector<Cycle> arc_violation_cycles;
  std::vector<Cycle> arc_step_edges;  // edges of arc step requests (the benches aim aborts at them)
  uint64_t aborted = 0;               // segments dropped by an abort (no seg_done)
  // Per accepted segment (the benches aim aborts with it): accept edge, DIR write edge of the
  // HOLD path (-1: none), last DIR write edge of a zero-gap reversal (-1: none), run edge R, end
  // edge, the abort edge that dropped it (-1: none), kind.
  struct SegTrace {
    Cycle accept, dir_edge, fast_dir, run, end, cut;
    char kind;  // 'L' line, 'D' dwell / no steps, 'P' profile, 'A' arc, 'Z' zero-length
  };
  std::vector<SegTrace> trace;
  // When set: the edge after which each segment stops keeping the executor busy (R + T; its
  // accept edge for T = 0, + 1 when taken on a last tick), in order (cnc_core busy).
  std::vector<Cycle>* entry_ends = nullptr;

 private:
  PulseState pulse_state(int a, Cycle now) {
    PulseState s{};
    transport(*pulse[a], gp_, clk_, s, now, tlm::TLM_READ_COMMAND);
    return s;
  }

  void on_abort(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    AbortSpan a = payload<AbortSpan>(gp);
    a.first = clk_.at(delay);
    aborts_.push_back(a);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  static constexpr Cycle kNever = std::numeric_limits<Cycle>::max();
  // The first abort edge after edge e (kNever: none).
  Cycle abort_after(Cycle e) const {
    for (const AbortSpan& a : aborts_)
      if (a.last > e) return std::max(a.first, e + 1);
    return kNever;
  }
  // The first edge >= e on which the executor may accept from IDLE: not an abort edge and at least
  // max(largest DIR setup, 1) edges after the last one (settle_reg).
  Cycle ready_from(Cycle e) const {
    uint32_t settle = 1;
    for (const auto& t : p_.timing) settle = std::max(settle, t.setup);
    for (const AbortSpan& a : aborts_)
      if (e >= a.first && e <= a.last + static_cast<Cycle>(settle))
        e = a.last + static_cast<Cycle>(settle) + 1;
    return e;
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
  static constexpr Cycle kLongAgo = -1'000'000'000;

  // A DIR write of axis a landing on edge e (the executor's dir_wr in the clock before e).
  void dir_write(int a, bool d, Cycle e) {
    PulseCmd c{d};
    transport(*pulse[a], gp_, clk_, c, e, tlm::TLM_WRITE_COMMAND, kDirWrite);
    last_wr_[static_cast<size_t>(a)] = e;
  }

  // Kind ARC from edge R (the walk's clock c is the clock after edge R + c): arc::Dda clock by
  // clock (rtl/motion/arc_dda.v's walk and pacing in exact integers); an event of clock c is a step
  // request on edge R + c + 2. X / Y reverse inside the arc: from the walk's W1 clock on the
  // executor knows the next move's direction (Dda::next_x_pos / next_y_pos); when it differs from
  // the DIR target the write becomes pending and lands on the first edge after a clock in which
  // the axis's DIR hold since its last STEP rise has elapsed and no arc step request of that axis
  // is high. An X / Y step whose direction is not on the pin yet, or that comes less than DIR
  // setup after the last DIR write of its axis, strobes `violation` (not delayed). Returns the
  // number of ticks (last move's clock + 2): the segment's last edge is R + ticks, the edge of the
  // last move's step request.
  // Abort: nothing lands on an edge >= cut (the walk stops; returns -1 when the arc's end edge
  // R + ticks is >= cut: the segment is dropped).
  Cycle run_arc(const Segment& s, Cycle r, Cycle cut) {
    ref::arc::Dda dda(s.arc_frame);
    std::array<bool, 2> tgt{s.dir[0], s.dir[1]}, pend{};
    std::array<bool, 2> pin{};
    std::array<Cycle, 2> last_rise{};
    std::array<Cycle, 3> req{kLongAgo, kLongAgo, kLongAgo};
    std::array<std::deque<Cycle>, 2> rises;  // rise edges not yet reached
    for (size_t k = 0; k < 2; ++k) {
      const PulseState st = pulse_state(static_cast<int>(k), r);
      pin[k] = st.dir;
      last_rise[k] = st.last_rise;
    }
    // the first clock with a DIR write possible for a pending axis k, at or after clock t
    auto write_if_ok = [&](size_t k, Cycle t) {
      while (!rises[k].empty() && rises[k].front() <= t) {
        last_rise[k] = rises[k].front();
        rises[k].pop_front();
      }
      const Cycle hold = p_.timing[k].hold;
      if (t + 1 >= last_rise[k] + hold && req[k] != t + 1) {
        dir_write(static_cast<int>(k), tgt[k], t + 1);
        pin[k] = tgt[k];
        pend[k] = false;
        ++arc_dir_writes;
      }
    };
    Cycle last = 0;
    while (!dda.done()) {
      const auto c = static_cast<Cycle>(dda.next_clock());
      const Cycle t = r + c;
      if (t + 1 >= cut) {  // aborted: nothing of this clock or later lands
        ++arcs;
        return -1;
      }
      for (size_t k = 0; k < 2; ++k)
        if (pend[k]) write_if_ok(k, t);
      if (dda.dir_valid()) {
        const std::array<bool, 2> nd{dda.next_x_pos(), dda.next_y_pos()};
        for (size_t k = 0; k < 2; ++k)
          if (nd[k] != tgt[k]) {
            tgt[k] = nd[k];
            pend[k] = true;
          }
      }
      const arc::Event ev = dda.clock();
      const Cycle e = t + 2;
      bool viol = false;
      const std::array<int, 3> d{ev.dx, ev.dy, ev.dz};
      for (size_t k = 0; k < 3 && k < static_cast<size_t>(kAxes); ++k) {
        if (d[k] == 0 || e >= cut) continue;  // (a request in flight on the abort edge: gated)
        const bool dir = d[k] > 0;
        if (k < 2) {
          if (dir != pin[k] || e - last_wr_[k] < static_cast<Cycle>(p_.timing[k].setup))
            viol = true;
        }
        PulseCmd cmd{dir};
        const Cycle rise = transport(*pulse[k], gp_, clk_, cmd, e);
        if (k < 2) rises[k].push_back(rise);
        req[k] = e;
        arc_step_edges.push_back(e);
      }
      if (viol) arc_violation_cycles.push_back(e);
      last = c;
    }
    const Cycle ticks = last + 2;
    // A write still pending at the end (only when the arc outran its DIR timing) lands from the
    // segment's last tick on (not with the last step request of its axis), as in IDLE or in the
    // next segment's run.
    for (size_t k = 0; k < 2; ++k)
      for (Cycle t = r + last + 1; pend[k] && t + 1 < cut; ++t) write_if_ok(k, t);
    ++arcs;
    if (dda.err()) {
      ++arc_errors;
      arc_err_cycles.push_back(r + last + 2);
    }
    return ticks;
  }

  void on_segment(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    Segment s = payload<Segment>(gp);
    const Cycle valid = clk_.at(delay);
    // ARC: never zero-length; its length is known once the walk has run (below).
    if (s.arc) s.total = 1;
    // PROFILE: the run in exact integers (profile_gen + dda_profile); the segment lasts J ticks
    // and is never zero-length (n_dom >= 1), so below it is handled as a segment of T = J.
    ProfileRun prof;
    if (s.prof) {
      prof = ref::run_profile(s.profile, s.steps);
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
    // Offered while the last tick of a running segment is issued: accepted on its last edge (a
    // running segment that an abort dropped is not running: running_ is false then).
    const bool on_last_tick = running_ && valid < run_end_;
    const bool queued = on_last_tick && s.total != 0 && (!change || s.dir_fast);
    Cycle accept, run;
    Cycle cut = kNever;  // the first abort edge after the accept edge
    Cycle dir_edge = -1, fast_dir = -1;
    if (s.prof && change) ++profiled_reversing;
    if (queued) {
      accept = run = run_end_;
      cut = abort_after(accept);
      ++zero_gap;
      if (s.prof) ++profiled_zero_gap;
      if (change) ++fast_reversals;
      for (int a = 0; a < kAxes; ++a) {
        if (!flip[a]) continue;
        const Cycle d =
            std::max<Cycle>(run_end_ + kFastDirDelay, st[a].last_rise + p_.timing[a].hold);
        fast_dir = std::max(fast_dir, d);
        if (d < cut) dir_write(a, s.dir[a], d);  // else cancelled by the abort (pend_reg)
      }
    } else {
      accept = on_last_tick ? run_end_ : ready_from(std::max(valid + 1, idle_after_ + 1));
      cut = abort_after(accept);
      if (on_last_tick && s.total == 0) ++zero_len_on_last_tick;
      if (on_last_tick && s.total != 0) ++hold_on_last_tick;
      run = accept;
      if (change) {
        dir_edge = accept + 1;
        uint32_t setup = 0;
        for (int a = 0; a < kAxes; ++a) {
          if (!flip[a]) continue;
          const PulseState now = pulse_state(a, accept);
          dir_edge = std::max(dir_edge, now.last_rise + p_.timing[a].hold);
          setup = std::max(setup, p_.timing[a].setup);
        }
        if (dir_edge < cut)  // an abort in HOLD cancels the write
          for (int a = 0; a < kAxes; ++a)
            if (flip[a]) dir_write(a, s.dir[a], dir_edge);
        run = dir_edge + std::max<uint32_t>(setup, 1);
      }
    }
    delay = clk_.delay_to(accept);
    // T = 0 completes at once; accepted on a last tick it passes one clock in ZERO.
    Cycle end = on_last_tick ? accept + 1 : accept;
    const char kind =
        s.arc                                                                            ? 'A'
        : s.prof                                                                         ? 'P'
        : s.total == 0                                                                   ? 'Z'
        : std::all_of(s.steps.begin(), s.steps.end(), [](uint32_t n) { return n == 0; }) ? 'D'
                                                                                         : 'L';
    running_ = s.total != 0;
    bool dropped = s.total != 0 ? run >= cut : end >= cut;  // HOLD / SETUP, or in ZERO
    if (s.arc && !dropped) {  // an arc the abort stops runs until edge `cut` (dropped there)
      const Cycle ticks = run_arc(s, run, cut);
      s.total = static_cast<uint64_t>(ticks < 0 ? cut - run : ticks);
    }
    if (s.total != 0 && !dropped) {
      seg_start_cycles.push_back(run);
      end = run + static_cast<Cycle>(s.total);
      dropped = end >= cut;
      if (s.code != 0 && s.power != 0) {  // laser low from the abort edge (combinational gate)
        pins_.add(run, models::kLaser, 1);
        pins_.add(std::min(end, cut), models::kLaser, 0);
      }
      for (int a = 0; a < kAxes && !s.arc; ++a) {
        if (s.steps[a] == 0) continue;
        if (s.prof) {  // a step in tick j: step request on edge R + j (STEP rises there)
          PulseCmd none{false};
          for (uint64_t j : prof.ticks[a]) {
            if (run + static_cast<Cycle>(j) >= cut) break;
            transport(*pulse[a], gp_, clk_, none, run + static_cast<Cycle>(j));
          }
          continue;
        }
        DdaLoad l{s.steps[a], s.total, cut};
        transport(*dda[a], gp_, clk_, l, run);
      }
      run_end_ = end;
    }
    trace.push_back(SegTrace{accept, dir_edge, fast_dir, run, end, dropped ? cut : -1, kind});
    if (dropped) {  // idle after the abort edge, no seg_done
      ++aborted;
      running_ = false;
      idle_after_ = cut;
      if (entry_ends) entry_ends->push_back(cut);
      return;
    }
    idle_after_ = end;
    if (entry_ends) entry_ends->push_back(end);
    SegDone d{s.v2};
    transport(done, gp_, clk_, d, end);
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  PinRecorder& pins_;
  Cycle idle_after_ = -1;               // state IDLE after this edge
  Cycle run_end_ = -1;                  // edge of the last tick of the last segment with T > 0
  bool running_ = false;                // the last segment accepted has T > 0
  std::array<Cycle, kAxes> last_wr_{};  // edge of the last DIR write per axis (since_wr_reg)
  std::vector<AbortSpan> aborts_;       // abort spans, in time order
  tlm::tlm_generic_payload gp_;
};

// make_axis_twins for the reference executor.
inline void make_axis_twins(ClockwiseExecutorTwin& exec, const CycleClock& clk, const CoreParams& p,
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

}  // namespace fpgacnc::twins::ref
