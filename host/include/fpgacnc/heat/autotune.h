// Relay autotune (Astrom-Hagglund): the heater output switches between u_low and u_high around a
// setpoint; the loop settles into a limit cycle whose period is the critical period Pu and whose
// amplitude a gives the critical gain Ku = 4 d / (pi a), d = (u_high - u_low) / 2 (the first
// harmonic of the relay square wave). PID gains are then proposed from (Ku, Pu).
//
// analyse_relay() works on a recorded series (time, temperature, relay output), wherever it comes
// from: a pure C++ plant loop (host/test/test_heat.cpp), or STATUS readings of a device whose
// heater runs in on/off mode (`fpgacnc autotune`, host/cli/autotune_cmd.cpp).
#pragma once

#include <string>
#include <vector>

namespace fpgacnc::heat {

struct RelaySample {
  double t_s = 0.0;     // plant time
  double temp_c = 0.0;  // measured temperature
  double u = 0.0;       // relay output in force at that time (volts, or duty)
};

struct RelayOptions {
  double setpoint_c = 60.0;
  double u_high = 12.0;  // the reference relay test: 0 / 12 V
  double u_low = 0.0;
  double hysteresis_c = 0.0625;  // relay switches at set - h (on) and set + h (off)
  int skip_cycles = 2;           // cycles left out (transient from the start)
  int cycles = 4;                // cycles measured after those
};

// The relay law: on below set - h, off above set + h, unchanged in between.
class RelayController {
 public:
  explicit RelayController(const RelayOptions& o) : o_(o) {}
  double update(double temp_c) {
    if (temp_c < o_.setpoint_c - o_.hysteresis_c) on_ = true;
    if (temp_c > o_.setpoint_c + o_.hysteresis_c) on_ = false;
    return on_ ? o_.u_high : o_.u_low;
  }
  bool on() const { return on_; }

 private:
  RelayOptions o_;
  bool on_ = true;
};

struct RelayResult {
  bool ok = false;
  std::string message;    // why not ok, or a one-line summary
  int cycles = 0;         // cycles measured
  int cycles_seen = 0;    // complete cycles in the series
  double period_s = 0.0;  // Pu: mean time between relay-on switches
  double period_min_s = 0.0, period_max_s = 0.0;
  double amplitude_c = 0.0;  // a: mean of (max - min) / 2 per cycle
  double d = 0.0;            // relay half amplitude
  double ku = 0.0;           // 4 d / (pi a), output units per degC
  double mean_c = 0.0;       // mean of the cycle centres (max + min) / 2
};

// Needs skip_cycles + cycles complete cycles (on -> on) in the series.
RelayResult analyse_relay(const std::vector<RelaySample>& s, const RelayOptions& o);

struct GainProposal {
  std::string rule;
  double kp = 0.0;  // output units per degC (volts per degC for a relay in volts)
  double ti_s = 0.0;
  double td_s = 0.0;
};

// Ziegler-Nichols PID (0.6 Ku, Pu/2, Pu/8), the reference bed's relay rule (0.6 Ku, Pu/2,
// 0.12 Pu: Kp 10.2, Ti 26.5, Td 6.4 from Ku 17, Pu 53), Ziegler-Nichols PI (0.45 Ku, Pu/1.2) and
// Tyreus-Luyben PID (0.45 Ku, 2.2 Pu, Pu/6.3; less overshoot).
std::vector<GainProposal> propose_gains(double ku, double pu);

// Multi-line report: period, amplitude, Ku, and a table of the proposed gains.
std::string format_autotune(const RelayResult& r, const RelayOptions& o,
                            const std::string& units = "V");

}  // namespace fpgacnc::heat
