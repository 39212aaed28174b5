// Twin of rtl/motion/step_pulse.v: STEP/DIR pin driver of one axis (docs/timing.md "Pulse shape").
//
// Target `req` (from the axis's dda_linear) and target `ctl` (from segment_executor):
//   write, address 0: a step request (DDA tick) on the delay's edge e. STEP rises on edge e,
//     or on the first edge its low time allows (rise of the previous pulse + high + low; that
//     is a timing violation, counted), and falls `high` edges later (0 counts as 1).
//   write, address kDirWrite: DIR takes PulseCmd::dir on the delay's edge.
//   read: PulseState: hold reference (DIR may change from edge last_rise + hold on), the edge
//     after which the generator is idle (last rise + high + low - 1), current DIR.
// position_after(t): the position counter after edge t (the STATUS frame's snapshot, asked in
// time order: rises up to the last edge asked for are folded into a base value).
// Pins go to the PinRecorder; the position counter follows every rise (+1 with DIR high).
// Abort (e-stop) needs nothing here: the executor and the DDA send no request or DIR write from
// the abort edge on, so a pulse already high finishes its high time, its low time still counts,
// and a request made before the abort that waits for its low time still rises (as the RTL's
// pending_reg, which the abort does not clear).
#pragma once

#include <deque>

#include "fpgacnc/twins/tlm_common.h"

namespace fpgacnc::twins {

// The hold reference after reset: the harness releases reset 20 edges before cycle 0 (1 clock
// of reset release, 16 configuration writes, 4 settle clocks), and the hold counter counts from
// the release edge as if STEP had risen there.
inline constexpr Cycle kResetHoldRef = -20;

class StepPulseTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<StepPulseTwin> req;
  tlm_utils::simple_target_socket<StepPulseTwin> ctl;

  StepPulseTwin(sc_core::sc_module_name name, const CycleClock& clk, const AxisTiming& t, int axis,
                PinRecorder& pins)
      : sc_module(name), req("req"), ctl("ctl"), clk_(clk), t_(t), axis_(axis), pins_(pins) {
    req.register_b_transport(this, &StepPulseTwin::b_transport);
    ctl.register_b_transport(this, &StepPulseTwin::b_transport);
  }

  void reset() {
    last_rise_ = kResetHoldRef;
    idle_from_ = -1;
    dir_ = false;
    position = 0;
    pulses = 0;
    violations = 0;
    history_.clear();
    base_position_ = 0;
    violation_cycles.clear();
    violation_strobes.clear();
  }
  int64_t position = 0;
  uint64_t pulses = 0, violations = 0;
  int64_t position_after(Cycle t) {
    while (!history_.empty() && history_.front().first <= t) {
      base_position_ += history_.front().second;
      history_.pop_front();
    }
    return base_position_;
  }
  std::vector<Cycle> violation_cycles;   // rise edges of late (violating) pulses
  std::vector<Cycle> violation_strobes;  // their request edges (the `violation` strobe after it)
  bool keep_history = false;             // answer position reads (the board's STATUS)

 private:
  void b_transport(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const Cycle e = clk_.at(delay);
    const Cycle high = std::max<uint32_t>(t_.high, 1), low = std::max<uint32_t>(t_.low, 1);
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (gp.is_read()) {
      payload<PulseState>(gp) = PulseState{last_rise_, idle_from_, dir_};
      return;
    }
    if (gp.get_address() == kDirWrite) {
      const bool d = payload<PulseCmd>(gp).dir;
      if (d != dir_) pins_.add(e, models::dir_signal(axis_), d ? 1 : 0);
      dir_ = d;
      return;
    }
    const Cycle rise = std::max(e, idle_from_ + 1);
    if (rise != e) {
      ++violations;
      violation_cycles.push_back(rise);
      violation_strobes.push_back(e);
    }
    pins_.add(rise, models::step_signal(axis_), 1);
    pins_.add(rise + high, models::step_signal(axis_), 0);
    last_rise_ = rise;
    idle_from_ = rise + high + low - 1;
    position += dir_ ? 1 : -1;
    if (keep_history) history_.emplace_back(rise, dir_ ? 1 : -1);
    ++pulses;
    delay = clk_.delay_to(rise);
  }

  const CycleClock& clk_;
  const AxisTiming& t_;
  int axis_;
  PinRecorder& pins_;
  Cycle last_rise_ = kResetHoldRef;
  Cycle idle_from_ = -1;
  bool dir_ = false;
  std::deque<std::pair<Cycle, int>> history_;  // rises not yet folded into base_position_
  int64_t base_position_ = 0;
};

}  // namespace fpgacnc::twins
