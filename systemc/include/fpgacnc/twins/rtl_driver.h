// The clock-by-clock side of every RTL harness (the Verilated C++ models in rtl_runner.cpp and in
// the co-simulation's cosim_rtl.cpp): the reset and configuration sequence, the rx
// pin level before each edge (the StopAndWaitHost's frames, SenderTiming bit boundaries), and
// after each edge the recording of pins and block events in the same form the twins give.
// Cycle numbering: reset is held for 8 edges, released on the next (cycle -20), 16 cfg writes
// (cycles -19..-4), 4 settle edges (-3..0); the job's first edge is cycle 1.
#pragma once

#include <optional>

#include "fpgacnc/models/edges.h"
#include "fpgacnc/twins/host_schedule.h"
#include "fpgacnc/twins/run_result.h"

namespace fpgacnc::twins {

struct CfgWrite {
  uint8_t addr;
  uint16_t data;
};
inline std::vector<CfgWrite> cfg_writes(const std::array<AxisTiming, kAxes>& t) {
  std::vector<CfgWrite> w;
  for (int a = 0; a < kAxes; ++a) {
    const AxisTiming& x = t[a];
    const uint32_t v[4] = {x.high, x.low, x.setup, x.hold};
    for (int f = 0; f < 4; ++f)
      w.push_back(CfgWrite{static_cast<uint8_t>(a * 4 + f), static_cast<uint16_t>(v[f])});
  }
  return w;
}
inline constexpr int kResetEdges = 8;
inline constexpr int kSettleEdges = 4;

class RtlDriver {
 public:
  // record_outputs: the machine output pins (coolant, fan, dout) as edges too; a fan pin high
  // keeps the job running (its PWM edges end when its duty is 0).
  RtlDriver(const CoreParams& p, const HostScript& script, bool record_tx,
            bool record_outputs = false)
      : p_(p),
        outputs_(record_outputs),
        sender_{p.clk_hz, p.baud},
        timer_(p.clk_hz, p.baud),
        host_ptr_(make_host(script, sender_, timer_.tx_boundary(10))),
        host_(*host_ptr_),
        mask_(record_tx ? 0x3ffu : 0x1ffu) {
    prev_sig_ &= mask_;
    for (int i = 0; i <= 10; ++i)
      centre_[i] = ceil_div(static_cast<__int128>(2 * i + 1) * timer_.mod, 2 * timer_.inc);
  }

  // rx level for edge c (c >= 1).
  int rx_for(Cycle c) {
    if (next_frame_ >= frames_.size() && (!cur_ || c >= frames_[*cur_].start + sender_.frame()))
      refill();
    while (next_frame_ < frames_.size() && frames_[next_frame_].start <= c) cur_ = next_frame_++;
    if (!cur_) return 1;
    const HostFrame& f = frames_[*cur_];
    const int64_t off = c - f.start;
    if (off >= sender_.frame()) return 1;
    return sender_.level(f.byte, off);
  }

  struct Outputs {
    uint32_t step, dir;
    bool laser, tx, busy, seg_start, seg_done;
    uint16_t packet_count;
    // machine outputs: bit 0 coolant_flood, 1 coolant_mist, 2 fan, 3..6 dout[0..3], 7 spindle_pwm
    uint32_t outputs = 0;
  };
  // Outputs seen after edge c.
  void after_edge(Cycle c, const Outputs& o) {
    const uint32_t sig =
        (o.step | (o.dir << 4) | (o.laser ? 1u << 8 : 0u) | (o.tx ? 1u << 9 : 0u)) & mask_;
    if (sig != prev_sig_) {
      const uint32_t ch = sig ^ prev_sig_;
      for (uint8_t s = 0; s < 10; ++s)
        if (ch >> s & 1u)
          r_.edges.push_back(
              models::Edge{static_cast<uint64_t>(c), s, static_cast<uint8_t>(sig >> s & 1u)});
      prev_sig_ = sig;
    }
    if (outputs_ && o.outputs != prev_out_) {
      static constexpr uint8_t kSig[8] = {
          models::kFlood,     models::kMist,      models::kFan,       models::kDout0,
          models::kDout0 + 1, models::kDout0 + 2, models::kDout0 + 3, models::kSpindlePwm};
      const uint32_t ch = o.outputs ^ prev_out_;
      for (int b = 0; b < 8; ++b)
        if (ch >> b & 1u)
          r_.edges.push_back(models::Edge{static_cast<uint64_t>(c), kSig[b],
                                          static_cast<uint8_t>(o.outputs >> b & 1u)});
      prev_out_ = o.outputs;
    }
    if (o.packet_count != prev_count_) {
      r_.packet_done.push_back(c - 1);
      prev_count_ = o.packet_count;
    }
    if (o.seg_start) r_.seg_start.push_back(c);
    if (o.seg_start && o.seg_done) ++r_.zero_gap;  // started on the previous one's last tick
    if (o.seg_done) r_.seg_done.push_back(c);
    // tx monitor: start edge, then samples at the bit centres.
    if (!tx_start_) {
      if (!o.tx && prev_tx_) {
        tx_start_ = c;
        tx_byte_ = 0;
      }
    } else {
      const int64_t off = c - *tx_start_;
      for (int i = 1; i <= 9; ++i) {
        if (off != centre_[i]) continue;
        if (i <= 8)
          tx_byte_ |= static_cast<uint8_t>((o.tx ? 1 : 0) << (i - 1));
        else {
          host_.on_tx_byte(*tx_start_, tx_byte_);
          tx_start_.reset();
        }
      }
    }
    prev_tx_ = o.tx;
    if (o.busy || o.step || tx_start_ || (outputs_ && (o.outputs & 4u))) last_active_ = c;
    cycle_ = c;
  }

  // True when the job is over (every packet sent and answered, the core quiet, and the last
  // ACK's frame ended) or the host waits for an ACK that does not come.
  bool finished() const {
    if (!r_.error.empty()) return true;
    return host_.done() && cycle_ >= host_.ready() && cycle_ > last_active_ + 2;
  }
  // Checks for a missing answer (call after after_edge).
  void check_stall() {
    if (host_.waiting() && next_frame_ >= frames_.size() && cycle_ > host_.ready() + 64 &&
        cycle_ > last_active_ + 64 + 2 * timer_.tx_boundary(10))
      r_.error = "no answer for packet " + std::to_string(host_.packets_sent());
  }
  const Host& host() const { return host_; }

  RunResult take_result(const std::array<int64_t, kAxes>& position, uint64_t timeouts,
                        uint64_t overruns, uint64_t frame_errors, uint64_t violations) {
    r_.acks = host_.acks;
    r_.end_cycle = host_.ready();
    if (!r_.edges.empty())
      r_.end_cycle = std::max<Cycle>(r_.end_cycle, static_cast<Cycle>(r_.edges.back().cycle));
    r_.position = position;
    r_.moves_done = r_.seg_done.size();
    r_.packets = r_.packet_done.size();
    r_.timeouts = timeouts;
    r_.overruns = overruns;
    r_.frame_errors = frame_errors;
    r_.violations = violations;
    r_.packets_sent = host_.packets_sent();
    if (auto* h = dynamic_cast<V2StreamHost*>(&host_)) {
      r_.device_frames = h->acks.size();
      r_.naks = h->naks;
      r_.retransmitted = h->retransmitted;
      r_.segments_done = h->device_done();
      for (const auto& f : h->statuses) r_.statuses.push_back(f.payload);
    }
    return std::move(r_);
  }
  void reserve(size_t n) { r_.edges.reserve(n); }
  const CoreParams& params() const { return p_; }

 private:
  // The next packet, once the current one's frames are all out.
  void refill() {
    if (host_.waiting() || host_.done()) return;
    auto f = host_.next_packet();
    if (f.empty()) return;
    frames_ = std::move(f);
    next_frame_ = 0;
    cur_.reset();
  }

  CoreParams p_;
  bool outputs_;
  uint32_t prev_out_ = 0;
  SenderTiming sender_;
  BitTimer timer_;
  std::unique_ptr<Host> host_ptr_;
  Host& host_;
  uint32_t mask_;
  std::vector<HostFrame> frames_;
  size_t next_frame_ = 0;
  std::optional<size_t> cur_;
  RunResult r_;
  uint32_t prev_sig_ = 1u << 9;  // tx idles high (masked off unless recorded)
  uint16_t prev_count_ = 0;
  bool prev_tx_ = true;
  std::optional<Cycle> tx_start_;
  uint8_t tx_byte_ = 0;
  std::array<int64_t, 11> centre_{};
  Cycle last_active_ = 0;
  Cycle cycle_ = 0;
};

// One run of a job on a Verilated cnc_core model `m` (any build of it: the ports are the same)
// through `drv`, the loop of every harness: reset, the cfg port's step timing, the settle edges,
// then one clock per edge until the host is done. Each clock the inputs are set (rx from the
// host, the hold and cycle-start buttons from `buttons`; e-stop released, no switch, no probe,
// ADC SDO low), then the rising and the falling edge are evaluated and the outputs read. With
// limit > 0 the run stops at that edge with RunResult::error saying so, instead of running on.
template <class Core>
RunResult run_core(Core& m, RtlDriver& drv, const std::array<AxisTiming, kAxes>& timing,
                   const std::vector<ButtonPress>& buttons, Cycle limit = 0) {
  auto edge = [&m] {
    m.clk = 1;
    m.eval();
    m.clk = 0;
    m.eval();
  };
  m.estop = 0;
  m.limit_min = 0;
  m.limit_max = 0;
  m.probe_in = 0;
  m.adc_sdo = 0;
  m.hold_in = 0;
  m.start_in = 0;
  m.rst = 1;
  m.rx = 1;
  m.cfg_wr = 0;
  m.clk = 0;
  m.eval();
  for (int i = 0; i < kResetEdges; ++i) edge();
  m.rst = 0;
  edge();
  for (const CfgWrite& w : cfg_writes(timing)) {
    m.cfg_wr = 1;
    m.cfg_addr = w.addr;
    m.cfg_wdata = w.data;
    edge();
  }
  m.cfg_wr = 0;
  for (int i = 0; i < kSettleEdges; ++i) edge();
  Cycle c = 0;
  size_t press = 0;  // the first button press not over
  bool over = false;
  while (!drv.finished()) {
    if (limit > 0 && c >= limit) {
      over = true;
      break;
    }
    ++c;
    m.rx = drv.rx_for(c) != 0;
    while (press < buttons.size() && buttons[press].from + buttons[press].clocks <= c) ++press;
    bool level[2] = {false, false};
    for (size_t k = press; k < buttons.size() && buttons[k].from <= c; ++k)
      if (c < buttons[k].from + buttons[k].clocks) level[buttons[k].button & 1] = true;
    m.hold_in = level[0];
    m.start_in = level[1];
    edge();
    drv.after_edge(
        c, RtlDriver::Outputs{m.step, m.dir, m.laser != 0, m.tx != 0, m.busy != 0, m.seg_start != 0,
                              m.seg_done != 0, static_cast<uint16_t>(m.packet_count),
                              (m.coolant_flood ? 1u : 0u) | (m.coolant_mist ? 2u : 0u) |
                                  (m.fan ? 4u : 0u) | (static_cast<uint32_t>(m.dout) << 3) |
                                  (m.spindle_pwm ? 128u : 0u)});
    if ((c & 1023) == 0) drv.check_stall();
  }
  std::array<int64_t, kAxes> pos{};
  for (int a = 0; a < kAxes; ++a) pos[a] = static_cast<int32_t>(m.position[a]);
  RunResult r = drv.take_result(pos, m.timeouts, m.overruns, m.frame_errors, m.violations);
  if (over)
    r.error = "RTL job not finished at clock " + std::to_string(c) + " (limit " +
              std::to_string(limit) + ")";
  return r;
}

}  // namespace fpgacnc::twins
