#include "fpgacnc/heat/autotune.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fpgacnc::heat {

RelayResult analyse_relay(const std::vector<RelaySample>& s, const RelayOptions& o) {
  RelayResult r;
  r.d = (o.u_high - o.u_low) / 2.0;
  const double mid = (o.u_high + o.u_low) / 2.0;
  // Relay-on switching samples (u goes from below the middle to above it).
  std::vector<size_t> on;
  for (size_t i = 1; i < s.size(); ++i) {
    if (s[i - 1].u < mid && s[i].u >= mid) on.push_back(i);
  }
  r.cycles_seen = on.size() < 2 ? 0 : static_cast<int>(on.size() - 1);
  const int need = o.skip_cycles + o.cycles;
  if (r.cycles_seen < need) {
    r.message = fmt::format("only {} complete relay cycles in {:.0f} s (need {}: {} skipped + {})",
                            r.cycles_seen, s.empty() ? 0.0 : s.back().t_s - s.front().t_s, need,
                            o.skip_cycles, o.cycles);
    return r;
  }
  // Switch instants: the relay went on between samples i-1 and i, when the temperature fell
  // through set - h; interpolated on that crossing when the two samples straddle it (a device
  // polled less often than it samples), else the midpoint.
  const double thr = o.setpoint_c - o.hysteresis_c;
  auto t_on = [&](size_t i) {
    const auto& a = s[i - 1];
    const auto& b = s[i];
    if (a.temp_c > thr && b.temp_c <= thr) {
      return a.t_s + (a.temp_c - thr) / (a.temp_c - b.temp_c) * (b.t_s - a.t_s);
    }
    return (a.t_s + b.t_s) / 2.0;
  };
  double sum_p = 0.0, sum_a = 0.0, sum_m = 0.0;
  r.period_min_s = 1e300;
  r.period_max_s = 0.0;
  // The last `cycles` complete cycles (the oscillation settles as the transient dies out).
  const size_t first = on.size() - 1 - static_cast<size_t>(o.cycles);
  for (size_t c = first; c + 1 < on.size(); ++c) {
    const double p = t_on(on[c + 1]) - t_on(on[c]);
    double lo = 1e300, hi = -1e300;
    for (size_t i = on[c]; i < on[c + 1]; ++i) {
      lo = std::min(lo, s[i].temp_c);
      hi = std::max(hi, s[i].temp_c);
    }
    sum_p += p;
    sum_a += (hi - lo) / 2.0;
    sum_m += (hi + lo) / 2.0;
    r.period_min_s = std::min(r.period_min_s, p);
    r.period_max_s = std::max(r.period_max_s, p);
  }
  r.cycles = o.cycles;
  r.period_s = sum_p / o.cycles;
  r.amplitude_c = sum_a / o.cycles;
  r.mean_c = sum_m / o.cycles;
  if (!(r.amplitude_c > 0.0)) {
    r.message = "no temperature oscillation (amplitude 0)";
    return r;
  }
  r.ku = 4.0 * r.d / (std::numbers::pi * r.amplitude_c);
  r.ok = true;
  r.message = fmt::format("Pu {:.1f} s, a {:.3f} degC, Ku {:.2f}", r.period_s, r.amplitude_c, r.ku);
  return r;
}

std::vector<GainProposal> propose_gains(double ku, double pu) {
  return {
      {"Ziegler-Nichols PID", 0.6 * ku, 0.5 * pu, 0.125 * pu},
      {"reference bed relay rule", 0.6 * ku, 0.5 * pu, 0.12 * pu},
      {"Ziegler-Nichols PI", 0.45 * ku, pu / 1.2, 0.0},
      {"Tyreus-Luyben PID", 0.45 * ku, 2.2 * pu, pu / 6.3},
  };
}

std::string format_autotune(const RelayResult& r, const RelayOptions& o, const std::string& units) {
  std::string out;
  out += fmt::format("relay {:g}/{:g} {} around {:g} degC (hysteresis {:g} degC)\n", o.u_low,
                     o.u_high, units, o.setpoint_c, o.hysteresis_c);
  if (!r.ok) return out + "autotune failed: " + r.message + "\n";
  out += fmt::format(
      "critical period Pu {:.1f} s (cycles {:.1f}..{:.1f} s, last {} of {} cycles), amplitude "
      "a {:.3f} degC around {:.2f} degC\n",
      r.period_s, r.period_min_s, r.period_max_s, r.cycles, r.cycles_seen, r.amplitude_c, r.mean_c);
  out +=
      fmt::format("critical gain Ku = 4 d / (pi a) = 4 * {:g} / (pi * {:.3f}) = {:.2f} {}/degC\n",
                  r.d, r.amplitude_c, r.ku, units);
  out += fmt::format("{:<26} {:>10} {:>8} {:>8}\n", "proposed gains", "Kp " + units + "/degC",
                     "Ti s", "Td s");
  for (const auto& g : propose_gains(r.ku, r.period_s)) {
    out += fmt::format("{:<26} {:>10.2f} {:>8.1f} {:>8.1f}\n", g.rule, g.kp, g.ti_s, g.td_s);
  }
  return out;
}

}  // namespace fpgacnc::heat
