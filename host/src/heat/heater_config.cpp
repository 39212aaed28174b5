#include "fpgacnc/heat/heater_config.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "fpgacnc/config/machine.h"
#include "heater_toml.h"

namespace fpgacnc::heat {

namespace {
constexpr double kKelvin = 273.15;
}

const char* mode_name(Mode m) {
  switch (m) {
    case Mode::kOff:
      return "off";
    case Mode::kManual:
      return "manual";
    case Mode::kOnOff:
      return "onoff";
    case Mode::kP:
      return "p";
    case Mode::kPid:
      return "pid";
  }
  return "?";
}

bool parse_mode(const std::string& s, Mode& out) {
  for (Mode m : {Mode::kOff, Mode::kManual, Mode::kOnOff, Mode::kP, Mode::kPid}) {
    if (s == mode_name(m)) {
      out = m;
      return true;
    }
  }
  return false;
}

HeaterConfig default_bed() {
  HeaterConfig h;  // the struct defaults are the reference bed
  return h;
}

HeaterConfig default_hotend() {
  HeaterConfig h;
  // The reference relay rule on the hot-end model of models/include/fpgacnc/models/thermal_plant.h
  // (relay 0/24 V at 200 degC: Pu 12.5 s, a 2.95 degC, Ku 5.17 V/degC): 20 -> 200 degC with 0.4
  // degC overshoot.
  h.kp_v_per_c = 3.1;
  h.ti_s = 6.2;
  h.td_s = 1.5;
  h.max_temp_c = 275.0;
  h.watch_rise_c = 2.0;
  h.watch_period_s = 20.0;
  h.wait_tolerance_c = 2.0;
  h.wait_settle_s = 5.0;
  h.wait_timeout_s = 600.0;
  return h;
}

HeaterSet::HeaterSet() {
  ch[kHotend] = default_hotend();
  ch[kBed] = default_bed();
}

std::string check_heater(const HeaterConfig& h, const std::string& key) {
  auto bad = [&](const char* k, const char* rule) { return fmt::format("{}.{} {}", key, k, rule); };
  if (!(h.kp_v_per_c >= 0.0)) return bad("kp", "must be >= 0");
  if (!(h.ti_s >= 0.0)) return bad("ti_s", "must be >= 0 (0: no integral term)");
  if (!(h.td_s >= 0.0)) return bad("td_s", "must be >= 0");
  if (!(h.supply_v > 0.0)) return bad("supply_v", "must be > 0");
  if (!(h.u_max_v > 0.0) || h.u_max_v > h.supply_v)
    return bad("u_max_v", "must be in (0, supply_v]");
  if (!(h.manual_v >= 0.0) || h.manual_v > h.u_max_v)
    return bad("manual_v", "must be in [0, u_max_v]");
  if (!(h.hysteresis_c >= 0.0)) return bad("hysteresis_c", "must be >= 0");
  if (!(h.sample_s > 0.0)) return bad("sample_s", "must be > 0");
  if (!(h.max_temp_c > h.min_temp_c)) return bad("max_temp_c", "must be above min_temp_c");
  if (!(h.runaway_band_c > 0.0)) return bad("runaway_band_c", "must be > 0");
  if (!(h.runaway_period_s > 0.0)) return bad("runaway_period_s", "must be > 0");
  if (!(h.watch_rise_c >= 0.0)) return bad("watch_rise_c", "must be >= 0");
  if (!(h.watch_period_s > 0.0)) return bad("watch_period_s", "must be > 0");
  if (!(h.wait_tolerance_c > 0.0)) return bad("wait_tolerance_c", "must be > 0");
  if (!(h.wait_settle_s >= 0.0)) return bad("wait_settle_s", "must be >= 0");
  if (!(h.wait_timeout_s > 0.0)) return bad("wait_timeout_s", "must be > 0");
  const auto& t = h.thermistor;
  if (t.source != "beta" && t.source != "file")
    return bad("thermistor.source", "must be \"beta\" or \"file\"");
  if (t.source == "file" && t.file.empty()) return bad("thermistor.file", "must name a CSV file");
  if (!(t.beta > 0.0) || !(t.r25_ohm > 0.0) || !(t.pullup_ohm > 0.0) || !(t.supply_v > 0.0) ||
      !(t.adc_vref_v > 0.0))
    return bad("thermistor", "beta, r25_ohm, pullup_ohm, supply_v, adc_vref_v must be > 0");
  return "";
}

double ThermistorCurve::resistance(double temp_c) const {
  if (!table) return r25 * std::exp(beta * (1.0 / (temp_c + kKelvin) - 1.0 / (25.0 + kKelvin)));
  // log(R) linear in temperature between points; extrapolated from the end segments.
  size_t i = 1;
  while (i + 1 < points.size() && points[i].first < temp_c) ++i;
  const auto& [t0, r0] = points[i - 1];
  const auto& [t1, r1] = points[i];
  const double f = (temp_c - t0) / (t1 - t0);
  return std::exp(std::log(r0) + f * (std::log(r1) - std::log(r0)));
}

double ThermistorCurve::temperature(double ohm) const {
  if (!table) return 1.0 / (1.0 / (25.0 + kKelvin) + std::log(ohm / r25) / beta) - kKelvin;
  // R falls with temperature (NTC).
  size_t i = 1;
  while (i + 1 < points.size() && points[i].second > ohm) ++i;
  const auto& [t0, r0] = points[i - 1];
  const auto& [t1, r1] = points[i];
  const double f = (std::log(ohm) - std::log(r0)) / (std::log(r1) - std::log(r0));
  return t0 + f * (t1 - t0);
}

ThermistorCurve make_curve(const ThermistorConfig& t) {
  ThermistorCurve c;
  c.beta = t.beta;
  c.r25 = t.r25_ohm;
  if (t.source != "file") return c;
  std::ifstream in(t.file);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open thermistor table", t.file));
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    double tc = 0, r = 0;
    if (!(ss >> tc >> r)) {
      if (c.points.empty() && n == 1) continue;  // header
      throw std::runtime_error(
          fmt::format("{}:{}: expected \"temperature_c,resistance_ohm\"", t.file, n));
    }
    if (!(r > 0.0) ||
        (!c.points.empty() && !(tc > c.points.back().first && r < c.points.back().second)))
      throw std::runtime_error(fmt::format(
          "{}:{}: rows must have rising temperature and falling resistance (NTC)", t.file, n));
    c.points.emplace_back(tc, r);
  }
  if (c.points.size() < 2)
    throw std::runtime_error(fmt::format("{}: a thermistor table needs at least 2 rows", t.file));
  c.table = true;
  return c;
}

double adc_code_of(const ThermistorConfig& t, const ThermistorCurve& c, double temp_c) {
  const double r = c.resistance(temp_c);
  const double v = t.supply_v * r / (r + t.pullup_ohm);
  return std::clamp(4096.0 * v / t.adc_vref_v, 0.0, 4095.0);
}

double temp_of_code(const ThermistorConfig& t, const ThermistorCurve& c, double code) {
  const double v = code / 4096.0 * t.adc_vref_v;
  if (v <= 0.0) return 1e9;              // short
  if (v >= t.supply_v) return -kKelvin;  // open
  const double r = t.pullup_ohm * v / (t.supply_v - v);
  return c.temperature(r);
}

// ---- TOML ----

namespace {

class HeaterReader {
 public:
  explicit HeaterReader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::value& v, const std::string& key, const std::string& msg) {
    const auto loc = v.location();
    throw config::Error(file_, static_cast<int>(loc.line()), static_cast<int>(loc.column()),
                        fmt::format("key '{}': {}", key, msg));
  }
  double number(const toml::value& v, const std::string& key) {
    if (v.is_integer()) return static_cast<double>(v.as_integer());
    if (v.is_floating()) return v.as_floating();
    fail(v, key, "expected a number");
  }
  std::string string(const toml::value& v, const std::string& key) {
    if (!v.is_string()) fail(v, key, "expected a string");
    return v.as_string().str;
  }

  void thermistor(const toml::value& v, const std::string& key, ThermistorConfig& t) {
    if (!v.is_table()) fail(v, key, "expected a table");
    for (const auto& [k, x] : v.as_table()) {
      const std::string full = key + "." + k;
      if (k == "source") {
        t.source = string(x, full);
        if (t.source != "beta" && t.source != "file")
          fail(x, full, "expected \"beta\" or \"file\"");
      } else if (k == "file") {
        t.file = string(x, full);
      } else if (k == "beta") {
        t.beta = number(x, full);
      } else if (k == "r25_ohm") {
        t.r25_ohm = number(x, full);
      } else if (k == "pullup_ohm") {
        t.pullup_ohm = number(x, full);
      } else if (k == "supply_v") {
        t.supply_v = number(x, full);
      } else if (k == "adc_vref_v") {
        t.adc_vref_v = number(x, full);
      } else {
        fail(x, full, "unknown key");
      }
    }
  }

  void channel(const toml::value& v, const std::string& key, HeaterConfig& h) {
    if (!v.is_table()) fail(v, key, "expected a table");
    for (const auto& [k, x] : v.as_table()) {
      const std::string full = key + "." + k;
      double* num = nullptr;
      if (k == "enabled") {
        if (!x.is_boolean()) fail(x, full, "expected true or false");
        h.enabled = x.as_boolean();
        continue;
      }
      if (k == "mode") {
        if (!parse_mode(string(x, full), h.mode))
          fail(x, full, "expected \"pid\", \"p\", \"onoff\", \"manual\" or \"off\"");
        continue;
      }
      if (k == "thermistor") {
        thermistor(x, full, h.thermistor);
        continue;
      }
      static const std::pair<const char*, double HeaterConfig::*> kNums[] = {
          {"kp", &HeaterConfig::kp_v_per_c},
          {"ti_s", &HeaterConfig::ti_s},
          {"td_s", &HeaterConfig::td_s},
          {"supply_v", &HeaterConfig::supply_v},
          {"u_max_v", &HeaterConfig::u_max_v},
          {"hysteresis_c", &HeaterConfig::hysteresis_c},
          {"manual_v", &HeaterConfig::manual_v},
          {"sample_s", &HeaterConfig::sample_s},
          {"min_temp_c", &HeaterConfig::min_temp_c},
          {"max_temp_c", &HeaterConfig::max_temp_c},
          {"runaway_band_c", &HeaterConfig::runaway_band_c},
          {"runaway_period_s", &HeaterConfig::runaway_period_s},
          {"watch_rise_c", &HeaterConfig::watch_rise_c},
          {"watch_period_s", &HeaterConfig::watch_period_s},
          {"wait_tolerance_c", &HeaterConfig::wait_tolerance_c},
          {"wait_settle_s", &HeaterConfig::wait_settle_s},
          {"wait_timeout_s", &HeaterConfig::wait_timeout_s},
      };
      for (const auto& [name, member] : kNums) {
        if (k == name) num = &(h.*member);
      }
      if (!num) fail(x, full, "unknown key");
      *num = number(x, full);
    }
    const std::string err = check_heater(h, key);
    if (!err.empty()) fail(v, key, err);
  }

  void read(const toml::value& v, HeaterSet& out) {
    if (!v.is_table()) fail(v, "heater", "expected a table ([heater.bed], [heater.hotend])");
    for (const auto& [k, x] : v.as_table()) {
      const std::string full = "heater." + k;
      if (k == "hotend") {
        channel(x, full, out.hotend());
      } else if (k == "bed") {
        channel(x, full, out.bed());
      } else if (k == "watchdog_s") {
        out.watchdog_s = number(x, full);
        if (!(out.watchdog_s >= 0.0)) fail(x, full, "must be >= 0 (0: off)");
      } else {
        fail(x, full, "unknown key (expected hotend, bed or watchdog_s)");
      }
    }
  }

 private:
  std::string file_;
};

}  // namespace

void read_heater_toml(const toml::value& heater, HeaterSet& out, const std::string& file) {
  HeaterReader(file).read(heater, out);
}

}  // namespace fpgacnc::heat
