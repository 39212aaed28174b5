// Twin of rtl/motion/segment_executor.v: DIR hold/setup sequencing, the run of a segment, queued
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
//   Kind ARC (Segment::arc, from an ARC frame): run_arc below (arc::Dda, an event of
//   walk clock c a step request on edge R + c + 2, in-arc DIR writes and DIR-setup violations,
//   arc error); the segment lasts c_last + 2 ticks (c_last: the clock of the last move), so the
//   last move's step request lands on the segment's last edge as for every other kind. dir_fast
//   is 0; otherwise as a segment of that T.
// The motion rate (member `rate`, feed_rate.h; null: every clock is a tick): "tick j" of a run
//   started on edge R is the j-th clock with `adv` high from the clock after R, "edge R + j" the
//   edge after it (FeedRate::tick_edge), for the LINE DDAs, the PROFILE ticks and the end edge
//   R + T; the arc's walk clock c is its (c + 1)-th tick, its step request lands two edges after
//   that clock (in the clock after the walk's tick whether or not that clock is a tick) and its
//   last tick is the first tick after the walk's ending tick. DIR hold / setup and the HOLD /
//   SETUP waits count real clocks. The laser is low in every clock with r = 0 (cnc_core's gate:
//   laser_rate_gate, off for the block alone). Every accepted
//   segment sends its code to the rate on its accept edge (the target: rapid for code 0, else
//   feed). A segment whose ticks never come (a hold never resumed) ends at kHeldForever.
// Target `abort` (write, AbortSpan): the e-stop input high on edges first..last (rtl `abort`),
//   sent before any segment that can reach it. With X = the first abort edge after a segment's
//   accept edge A: no step request on an edge >= X (DDA, profile and arc requests are cut there;
//   a STEP already high finishes its high time, its low time still counts: step_pulse sees
//   nothing new), no DIR write on an edge >= X (a pending write is cancelled; DIR keeps its level
//   and the next segment is compared with it), the arc walk stops, no arc error or arc DIR
//   violation from X on. A segment whose end edge (R + T; A + 1 for a zero-length one taken on a
//   last tick) or run edge R is >= X is dropped at X: no seg_start (R >= X), no seg_done, laser low
//   from edge X, the executor idle after X. No segment is accepted on an abort edge, and from IDLE
//   only from edge last + max(largest DIR setup, 1) + 1 (settle_reg). An offer held through the
//   abort is accepted then (the block bench); in cnc_core segment_prep drops it (the prep twin
//   models that for CANCEL's flush: accept_edge).
// Target `status` (read): ExecIdle, the edge after which the executor and every pulse are idle.
// output(H, cmd): an OUTPUT entry handed over on edge H (segment_prep's on_output). It takes effect
//   on edge max(H, end edge of the last segment accepted), the edge that ends the segment in
//   progress (R + T, or A + 1 of a zero-length one in ZERO), H when idle; entries taking effect
//   on one edge are merged (later bits win). Sent to `done` as SegDone::outputs on that edge
//   (out_done). With record_outputs the levels are pin edges (coolant_flood, coolant_mist,
//   dout[n]) and the fan duty drives the fan pin's PWM (rtl/machine/pwm.v: 256 counts of fan_div()
//   clocks counted from fan_phase clocks before cycle 0, the duty taken at each period boundary,
//   255 always high), generated by flush_outputs(horizon) at the end of a job: every edge up to
//   the pin settling low at duty 0, or up to `horizon` while the duty is not 0. Not modelled: the
//   abort (e-stop) clearing the outputs (the boards using outputs have no e-stop input).
// The laser / spindle PWM (rtl/machine/laser_pwm.v, laser_scale.v; docs/machine.md "Laser and
//   spindle PWM"), with record_outputs, also from flush_outputs: within each span of the laser
//   pin high (back-to-back spans joined), periods of 256 * laser_div() clocks from laser_lat + 1
//   clocks after its start, each high for its duty's counts (255: the whole period) and low from
//   the span's end; the duty from the clock laser_lat + 1 before the period (the span's first
//   clock for the first): the power of the segment last accepted, with the M3 / M4 mode of OUTPUT
//   mask bit 7 applied by then (M4: times floor(r / 2^16) and, for a PROFILE, floor(2^16 V /
//   V_cruise), V = V(1 + the run's ticks before that clock), over 2^32). Its cost grows with the
//   periods.
#pragma once

#include <algorithm>
#include <array>
#include <deque>
#include <limits>
#include <memory>

#include "fpgacnc/twins/dda_linear.h"
#include "fpgacnc/twins/feed_rate.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/step_pulse.h"

namespace fpgacnc::twins {

inline constexpr Cycle kFastDirDelay = 1;  // earliest DIR change after a zero-gap accept edge
// The end edge of a segment whose ticks never come (the rate held at 0 for good): far beyond any
// job (6 hours at 50 MHz), so that nothing after it is scheduled.
inline constexpr Cycle kHeldForever = Cycle{1} << 40;

class SegmentExecutorTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<SegmentExecutorTwin> segments;
  tlm_utils::simple_target_socket<SegmentExecutorTwin> status;
  tlm_utils::simple_target_socket<SegmentExecutorTwin> abort;
  tlm_utils::simple_initiator_socket<SegmentExecutorTwin> done;
  // One DDA load socket and one step_pulse socket (DIR write, state read) per axis.
  std::array<std::unique_ptr<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>, kAxes> dda,
      pulse;

  SegmentExecutorTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p,
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
    segments.register_b_transport(this, &SegmentExecutorTwin::on_segment);
    status.register_b_transport(this, &SegmentExecutorTwin::on_status);
    abort.register_b_transport(this, &SegmentExecutorTwin::on_abort);
    for (int a = 0; a < kAxes; ++a) {
      dda[a] = std::make_unique<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>(
          sc_core::sc_gen_unique_name("dda"));
      pulse[a] = std::make_unique<tlm_utils::simple_initiator_socket<SegmentExecutorTwin>>(
          sc_core::sc_gen_unique_name("pulse"));
    }
  }

  void reset() {
    lvl_ = duty_ = 0;
    power_segs_.clear();
    dyn_events_.clear();
    laser_spans_.clear();
    pend_n_ = 0;
    pend_edge_ = -1;
    duty_events_.clear();
    outputs_applied = 0;
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
  bool record_outputs = false;        // machine outputs as pin edges (output(), flush_outputs())
  uint64_t outputs_applied = 0;       // OUTPUT entries
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
  // The motion rate (ticks and the laser's r = 0 gate); null: every clock is a tick.
  FeedRate* rate = nullptr;
  // The laser low while r = 0 (cnc_core gates the executor's laser with feed_rate's `stopped`;
  // off for the block alone).
  bool laser_rate_gate = true;

 private:
  // The edge of tick j of a run started on edge r (j = 0: r).
  Cycle tick_edge(Cycle r, uint64_t j) {
    if (rate == nullptr) return r + static_cast<Cycle>(j);
    const Cycle e = rate->tick_edge(r, j);
    return e == FeedRate::kNever ? kHeldForever : std::min(e, kHeldForever);
  }
  // The clock of walk clock c of an arc run from edge r (its (c + 1)-th tick).
  Cycle walk_clock(Cycle r, Cycle c) { return tick_edge(r, static_cast<uint64_t>(c) + 1) - 1; }
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
  // The edge on which a segment offered from edge `valid` would be accepted (on_segment's rule),
  // without taking it: segment_prep drops a prepared segment the executor would take on or after
  // an abort edge (cnc_core).
  Cycle accept_edge(const Segment& s, Cycle valid) {
    const bool moves = s.arc || s.prof || s.total != 0;
    bool change = false;
    for (int a = 0; a < kAxes && moves; ++a)
      if (s.steps[a] != 0 && pulse_state(a, valid).dir != s.dir[a]) change = true;
    const bool on_last_tick = running_ && valid < run_end_;
    if (on_last_tick && moves && (!change || s.dir_fast)) return run_end_;
    return on_last_tick ? run_end_ : ready_from(std::max(valid + 1, idle_after_ + 1));
  }
  void output(Cycle h, const OutputCmd& o) {
    const Cycle e = std::max(h, idle_after_);
    if (pend_n_ > 0 && e != pend_edge_) flush_group();
    if (pend_n_ == 0) {
      pend_edge_ = e;
      pend_lvl_ = lvl_;
      pend_duty_ = duty_;
    }
    if (o.mask & spec::kOutLaserDyn)
      dyn_events_.emplace_back(e, (o.value & spec::kOutLaserDyn) != 0);
    const uint8_t m = o.mask & 0x7B;  // flood, mist, dout[0..3]
    pend_lvl_ = static_cast<uint8_t>((pend_lvl_ & ~m) | (o.value & m));
    if (o.mask & 0x04) pend_duty_ = o.duty;
    ++pend_n_;
    ++outputs_applied;
    if (entry_ends) entry_ends->push_back(e);
    SegDone d{false, 1};
    transport(done, gp_, clk_, d, e);
  }
  // Emits the pin edges of the outputs (see output()); the fan's PWM edges up to `horizon` while
  // its duty is not 0 (then every edge until the pin settles low).
  void flush_outputs(Cycle horizon) {
    if (pend_n_ > 0) flush_group();
    flush_spindle();
    if (!record_outputs || duty_events_.empty()) return;
    const auto div = static_cast<Cycle>(p_.fan_div());
    const Cycle period = 256 * div;
    // the first boundary edge b (b + fan_phase a multiple of the period) after the first change
    const Cycle first = duty_events_.front().first + 1;
    Cycle b = first + ((period - (first + p_.fan_phase) % period) % period);
    size_t i = 0;
    int active = 0;
    bool level = false;
    for (;; b += period) {
      for (; i < duty_events_.size() && duty_events_[i].first <= b - 1; ++i)
        active = duty_events_[i].second == 255 ? 256 : duty_events_[i].second;
      if (i == duty_events_.size() && active == 0 && !level) break;
      if (active != 0 && b > horizon) break;
      if ((active > 0) != level) {
        level = active > 0;
        pins_.add(b, models::kFan, level ? 1 : 0);
      }
      if (active > 0 && active < 256) {
        pins_.add(b + active * div, models::kFan, 0);
        level = false;
      }
    }
    duty_events_.clear();
  }

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

  // Kind ARC from edge R: arc::Dda from event to event (rtl/motion/arc_dda.v's walk and pacing in
  // exact integers). Walk clock c runs in the clock of the run's (c + 1)-th tick, tau(c) (R + c
  // at full rate); its event is a step request on edge tau(c) + 2 (arc_dda's output register,
  // high in the clock after the tick whether or not that one is a tick). The executor reads the
  // walk's DIR outputs in its ticks (arc_ann). X / Y reverse inside the arc: from the walk's W1
  // clock on the executor knows the next move's
  // direction (Dda::next_x_pos / next_y_pos); when it differs from the DIR target the write
  // becomes pending and lands on the first edge after a clock in which the axis's DIR hold since
  // its last STEP rise has elapsed and no arc step request of that axis is high (real clocks). An
  // X / Y step whose direction is not on the pin yet, or that comes less than DIR setup after the
  // last DIR write of its axis, strobes `violation` (not delayed). Returns the number of ticks
  // (last move's clock + 2): the segment's last tick is the first tick after the walk's ending
  // tick, whose edge is the last move's step request at full rate.
  // Abort: nothing lands on an edge >= cut (the walk stops; returns -1 when a walk clock's
  // tau + 1 is >= cut: the segment is dropped).
  Cycle run_arc(const Segment& s, Cycle r, Cycle cut) {
    models::arc::Dda dda(s.arc_frame);
    // the physical axes of the walk's u, v and the helix (the plane)
    const ArcAxes pl = arc_axes(s.plane);
    const std::array<int, 3> axis{pl.u, pl.v, pl.h};
    std::array<bool, 2> tgt{s.dir[axis[0]], s.dir[axis[1]]}, pend{};
    std::array<bool, 2> pin{};
    std::array<Cycle, 2> last_rise{};
    std::array<Cycle, 2> from{};  // a pending write: the first clock it may land from
    std::array<Cycle, 3> req{kLongAgo, kLongAgo, kLongAgo};
    std::array<std::deque<Cycle>, 2> rises;  // rise edges not yet reached
    for (size_t k = 0; k < 2; ++k) {
      const PulseState st = pulse_state(axis[k], r);
      pin[k] = st.dir;
      last_rise[k] = st.last_rise;
    }
    // the first clock with a DIR write possible for a pending axis k, at or after clock t
    auto write_if_ok = [&](size_t k, Cycle t) {
      while (!rises[k].empty() && rises[k].front() <= t) {
        last_rise[k] = rises[k].front();
        rises[k].pop_front();
      }
      const Cycle hold = p_.timing[axis[k]].hold;
      if (t + 1 >= last_rise[k] + hold && req[k] != t + 1) {
        dir_write(axis[k], tgt[k], t + 1);
        pin[k] = tgt[k];
        pend[k] = false;
        ++arc_dir_writes;
      }
    };
    // The first clock >= t at which write_if_ok(k, ·) writes, with no new step request of axis k
    // before it (the rises still queued are taken into account, none is consumed).
    auto first_write = [&](size_t k, Cycle t) {
      Cycle lr = last_rise[k];
      size_t next_rise = 0;
      const Cycle hold = p_.timing[axis[k]].hold;
      for (;;) {
        while (next_rise < rises[k].size() && rises[k][next_rise] <= t) lr = rises[k][next_rise++];
        if (t + 1 < lr + hold) {
          t = lr + hold - 1;
        } else if (req[k] == t + 1) {
          ++t;
        } else {
          return t;
        }
      }
    };
    // Lands the pending writes whose clock is <= upto (and whose edge is before the abort's); a
    // write still pending looks no earlier than upto + 1 from then on (the clocks up to upto had
    // the step requests known now).
    auto flush = [&](Cycle upto) {
      for (size_t k = 0; k < 2; ++k) {
        if (!pend[k]) continue;
        const Cycle w = first_write(k, from[k]);
        if (w <= upto && w + 1 < cut)
          write_if_ok(k, w);
        else
          from[k] = std::max(from[k], upto + 1);
      }
    };
    // the walk clocks c with tau(c) + 1 < cut
    const Cycle stop = cut == kNever     ? kNever
                       : rate == nullptr ? cut - 1 - r
                       : cut - 2 < r     ? 0
                                         : static_cast<Cycle>(rate->ticks_in(r, cut - 2));
    Cycle last = 0, last_tau = r;
    while (!dda.done()) {
      // Quiet walk clocks (no event, the same DIR outputs) are skipped up to the next event or
      // the abort's.
      {
        const auto c0 = static_cast<Cycle>(dda.next_clock());
        if (stop > c0) dda.skip_quiet(static_cast<uint64_t>(stop - c0));
      }
      const auto c = static_cast<Cycle>(dda.next_clock());
      const Cycle tau = walk_clock(r, c);
      flush(tau);
      if (dda.dir_valid()) {  // the executor takes the walk's DIR outputs on its ticks
        const std::array<bool, 2> nd{dda.next_x_pos(), dda.next_y_pos()};
        for (size_t k = 0; k < 2; ++k)
          if (nd[k] != tgt[k]) {
            tgt[k] = nd[k];
            pend[k] = true;
            from[k] = tau + 1;
          }
      }
      if (tau + 1 >= cut) {  // aborted: nothing of this walk clock or later lands
        ++arcs;
        return -1;
      }
      const models::arc::Event ev = dda.clock();
      const Cycle e = tau + 2;
      bool viol = false;
      const std::array<int, 3> d{ev.dx, ev.dy, ev.dz};
      for (size_t k = 0; k < 3; ++k) {
        if (axis[k] >= kAxes) continue;
        if (d[k] == 0 || e >= cut) continue;  // (a request in flight on the abort edge: gated)
        const bool dir = d[k] > 0;
        const auto ak = static_cast<size_t>(axis[k]);
        if (k < 2) {
          if (dir != pin[k] || e - last_wr_[ak] < static_cast<Cycle>(p_.timing[ak].setup))
            viol = true;
        }
        PulseCmd cmd{dir};
        const Cycle rise = transport(*pulse[ak], gp_, clk_, cmd, e);
        if (k < 2) rises[k].push_back(rise);
        req[k] = e;
        arc_step_edges.push_back(e);
      }
      if (viol) arc_violation_cycles.push_back(e);
      last = c;
      last_tau = tau;
    }
    const Cycle ticks = last + 2;
    // A write still pending at the end (only when the arc outran its DIR timing) lands from the
    // segment's last tick on (not with the last step request of its axis), as in IDLE or in the
    // next segment's run.
    const Cycle last_tick = tick_edge(r, static_cast<uint64_t>(ticks)) - 1;
    for (size_t k = 0; k < 2; ++k) {
      if (!pend[k]) continue;
      const Cycle t = first_write(k, std::max(from[k], last_tick));
      if (t + 1 < cut) write_if_ok(k, t);
    }
    ++arcs;
    if (dda.err()) {
      ++arc_errors;
      arc_err_cycles.push_back(last_tau + 2);
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
    if (rate) rate->segment_code(accept, s.code);  // the rate's target from the accept edge on
    // T = 0 completes at once; accepted on a last tick it passes one clock in ZERO.
    Cycle end = on_last_tick ? accept + 1 : accept;
    power_segs_.push_back(PowerSeg{accept, run, s.power, s.prof, s.profile.v_cruise, {}});
    if (s.prof) power_segs_.back().v = prof.v_points;
    const char kind =
        s.arc                                                                            ? 'A'
        : s.prof                                                                         ? 'P'
        : s.total == 0                                                                   ? 'Z'
        : std::all_of(s.steps.begin(), s.steps.end(), [](uint32_t n) { return n == 0; }) ? 'D'
                                                                                         : 'L';
    running_ = s.total != 0;
    bool dropped = s.total != 0 ? run >= cut : end >= cut;  // HOLD / SETUP, or in ZERO
    Cycle arc_end = -1;       // an arc stopped by the abort (or a hold for good) ends there
    if (s.arc && !dropped) {  // an arc the abort stops runs until edge `cut` (dropped there)
      const Cycle arc_cut = rate ? std::min(cut, kHeldForever) : cut;
      const Cycle ticks = run_arc(s, run, arc_cut);
      if (ticks < 0) arc_end = arc_cut;
      s.total = static_cast<uint64_t>(ticks < 0 ? arc_cut - run : ticks);
    }
    if (s.total != 0 && !dropped) {
      seg_start_cycles.push_back(run);
      end = arc_end >= 0 ? arc_end : tick_edge(run, s.total);
      dropped = end >= cut;
      if (s.code != 0 && s.power != 0) {  // laser low from the abort edge (combinational gate)
        // and in every clock with r = 0
        Cycle on = run;
        const Cycle off = std::min(end, cut);
        if (rate && laser_rate_gate)
          for (const auto& [a, b] : rate->stopped(run, off)) {
            if (a > on) {
              pins_.add(on, models::kLaser, 1);
              pins_.add(a, models::kLaser, 0);
              laser_spans_.emplace_back(on, a);
            }
            on = b;
          }
        if (on < off) {
          pins_.add(on, models::kLaser, 1);
          pins_.add(off, models::kLaser, 0);
          laser_spans_.emplace_back(on, off);
        }
      }
      for (int a = 0; a < kAxes && !s.arc; ++a) {
        if (s.steps[a] == 0) continue;
        if (s.prof) {  // a step in tick j: step request on edge R + j (STEP rises there)
          PulseCmd none{false};
          for (uint64_t j : prof.ticks[a]) {
            const Cycle e = tick_edge(run, j);
            if (e >= cut || e >= kHeldForever) break;
            transport(*pulse[a], gp_, clk_, none, e);
          }
          continue;
        }
        DdaLoad l{s.steps[a], s.total, cut, rate};
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

  // The merged OUTPUT entries of one edge become the levels (pin edges where they change).
  void flush_group() {
    if (record_outputs) {
      for (int b : {0, 1, 3, 4, 5, 6}) {
        if (((pend_lvl_ ^ lvl_) >> b & 1) == 0) continue;
        const int sig = b == 0   ? int{models::kFlood}
                        : b == 1 ? int{models::kMist}
                                 : int{models::kDout0} + b - 3;
        pins_.add(pend_edge_, static_cast<uint8_t>(sig), static_cast<uint8_t>(pend_lvl_ >> b & 1));
      }
    }
    if (pend_duty_ != duty_) duty_events_.emplace_back(pend_edge_, pend_duty_);
    lvl_ = pend_lvl_;
    duty_ = pend_duty_;
    pend_n_ = 0;
  }

  // The laser / spindle PWM's inputs: per accepted segment (in accept order) its accept and run
  // edges, power and, for a PROFILE, V_cruise and V per tick; the mode changes (edge, M4); the
  // laser pin's high spans.
  struct PowerSeg {
    Cycle accept, run;
    uint8_t power;
    bool prof;
    uint64_t v_cruise;
    std::vector<std::pair<uint64_t, uint64_t>> v;  // ProfileRun::v_points
  };
  std::vector<PowerSeg> power_segs_;
  std::vector<std::pair<Cycle, bool>> dyn_events_;
  std::vector<std::pair<Cycle, Cycle>> laser_spans_;

  // laser_scale's duty from the values of clock c (docs/machine.md "Laser and spindle PWM").
  int spindle_duty(Cycle c) {
    auto g = std::upper_bound(power_segs_.begin(), power_segs_.end(), c,
                              [](Cycle x, const PowerSeg& p) { return x < p.accept; });
    if (g == power_segs_.begin()) return 0;
    --g;
    bool dyn = false;
    for (const auto& [e, m4] : dyn_events_)
      if (e <= c) dyn = m4;
    using u128 = unsigned __int128;
    uint64_t qr = 1u << 16, qv = 1u << 16;
    if (dyn) {
      if (rate) qr = rate->rate(c) >> 16;
      if (g->prof && g->v_cruise != 0) {
        uint64_t j = 1;
        if (c > g->run)
          j += rate ? rate->ticks_in(g->run, c - 1) : static_cast<uint64_t>(c - g->run);
        qv = static_cast<uint64_t>((static_cast<u128>(profile_v_at(g->v, j)) << 16) / g->v_cruise);
      }
    }
    return static_cast<int>((static_cast<u128>(g->power) * qr * qv) >> 32);
  }

  // The spindle_pwm edges of every laser span (see the header).
  void flush_spindle() {
    if (record_outputs && !laser_spans_.empty()) {
      std::sort(laser_spans_.begin(), laser_spans_.end());
      std::vector<std::pair<Cycle, Cycle>> spans;
      for (const auto& sp : laser_spans_) {
        if (!spans.empty() && sp.first <= spans.back().second)
          spans.back().second = std::max(spans.back().second, sp.second);
        else
          spans.push_back(sp);
      }
      const auto div = static_cast<Cycle>(p_.laser_div());
      const Cycle period = 256 * div, lat = p_.laser_lat;
      for (const auto& [on, off] : spans) {
        bool level = false;
        for (Cycle s = on + lat + 1; s < off; s += period) {
          const int d = spindle_duty(s == on + lat + 1 ? on : s - lat - 1);
          const int d9 = d == 255 ? 256 : d;
          if ((d9 > 0) != level) {
            level = d9 > 0;
            pins_.add(s, models::kSpindlePwm, level ? 1 : 0);
          }
          if (d9 > 0 && d9 < 256 && s + d9 * div < off) {
            pins_.add(s + d9 * div, models::kSpindlePwm, 0);
            level = false;
          }
        }
        if (level) pins_.add(off, models::kSpindlePwm, 0);
      }
    }
    laser_spans_.clear();
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  PinRecorder& pins_;
  uint8_t lvl_ = 0, duty_ = 0;  // output levels (mask bit layout) and fan duty now
  uint32_t pend_n_ = 0;         // OUTPUT entries taking effect on pend_edge_
  Cycle pend_edge_ = -1;
  uint8_t pend_lvl_ = 0, pend_duty_ = 0;
  std::vector<std::pair<Cycle, uint8_t>> duty_events_;  // fan duty register changes
  Cycle idle_after_ = -1;                               // state IDLE after this edge
  Cycle run_end_ = -1;                  // edge of the last tick of the last segment with T > 0
  bool running_ = false;                // the last segment accepted has T > 0
  std::array<Cycle, kAxes> last_wr_{};  // edge of the last DIR write per axis (since_wr_reg)
  std::vector<AbortSpan> aborts_;       // abort spans, in time order
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
