// Twin of rtl/motion/segment_prep.v: the command FIFO entry becomes a prepared segment
// (docs/protocol.md "Timing semantics" and "LINE", docs/timing.md "Segment length" and "Queued
// segments").
//
// Target `commands`: a FifoEntry valid from the delay's edge V. It is accepted (popped) on the
// first edge after V on which the block is idle (its previous segment taken by the executor);
// the delay returned names the accept edge. Then, by kind:
//   numerators (v1 init or v2 NUMERATORS): also waits until the executor and every STEP pulse
//     are idle (asked on initiator `exec_status`); sets NUMERATOR_X/Y on the accept edge
//     (init_applied); a v2 one is reported on initiator `applied` (it counts as a segment done).
//   v1 motion: dominant axis, P = NUMERATOR_dom / feed or FEED0_PERIOD, raised to min_period,
//     T = P * N; valid PREP_LATENCY (68) edges after acceptance.
//   v2 motion: n_dom = max |steps|, P = floor(T / n_dom); P < min_period raises T to
//     n_dom * min_period (counted: clamped); T and no steps is a segment of T ticks without
//     steps; valid kPrepLatencyV2 (+ kPrepClampExtra when clamped) edges after acceptance.
//   dwell: T ticks, no steps, laser off; valid kPrepLatencyDwell edges after acceptance.
//   kind 3, v2 (never written by the decoder): a zero-length segment, as a dwell of T = 0.
//   OUTPUT (kind 3, v2 = 0): not prepared: handed to the executor (`on_output`, called with the
//     accept edge) on its accept edge; the block takes the next entry from the edge after.
//   LINE_PROFILE (prof): a PROFILE segment carrying the profile fields (V_entry, V_cruise,
//     V_exit, A, D) and |steps|; total = period = tmn = 0, dir_fast = 0 (a reversing axis always
//     takes the executor's HOLD/SETUP path); valid kPrepLatencyProfile (25 + N_AXES) edges after
//     acceptance. The executor twin derives the RTL's products from the fields (prepare_profile).
//   ARC (arc): a segment of kind ARC carrying the frame's fields (Segment::arc_frame; the executor
//     runs arc::Dda, which derives dt_q, dt_r and the Z products as the prep's shift-add squares,
//     divider and multipliers do); steps X = Y = 1 and Z = |DZ|, DIR X / Y the tangent signs at
//     the start point (a zero component inward), Z the sign of DZ; total = period = tmn = 0,
//     dir_fast = 0; valid kPrepLatencyArc (80) edges after acceptance. The arc's last X / Y
//     directions are not tracked: dir_fast is 0 for later segments moving X or Y until that axis
//     has moved in a non-arc segment (unk_reg).

// DIR per axis is the sign of the entry's steps field (1 for 0) whatever the kind.
// tmn[a] = T - |steps_a|. The prepared segment carries DIR per axis and dir_fast: the block
// tracks the DIR each axis will have when the segment starts (all low after reset) and sets
// dir_fast when every moving axis that reverses has floor(T / n_dom) >= its DIR hold + setup.
// It is offered on initiator `segments`; the block is idle again from the edge after the
// executor takes it.
// Flush (a CANCEL's abort on edge X = FifoEntry::flush): an entry that would be accepted on or
// after X is not taken (the FIFO drops it: the delay returned names X); a prepared segment the
// executor would take on or after X (accept_probe) is dropped on X (not offered, its end X in
// `entry_ends`, the block idle after X); every axis's DIR is unknown for the entries accepted
// after X (unk_reg); a `clamped` strobe after X is not counted. Not modelled: an OUTPUT entry
// handed to the executor before X and still pending there (the executor twin keeps it).
#pragma once

#include <functional>
#include <stdexcept>

#include "fpgacnc/twins/tlm_common.h"
#include "fpgacnc/twins/v2_frames.h"

namespace fpgacnc::twins {

// PREP_LATENCY: v1 motion 68 (divider, clamp, multiplier, subtract); v2 entries (LINE, DWELL)
// first scan the axes for n_dom (N_AXES - 1 clocks): 67 + N_AXES, clamped or not.
inline constexpr Cycle kPrepLatency = 68;
inline constexpr Cycle kPrepLatencyV2 = 67 + kAxes;
inline constexpr Cycle kPrepClampExtra = 0;
inline constexpr Cycle kPrepClampStrobe = kAxes + 33;  // `clamped`: scan, divider, clamp
inline constexpr Cycle kPrepLatencyDwell = 67 + kAxes;
// LINE_PROFILE: the scan (N_AXES - 1), a 25-clock shift-add multiplier, the first master update.
inline constexpr Cycle kPrepLatencyProfile = 25 + kAxes;
// ARC: squares and Z products (AMUL, 32 clocks), the restoring divider (ADIV, 47), AFIX (1).
inline constexpr Cycle kPrepLatencyArc = 80;

struct ExecIdle {  // segment_executor status read: idle (and every STEP pulse done) after `edge`
  Cycle edge;
};
struct Applied {  // segment_prep -> response side: a v2 NUMERATORS entry applied on the edge
  bool v2;
};

class SegmentPrepTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<SegmentPrepTwin> commands;
  tlm_utils::simple_initiator_socket<SegmentPrepTwin> segments;
  tlm_utils::simple_initiator_socket<SegmentPrepTwin> exec_status;
  tlm_utils::simple_initiator_socket<SegmentPrepTwin> applied;  // bind when used (optional)

  SegmentPrepTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p)
      : sc_module(name),
        commands("commands"),
        segments("segments"),
        exec_status("exec_status"),
        applied("applied"),
        clk_(clk),
        p_(p) {
    commands.register_b_transport(this, &SegmentPrepTwin::b_transport);
  }

  void reset() {
    free_from_ = 0;
    last_flush_ = -1;
    dropped = 0;
    num_x = num_y = p_.default_numerator;
    last_period = 0;
    last_feed = 0;
    last_code = 0;
    dir_track_ = {};
    unknown_ = {};
    clamped = 0;
    clamp_cycles.clear();
    applied_cycles.clear();
  }
  uint32_t num_x = 18'750'000, num_y = 18'750'000;
  uint32_t last_period = 0;
  uint16_t last_feed = 0;
  uint8_t last_code = 0;
  uint64_t clamped = 0;
  std::vector<Cycle> clamp_cycles;           // edges of the `clamped` strobe
  std::vector<Cycle> applied_cycles;         // edges of init_applied (v1 init and v2 NUMERATORS)
  bool report_applied = false;               // `applied` is bound
  std::vector<Cycle>* entry_ends = nullptr;  // numerators entries end on their accept edge
  // OUTPUT entries: the executor's output port (segment_executor s_out_*), called with the edge
  // the entry is handed over on (its accept edge) in entry order.
  std::function<void(Cycle, const OutputCmd&)> on_output;
  // The executor's accept edge of a segment offered from an edge
  // (SegmentExecutorTwin::accept_edge).
  std::function<Cycle(const Segment&, Cycle)> accept_probe;
  const std::vector<Cycle>* flushes = nullptr;  // abort edges of CANCELs (sorted)
  uint64_t dropped = 0;                         // prepared segments dropped by a flush

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const FifoEntry c = payload<FifoEntry>(gp);
    Cycle accept = std::max(clk_.at(delay) + 1, free_from_);
    if (c.kind == kEntryNumerators) {
      ExecIdle idle{0};
      transport(exec_status, gp_, clk_, idle, clk_.at(delay), tlm::TLM_READ_COMMAND);
      accept = std::max(accept, idle.edge + 1);
    }
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (c.flush >= 0 && accept >= c.flush) {  // flushed in the FIFO
      delay = clk_.delay_to(c.flush);
      return;
    }
    if (flush_before(accept)) unknown_.fill(true);
    if (c.kind == kEntryOutput && !c.v2) {
      OutputCmd o{static_cast<uint8_t>(c.t >> 16), static_cast<uint8_t>(c.t >> 8),
                  static_cast<uint8_t>(c.t)};
      if (on_output) on_output(accept, o);
      free_from_ = accept + 1;
    } else if (c.kind == kEntryNumerators) {
      num_x = c.steps[0];
      num_y = c.steps[1];
      free_from_ = accept + 1;
      applied_cycles.push_back(accept);
      if (entry_ends) entry_ends->push_back(accept);
      if (report_applied) {
        Applied a{c.v2};
        transport(applied, gp_, clk_, a, accept);
      }
    } else {
      Segment s{};
      Cycle latency = kPrepLatency;
      std::array<uint32_t, kAxes> abs{};
      for (int a = 0; a < kAxes; ++a) {
        const auto v = static_cast<int32_t>(c.steps[a]);
        abs[a] = v < 0 ? 0u - c.steps[a] : c.steps[a];
        s.dir[a] = v >= 0;
      }
      if (c.arc && c.kind == kEntryMotion && c.v2) {  // ARC: kind ARC
        s.code = c.code;
        s.power = c.power;
        s.v2 = true;
        s.arc = true;
        s.plane = static_cast<uint8_t>(c.t & 3);
        s.arc_frame = v2::arc_frame_from_raw(c.arc_raw, (c.code & 1) != 0);
        const models::arc::Frame& f = s.arc_frame;
        const ArcAxes ax = arc_axes(s.plane);
        // u, v: the tangent signs at the start (-I, -J), a zero component inward (arc_dda's rule)
        const std::array<bool, 2> d0 = models::arc::start_dirs(f.g);
        abs = {};
        abs[ax.u] = abs[ax.v] = 1;
        s.dir = {};
        s.dir[ax.u] = d0[0];
        s.dir[ax.v] = d0[1];
        if (kAxes >= 3) {
          abs[ax.h] = f.dz < 0 ? 0u - static_cast<uint32_t>(f.dz) : static_cast<uint32_t>(f.dz);
          s.dir[ax.h] = f.dz >= 0;
        }
        latency = kPrepLatencyArc;
      } else if (c.prof && c.kind == kEntryMotion && c.v2) {  // LINE_PROFILE: kind PROFILE
        s.code = c.code;
        s.power = c.power;
        s.v2 = true;
        s.prof = true;
        s.profile = ProfileParams{c.v_entry, c.v_cruise, c.v_exit, c.t, c.decel_at};
        for (auto& n : abs) n &= 0xffffffu;  // |steps| < 2^24 (the decoder's rule)
        latency = kPrepLatencyProfile;
      } else if (c.kind == kEntryMotion && !c.v2) {  // v1
        const auto feed = static_cast<uint16_t>(c.t & 0xffffu);
        abs[2] = abs[3] = 0;
        const PreparedTiming t =
            prepare_timing(abs[0], abs[1], num_x, num_y, feed, p_.feed0_period, p_.min_period());
        s.code = c.code;
        s.power = c.power;
        s.total = t.total;
        s.period = t.period;
        s.feed = feed;
        last_feed = feed;
      } else if (c.kind == kEntryMotion) {  // v2 LINE
        const V2Timing t = prepare_v2(abs, c.t, p_.min_period());
        s.code = c.code;
        s.power = c.power;
        s.total = t.total;
        s.period = t.period;
        s.v2 = true;
        latency = t.n_dom == 0 ? kPrepLatencyDwell : kPrepLatencyV2;
        if (t.clamped && (c.flush < 0 || accept + kPrepClampStrobe <= c.flush)) {
          latency += kPrepClampExtra;
          ++clamped;
          clamp_cycles.push_back(accept + kPrepClampStrobe);
        }
      } else {  // dwell; kind 3 (never written by the decoder): a zero-length segment
        abs = {};
        s.total = c.kind == kEntryDwell ? c.t : 0;
        s.power = 0;
        s.v2 = true;
        latency = kPrepLatencyDwell;
      }
      s.steps = abs;
      for (int a = 0; a < kAxes; ++a) s.tmn[a] = s.prof || s.arc ? 0 : s.total - s.steps[a];
      // DIR at the start of this segment, and whether its reversals fit in its first period.
      std::array<bool, kAxes> rev{};
      bool unknown_moves = false;
      for (int a = 0; a < kAxes; ++a) {
        if (abs[a] == 0) continue;
        rev[a] = dir_track_[a] != s.dir[a];
        dir_track_[a] = s.dir[a];
        unknown_moves = unknown_moves || unknown_[a];
        if (!s.arc) unknown_[a] = false;
      }
      uint32_t n_dom = 0;
      for (uint32_t n : abs) n_dom = std::max(n_dom, n);
      s.dir_fast = !s.prof && !s.arc && !unknown_moves &&
                   (n_dom == 0 || dir_fast(rev, p_.timing, s.total / n_dom));
      // After an arc prep does not know the X / Y DIR levels: no dir_fast for a segment moving X
      // or Y until that axis has moved in a prepared non-arc segment.
      if (s.arc) unknown_[arc_axes(s.plane).u] = unknown_[arc_axes(s.plane).v] = true;
      if (c.flush >= 0 && accept_probe && accept_probe(s, accept + latency) >= c.flush) {
        ++dropped;  // prepared or waiting on the abort edge: dropped
        if (entry_ends) entry_ends->push_back(c.flush);
        free_from_ = c.flush + 1;
        delay = clk_.delay_to(accept);
        return;
      }
      const Cycle taken = transport(segments, gp_, clk_, s, accept + latency);
      free_from_ = taken + 1;
      last_period = s.period;
      last_code = s.code;
    }
    delay = clk_.delay_to(accept);
  }
  // Whether a flush edge lies after the last accept and on or before `accept` (then remembered).
  bool flush_before(Cycle accept) {
    if (!flushes) return false;
    const auto f = std::upper_bound(flushes->begin(), flushes->end(), last_flush_);
    if (f == flushes->end() || *f > accept) return false;
    last_flush_ = *(std::upper_bound(flushes->begin(), flushes->end(), accept) - 1);
    return true;
  }

  const CycleClock& clk_;
  const CoreParams& p_;
  Cycle free_from_ = 0;    // first edge on which a command can be accepted
  Cycle last_flush_ = -1;  // the last flush edge that made every DIR unknown
  std::array<bool, kAxes> dir_track_{};
  std::array<bool, kAxes> unknown_{};  // DIR unknown after an arc (unk_reg)
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
