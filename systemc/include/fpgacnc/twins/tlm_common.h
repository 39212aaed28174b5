// Shared plumbing of the twins: the clock-cycle <-> sc_time mapping, the transaction payloads
// that travel on the TLM sockets, and the pin recorder.
//
// Time (docs/systemc.md "Time"): one clock is 1e12 / CLK_HZ ps of sc_time (20 ns at 50 MHz).
// A transaction's time is sc_time_stamp() + its annotated delay; it is the clock edge on which
// the event it carries happens (a byte valid, a command accepted, ...). A target that accepts
// later than offered (backpressure) increases the delay: on return, the delay names the edge on
// which the transfer happened. No twin calls wait(): the host initiator is the only thread and
// synchronizes through a quantum keeper, so a whole move runs in one call chain.
#pragma once

#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>
#include <systemc>
#include <tlm>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/models/edges.h"
#include "fpgacnc/spec.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

using models::Edge;

// Maps clock cycles to sc_time. `base` is the sc_time of cycle 0 (a harness that runs several
// jobs in one elaboration starts each at a later base).
class CycleClock {
 public:
  explicit CycleClock(uint64_t clk_hz) {
    if (clk_hz == 0 || 1'000'000'000'000ull % clk_hz != 0)
      throw std::invalid_argument("twins: CLK_HZ must divide 1e12 (clock period in whole ps)");
    period_ps_ = 1'000'000'000'000ull / clk_hz;
  }
  void set_base(const sc_core::sc_time& base) { base_ps_ = base.value(); }
  uint64_t period_ps() const { return period_ps_; }
  // Cycle of the event at sc_time_stamp() + delay.
  Cycle at(const sc_core::sc_time& delay) const {
    const uint64_t t = (sc_core::sc_time_stamp() + delay).value();
    return static_cast<Cycle>((t - base_ps_) / period_ps_);
  }
  // Delay from now to cycle c (c must not be in the past of the current time).
  sc_core::sc_time delay_to(Cycle c) const {
    const uint64_t t = base_ps_ + static_cast<uint64_t>(c) * period_ps_;
    const uint64_t now = sc_core::sc_time_stamp().value();
    if (t < now) throw std::logic_error("twins: event scheduled in the past");
    return sc_core::sc_time::from_value(t - now);
  }

 private:
  uint64_t period_ps_ = 20'000;
  uint64_t base_ps_ = 0;
};

// Payloads (carried by data_ptr of a tlm_generic_payload, TLM_WRITE_COMMAND unless noted).
struct RxFrame {  // host -> uart_rx: one 8N1 frame on the rx pin, start edge at the delay
  uint8_t byte;
};
struct RxByte {  // uart_rx -> packet_decoder_v1: m_axis byte valid from the delay's edge
  uint8_t byte;
};
struct Command {  // packet_decoder_v1 -> segment_prep (valid from the delay's edge)
  bool init;
  uint8_t code;
  uint32_t a, b;  // NUMERATOR_X/Y or steps_x/steps_y (two's complement)
  uint16_t feed;
};
// The command FIFO entry (frame_decoder -> segment_fifo -> segment_prep), the fields of
// { v2, kind[1:0], code[1:0], power[7:0], t[31:0], steps[32*N_AXES-1:0] }:
//   kind 0 motion: v1 (t = feed, steps X/Y, power 0xFF) or v2 LINE (t = T, steps per axis)
//   kind 1 numerators: steps[0] = NUMERATOR_X, steps[1] = NUMERATOR_Y (v1 init or v2 frame)
//   kind 2 dwell (v2): t = T clocks, no steps, laser off
//   kind 3 with v2 = 0 OUTPUT: t = {mask, value, fan duty} (bits 23..0); kind 3 with v2 = 1 is
//   segment_prep's zero-length segment (never written by the decoder)
inline constexpr uint8_t kEntryMotion = spec::kKindMotion, kEntryNumerators = spec::kKindNumerators,
                         kEntryDwell = spec::kKindDwell, kEntryOutput = spec::kKindOutput;
struct FifoEntry {
  bool v2;
  uint8_t kind;
  uint8_t code;
  uint8_t power;
  uint32_t t;
  std::array<uint32_t, kAxes> steps;  // two's complement
  // LINE_PROFILE (prof, kind 0, v2, t = A): the decoder twin checks and writes these fields as
  // the RTL does; segment_prep prepares them as a PROFILE segment.
  bool prof = false;
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;
  uint32_t decel_at = 0;
  // ARC (arc, kind 0, v2, code 2/3, power; t, steps and the profile fields 0): the payload bytes
  // 2..62 as received (I, J, DX, DY int24, DZ int32, N_RAMP u24, C_TOTAL u48, V_entry, V_cruise,
  // V_exit u64, A u48, D u48, big-endian), the entry's arc_raw[487:0] with byte 2 in the top bits.
  bool arc = false;
  std::array<uint8_t, spec::kArcRawBytes> arc_raw{};
  // ARC: t = the plane (flags bits 3:2: 0 XY, 1 ZX, 2 YZ)
  // The first flush edge (a CANCEL's abort) on or after the entry's write edge; -1: none. Set by
  // the FIFO twin for segment_prep.
  Cycle flush = -1;
};
// The axes of an ARC plane: the walk's u and v axes and the helix axis (docs/protocol.md "ARC").
struct ArcAxes {
  int u, v, h;
};
inline constexpr ArcAxes arc_axes(uint8_t plane) {
  return plane == 1 ? ArcAxes{2, 0, 1} : plane == 2 ? ArcAxes{1, 2, 0} : ArcAxes{0, 1, 2};
}
// frame_decoder -> segment_fifo: write on the delay's edge. Read (TLM_READ_COMMAND): the level
// after the delay's edge.
struct FifoLevel {
  uint32_t level;
};
struct Segment {  // segment_prep -> segment_executor (valid from the delay's edge)
  uint8_t code;
  std::array<bool, kAxes> dir;
  std::array<uint32_t, kAxes> steps;
  std::array<uint64_t, kAxes> tmn;
  uint64_t total;
  uint32_t period;
  uint16_t feed;
  uint8_t power = 0xFF;
  bool v2 = false;
  bool dir_fast = false;
  // Kind PROFILE (LINE_PROFILE): total = period = tmn = 0 and dir_fast = 0 (as segment_prep sends
  // them); the executor runs the profile (run_profile) and the segment lasts its J ticks.
  bool prof = false;
  ProfileParams profile{};
  // Kind ARC (ARC frame): the frame's fields (arc_walk.h; the executor runs arc::Dda, which derives
  // prep's products itself); steps X = Y = 1, Z = |DZ|, dir X / Y the tangent signs at the start,
  // Z the sign of DZ; total = period = tmn = 0, dir_fast = 0.
  bool arc = false;
  models::arc::Frame arc_frame{};
  uint8_t plane = 0;  // ARC: 0 XY, 1 ZX, 2 YZ (arc_axes)
};
// segment_executor -> step_pulse: write = step request on the delay's edge (the DDA tick);
// address kDirWrite: DIR load of `dir` on the delay's edge; read (TLM_READ_COMMAND) fills the
// pulse state.
struct PulseCmd {
  bool dir;
};
struct PulseState {
  Cycle last_rise;  // hold reference: hold_ok from edge last_rise + hold
  Cycle idle_from;  // first edge after which STEP is low and its low time elapsed
  bool dir;
};
// -> segment_executor (and segment_prep): the abort (e-stop) input is high in the clocks before
// edges first..last (the delay names `first`). The twins compute a segment's events when they
// accept it, so an abort is sent before any segment that could run into it (the stimulus knows
// its aborts up front); spans arrive in time order and do not overlap.
struct AbortSpan {
  Cycle first;
  Cycle last;
};
struct SegDone {    // segment_executor -> status/ACK: seg_done strobe after the delay's edge
  bool v2 = false;  // seg_done_v2
  // > 0: not a segment: this many OUTPUT entries applied on the edge (out_done; each counts in
  // `segments done` like a v2 segment, no seg_done strobe)
  uint32_t outputs = 0;
};
// segment_prep -> segment_executor: an OUTPUT entry handed over on the delay's edge.
struct OutputCmd {
  uint8_t mask, value, duty;
};
struct TxByte {  // status/ACK -> uart_tx (offered from the delay's edge; accept returned)
  uint8_t byte;
};
struct LineFrame {  // uart_tx -> host: a frame whose start edge is the delay's edge
  uint8_t byte;
};
inline constexpr uint64_t kDirWrite = 1;

// Sends `data` on `socket` with the event at cycle `c`; returns the cycle the target annotated
// (its accept edge).
template <class Socket, class T>
Cycle transport(Socket& socket, tlm::tlm_generic_payload& gp, const CycleClock& clk, T& data,
                Cycle c, tlm::tlm_command cmd = tlm::TLM_WRITE_COMMAND, uint64_t address = 0) {
  gp.set_command(cmd);
  gp.set_address(address);
  gp.set_data_ptr(reinterpret_cast<unsigned char*>(&data));
  gp.set_data_length(sizeof(T));
  gp.set_streaming_width(sizeof(T));
  gp.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
  sc_core::sc_time d = clk.delay_to(c);
  socket->b_transport(gp, d);
  if (gp.is_response_error()) throw std::runtime_error("twins: transaction error");
  return clk.at(d);
}

template <class T>
T& payload(tlm::tlm_generic_payload& gp) {
  if (gp.get_data_length() != sizeof(T)) throw std::logic_error("twins: payload size mismatch");
  return *reinterpret_cast<T*>(gp.get_data_ptr());
}

// The board's pins as an edge list (signal numbers of fpgacnc/models/edges.h). Twins add edges out
// of time order (a move's steps are computed when it is accepted); take_sorted() orders them by
// (cycle, signal, value) as the RTL recorder sees them, a laser fall and rise on the same edge
// cancelling (back-to-back cutting segments keep the pin high).
// Storage: 8 bytes per edge (cycle < 2^56), one stream per signal in chunks that are never
// reallocated (no copy, no doubling of the resident size while a job records); take_sorted()
// merges the streams into the result and frees each chunk once it is merged, so the peak is the
// result plus a chunk per signal. Each signal's edges mostly arrive in time order; a stream that
// does not is sorted before the merge.

// Back-to-back cutting segments: in edges sorted by (cycle, signal, value), a laser fall at R + T
// and the next segment's rise on the same edge cancel (the pin stays high). Compacted in place.
inline void drop_laser_pairs(std::vector<Edge>& edges) {
  size_t w = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    const Edge e = edges[i];
    if (e.signal == models::kLaser && i + 1 < edges.size() && edges[i + 1].cycle == e.cycle &&
        edges[i + 1].signal == e.signal && edges[i + 1].value != e.value) {
      ++i;
      continue;
    }
    edges[w++] = e;
  }
  edges.resize(w);
}

// What take_summary() gives instead of the edge list: the net steps per axis as
// models::net_steps() counts them, the number of edges and the cycle of the last one, all of the
// list take_sorted() would have returned (0 when it is empty).
struct EdgeSummary {
  std::array<int64_t, models::kBoardAxes> net{};
  uint64_t edges = 0;
  Cycle last = 0;
};

class PinRecorder {
 public:
  bool record_tx = false;
  // Summary only (take_summary()): a STEP fall is counted, not stored, so a job of hundreds of
  // millions of edges keeps 8 bytes per STEP rise and DIR edge instead of the sorted list.
  bool summary_only = false;
  void add(Cycle c, uint8_t signal, uint8_t value) {
    if (signal == models::kTx && !record_tx) return;
    if (signal >= kSignals || c < 0 || c >= (Cycle{1} << 56))
      throw std::logic_error("twins: pin edge out of range");
    if (summary_only && signal < models::kBoardAxes && value == 0) {
      ++uncounted_falls_;
      uncounted_last_ = std::max(uncounted_last_, c);
      return;
    }
    streams_[signal].push((static_cast<uint64_t>(c) << 8) | value);
    ++size_;
  }
  // The summary of the recorded edges (the recorder is empty afterwards). The net steps walk each
  // axis's STEP rises against its DIR edges in (cycle, signal) order: a DIR edge on the clock of
  // a STEP rise comes after it, as in the sorted list.
  EdgeSummary take_summary() {
    EdgeSummary out;
    out.edges = size_ + uncounted_falls_;
    out.last = uncounted_last_;
    for (int sig = 0; sig < kSignals; ++sig) {
      Stream& st = streams_[static_cast<size_t>(sig)];
      if (st.size == 0) continue;
      st.sort_if_needed();
      if (sig != models::kLaser)
        out.last = std::max(out.last, static_cast<Cycle>(st.chunks.back().back() >> 8));
    }
    for (int a = 0; a < models::kBoardAxes; ++a) {
      Reader dir(streams_[static_cast<size_t>(models::dir_signal(a))]);
      Reader step(streams_[static_cast<size_t>(models::step_signal(a))]);
      bool fwd = false;
      int64_t net = 0;
      for (; !step.done(); step.next()) {
        const uint64_t k = step.key();
        if ((k & 0xff) == 0) continue;
        for (; !dir.done() && (dir.key() >> 8) < (k >> 8); dir.next())
          fwd = (dir.key() & 0xff) != 0;
        net += fwd ? 1 : -1;
      }
      out.net[static_cast<size_t>(a)] = net;
    }
    // Back-to-back cutting segments: a laser fall and rise on one clock are not edges.
    constexpr uint64_t kNone = ~uint64_t{0};
    uint64_t prev = kNone;  // the laser edge before, not yet known to stay
    auto keep = [&](uint64_t k) { out.last = std::max(out.last, static_cast<Cycle>(k >> 8)); };
    for (Reader las(streams_[models::kLaser]); !las.done(); las.next()) {
      const uint64_t k = las.key();
      if (prev != kNone && (prev >> 8) == (k >> 8) && (prev & 0xff) != (k & 0xff)) {
        out.edges -= 2;
        prev = kNone;
        continue;
      }
      if (prev != kNone) keep(prev);
      prev = k;
    }
    if (prev != kNone) keep(prev);
    clear();
    return out;
  }
  // Sorts and hands the list over (the recorder is empty afterwards).
  std::vector<Edge> take_sorted() {
    std::vector<Edge> out;
    out.reserve(size_);
    struct Head {
      const uint64_t* p;  // next key of the current chunk
      const uint64_t* end;
      size_t chunk;
    };
    std::array<Head, kSignals> h{};
    std::array<int, kSignals> live{};
    int n_live = 0;
    for (int s = 0; s < kSignals; ++s) {
      Stream& st = streams_[static_cast<size_t>(s)];
      if (st.size == 0) continue;
      st.sort_if_needed();
      h[static_cast<size_t>(s)] =
          Head{st.chunks[0].data(), st.chunks[0].data() + st.chunks[0].size(), 0};
      live[static_cast<size_t>(n_live++)] = s;
    }
    // (cycle, signal, value) order: the stream whose head has the smallest cycle, then signal
    // (streams are scanned in signal order, ties keep the first), then value (within the stream).
    while (n_live > 0) {
      int best = 0;
      uint64_t best_cycle = *h[static_cast<size_t>(live[0])].p >> 8;
      for (int i = 1; i < n_live; ++i) {
        const uint64_t c = *h[static_cast<size_t>(live[static_cast<size_t>(i)])].p >> 8;
        if (c < best_cycle) {
          best_cycle = c;
          best = i;
        }
      }
      const int s = live[static_cast<size_t>(best)];
      Head& hd = h[static_cast<size_t>(s)];
      Stream& st = streams_[static_cast<size_t>(s)];
      // the run of this stream up to the next head's cycle (at least one edge)
      uint64_t other = ~uint64_t{0};
      for (int i = 0; i < n_live; ++i)
        if (i != best) {
          const int o = live[static_cast<size_t>(i)];
          const uint64_t c = *h[static_cast<size_t>(o)].p >> 8;
          // a later signal with the same cycle comes after this stream's edges of that cycle
          other = std::min(other, o > s ? c + 1 : c);
        }
      do {
        const uint64_t k = *hd.p++;
        out.push_back(Edge{k >> 8, static_cast<uint8_t>(s), static_cast<uint8_t>(k & 0xff)});
        if (hd.p == hd.end) {
          std::vector<uint64_t>().swap(st.chunks[hd.chunk]);
          if (++hd.chunk == st.chunks.size()) {
            live[static_cast<size_t>(best)] = live[static_cast<size_t>(--n_live)];
            // keep the live list in signal order (ties go to the lower signal)
            std::sort(live.begin(), live.begin() + n_live);
            break;
          }
          hd.p = st.chunks[hd.chunk].data();
          hd.end = hd.p + st.chunks[hd.chunk].size();
        }
      } while ((*hd.p >> 8) < other);
    }
    clear();
    drop_laser_pairs(out);
    return out;
  }
  size_t size() const { return size_; }
  void clear() {
    for (Stream& s : streams_) s = Stream{};
    size_ = 0;
    uncounted_falls_ = 0;
    uncounted_last_ = 0;
  }

 private:
  static constexpr int kSignals = models::kSignalCount;
  struct Stream {
    std::vector<std::vector<uint64_t>> chunks;
    size_t size = 0;
    uint64_t last = 0;
    bool sorted = true;
    void push(uint64_t key) {
      if (chunks.empty() || chunks.back().size() == chunks.back().capacity()) {
        const size_t n =
            chunks.empty() ? 1024 : std::min<size_t>(chunks.back().capacity() * 2, 1 << 22);
        chunks.emplace_back().reserve(n);
      }
      if (size != 0 && key < last) sorted = false;
      chunks.back().push_back(key);
      last = key;
      ++size;
    }
    void sort_if_needed() {
      if (sorted) return;
      std::vector<uint64_t> all;
      all.reserve(size);
      for (auto& c : chunks) {
        all.insert(all.end(), c.begin(), c.end());
        std::vector<uint64_t>().swap(c);
      }
      std::sort(all.begin(), all.end());
      chunks.clear();
      chunks.push_back(std::move(all));
      sorted = true;
    }
  };
  // Walks a sorted stream's keys in order.
  struct Reader {
    const Stream& st;
    size_t chunk = 0, i = 0;
    explicit Reader(const Stream& s) : st(s) { skip(); }
    void skip() {
      while (chunk < st.chunks.size() && i == st.chunks[chunk].size()) {
        ++chunk;
        i = 0;
      }
    }
    bool done() const { return chunk == st.chunks.size(); }
    uint64_t key() const { return st.chunks[chunk][i]; }
    void next() {
      ++i;
      skip();
    }
  };
  std::array<Stream, kSignals> streams_{};
  size_t size_ = 0;
  uint64_t uncounted_falls_ = 0;  // summary_only: STEP falls counted, not stored
  Cycle uncounted_last_ = 0;      // and the last one's cycle
};

}  // namespace fpgacnc::twins
