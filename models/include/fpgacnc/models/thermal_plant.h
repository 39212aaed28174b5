// Thermal plant models for the heater benches and the simulated board (docs/heater.md).
// Header-only, no dependencies beyond the C++ standard library. All times in seconds, temperatures
// in degC, voltages in volts. Every model is a discrete-time stepper: step(dt, input) advances it
// by dt seconds with the input held constant (zero-order hold), exactly (no Euler error) for the
// linear parts.
//
//   BedPlant      the reference heated bed of heater.md: first order plus dead time from heater
//                 voltage to temperature, K 4.8 degC/V, L 10 s, T 370 s, ambient 20 degC; input
//                 duty in [0, 1] of the supply (kBedSupplyV = 24 V: Umax = 24 V).
//   HotEndPlant   a 40 W / 24 V cartridge in a 12 J/K block, 8 K/W to ambient, 1 s transport
//                 delay and a 2 s thermistor lag (see HotEndParams for why).
//   DelayedSensor the reference bed sensor: one reading per sample, `delay_s` old.
//   Thermistor    100k NTC, beta 3950, 4.7k pull-up to 3.3 V, the LTC2308 input (0..4.095 V).
//   adc_code()    the LTC2308 unipolar transfer, 12 bits, LSB 1 mV (4.096 V internal reference).
//   thermistor_table()  the 65-entry table the host loads (THERMISTOR_TABLE frames): entry i is
//                 the temperature at ADC code 64*i in Q11.4 (1/16 degC), clamped to
//                 [kTableMinC, kTableMaxC]; table_lookup() is the RTL's interpolation, bit exact.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>

namespace fpgacnc::models::thermal {

// ------------------------------------------------------------------------------------ bed
struct BedParams {
  double gain_c_per_v = 4.8;  // K
  double dead_time_s = 10.0;  // L
  double tau_s = 370.0;       // T
  double ambient_c = 20.0;    // temperature at 0 V
  double supply_v = 24.0;     // Umax: duty 1.0 = 24 V
};
inline constexpr double kBedSupplyV = 24.0;

// First order plus dead time: T' = (ambient + K * u(t - L) - T) / tau, u in volts.
// The dead time is a FIFO of input samples of the step size in use; call step() with a constant dt
// (the benches use the sample period, 1 s, or an integer fraction of it) for an exact delay.
class BedPlant {
 public:
  explicit BedPlant(const BedParams& p = {}, double initial_c = 20.0) : p_(p), t_(initial_c) {}

  // Advance dt seconds with heater duty `duty` (clamped to [0, 1]) held; returns the temperature.
  double step(double dt, double duty) {
    const double u = std::clamp(duty, 0.0, 1.0) * p_.supply_v;
    const size_t n = static_cast<size_t>(std::lround(p_.dead_time_s / dt));
    if (hist_.size() != n || dt != last_dt_) {  // (re)size the delay line, filled with zero volts
      hist_.assign(n, 0.0);
      last_dt_ = dt;
    }
    double ud = u;
    if (n > 0) {
      hist_.push_back(u);
      ud = hist_.front();
      hist_.pop_front();
    }
    const double target = p_.ambient_c + p_.gain_c_per_v * ud;
    t_ = target + (t_ - target) * std::exp(-dt / p_.tau_s);
    return t_;
  }
  double temperature() const { return t_; }
  const BedParams& params() const { return p_; }

 private:
  BedParams p_;
  double t_;
  std::deque<double> hist_;
  double last_dt_ = -1.0;
};

// ------------------------------------------------------------------------------------ hot end
// A 40 W cartridge (24 V, 14.4 ohm) in an aluminium heater block with nozzle: heat capacity
// 12 J/K (about 20 g of aluminium and brass plus the cartridge), 8 K/W to ambient (still air and
// the heat break): full-power equilibrium ambient + 320 degC, time constant R*C = 96 s, so 20 ->
// 200 degC at full power in about 83 s (one to two minutes, as heater.md asks). Heat takes about
// 1 s to travel from the cartridge to the thermistor bead (dead time) and the bead lags the block
// with a 2 s time constant: the fast plant of a hot end with its sensor lag.
struct HotEndParams {
  double power_w = 40.0;
  double heat_capacity_j_per_k = 12.0;
  double r_thermal_k_per_w = 8.0;
  double dead_time_s = 1.0;
  double sensor_tau_s = 2.0;
  double ambient_c = 20.0;
};

class HotEndPlant {
 public:
  explicit HotEndPlant(const HotEndParams& p = {}, double initial_c = 20.0)
      : p_(p), block_(initial_c), sensor_(initial_c) {}

  // Advance dt seconds with duty (clamped to [0, 1]) held; returns the thermistor temperature.
  double step(double dt, double duty) {
    const double pw = std::clamp(duty, 0.0, 1.0) * p_.power_w;
    const size_t n = static_cast<size_t>(std::lround(p_.dead_time_s / dt));
    if (hist_.size() != n || dt != last_dt_) {
      hist_.assign(n, 0.0);
      last_dt_ = dt;
    }
    double pd = pw;
    if (n > 0) {
      hist_.push_back(pw);
      pd = hist_.front();
      hist_.pop_front();
    }
    const double tau = p_.r_thermal_k_per_w * p_.heat_capacity_j_per_k;
    const double target = p_.ambient_c + p_.r_thermal_k_per_w * pd;
    const double b0 = block_;
    block_ = target + (b0 - target) * std::exp(-dt / tau);
    // Sensor: first-order lag behind the block; the block moves within the step, integrate the
    // lag in 8 sub-steps (ample for dt <= 1 s against a 2 s lag).
    const int sub = 8;
    for (int i = 1; i <= sub; ++i) {
      const double bi = target + (b0 - target) * std::exp(-dt * i / sub / tau);
      sensor_ = bi + (sensor_ - bi) * std::exp(-dt / sub / p_.sensor_tau_s);
    }
    return sensor_;
  }
  double temperature() const { return sensor_; }  // what the thermistor sees
  double block_temperature() const { return block_; }
  const HotEndParams& params() const { return p_; }

 private:
  HotEndParams p_;
  double block_;
  double sensor_;
  std::deque<double> hist_;
  double last_dt_ = -1.0;
};

// ------------------------------------------------------------------------------------ sensor lag
// The reference bed's sensor: the reading taken at sample k is the plant temperature of
// `delay_samples` samples before (heater.md: "one reading per second, about 1 s old").
class DelayedSensor {
 public:
  explicit DelayedSensor(int delay_samples = 1, double initial_c = 20.0)
      : hist_(static_cast<size_t>(delay_samples), initial_c) {}
  // Push the current plant temperature, get the reading (the temperature delay_samples ago).
  double sample(double plant_c) {
    if (hist_.empty()) return plant_c;
    hist_.push_back(plant_c);
    const double r = hist_.front();
    hist_.pop_front();
    return r;
  }

 private:
  std::deque<double> hist_;
};

// ------------------------------------------------------------------------------------ thermistor
// NTC thermistor (beta model) at the bottom of a divider with a pull-up to `vcc`:
//   R(T) = r25 * exp(beta * (1/T - 1/298.15)), V = vcc * R / (R + pullup).
// 100k/3950 with 4.7k to 3.3 V: 25 degC -> 3.143 V, 60 degC -> 2.776 V (about 15.7 mV/degC, 0.064
// degC per ADC code), 200 degC -> 0.451 V (6.9 mV/degC, 0.15 degC per code); an open sensor reads
// 3.3 V (code 3300), a short 0 V (code 0): both map to impossible temperatures in the table.
struct Thermistor {
  double r25_ohm = 100e3;
  double beta = 3950.0;
  double pullup_ohm = 4700.0;
  double vcc = 3.3;

  double resistance(double temp_c) const {
    return r25_ohm * std::exp(beta * (1.0 / (temp_c + 273.15) - 1.0 / 298.15));
  }
  double voltage(double temp_c) const {
    const double r = resistance(temp_c);
    return vcc * r / (r + pullup_ohm);
  }
  // Inverse of voltage(); v >= vcc (open) gives -inf, v <= 0 (short) +inf.
  double temperature(double v) const {
    if (v >= vcc) return -INFINITY;
    if (v <= 0.0) return INFINITY;
    const double r = pullup_ohm * v / (vcc - v);
    return 1.0 / (1.0 / 298.15 + std::log(r / r25_ohm) / beta) - 273.15;
  }
};

// ------------------------------------------------------------------------------------ ADC
inline constexpr double kAdcLsbV = 4.096 / 4096.0;  // LTC2308 unipolar, internal 4.096 V ref
// Ideal unipolar transfer (straight binary): code = floor(v / LSB), clamped to 0..4095.
inline int adc_code(double v) {
  const double c = std::floor(v / kAdcLsbV);
  return static_cast<int>(std::clamp(c, 0.0, 4095.0));
}

// ------------------------------------------------------------------------------------ table
inline constexpr int kTableEntries = 65;  // breakpoints at codes 0, 64, ..., 4096
inline constexpr int kTableShift = 6;     // 64 codes per interval
inline constexpr double kTableMinC = -100.0;
inline constexpr double kTableMaxC = 500.0;
using Table = std::array<int16_t, kTableEntries>;

inline int16_t to_q4(double c) {  // degC -> Q11.4, rounded, saturated to int16
  const double q = std::round(c * 16.0);
  return static_cast<int16_t>(std::clamp(q, -32768.0, 32767.0));
}
inline double from_q4(int v) {
  return v / 16.0;
}

// Entry i: the thermistor temperature at the code's voltage (code 64*i, V = code * LSB),
// clamped to [kTableMinC, kTableMaxC] (the short and open ends).
inline Table thermistor_table(const Thermistor& th = {}) {
  Table t{};
  for (int i = 0; i < kTableEntries; ++i) {
    const double v = (i << kTableShift) * kAdcLsbV;
    t[static_cast<size_t>(i)] = to_q4(std::clamp(th.temperature(v), kTableMinC, kTableMaxC));
  }
  return t;
}

// The RTL's interpolation (rtl/heater/temp_table.v), bit exact: i = code >> 6, f = code & 63,
// T = t[i] + floor((t[i+1] - t[i]) * f / 64) (arithmetic shift), in Q11.4.
inline int table_lookup(const Table& t, int code) {
  const int i = code >> kTableShift;
  const int f = code & ((1 << kTableShift) - 1);
  const int a = t[static_cast<size_t>(i)];
  const int b = t[static_cast<size_t>(i + 1)];
  return a + (((b - a) * f) >> kTableShift);  // >> of a negative int: arithmetic (C++20)
}

}  // namespace fpgacnc::models::thermal
