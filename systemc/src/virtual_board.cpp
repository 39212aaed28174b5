#include "fpgacnc/twins/virtual_board.h"

#include <algorithm>
#include <chrono>
#include <limits>

namespace fpgacnc::twins {

void sort_edges(std::vector<Edge>& edges_) {
  std::sort(edges_.begin(), edges_.end(), [](const Edge& a, const Edge& b) {
    if (a.cycle != b.cycle) return a.cycle < b.cycle;
    if (a.signal != b.signal) return a.signal < b.signal;
    return a.value < b.value;
  });
  drop_laser_pairs(edges_);
}

VirtualBoard::VirtualBoard(sc_core::sc_module_name name, const CoreParams& p, bool record_tx)
    : sc_module(name),
      p_(p),
      clk_(p.clk_hz),
      rx_("uart_rx", clk_, p_),
      dec_("frame_decoder", clk_, p_),
      fifo_("segment_fifo", clk_, v2::kFifoDepth),
      prep_("segment_prep", clk_, p_),
      exec_("segment_executor", clk_, p_, pins_),
      rate_(p.rate_phase),
      enc_("response_encoder", clk_,
           EncoderParams{v2::kFifoDepth, p.clk_hz, p.baud, v2::kBuildId, true}),
      tx_("uart_tx", clk_, p_, pins_),
      host_pin_("host_pin"),
      host_line_("host_line"),
      cfg_("cfg"),
      state_("state"),
      abort_("abort") {
  pins_.record_tx = record_tx;
  host_pin_.bind(rx_.pin);
  rx_.bytes.bind(dec_.bytes);
  dec_.fifo.bind(fifo_.in);
  dec_.resp.bind(enc_.req);
  dec_.cfg.bind(cfg_);
  fifo_.out.bind(prep_.commands);
  prep_.segments.bind(exec_.segments);
  prep_.exec_status.bind(exec_.status);
  abort_.bind(exec_.abort);
  prep_.applied.bind(enc_.applied);
  prep_.report_applied = true;
  prep_.entry_ends = &entry_ends_;
  prep_.on_output = [this](Cycle h, const OutputCmd& o) { exec_.output(h, o); };
  exec_.entry_ends = &entry_ends_;
  exec_.rate = &rate_;
  fifo_.flushes = &flush_edges_;
  fifo_.entry_ends = &entry_ends_;
  prep_.flushes = &flush_edges_;
  prep_.accept_probe = [this](const Segment& s, Cycle v) { return exec_.accept_edge(s, v); };
  dec_.on_motion = [this](const MotionReq& m) {
    const size_t i = observed_motion_.size();
    observed_motion_.push_back(m);
    if (i >= known_motion_.size() || !(known_motion_[i] == m)) motion_mismatch_ = true;
  };
  make_axis_twins(exec_, clk_, p_, pins_, dda_, pulse_);
  for (auto& pulse : pulse_) pulse->keep_history = true;
  exec_.done.bind(enc_.done);
  enc_.tx.bind(tx_.bytes);
  enc_.state.bind(state_);
  enc_.before_decide = [this](Cycle d) { dec_.advance(d); };
  dec_.before_write = [this](Cycle w) { apply_cfg(w); };
  tx_.line.bind(host_line_);
  host_line_.register_b_transport(this, &VirtualBoard::on_line);
  cfg_.register_b_transport(this, &VirtualBoard::on_cfg);
  state_.register_b_transport(this, &VirtualBoard::on_state);
  const BitTimer t(p.clk_hz, p.baud);
  tx_centre9_ = ceil_div(static_cast<__int128>(19) * t.mod, 2 * t.inc);
  SC_THREAD(host_thread);
}

void VirtualBoard::reset(const std::array<AxisTiming, kAxes>& timing) {
  p_.timing = timing;
  pins_.clear();
  rx_.reset();
  dec_.reset();
  fifo_.reset();
  prep_.reset();
  exec_.reset();
  rate_.reset();
  observed_motion_.clear();
  motion_mismatch_ = false;
  for (const MotionReq& m : known_motion_)
    rate_.motion(m.from, m.hold, m.resume, m.feed, m.rapid, m.ramp, m.cancel);
  for (auto& p : pulse_) p->reset();
  // The flushes of the CANCELs known up front: the rate's hold ends, the FIFO, prep and executor
  // drop what they hold on the abort edge (the clock after the flush clock).
  flush_edges_.clear();
  known_flush_.resize(known_motion_.size(), kFlushUnknown);
  for (size_t k = 0; k < known_motion_.size(); ++k) {
    if (known_flush_[k] < 0) continue;
    const Cycle x = known_flush_[k] + 1;
    rate_.flush(x);
    flush_edges_.push_back(x);
    AbortSpan a{x, x};
    transport(abort_, gp_, clk_, a, x);
  }
  enc_.reset();
  tx_.reset();
  tx_bytes_.clear();
  entry_ends_.clear();
  pending_cfg_.clear();
}

void VirtualBoard::on_line(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
  tx_bytes_.emplace_back(clk_.at(delay), payload<LineFrame>(gp).byte);
  gp.set_response_status(tlm::TLM_OK_RESPONSE);
}

// CONFIG_AXIS (cnc_core "configuration"): the write strobe after edge c lands in the shadow
// registers on c + 1; they become active on an edge e >= c + 2 at which the board was quiet
// after e - 1 (FIFO empty, nothing prepared, executor and every STEP pulse idle), so a setting
// never changes in the middle of a move. The twins read the step timing from p_ when they
// compute, and compute everything an entry causes when it is written: a pending setting is
// applied before the next FIFO write W if the board was quiet before it (e <= W).
void VirtualBoard::on_cfg(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
  pending_cfg_.emplace_back(clk_.at(delay), payload<CfgAxis>(gp));
  gp.set_response_status(tlm::TLM_OK_RESPONSE);
}

void VirtualBoard::apply_cfg(Cycle write) {
  if (pending_cfg_.empty()) return;
  Cycle quiet = exec_.idle_edge(write);
  if (!fifo_.pops().empty()) quiet = std::max(quiet, fifo_.pops().back());
  const Cycle active = std::max(pending_cfg_.back().first + 2, quiet + 1);
  if (active > write) return;
  for (const auto& [c, a] : pending_cfg_) p_.timing[a.axis] = a.timing;
  pending_cfg_.clear();
}

// The live state a response frame starting on edge d is filled in from: registers as they are
// after edge d - 1.
void VirtualBoard::on_state(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
  const Cycle t = clk_.at(delay) - 1;
  StatusSnapshot s;
  s.dec = dec_.state_after(t);
  s.fifo_level = fifo_.level_after(t);
  // Busy (cnc_core: executor busy, prep busy or FIFO not empty): an entry in the FIFO, or the
  // last one popped still prepared or running (entries end in order).
  const auto& pops = fifo_.pops();
  const auto popped = std::upper_bound(pops.begin(), pops.end(), t) - pops.begin();
  s.busy = s.fifo_level > 0 || (popped > 0 && static_cast<size_t>(popped) <= entry_ends_.size() &&
                                entry_ends_[static_cast<size_t>(popped) - 1] > t);
  for (int a = 0; a < kAxes; ++a) {
    s.position[a] = static_cast<int32_t>(pulse_[a]->position_after(t));
    for (Cycle v : pulse_[a]->violation_cycles)
      if (v <= t && v > enc_.fault_clear_at) s.fault = true;
  }
  // An arc's DIR violation strobe after edge v latches faults bit 0 on v + 1, an inconsistent arc
  // latches bit 1 on its edge; a FAULT_CLEAR strobe after edge f clears on f + 1 (a set wins).
  for (Cycle v : exec_.arc_violation_cycles)
    if (v + 1 <= t && v >= enc_.fault_clear_at) s.fault = true;
  for (Cycle v : exec_.arc_err_cycles)
    if (v <= t && v > enc_.fault_clear_at) s.faults |= 2;
  s.frame_errors = static_cast<uint16_t>(rx_.frame_errors);
  s.hold = rate_.hold(t);
  s.stopped = rate_.rate(t) == 0;
  const auto& cl = prep_.clamp_cycles;
  s.clamped = static_cast<uint16_t>(std::upper_bound(cl.begin(), cl.end(), t) - cl.begin());
  payload<StatusSnapshot>(gp) = s;
  gp.set_response_status(tlm::TLM_OK_RESPONSE);
}

size_t VirtualBoard::deliver(Cycle before, bool one) {
  size_t n = 0;
  while (!tx_bytes_.empty() && tx_bytes_.front().first + tx_centre9_ < before) {
    const auto [start, byte] = tx_bytes_.front();
    tx_bytes_.pop_front();
    if (host_) host_->on_tx_byte(start, byte);
    ++n;
    if (one) break;
  }
  return n;
}

std::vector<Cycle> VirtualBoard::observe_flushes() {
  std::vector<Cycle> f(known_motion_.size(), kFlushNone);
  Cycle last = -1;  // the last flush clock
  for (size_t k = 0; k < known_motion_.size(); ++k) {
    const MotionReq& m = known_motion_[k];
    if (!m.cancel || m.from <= last) continue;  // a CANCEL before that flush: the same cancel
    const Cycle c = rate_.first_stop(m.from);
    if (c == FeedRate::kNever) {
      f[k] = kFlushUnknown;
      break;
    }
    f[k] = last = c;
  }
  return f;
}

bool VirtualBoard::settle_motion() {
  if (motion_mismatch_) {
    // The requests up to the first one this run did not know (everything before it was exact);
    // that one's flush is not known yet.
    if (observed_motion_.empty()) throw std::logic_error("virtual board: MOTION mismatch, none");
    const size_t i = observed_motion_.size() - 1;
    known_motion_ = observed_motion_;
    known_flush_.resize(i);
    known_flush_.push_back(known_motion_[i].cancel ? kFlushUnknown : kFlushNone);
    return false;
  }
  std::vector<Cycle> f = observe_flushes();
  if (f == known_flush_) return true;
  known_flush_ = std::move(f);
  return false;
}

RunResult VirtualBoard::run_job(const TwinJob& job) {
  // Runs until the MOTION requests and the flush clocks of their CANCELs known up front are the
  // ones the run has (see the header).
  known_motion_.clear();
  known_flush_.clear();
  dec_.accept_motion = true;
  for (runs_ = 1;; ++runs_) {
    // (a run again takes no SystemC time: the job's time passed in its first run)
    RunResult r = run_once(job, runs_ == 1);
    r.runs = runs_;
    if (settle_motion()) return r;
    if (static_cast<size_t>(runs_) > 4 * known_motion_.size() + 16)
      throw std::logic_error("virtual board: the MOTION requests and flushes do not settle");
  }
}

RunResult VirtualBoard::run_once(const TwinJob& job, bool sync) {
  const auto t0 = std::chrono::steady_clock::now();
  tlm_utils::tlm_quantumkeeper qk;
  qk.set_global_quantum(quantum_);
  qk.reset();
  // Cycle 0 of this job: the next whole clock from now.
  const uint64_t per = clk_.period_ps();
  const uint64_t now = sc_core::sc_time_stamp().value();
  clk_.set_base(sc_core::sc_time::from_value((now + per - 1) / per * per));
  reset(job.timing);
  // the feed hold and cycle-start buttons, known up front
  for (Cycle t : button_requests(job.script.buttons, 0, p_.button_filter_clks)) rate_.hold_input(t);
  for (Cycle t : button_requests(job.script.buttons, 1, p_.button_filter_clks))
    rate_.start_input(t);
  auto host = make_host(job.script, SenderTiming{p_.clk_hz, p_.baud}, tx_.frame_clocks());
  host_ = host.get();
  constexpr Cycle kNever = std::numeric_limits<Cycle>::max();
  RunResult r;
  bool woke = false;
  while (!host->done()) {
    if (flush_unknown_before(host->ready())) {  // run again with that flush known (run_job)
      host_ = nullptr;
      return r;
    }
    if (host->waiting()) {
      // Nothing comes from the host until an answer: the next tx byte, computing the next
      // frame of the encoder when none is queued. The host decides again right after the
      // byte that ends its wait.
      if (deliver(kNever, true) == 0 && !enc_.step(kNever)) {
        r.error = "no answer for packet " + std::to_string(host->packets_sent());
        break;
      }
      woke = true;
      continue;
    }
    if (!woke) {
      // The host decides on edge ready(): answers that start by then are final; it has heard
      // the bytes whose stop-bit centre is before it.
      const Cycle ready = host->ready();
      while (enc_.step(ready + 1)) {
      }
      deliver(ready, false);
      // Every event computed from now on is later than `ready`: time may advance to it.
      qk.set(clk_.delay_to(ready));
      if (sync && qk.need_sync()) qk.sync();
    }
    woke = false;
    for (const HostFrame& f : host->next_packet()) {
      RxFrame frame{f.byte};
      transport(host_pin_, gp_, clk_, frame, f.start);
    }
    if (motion_mismatch_) {  // a request not known up front: this run is over (run_job)
      host_ = nullptr;
      return r;
    }
  }
  // Answers after the last decision (DONE frames, the last ACK's tail). A packet cut short at
  // the very end is not timed out: the RTL harness stops when the core is quiet.
  while (enc_.step(kNever)) {
  }
  deliver(kNever, false);
  if (sync) qk.sync();
  host_ = nullptr;
  exec_.flush_outputs(host->ready());
  Cycle last_edge = 0;
  if (pins_.summary_only) {
    const EdgeSummary sum = pins_.take_summary();
    r.net_steps = sum.net;
    r.edge_count = sum.edges;
    last_edge = sum.last;
  } else {
    r.edges = pins_.take_sorted();
    r.net_steps = models::net_steps(r.edges);
    r.edge_count = r.edges.size();
    if (!r.edges.empty()) last_edge = static_cast<Cycle>(r.edges.back().cycle);
  }
  pins_.clear();
  r.acks = host->acks;
  r.packet_done = dec_.packet_done_cycles;
  r.seg_start = exec_.seg_start_cycles;
  r.seg_done = enc_.seg_done_cycles;
  r.end_cycle = std::max<Cycle>(host->ready(), last_edge);
  // cnc_core counts the clocks with a `violation` strobe (any axis, or an arc's DIR check)
  std::vector<Cycle> strobes = exec_.arc_violation_cycles;
  for (int a = 0; a < kAxes; ++a) {
    r.position[a] = pulse_[a]->position;
    strobes.insert(strobes.end(), pulse_[a]->violation_strobes.begin(),
                   pulse_[a]->violation_strobes.end());
  }
  std::sort(strobes.begin(), strobes.end());
  r.violations =
      static_cast<uint64_t>(std::unique(strobes.begin(), strobes.end()) - strobes.begin());
  const DecoderState& d = dec_.current();
  r.moves_done = enc_.moves_done;
  r.packets = dec_.packets;
  r.timeouts = d.timeouts;
  r.overruns = d.overruns;
  r.frame_errors = rx_.frame_errors;
  r.packets_sent = host->packets_sent();
  r.segments_done = enc_.segments_done;  // (v2: replaced by what the host saw, below)
  r.frames_ok = d.frames_ok;
  r.clamped = prep_.clamped;
  r.zero_gap = exec_.zero_gap;
  r.flushed = fifo_.dropped + prep_.dropped + (flush_edges_.empty() ? 0 : exec_.aborted);
  for (const MotionReq& m : observed_motion_) {
    r.motion_from.push_back(m.from);
    size_t k = 3;
    for (const auto& t : exec_.trace)
      if (t.run <= m.from && m.from < t.end && t.cut < 0 && t.kind != 'Z')
        k = t.kind == 'P' ? 1 : t.kind == 'A' ? 2 : 0;
    ++r.motion_in[k];
  }
  if (auto* h = dynamic_cast<V2StreamHost*>(host.get())) {
    r.device_frames = h->acks.size();
    r.naks = h->naks;
    r.retransmitted = h->retransmitted;
    r.segments_done = h->device_done();
    for (const auto& f : h->statuses) r.statuses.push_back(f.payload);
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

bool VirtualBoard::flush_unknown_before(Cycle t) const {
  for (size_t k = 0; k < known_motion_.size() && k < known_flush_.size(); ++k)
    if (known_flush_[k] == kFlushUnknown) return known_motion_[k].from + 3 <= t;
  return false;
}

void VirtualBoard::host_thread() {
  for (auto& job : jobs_) {
    RunResult r = run_job(job);
    if (job.done) job.done(std::move(r));
  }
  if (live) live(*this);
}

RunResult run_on_twins(const CoreParams& p, HostScript script, bool record_tx) {
  VirtualBoard board("virtual_board", p, record_tx);
  RunResult out;
  board.add_job(TwinJob{std::move(script), p.timing, [&](RunResult&& r) { out = std::move(r); }});
  sc_core::sc_start();
  return out;
}

}  // namespace fpgacnc::twins
