// Double-precision reference of the heater control law (heater.md, docs/heater.md "Control law").
// Header-only, no dependencies. Output u is a duty in [0, umax] (fraction of full power); inputs
// in degC. The RTL (rtl/heater/pid_incr.v) computes the same law in fixed point; with the
// coefficients quantised as the RTL holds them (quantise()), its duty equals floor(u * 2^PWM_BITS)
// of this reference for every sample (the RTL's accumulator is exact, the PWM drops the low bits).
//
// Modes (HEATER_CONFIG mode byte):
//   0 OFF     u = 0
//   1 MANUAL  u = min(manual, umax)
//   2 ON_OFF  e = set - T: e > hyst -> umax, e < -hyst -> 0, else u(k-1)
//   3 P       u = clamp(kp * e, 0, umax)                               (position form)
//   4 PID     u = clamp(u(k-1) + kp*(e - e1) + ki*e*[integrate] + kd*(e - 2 e1 + e2), 0, umax)
//             integrate = !((u(k-1) >= umax && e > 0) || (u(k-1) <= 0 && e < 0))
//             (conditional integration, decided on the previous output). On the first sample
//             after a (re)start e1 = e2 = e (no derivative kick) and u(k-1) = 0.
// kp, ki, kd are in duty per degC: kp = Kp/Umax, ki = Kp*Ts/Ti/Umax, kd = Kp*Td/(Ts*Umax) for a
// gain Kp in V/degC on a supply of Umax volts (pid_coeffs()).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fpgacnc::models::thermal {

enum class HeatMode : int { kOff = 0, kManual = 1, kOnOff = 2, kP = 3, kPid = 4 };

struct PidCoeffs {
  double kp = 0.0;      // duty / degC
  double ki = 0.0;      // duty / degC, per sample (Kp * Ts / Ti)
  double kd = 0.0;      // duty / degC (Kp * Td / Ts)
  double umax = 1.0;    // output limit, duty (0..1)
  double hyst = 0.0;    // on/off half band, degC
  double manual = 0.0;  // manual duty
  HeatMode mode = HeatMode::kPid;
};

// Coefficients from heater.md gains: Kp in V/degC, Ti and Td in s, sample period ts in s, on a
// supply of umax_v volts.
inline PidCoeffs pid_coeffs(double kp_v, double ti_s, double td_s, double ts_s, double umax_v) {
  PidCoeffs c;
  c.kp = kp_v / umax_v;
  c.ki = (ti_s > 0.0) ? kp_v * ts_s / ti_s / umax_v : 0.0;
  c.kd = kp_v * td_s / ts_s / umax_v;
  return c;
}

// Fixed-point register values (docs/heater.md): gains Q8.24 (u32), duty Q1.15 (u16, 0x8000 = 1),
// hysteresis Q12.4 (u16).
inline uint32_t to_q8_24(double x) {
  return static_cast<uint32_t>(std::clamp(std::round(x * 16777216.0), 0.0, 4294967295.0));
}
inline uint16_t to_q1_15(double x) {
  return static_cast<uint16_t>(std::clamp(std::round(x * 32768.0), 0.0, 32768.0));
}
inline uint16_t to_u_q4(double x) {
  return static_cast<uint16_t>(std::clamp(std::round(x * 16.0), 0.0, 65535.0));
}
// The coefficients exactly as the RTL holds them.
inline PidCoeffs quantise(const PidCoeffs& c) {
  PidCoeffs q = c;
  q.kp = to_q8_24(c.kp) / 16777216.0;
  q.ki = to_q8_24(c.ki) / 16777216.0;
  q.kd = to_q8_24(c.kd) / 16777216.0;
  q.umax = to_q1_15(c.umax) / 32768.0;
  q.manual = std::min(to_q1_15(c.manual) / 32768.0, q.umax);
  q.hyst = to_u_q4(c.hyst) / 16.0;
  return q;
}

class PidRef {
 public:
  explicit PidRef(const PidCoeffs& c = {}) : c_(c) {}
  void set_coeffs(const PidCoeffs& c) {
    if (c.mode != c_.mode) restart();
    c_ = c;
  }
  const PidCoeffs& coeffs() const { return c_; }
  // Forget the history: the next sample is a first sample (u(k-1) = 0, e1 = e2 = e).
  void restart() {
    fresh_ = true;
    u_ = 0.0;
  }

  // One sample: setpoint and measured temperature in degC; returns u(k).
  double step(double set_c, double temp_c) {
    const double e = set_c - temp_c;
    switch (c_.mode) {
      case HeatMode::kOff:
        u_ = 0.0;
        break;
      case HeatMode::kManual:
        u_ = std::min(c_.manual, c_.umax);
        break;
      case HeatMode::kOnOff:
        if (fresh_) u_ = 0.0;
        if (e > c_.hyst)
          u_ = c_.umax;
        else if (e < -c_.hyst)
          u_ = 0.0;
        break;
      case HeatMode::kP:
        u_ = std::clamp(c_.kp * e, 0.0, c_.umax);
        break;
      case HeatMode::kPid: {
        if (fresh_) {
          e1_ = e;
          e2_ = e;
          u_ = 0.0;
        }
        const bool sat_hi = (u_ >= c_.umax && e > 0.0);
        const bool sat_lo = (u_ <= 0.0 && e < 0.0);
        double du = c_.kp * (e - e1_) + c_.kd * (e - 2.0 * e1_ + e2_);
        if (!sat_hi && !sat_lo) du += c_.ki * e;
        u_ = std::clamp(u_ + du, 0.0, c_.umax);
        e2_ = e1_;
        e1_ = e;
        break;
      }
    }
    fresh_ = false;
    return u_;
  }
  double output() const { return u_; }

 private:
  PidCoeffs c_;
  bool fresh_ = true;
  double u_ = 0.0;
  double e1_ = 0.0;
  double e2_ = 0.0;
};

}  // namespace fpgacnc::models::thermal
