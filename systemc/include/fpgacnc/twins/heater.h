// Twins of the heater RTL (docs/heater.md): rtl/machine/pwm.v, rtl/heater/pid_incr.v,
// rtl/heater/heater_safety.v and the channel glue of rtl/heater/heater_channel.v / heater_block.v
// (settings, enable, watchdog), with the same integer arithmetic.
//
//   PidTwin      u(k) in Q1.28 from e = set - T (Q11.4), gains Q8.24, limits Q1.15: the
//                incremental law with conditional integration, exactly as pid_incr computes it
//                (int64 arithmetic: every product and sum of the RTL fits).
//   SafetyTwin   the supervision state machine and fault bits of heater_safety, one call per eval.
//   ChannelTwin  one channel at sample granularity: frames (config, setpoint, safety), fault
//                clear, and sample(temp, kill) -> u, faults, enabled, in the RTL's edge order
//                (a fault found on an eval zeroes that eval's controller output).
//   WatchdogTwin ticks without a valid frame.
//   PwmTwin      the pin of pwm.v from a list of (cycle, duty) and (cycle, force_off) changes:
//                period boundaries every PWM_DIV * 2^PWM_BITS clocks after reset, duty taken at
//                a boundary, force_off gating one edge later; returns the edge list.
// Plain C++ (no SystemC header): the co-simulation (systemc/cosim/cosim_heater.cpp) puts them
// behind a TLM-2.0 target socket and drives them with the RTL job's events.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins::heater {

enum Mode : int { kOff = 0, kManual = 1, kOnOff = 2, kP = 3, kPid = 4 };

struct PidSettings {
  int mode = kOff;
  uint32_t kp = 0, ki = 0, kd = 0;
  uint32_t umax = 0x8000, hyst = 16, manual = 0;
};

class PidTwin {
 public:
  void restart() { fresh_ = true; }
  void reset() {
    fresh_ = true;
    u_ = 0;
    e1_ = e2_ = 0;
  }
  // One sample: enable as the RTL sees it one clock after start. Returns u (Q1.28).
  int64_t sample(const PidSettings& s, int set, int temp, bool enable) {
    const int64_t e = static_cast<int64_t>(set) - temp;
    const int64_t umax = static_cast<int64_t>(s.umax) << 13;
    if (!enable || s.mode > kPid || s.mode == kOff) {
      u_ = 0;
      fresh_ = true;
      return u_;
    }
    if (s.mode == kManual) {
      u_ = s.manual > s.umax ? umax : static_cast<int64_t>(s.manual) << 13;
      fresh_ = false;
      return u_;
    }
    if (s.mode == kOnOff) {
      const int64_t h = s.hyst;
      if (e > h)
        u_ = umax;
      else if (e < -h)
        u_ = 0;
      else if (fresh_)
        u_ = 0;
      fresh_ = false;
      return u_;
    }
    int64_t sum;
    if (s.mode == kP) {
      sum = static_cast<int64_t>(s.kp) * e;
    } else {
      if (fresh_) e1_ = e2_ = e;
      const int64_t up = fresh_ ? 0 : u_;
      const bool integrate = !((up >= umax && e > 0) || (up == 0 && e < 0));
      sum = up + static_cast<int64_t>(s.kp) * (e - e1_) +
            static_cast<int64_t>(s.kd) * (e - 2 * e1_ + e2_);
      if (integrate) sum += static_cast<int64_t>(s.ki) * e;
      e2_ = e1_;
      e1_ = e;
    }
    u_ = std::clamp<int64_t>(sum, 0, umax);
    fresh_ = false;
    return u_;
  }
  int64_t u() const { return u_; }

 private:
  bool fresh_ = true;
  int64_t u_ = 0, e1_ = 0, e2_ = 0;
};

struct SafetySettings {
  int tmin = 80, tmax = 4400;
  int band = 64, rperiod = 40, wrise = 32, wperiod = 20;
};

class SafetyTwin {
 public:
  enum Q { kIdle, kWatch, kHold, kCool };
  void reset() {
    q_ = kIdle;
    faults = 0;
    ref_ = wtimer_ = rtimer_ = 0;
    arm_pend_ = false;
  }
  void disable() {
    q_ = kIdle;
    wtimer_ = rtimer_ = 0;
    arm_pend_ = false;
  }
  void arm() { arm_pend_ = true; }
  void clear() { faults = 0; }
  // One eval with the channel enabled: returns the bits found on this eval.
  int eval(const SafetySettings& s, int set, int t) {
    const bool above = t > set + s.band, below = t < set - s.band;
    int found = 0;
    if (t < s.tmin) found |= 1;
    if (t > s.tmax) found |= 2;
    if (!arm_pend_ && q_ == kHold && (above || below) && s.rperiod != 0 && rtimer_ + 1 >= s.rperiod)
      found |= 4;
    if (!arm_pend_ && q_ == kWatch && below && t < ref_ + s.wrise && s.wperiod != 0 &&
        wtimer_ + 1 >= s.wperiod)
      found |= 8;
    if (arm_pend_) {
      arm_pend_ = false;
      ref_ = t;
      wtimer_ = rtimer_ = 0;
      q_ = below ? kWatch : above ? kCool : kHold;
    } else if (q_ == kWatch) {
      if (!below) {
        q_ = kHold;
        rtimer_ = 0;
      } else if (t >= ref_ + s.wrise) {
        ref_ = t;
        wtimer_ = 0;
      } else {
        wtimer_ = (wtimer_ + 1) & 0xFFFF;
      }
    } else if (q_ == kHold) {
      rtimer_ = (above || below) ? ((rtimer_ + 1) & 0xFFFF) : 0;
    } else if (q_ == kCool) {
      if (!above) {
        q_ = kHold;
        rtimer_ = 0;
      }
    }
    faults |= found;
    return found;
  }
  bool holding() const { return q_ == kHold; }
  int faults = 0;

 private:
  Q q_ = kIdle;
  int ref_ = 0, wtimer_ = 0, rtimer_ = 0;
  bool arm_pend_ = false;
};

struct SampleOut {
  int64_t u = 0;
  int faults = 0;
  bool enabled = false;
};

class ChannelTwin {
 public:
  explicit ChannelTwin(const SafetySettings& defaults) : defaults_(defaults) { reset(); }
  void reset() {
    pid = PidSettings{};
    safe = defaults_;
    set_ = 0;
    enabled_ = false;
    pid_.reset();
    saf_.reset();
  }
  void config(const PidSettings& s) {
    if (s.mode != pid.mode) pid_.restart();
    pid = s;
  }
  // HEATER_SETPOINT; kill: e-stop or watchdog latched at that moment.
  void setpoint(int set, bool kill) {
    set_ = set;
    if (set > 0 && saf_.faults == 0 && !kill) {
      if (!enabled_) pid_.restart();
      enabled_ = true;
      saf_.arm();
    } else {
      disable();
    }
  }
  void safety(const SafetySettings& s) { safe = s; }
  void fault_clear() { saf_.clear(); }
  void kill() { disable(); }
  SampleOut sample(int temp, bool kill) {
    if (enabled_) saf_.eval(safe, set_, temp);
    SampleOut o;
    o.u = pid_.sample(pid, set_, temp, enabled_ && !kill && saf_.faults == 0);
    if (saf_.faults != 0 || kill) disable();
    o.faults = saf_.faults;
    o.enabled = enabled_;
    return o;
  }
  int faults() const { return saf_.faults; }
  bool enabled() const { return enabled_; }
  PidSettings pid;
  SafetySettings safe;

 private:
  void disable() {
    enabled_ = false;
    saf_.disable();
  }
  SafetySettings defaults_;
  int set_ = 0;
  bool enabled_ = false;
  PidTwin pid_;
  SafetyTwin saf_;
};

class WatchdogTwin {
 public:
  void period(int p) {
    period_ = p;
    count_ = 0;
  }
  void frame_ok() { count_ = 0; }
  void tick() {
    if (period_ != 0 && count_ != 0xFFFF) ++count_;
  }
  bool expired() const { return period_ != 0 && count_ >= period_; }

 private:
  int period_ = 0, count_ = 0;
};

// pwm.v as edges. Cycle n = the n-th clock edge after reset was released (edge 1 is the first).
// Inputs: changes of the duty input and of force_off, each (n, value): the value the input has
// in the clock before edge n (sorted by n). After edge n: div = n mod DIV, count(n) =
// floor(n / DIV) mod 2^BITS, the active duty is reloaded from the duty input when
// n mod (DIV * 2^BITS) == 0, and out = !force(n) && count(n) < active(n).
struct PinEdge {
  Cycle cycle;  // the output has `level` after this edge
  bool level;
};

class PwmTwin {
 public:
  PwmTwin(int bits, int div) : bits_(bits), div_(div) {}
  std::vector<PinEdge> run(const std::vector<std::pair<Cycle, int>>& duty,
                           const std::vector<std::pair<Cycle, bool>>& force, Cycle last) const {
    std::vector<PinEdge> out;
    const int64_t period = static_cast<int64_t>(div_) << bits_;
    int cur_duty = 0, active = 0;
    bool cur_force = false, level = false;
    size_t di = 0, fi = 0;
    Cycle c = 1;
    while (c <= last) {
      while (di < duty.size() && duty[di].first <= c) cur_duty = duty[di++].second;
      while (fi < force.size() && force[fi].first <= c) cur_force = force[fi++].second;
      const int64_t count = (c / div_) % (int64_t{1} << bits_);
      if (c % period == 0) active = cur_duty;
      const bool lv = !cur_force && count < active;
      if (lv != level) {
        out.push_back(PinEdge{c, lv});
        level = lv;
      }
      // Next edge where anything may change: a count step (which holds the period starts) or an
      // input change.
      Cycle next = c + (div_ - c % div_);
      if (di < duty.size()) next = std::min<Cycle>(next, duty[di].first);
      if (fi < force.size()) next = std::min<Cycle>(next, force[fi].first);
      c = std::max<Cycle>(next, c + 1);
    }
    return out;
  }

 private:
  int bits_, div_;
};

}  // namespace fpgacnc::twins::heater
