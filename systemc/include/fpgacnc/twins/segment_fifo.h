// Twin of rtl/protocol/segment_fifo.v: the command FIFO between frame_decoder and segment_prep
// (docs/protocol.md "v2": FIFO_DEPTH entries in block RAM, registered read).
//
// Target `in`: write of a FifoEntry on the delay's edge W (the writer checks for room first with
// a read: FifoLevel after an edge). Entries leave in order: entry k is valid on initiator `out`
// (segment_prep) from edge max(W + kFifoWriteToValid, pop of entry k-1 + kFifoPopToValid); the
// accept edge returned by segment_prep is the pop edge. The level after edge t counts the
// entries written on edges <= t and not popped on edges <= t (FIFO level / free in ACK and
// STATUS). Everything is computed when the entry is written: the reader's accept edge is known
// then (segment_prep answers at once).
// Flush (`flushes`: the abort edges X of CANCELs, sorted, known before any entry that can reach
// them): the FIFO is empty after edge X; an entry written on X, or not popped before X (the
// reader answers X: no pop on an abort edge), is dropped on X (counted as popped there, its end
// X in `entry_ends`).
#pragma once

#include <algorithm>

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

// First-word-fall-through with a registered RAM read: an entry written on edge W is in the output
// register after edge W + 1 (first pop on W + 2); a stream kept ready pops one entry per clock.
inline constexpr Cycle kFifoWriteToValid = 2;  // write edge -> first edge it can be popped
inline constexpr Cycle kFifoPopToValid = 1;    // pop edge -> first edge the next can be popped

class SegmentFifoTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<SegmentFifoTwin> in;
  tlm_utils::simple_initiator_socket<SegmentFifoTwin> out;

  SegmentFifoTwin(sc_core::sc_module_name name, const CycleClock& clk, uint32_t depth)
      : sc_module(name), in("in"), out("out"), clk_(clk), depth_(depth) {
    in.register_b_transport(this, &SegmentFifoTwin::b_transport);
  }

  void reset() {
    writes_.clear();
    pops_.clear();
    dropped = 0;
  }
  const std::vector<Cycle>* flushes = nullptr;
  std::vector<Cycle>* entry_ends = nullptr;
  uint64_t dropped = 0;  // entries dropped by a flush while in the FIFO
  uint32_t depth() const { return depth_; }
  uint32_t level_after(Cycle t) const {
    const auto w = std::upper_bound(writes_.begin(), writes_.end(), t) - writes_.begin();
    const auto p = std::upper_bound(pops_.begin(), pops_.end(), t) - pops_.begin();
    return static_cast<uint32_t>(w - p);
  }
  // Pop edge of every entry so far (the busy state of the board).
  const std::vector<Cycle>& pops() const { return pops_; }
  const std::vector<Cycle>& writes() const { return writes_; }

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Cycle w = clk_.at(delay);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (gp.is_read()) {
      payload<FifoLevel>(gp).level = level_after(w);
      return;
    }
    if (level_after(w) >= depth_) throw std::logic_error("segment_fifo twin: write when full");
    FifoEntry e = payload<FifoEntry>(gp);
    Cycle valid = w + kFifoWriteToValid;
    if (!pops_.empty()) valid = std::max(valid, pops_.back() + kFifoPopToValid);
    writes_.push_back(w);
    if (flushes) {
      const auto f = std::lower_bound(flushes->begin(), flushes->end(), w);
      e.flush = f == flushes->end() ? -1 : *f;
    }
    // The reader answers with its accept (pop) edge; the entry is valid from `valid - 1` so
    // that the reader's "first edge after V" is `valid`.
    const Cycle pop = e.flush == w ? w : transport(out, gp_, clk_, e, valid - 1);
    pops_.push_back(pop);
    if (pop == e.flush) {
      ++dropped;
      if (entry_ends) entry_ends->push_back(pop);
    }
  }

  const CycleClock& clk_;
  uint32_t depth_;
  std::vector<Cycle> writes_, pops_;
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
