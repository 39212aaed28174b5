#include "fpgacnc/link/homing.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fpgacnc/link/cycle_move.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::link {
namespace v2 = protocol::v2;
using std::chrono::milliseconds;

namespace {
constexpr double kSeekScale = 1.5;    // seek: 1.5 x max travel (grbl's HOMING_AXIS_SEARCH_SCALAR)
constexpr double kLocateScale = 2.0;  // locate: 2 x pull-off
}  // namespace

double homing_max_travel(const config::MachineConfig& cfg, size_t axis) {
  if (cfg.homing.max_travel_mm[axis] > 0.0) return cfg.homing.max_travel_mm[axis];
  const config::Travel& t = cfg.travel[axis];
  return t.enabled ? t.max_mm - t.min_mm : 200.0;
}

uint16_t homing_switches(const config::MachineConfig& cfg, uint32_t axes, uint16_t wired) {
  uint16_t m = 0;
  for (size_t a = 0; a < 3; ++a) {
    if (!((axes >> a) & 1u)) continue;
    const bool toward_min = (cfg.homing.dir_invert_mask >> a) & 1u;
    m |= v2::switch_bit(a, !toward_min);
  }
  return static_cast<uint16_t>(m & wired);
}

int32_t homing_home_steps(const config::MachineConfig& cfg, size_t axis) {
  const bool toward_min = (cfg.homing.dir_invert_mask >> axis) & 1u;
  const double mm =
      toward_min ? -homing_max_travel(cfg, axis) + cfg.homing.pulloff_mm : -cfg.homing.pulloff_mm;
  return static_cast<int32_t>(std::lround(mm * cfg.steps_per_mm[axis]));
}

HomingCycle::HomingCycle(Link& link, const config::MachineConfig& cfg, const v2::Ident& ident,
                         uint16_t wired, std::function<V2Session&()> open_session)
    : link_(link), cfg_(cfg), ident_(ident), open_session_(std::move(open_session)) {
  for (size_t a = 0; a < config::kAxes; ++a) {
    travel_on_[a] = cfg_.travel[a].enabled;
    cfg_.travel[a].enabled = false;
  }
  for (const uint32_t c : cfg.homing.cycles) {
    uint32_t axes = 0;
    for (size_t a = 0; a < 3 && a < ident.n_axes; ++a)
      if (((c >> a) & 1u) && (homing_switches(cfg, 1u << a, wired) != 0)) axes |= 1u << a;
    if (axes) groups_.push_back({axes, homing_switches(cfg, axes, wired)});
  }
  if (groups_.empty()) {
    phase_ = Phase::kFinished;
    result_.alarm = 9;
    result_.message = "no axis of the homing cycles has a switch wired on its homing side";
  }
}

uint32_t HomingCycle::axes_of(uint16_t switches) const {
  return (switches | (switches >> 8)) & 0xFFu;
}

std::string HomingCycle::names(uint16_t switches) const {
  std::string out;
  for (size_t a = 0; a < 8; ++a) {
    for (const bool max : {false, true}) {
      if (!(switches & v2::switch_bit(a, max))) continue;
      out += (out.empty() ? "" : ", ") +
             v2::limit_switch_name(static_cast<uint8_t>(a | (max ? 0x10 : 0)));
    }
  }
  return out;
}

void HomingCycle::open() {
  session_ = &open_session_();
  // Device soft limits off: the seek leaves the travel on purpose.
  for (uint8_t a = 0; a < ident_.n_axes && a < config::kAxes; ++a)
    if (travel_on_[a]) s().push({v2::config_travel(0, a, false, 0, 0)});
}

void HomingCycle::move(uint32_t axes, bool toward, const std::array<double, 3>& dist_mm,
                       double feed) {
  gcode::Move m;
  m.motion = gcode::Motion::kLinear;
  size_t n = 0;
  for (size_t a = 0; a < 3; ++a) {
    if (!((axes >> a) & 1u)) continue;
    const bool to_min = (cfg_.homing.dir_invert_mask >> a) & 1u;
    const double sign = (toward != to_min) ? 1.0 : -1.0;
    m.end[a] = sign * dist_mm[a];
    ++n;
  }
  // Every axis at the feed (grbl scales the rate by sqrt(axes) for the same reason).
  m.feed_mm_min = feed * std::sqrt(static_cast<double>(std::max<size_t>(n, 1)));
  m.spindle_on = false;
  push_cycle_move(s(), cfg_, m, "homing");
  wait_ = Wait::kMoveDone;
}

void HomingCycle::arm(uint16_t switches) {
  s().push({v2::trigger(0, v2::TriggerMode::Home, switches, ident_.n_axes)});
  watch_.armed(s());
}

void HomingCycle::ask_status() {
  status_.ask(s());
  wait_ = Wait::kStatus;
}

void HomingCycle::fail(int alarm, std::string msg) {
  result_.ok = false;
  result_.alarm = alarm;
  result_.message = std::move(msg);
  // A HOME left armed keeps its switches' trips suppressed: DISARM before anything else moves.
  s().push({v2::trigger(0, v2::TriggerMode::Disarm)});
  phase_ = Phase::kDisarm;
  wait_ = Wait::kMoveDone;
}

void HomingCycle::enter(Phase p) {
  phase_ = p;
  const Group& g = groups_[group_];
  const double po = cfg_.homing.pulloff_mm;
  const std::array<double, 3> pull{po, po, po};
  switch (p) {
    case Phase::kPrePull:
      move(axes_of(pressed_), false, pull, cfg_.homing.seek_feed_mm_min);
      break;
    case Phase::kSeek: {
      std::array<double, 3> d{};
      for (size_t a = 0; a < 3; ++a) d[a] = kSeekScale * homing_max_travel(cfg_, a);
      arm(g.switches);
      move(g.axes, true, d, cfg_.homing.seek_feed_mm_min);
      break;
    }
    case Phase::kPull1:
    case Phase::kPull2:
      move(g.axes, false, pull, cfg_.homing.seek_feed_mm_min);
      break;
    case Phase::kLocate: {
      const double l = kLocateScale * po;
      arm(g.switches);
      move(g.axes, true, {l, l, l}, cfg_.homing.locate_feed_mm_min);
      break;
    }
    default:
      break;
  }
}

bool HomingCycle::step(milliseconds wait) {
  if (phase_ == Phase::kFinished) return true;
  if (phase_ == Phase::kOpen) {
    open();
    pressed_ = static_cast<uint16_t>(s().last_status().switches & groups_[group_].switches);
    enter(pressed_ ? Phase::kPrePull : Phase::kSeek);
    return false;
  }
  s().poll(wait);
  const Group& g = groups_[group_];
  const bool trigger_phase = phase_ == Phase::kSeek || phase_ == Phase::kLocate;
  if (trigger_phase) {
    // Watch the trigger while the move runs; a move that completed without DONE gets one more
    // query sent after its completion (the switch may have fired on its last step).
    if (wait_ == Wait::kMoveDone) {
      if (watch_.answered(s()) && s().last_trigger().done()) wait_ = Wait::kNone;
      if (wait_ == Wait::kMoveDone) {
        if (s().complete() && !watch_.asked()) wait_ = Wait::kTriggerFinal;
        watch_.ask(s(), link_.now());
        return false;
      }
    } else if (wait_ == Wait::kTriggerFinal) {
      if (!watch_.answered(s())) {
        watch_.ask(s(), link_.now());
        return false;
      }
      if (!s().last_trigger().done()) {
        const uint16_t missing = static_cast<uint16_t>(g.switches & ~s().last_trigger().fired);
        const std::string where = phase_ == Phase::kSeek
                                      ? std::string("seek (1.5 x max travel)")
                                      : fmt::format("locate (2 x pull-off, {:g} mm)",
                                                    kLocateScale * cfg_.homing.pulloff_mm);
        fail(9, fmt::format("homing: {} not found within the {}", names(missing), where));
        return false;
      }
      wait_ = Wait::kNone;
    }
    if (wait_ == Wait::kNone) {
      // DONE: the board drops the move (no DONE for it); a new session once it is at rest.
      if (phase_ == Phase::kLocate) {
        locate_.resize(group_ + 1);
        locate_[group_] = s().last_trigger();
      }
      // Frames of the dropped move not sent yet are given up; those on the line must be
      // acknowledged before the next session starts at the board's next_seq.
      s().abandon();
      ask_status();
      return false;
    }
    if (!status_.at_rest(s())) return false;  // wait_ is kStatus, set when the STATUS was asked
    const Phase next = phase_ == Phase::kSeek ? Phase::kPull1 : Phase::kPull2;
    open();
    enter(next);
    return false;
  }
  if (phase_ == Phase::kDisarm || phase_ == Phase::kSetPosition) {
    if (!s().complete()) return false;
    if (phase_ == Phase::kDisarm) {
      phase_ = Phase::kFinished;
      return true;
    }
    if (++group_ < groups_.size()) {
      phase_ = Phase::kOpen;
      return false;
    }
    result_.ok = true;
    phase_ = Phase::kFinished;
    return true;
  }
  // Pull-offs: the move's DONE, then a fresh STATUS: the switches released, the board idle.
  if (wait_ == Wait::kMoveDone) {
    if (!s().complete()) return false;
    ask_status();
    return false;
  }
  if (wait_ == Wait::kStatus) {
    if (!status_fresh()) {
      s().request_status();
      return false;
    }
    const v2::Status& st = s().last_status();
    const uint16_t held =
        static_cast<uint16_t>(st.switches & (phase_ == Phase::kPrePull ? pressed_ : g.switches));
    if (held) {
      fail(8, fmt::format("homing: {} still pressed after the pull-off of {:g} mm (ALARM:8)",
                          names(held), cfg_.homing.pulloff_mm));
      return false;
    }
    if (st.state & v2::kStateBusy) {  // SET_POSITION needs the motion idle
      ask_status();
      return false;
    }
    wait_ = Wait::kNone;
    if (phase_ == Phase::kPrePull) {
      enter(Phase::kSeek);
    } else if (phase_ == Phase::kPull1) {
      enter(Phase::kLocate);
    } else {
      // Pulled off after the locate: machine zero as grbl puts it.
      std::vector<int32_t> pos(ident_.n_axes, 0);
      uint16_t mask = 0;
      const v2::TriggerReport& rep = locate_[group_];
      for (size_t a = 0; a < 3 && a < ident_.n_axes; ++a) {
        if (!((g.axes >> a) & 1u)) continue;
        mask |= static_cast<uint16_t>(1u << a);
        pos[a] = homing_home_steps(cfg_, a);
        HomedAxis h;
        h.axis = a;
        h.max_side = (g.switches & v2::switch_bit(a, true)) != 0;
        h.latched_raw = rep.latched[a];
        h.home = pos[a];
        h.latched = rep.latched[a] + (pos[a] - st.position[a]);
        result_.axes.push_back(h);
      }
      s().push({v2::set_position(0, mask, pos)});
      s().push({v2::trigger(0, v2::TriggerMode::Disarm)});
      phase_ = Phase::kSetPosition;
      wait_ = Wait::kMoveDone;
    }
  }
  return false;
}

}  // namespace fpgacnc::link
