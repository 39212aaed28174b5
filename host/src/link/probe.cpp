#include "fpgacnc/link/probe.h"

#include <fmt/format.h>

#include <cmath>

#include "fpgacnc/link/cycle_move.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::link {
namespace v2 = protocol::v2;
using std::chrono::milliseconds;

ProbeCycle::ProbeCycle(Link& link, const config::MachineConfig& cfg, const v2::Ident& ident,
                       ProbeRequest request, std::function<V2Session&()> open_session)
    : link_(link), cfg_(cfg), ident_(ident), req_(request), open_session_(std::move(open_session)) {
  // The move is planned from 0 by its step deltas; the caller checks the target against the
  // travel, and the device's own soft limits stay as the caller's session set them.
  for (auto& t : cfg_.travel) t.enabled = false;
}

std::vector<int32_t> ProbeCycle::position() const {
  return session_->last_status().position;
}

void ProbeCycle::start() {
  session_ = &open_session_();
  const v2::Status& st = s().last_status();
  result_.start = position();
  const bool touching = (st.state & v2::kStateProbe) != 0;
  if (touching == req_.toward) {
    result_.alarm = 4;
    result_.message = req_.toward
                          ? "probe: already touching before the move (G38.2 / G38.3 start clear "
                            "of the contact)"
                          : "probe: not touching before the move (G38.4 / G38.5 start in contact)";
    result_.latched = result_.final_position = result_.start;
    phase_ = Phase::kFinished;
    return;
  }
  gcode::Move m;
  m.motion = gcode::Motion::kLinear;
  bool any = false;
  for (size_t a = 0; a < 3 && a < result_.start.size(); ++a) {
    const double spm = cfg_.steps_per_mm[a];
    const int64_t d = std::llround(req_.target_mm[a] * spm) - result_.start[a];
    result_.move_steps[a] = d;
    m.end[a] = static_cast<double>(d) / spm;
    any |= d != 0;
  }
  if (!any) {  // the target is where the machine is: no move, no edge
    result_.latched = result_.final_position = result_.start;
    if (req_.error_on_miss) {
      result_.alarm = 5;
      result_.message = "probe: the target is the machine's position (no move, no contact)";
    } else {
      result_.ok = true;
    }
    phase_ = Phase::kFinished;
    return;
  }
  m.feed_mm_min = req_.feed_mm_min;
  m.spindle_on = false;
  s().push({v2::trigger(0, req_.toward ? v2::TriggerMode::Probe : v2::TriggerMode::ProbeRelease, 0,
                        ident_.n_axes)});
  watch_.armed(s());
  push_cycle_move(s(), cfg_, m, "probe");
  phase_ = Phase::kMove;
}

bool ProbeCycle::step(milliseconds wait) {
  if (phase_ == Phase::kFinished) return true;
  if (phase_ == Phase::kOpen) {
    start();
    return finished();
  }
  s().poll(wait);
  if (phase_ == Phase::kMove || phase_ == Phase::kFinal) {
    // TRIGGER_QUERY only, no STATUS polling while the move runs: the device's answer encoder
    // sends a pending STATUS before a pending TRIGGER_REPORT, and STATUS_QUERY after STATUS_QUERY
    // can keep the report from ever going out (seen with a front end's polls).
    const bool answered = watch_.answered(s());
    if (answered && s().last_trigger().done()) {
      // The board latched the edge and cancels the move along its ramp (no DONE for it): the
      // frames not sent yet are given up, those on the line must be acknowledged before the
      // next session starts at the board's next_seq.
      result_.found = true;
      result_.latched = s().last_trigger().latched;
      s().abandon();
      ask_status();
      phase_ = Phase::kRest;
      return false;
    }
    if (phase_ == Phase::kFinal && answered) {
      // The move ran to its end without an edge; the trigger stays armed until DISARM.
      s().push({v2::trigger(0, v2::TriggerMode::Disarm)});
      status_asked_ = false;
      phase_ = Phase::kDisarm;
      return false;
    }
    // The move complete without DONE: one more query after it (the edge may have come on its
    // last step).
    if (phase_ == Phase::kMove && s().complete() && !watch_.asked()) phase_ = Phase::kFinal;
    watch_.ask(s(), link_.now());
    return false;
  }
  if (phase_ == Phase::kRest) {
    if (!status_.at_rest(s())) return false;
    // At rest: a new session, and the trigger disarmed in it.
    session_ = &open_session_();
    s().push({v2::trigger(0, v2::TriggerMode::Disarm)});
    status_asked_ = false;
    phase_ = Phase::kDisarm;
    return false;
  }
  // kDisarm: acknowledged, then a STATUS newer than it: where the machine rests.
  if (!s().complete()) return false;
  if (!status_asked_) {
    ask_status();
    status_asked_ = true;
    return false;
  }
  if (!status_fresh()) {
    s().request_status();
    return false;
  }
  result_.final_position = position();
  if (!result_.found) result_.latched = result_.final_position;
  if (!result_.found && req_.error_on_miss) {
    result_.alarm = 5;
    result_.message = fmt::format("probe: no {} within the move",
                                  req_.toward ? "contact" : "release of the contact");
  } else {
    result_.ok = true;
  }
  phase_ = Phase::kFinished;
  return true;
}

}  // namespace fpgacnc::link
