#include "fpgacnc/twins/virtual_board.h"

#include <algorithm>
#include <chrono>

namespace fpgacnc::twins {

std::vector<Edge> PinRecorder::take_sorted() {
  std::sort(edges_.begin(), edges_.end(), [](const Edge& a, const Edge& b) {
    return a.cycle != b.cycle ? a.cycle < b.cycle : a.signal < b.signal;
  });
  return std::move(edges_);
}

VirtualBoard::VirtualBoard(sc_core::sc_module_name name, const CoreParams& p, bool record_tx)
    : sc_module(name),
      p_(p),
      clk_(p.clk_hz),
      rx_("uart_rx", clk_, p_),
      dec_("packet_decoder_v1", clk_, p_),
      prep_("segment_prep", clk_, p_),
      exec_("segment_executor", clk_, p_, pins_),
      status_("status_ack", clk_),
      tx_("uart_tx", clk_, p_, pins_),
      host_pin_("host_pin"),
      host_line_("host_line") {
  pins_.record_tx = record_tx;
  host_pin_.bind(rx_.pin);
  rx_.bytes.bind(dec_.bytes);
  dec_.commands.bind(prep_.commands);
  prep_.segments.bind(exec_.segments);
  prep_.exec_status.bind(exec_.status);
  for (int a = 0; a < kAxes; ++a) {
    dda_[a] = std::make_unique<DdaLinearTwin>(sc_core::sc_gen_unique_name("dda_linear"), clk_);
    pulse_[a] = std::make_unique<StepPulseTwin>(sc_core::sc_gen_unique_name("step_pulse"), clk_,
                                                p_.timing[a], a, pins_);
    exec_.dda[a]->bind(dda_[a]->load);
    exec_.pulse[a]->bind(pulse_[a]->ctl);
    dda_[a]->step.bind(pulse_[a]->req);
  }
  exec_.done.bind(status_.done);
  status_.tx.bind(tx_.bytes);
  tx_.line.bind(host_line_);
  host_line_.register_b_transport(this, &VirtualBoard::on_line);
  SC_THREAD(host_thread);
}

void VirtualBoard::reset(const std::array<AxisTiming, kAxes>& timing) {
  p_.timing = timing;
  pins_.clear();
  rx_.reset();
  dec_.reset();
  prep_.reset();
  exec_.reset();
  for (auto& p : pulse_) p->reset();
  status_.reset();
  tx_.reset();
}

void VirtualBoard::on_line(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
  if (host_) host_->on_tx_byte(clk_.at(delay), payload<LineFrame>(gp).byte);
  gp.set_response_status(tlm::TLM_OK_RESPONSE);
}

RunResult VirtualBoard::run_job(const TwinJob& job) {
  const auto t0 = std::chrono::steady_clock::now();
  tlm_utils::tlm_quantumkeeper qk;
  qk.set_global_quantum(quantum_);
  qk.reset();
  // Cycle 0 of this job: the next whole clock from now.
  const uint64_t per = clk_.period_ps();
  const uint64_t now = sc_core::sc_time_stamp().value();
  clk_.set_base(sc_core::sc_time::from_value((now + per - 1) / per * per));
  reset(job.timing);
  StopAndWaitHost host(job.packets, SenderTiming{p_.clk_hz, p_.baud}, tx_.frame_clocks());
  host_ = &host;
  RunResult r;
  while (!host.done()) {
    if (host.waiting()) {
      r.error = "no ACK for packet " + std::to_string(host.packets_sent());
      break;
    }
    for (const HostFrame& f : host.next_packet()) {
      RxFrame frame{f.byte};
      transport(host_pin_, gp_, clk_, frame, f.start);
      qk.set(clk_.delay_to(f.start));
      if (qk.need_sync()) qk.sync();
    }
  }
  qk.sync();
  host_ = nullptr;
  r.edges = pins_.take_sorted();
  pins_.clear();
  r.acks = host.acks;
  r.packet_done = dec_.packet_done_cycles;
  r.seg_start = exec_.seg_start_cycles;
  r.seg_done = status_.seg_done_cycles;
  r.end_cycle = host.ready();
  if (!r.edges.empty())
    r.end_cycle = std::max<Cycle>(r.end_cycle, static_cast<Cycle>(r.edges.back().cycle));
  for (int a = 0; a < kAxes; ++a) {
    r.position[a] = pulse_[a]->position;
    r.violations += pulse_[a]->violations;
  }
  r.moves_done = status_.moves_done;
  r.packets = dec_.packets;
  r.timeouts = dec_.timeouts;
  r.overruns = dec_.overruns;
  r.frame_errors = rx_.frame_errors;
  r.packets_sent = host.packets_sent();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

void VirtualBoard::host_thread() {
  for (auto& job : jobs_) {
    RunResult r = run_job(job);
    if (job.done) job.done(std::move(r));
  }
}

RunResult run_on_twins(const CoreParams& p, std::vector<HostPacket> packets, bool record_tx) {
  VirtualBoard board("virtual_board", p, record_tx);
  RunResult out;
  board.add_job(TwinJob{std::move(packets), p.timing, [&](RunResult&& r) { out = std::move(r); }});
  sc_core::sc_start();
  return out;
}

}  // namespace fpgacnc::twins
