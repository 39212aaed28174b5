#include "fpgacnc/grbl/settings.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "fpgacnc/error.h"

namespace fpgacnc::grbl {
namespace {

// Settings grbl prints without decimals (masks, booleans, milliseconds, RPM).
const std::set<int> kIntegers{1, 2, 3, 4, 5, 6, 10, 13, 20, 21, 22, 23, 26, 30, 31, 32};

double us_of(uint32_t clocks, uint64_t clk_hz) {
  return static_cast<double>(clocks) * 1e6 / static_cast<double>(clk_hz);
}

}  // namespace

Settings settings_from_config(const config::MachineConfig& cfg) {
  Settings s;
  auto& v = s.values;
  v[0] = us_of(cfg.step_timing.step_high, cfg.clk_hz);  // step pulse, us
  v[1] = 25;                                            // step idle delay, ms (no enable pin)
  for (int n : {2, 3, 4, 5, 6}) v[n] = 0;               // pin inversions (no such pins)
  v[10] = 1;                                            // status report: MPos
  v[11] = cfg.junction_deviation_mm;
  v[12] = cfg.arc_tolerance_mm;
  v[13] = 0;  // report in mm
  v[21] = 0;
  v[22] = cfg.homing.enabled ? 1 : 0;
  v[23] = cfg.homing.dir_invert_mask;
  // Soft limits: on when the configuration gives a travel for X, Y or Z ([travel]).
  v[20] = cfg.travel[config::kX].enabled || cfg.travel[config::kY].enabled ||
                  cfg.travel[config::kZ].enabled
              ? 1
              : 0;
  v[24] = cfg.homing.locate_feed_mm_min;
  v[25] = cfg.homing.seek_feed_mm_min;
  v[26] = cfg.homing.debounce_ms;
  v[27] = cfg.homing.pulloff_mm;
  v[30] = cfg.laser_s_max;
  v[31] = cfg.laser_s_min;
  v[32] = 1;  // laser mode: S changes never stop the motion (LINE_PROFILE carries the power)
  for (int a = 0; a < 3; ++a) {
    v[100 + a] = cfg.steps_per_mm[static_cast<size_t>(a)];
    v[110 + a] = cfg.max_feed_mm_min[static_cast<size_t>(a)];
    v[120 + a] = cfg.max_accel_mm_s2[static_cast<size_t>(a)];
    const config::Travel& t = cfg.travel[static_cast<size_t>(a)];
    const double h = cfg.homing.max_travel_mm[static_cast<size_t>(a)];
    v[130 + a] = h > 0.0 ? h : t.enabled ? t.max_mm - t.min_mm : 200.0;  // grbl's default 200 mm
  }
  return s;
}

config::MachineConfig apply_settings(const config::MachineConfig& base, const Settings& s) {
  config::MachineConfig cfg = base;
  auto get = [&](int n) { return s.values.at(n); };
  const double clocks = std::round(get(0) * static_cast<double>(cfg.clk_hz) / 1e6);
  cfg.step_timing.step_high = cfg.step_timing.step_low =
      static_cast<uint32_t>(std::clamp(clocks, 1.0, 65535.0));
  cfg.junction_deviation_mm = get(11);
  cfg.arc_tolerance_mm = get(12);
  if (get(30) > 0) cfg.laser_s_max = get(30);
  // $31 below $30 (else the map from S to the power byte would be empty: the last good one stays)
  if (get(31) >= 0 && get(31) < cfg.laser_s_max) cfg.laser_s_min = get(31);
  double rapid = 0.0;
  for (int a = 0; a < 3; ++a) {
    const auto i = static_cast<size_t>(a);
    cfg.steps_per_mm[i] = get(100 + a);
    cfg.max_feed_mm_min[i] = get(110 + a);
    cfg.max_accel_mm_s2[i] = get(120 + a);
    rapid = std::max(rapid, get(110 + a));
  }
  cfg.homing.enabled = get(22) != 0.0;
  cfg.homing.dir_invert_mask = static_cast<uint32_t>(get(23)) & 7u;
  cfg.homing.locate_feed_mm_min = get(24);
  cfg.homing.seek_feed_mm_min = get(25);
  cfg.homing.debounce_ms = get(26);
  cfg.homing.pulloff_mm = get(27);
  for (size_t a = 0; a < 3; ++a) cfg.homing.max_travel_mm[a] = get(130 + static_cast<int>(a));
  // G0 runs at each axis's maximum rate (grbl): the planner limits every axis to its own.
  cfg.rapid_feed_mm_min = rapid;
  // $20 on: an axis the configuration gives a travel travels $130-$132 mm from its min; when
  // the configuration gives none on X, Y, Z, each gets grbl's own [-$13x, 0]. Off: none on X, Y, Z.
  const bool configured = base.travel[config::kX].enabled || base.travel[config::kY].enabled ||
                          base.travel[config::kZ].enabled;
  for (int a = 0; a < 3; ++a) {
    config::Travel& t = cfg.travel[static_cast<size_t>(a)];
    if (get(20) == 0) {
      t.enabled = false;
    } else if (t.enabled) {
      t.max_mm = t.min_mm + get(130 + a);
    } else if (!configured) {
      t = {true, -get(130 + a), 0.0};
    }
  }
  return cfg;
}

int set_value(Settings& s, int number, double value, bool hard_limits) {
  auto it = s.values.find(number);
  if (it == s.values.end()) return 3;
  if (!std::isfinite(value)) return 2;
  if (value < 0.0) return 4;
  if (kIntegers.count(number)) value = std::trunc(value);
  switch (number) {
    case 20:  // a flag in grbl: any non-zero value is on
      value = value != 0.0 ? 1.0 : 0.0;
      break;
    case 21:  // hard limits: only where the board has limit switches
      if (value != 0.0 && !hard_limits) return 3;
      break;
    case 22:  // homing: only where the board has limit switches
      if (value != 0.0 && !hard_limits) return 3;
      value = value != 0.0 ? 1.0 : 0.0;
      break;
    case 24:
    case 25:
    case 27:
    case 130:
    case 131:
    case 132:
      if (value == 0.0) return 4;  // feeds and distances of the homing cycle
      break;
    case 0:
    case 11:
    case 12:
    case 100:
    case 101:
    case 102:
    case 110:
    case 111:
    case 112:
    case 120:
    case 121:
    case 122:
      if (value == 0.0) return 4;  // a value the planner divides by
      break;
    default:
      break;
  }
  it->second = value;
  return 0;
}

std::string format_settings(const Settings& s) {
  std::string out;
  for (const auto& [n, v] : s.values) {
    if (kIntegers.count(n) || (n == 0 && v == std::trunc(v))) {
      out += fmt::format("${}={}\n", n, static_cast<long long>(v));
    } else {
      out += fmt::format("${}={:.3f}\n", n, v);
    }
  }
  return out;
}

std::optional<Settings> load_settings(const std::string& path, const Settings& defaults) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  Settings s = defaults;
  std::string line;
  int ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    auto bad = [&](const std::string& why) { throw SourceError(path, ln, 1, why); };
    if (line[0] != '$') bad("expected '$N=value', '$N0=line', '$N1=line' or '$I=text'");
    const auto eq = line.find('=');
    if (eq == std::string::npos) bad("missing '='");
    const std::string key = line.substr(1, eq - 1);
    const std::string val = line.substr(eq + 1);
    if (key == "N0" || key == "N1") {
      s.startup[key == "N0" ? 0 : 1] = val;
    } else if (key == "I") {
      s.info = val;
    } else {
      char* end = nullptr;
      const long n = std::strtol(key.c_str(), &end, 10);
      if (key.empty() || *end) bad(fmt::format("'{}' is not a setting number", key));
      errno = 0;
      const double d = std::strtod(val.c_str(), &end);
      if (val.empty() || *end || errno) bad(fmt::format("'{}' is not a number", val));
      // $21=1 is kept as stored; the engine lowers it where the board has no switches.
      const int rc = set_value(s, static_cast<int>(n), d, true);
      if (rc) bad(fmt::format("${}={}: refused (grbl error:{})", n, val, rc));
    }
  }
  return s;
}

void save_settings(const std::string& path, const Settings& s) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write the settings file", tmp));
    out << "# fpgacnc grbl settings (docs/grbl.md); written by $N=value, $N0=, $N1=, $I=, $RST=\n";
    out << format_settings(s);
    out << "$N0=" << s.startup[0] << "\n$N1=" << s.startup[1] << "\n$I=" << s.info << "\n";
    if (!out) throw std::runtime_error(fmt::format("{}: write failed", tmp));
  }
  std::filesystem::rename(tmp, p);
}

std::string default_settings_path() {
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x)
    return std::string(x) + "/fpgacnc/grbl-settings.txt";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.config/fpgacnc/grbl-settings.txt";
}

}  // namespace fpgacnc::grbl
