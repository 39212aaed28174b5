#include "fpgacnc/heat/heater_job.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>

#include "fpgacnc/gcode/interpreter.h"

namespace fpgacnc::heat {
namespace v2 = protocol::v2;

namespace {

// Column (1-based) of the first `letter` word on line `line` of `path` outside comments; 0 when
// the file or the word cannot be found.
int word_column(const std::string& path, int line, char letter) {
  if (path.empty() || line <= 0) return 0;
  std::ifstream in(path);
  if (!in) return 0;
  std::string text;
  for (int i = 0; i < line; ++i) {
    if (!std::getline(in, text)) return 0;
  }
  bool paren = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ';') break;
    if (c == '(') paren = true;
    if (c == ')') paren = false;
    if (!paren && std::toupper(static_cast<unsigned char>(c)) == letter) {
      return static_cast<int>(i) + 1;
    }
  }
  return 0;
}

int mword_column(const std::string& path, int line) {
  return word_column(path, line, 'M');
}

uint32_t q24(double v) {
  const double x = std::round(v * 16777216.0);
  if (!(x >= 0.0) || x > 4294967295.0) {
    throw std::invalid_argument(fmt::format("heater gain {} duty/degC does not fit Q8.24", v));
  }
  return static_cast<uint32_t>(x);
}

uint16_t q15(double frac) {
  return static_cast<uint16_t>(std::lround(std::clamp(frac, 0.0, 1.0) * 32768.0));
}

uint16_t uq4(double c) {
  return static_cast<uint16_t>(std::clamp<long>(std::lround(c * 16.0), 0, 65535));
}

}  // namespace

int16_t to_q4(double temp_c) {
  return static_cast<int16_t>(std::clamp<long>(std::lround(temp_c * 16.0), -32768, 32767));
}

uint16_t ticks(double seconds, double sample_s) {
  return static_cast<uint16_t>(std::clamp<long>(std::lround(seconds / sample_s), 0, 65535));
}

v2::HeaterConfigFrame config_frame(const HeaterConfig& h, uint8_t channel) {
  v2::HeaterConfigFrame f;
  f.channel = channel;
  f.mode = static_cast<uint8_t>(h.mode);
  const double umax = h.supply_v;  // duty 1 = the supply voltage
  const double ts = h.sample_s;
  f.kp = q24(h.kp_v_per_c / umax);
  f.ki = h.ti_s > 0.0 ? q24(h.kp_v_per_c * ts / (h.ti_s * umax)) : 0;
  f.kd = q24(h.kp_v_per_c * h.td_s / (ts * umax));
  f.duty_max = q15(h.u_max_v / h.supply_v);
  f.hysteresis_q4 = uq4(h.hysteresis_c);
  f.manual = q15(h.manual_v / h.supply_v);
  return f;
}

v2::HeaterSafetyFrame safety_frame(const HeaterConfig& h, uint8_t channel) {
  v2::HeaterSafetyFrame f;
  f.channel = channel;
  f.tmin_q4 = to_q4(h.min_temp_c);
  f.tmax_q4 = to_q4(h.max_temp_c);
  f.runaway_band_q4 = uq4(h.runaway_band_c);
  f.runaway_ticks = ticks(h.runaway_period_s, h.sample_s);
  f.watch_rise_q4 = uq4(h.watch_rise_c);
  f.watch_ticks = ticks(h.watch_period_s, h.sample_s);
  return f;
}

std::vector<int16_t> thermistor_table(const HeaterConfig& h) {
  const auto curve = make_curve(h.thermistor);
  std::vector<int16_t> t;
  for (size_t i = 0; i < v2::kThermistorEntries; ++i) {
    const double temp = temp_of_code(h.thermistor, curve, 64.0 * static_cast<double>(i));
    t.push_back(to_q4(std::clamp(std::isfinite(temp) ? temp : -100.0, -100.0, 500.0)));
  }
  return t;
}

HeaterJob make_heater_job(const plan::Plan& plan, const config::MachineConfig& cfg) {
  HeaterJob hj;
  hj.config = cfg.heaters;
  hj.source = plan.source;
  for (const auto& item : plan.items) {
    const auto* hp = std::get_if<plan::HeaterCommand>(&item);
    if (!hp) continue;
    const auto& h = *hp;
    HeaterAction a;
    a.mcode = h.mcode;
    a.source_line = h.source_line;
    a.channel = (h.mcode == 104 || h.mcode == 109) ? kHotend : kBed;
    a.wait = h.mcode == 109 || h.mcode == 190;
    const auto& hc = cfg.heaters.ch[a.channel];
    const std::string key = fmt::format("heater.{}", kChannelNames[a.channel]);
    if (!hc.enabled) {
      throw gcode::Error(plan.source, h.source_line, mword_column(plan.source, h.source_line),
                         fmt::format("M{}: the {} heater is disabled in the machine configuration "
                                     "({}.enabled = false)",
                                     h.mcode, kChannelNames[a.channel], key));
    }
    if (!h.has_s) {
      throw gcode::Error(plan.source, h.source_line, mword_column(plan.source, h.source_line),
                         fmt::format("M{} needs an S word (target temperature in degC)", h.mcode));
    }
    if (h.s > hc.max_temp_c || (h.s > 0.0 && h.s < hc.min_temp_c)) {
      throw gcode::Error(
          plan.source, h.source_line, word_column(plan.source, h.source_line, 'S'),
          fmt::format(
              "M{} S{:g}: target outside the {} heater's range {:g}..{:g} degC ({}.min_temp_c, "
              "{}.max_temp_c; S0 switches it off)",
              h.mcode, h.s, kChannelNames[a.channel], hc.min_temp_c, hc.max_temp_c, key, key));
    }
    a.target_c = h.s;
    a.target_q4 = to_q4(h.s);
    hj.used[a.channel] = true;
    hj.actions.push_back(a);
  }
  for (uint8_t c = 0; c < kChannels; ++c) {
    if (!hj.used[c]) continue;
    const auto& hc = cfg.heaters.ch[c];
    hj.setup.push_back(v2::heater_config(0, config_frame(hc, c)));
    hj.setup.push_back(v2::heater_safety(0, safety_frame(hc, c)));
    const auto table = thermistor_table(hc);
    for (size_t i = 0; i < table.size(); i += v2::kThermistorChunk) {
      v2::ThermistorChunk ch;
      ch.channel = c;
      ch.first = static_cast<uint8_t>(i);
      ch.entries.assign(table.begin() + static_cast<std::ptrdiff_t>(i),
                        table.begin() + static_cast<std::ptrdiff_t>(
                                            std::min(table.size(), i + v2::kThermistorChunk)));
      hj.setup.push_back(v2::thermistor_table(0, ch));
    }
  }
  if (hj.any()) {
    const double ts = std::min(cfg.heaters.hotend().sample_s, cfg.heaters.bed().sample_s);
    hj.setup.push_back(v2::heater_watchdog(0, ticks(cfg.heaters.watchdog_s, ts)));
  }
  return hj;
}

std::string format_heaters(const v2::Status& s) {
  std::string out;
  for (size_t c = 0; c < s.heaters.size() && c < kChannels; ++c) {
    const auto& h = s.heaters[c];
    if (!out.empty()) out += "  ";
    if (h.enabled() || h.setpoint_q4 > 0) {
      out += fmt::format("{} {:.1f}/{:.0f}C {:.0f}%", kChannelNames[c], h.temp_c(), h.setpoint_c(),
                         h.duty() * 100.0);
    } else if (h.temp_q4 == INT16_MIN) {  // 0x8000: no thermistor table loaded
      out += fmt::format("{} off (no table)", kChannelNames[c]);
    } else {
      out += fmt::format("{} {:.1f}C off", kChannelNames[c], h.temp_c());
    }
    if (h.faults) out += " FAULT " + v2::heater_fault_names(h.faults);
  }
  return out;
}

std::string describe_faults(const protocol::v2::Status& stt, uint8_t bad) {
  namespace v2 = protocol::v2;
  std::string what;
  auto add = [&what](const std::string& x) { what += (what.empty() ? "" : "; ") + x; };
  for (size_t c = 0; c < stt.heaters.size() && c < kChannels; ++c) {
    const auto& h = stt.heaters[c];
    if (!h.faults) continue;
    std::string hint;
    if (h.faults & v2::kHeaterMinTemp) hint += ", below min_temp_c: sensor open or unplugged?";
    if (h.faults & v2::kHeaterMaxTemp) hint += ", above max_temp_c: overheating or sensor short?";
    if (h.faults & v2::kHeaterRunaway)
      hint += ", left the setpoint while holding (thermal runaway)";
    if (h.faults & v2::kHeaterHeating)
      hint += ", did not rise after the setpoint increase: heater disconnected?";
    add(fmt::format("{} heater fault {} at {:.1f} degC (setpoint {:.1f}){}", kChannelNames[c],
                    v2::heater_fault_names(h.faults), h.temp_c(), h.setpoint_c(), hint));
  }
  if ((bad & (v2::kFaultHotend | v2::kFaultBed)) && what.empty()) {
    add(fmt::format("heater fault bits 0x{:02X}", bad & (v2::kFaultHotend | v2::kFaultBed)));
  }
  if (bad & v2::kFaultWatchdog) add("heater watchdog: the device heard no frame for too long");
  if (bad & v2::kFaultEstop) add("e-stop: motion stopped, FIFO flushed, heaters off");
  if (bad & v2::kFaultLimit) {
    add("hard limit: motion stopped, FIFO flushed, laser and outputs off (" +
        v2::describe_limits(stt, stt.position.size()) + ")");
  }
  return what;
}

}  // namespace fpgacnc::heat
