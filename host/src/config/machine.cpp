#include "fpgacnc/config/machine.h"

#include "fpgacnc/gcode/dialect.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <toml.hpp>

#include "../heat/heater_toml.h"

namespace fpgacnc::config {
namespace {

class Reader {
 public:
  Reader(std::string name) : name_(std::move(name)) {}

  [[noreturn]] void fail(const toml::value& v, const std::string& key, const std::string& msg) {
    const auto loc = v.location();
    throw Error(name_, static_cast<int>(loc.line()), static_cast<int>(loc.column()),
                fmt::format("key '{}': {}", key, msg));
  }

  double number(const toml::value& v, const std::string& key) {
    if (v.is_integer()) return static_cast<double>(v.as_integer());
    if (v.is_floating()) return v.as_floating();
    fail(v, key, "expected a number");
  }
  uint64_t unsigned_int(const toml::value& v, const std::string& key, uint64_t max) {
    if (!v.is_integer()) fail(v, key, "expected an integer");
    const auto i = v.as_integer();
    if (i < 0 || static_cast<uint64_t>(i) > max) fail(v, key, "out of range");
    return static_cast<uint64_t>(i);
  }
  std::string string(const toml::value& v, const std::string& key) {
    if (!v.is_string()) fail(v, key, "expected a string");
    return v.as_string().str;
  }
  bool boolean(const toml::value& v, const std::string& key) {
    if (!v.is_boolean()) fail(v, key, "expected true or false");
    return v.as_boolean();
  }
  void axes(const toml::value& v, const std::string& key, std::array<double, kAxes>& out) {
    if (!v.is_table()) fail(v, key, "expected a table with keys x, y, z, e (or a)");
    bool fourth = false;
    for (const auto& [k, sub] : v.as_table()) {
      const std::string full = key + "." + k;
      int a = -1;
      if (k == "x") a = kX;
      if (k == "y") a = kY;
      if (k == "z") a = kZ;
      if (k == "e" || k == "a") {  // the fourth channel, named after the axis it drives
        if (fourth) fail(sub, full, "e and a are the same (fourth) axis: give one of them");
        fourth = true;
        a = kE;
      }
      if (a < 0) fail(sub, full, "unknown key (expected x, y, z, e or a)");
      const double d = number(sub, full);
      if (!(d > 0.0)) fail(sub, full, "must be > 0");
      out[static_cast<size_t>(a)] = d;
    }
  }

  // [homing]: grbl's $22..$27 and the cycles (docs/machine.md "Homing and probing (host)").
  void homing(const toml::value& v, const std::string& key, Homing& h) {
    if (!v.is_table()) fail(v, key, "expected a table");
    for (const auto& [k, sub] : v.as_table()) {
      const std::string full = key + "." + k;
      auto feed = [&]() {
        const double x = number(sub, full);
        if (!(x > 0.0)) fail(sub, full, "must be > 0");
        return x;
      };
      if (k == "enabled") {
        h.enabled = boolean(sub, full);
      } else if (k == "dir_invert_mask") {
        h.dir_invert_mask = static_cast<uint32_t>(unsigned_int(sub, full, 7));
      } else if (k == "locate_feed_mm_min") {
        h.locate_feed_mm_min = feed();
      } else if (k == "seek_feed_mm_min") {
        h.seek_feed_mm_min = feed();
      } else if (k == "debounce_ms") {
        h.debounce_ms = number(sub, full);
        if (!(h.debounce_ms >= 0.0)) fail(sub, full, "must be >= 0");
      } else if (k == "pulloff_mm") {
        h.pulloff_mm = feed();
      } else if (k == "cycles") {
        // ["Z", "XY"]: the axes homed together, in order.
        if (!sub.is_array()) fail(sub, full, "expected an array of axis strings (\"Z\", \"XY\")");
        h.cycles.clear();
        for (const auto& e : sub.as_array()) {
          uint32_t m = 0;
          for (const char ch : string(e, full)) {
            const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
            if (u != 'X' && u != 'Y' && u != 'Z') fail(e, full, "axes are X, Y and Z");
            m |= 1u << (u - 'X');
          }
          if (m == 0) fail(e, full, "an empty cycle");
          h.cycles.push_back(m);
        }
      } else if (k == "max_travel_mm") {
        std::array<double, kAxes> t{};
        axes(sub, full, t);
        for (size_t a = 0; a < 3; ++a) {
          if (t[a] < 0.0) fail(sub, full, "must be >= 0");
          h.max_travel_mm[a] = t[a];
        }
      } else {
        fail(sub, full, "unknown key");
      }
    }
  }

  // [travel]: x = { min = A, max = B } per axis (soft limits).
  void travel(const toml::value& v, const std::string& key, std::array<Travel, kAxes>& out) {
    if (!v.is_table()) fail(v, key, "expected a table with keys x, y, z, e (or a)");
    bool fourth = false;
    for (const auto& [k, sub] : v.as_table()) {
      const std::string full = key + "." + k;
      int a = -1;
      if (k == "x") a = kX;
      if (k == "y") a = kY;
      if (k == "z") a = kZ;
      if (k == "e" || k == "a") {
        if (fourth) fail(sub, full, "e and a are the same (fourth) axis: give one of them");
        fourth = true;
        a = kE;
      }
      if (a < 0) fail(sub, full, "unknown key (expected x, y, z, e or a)");
      if (!sub.is_table()) fail(sub, full, "expected { min = MM, max = MM }");
      Travel t;
      bool has_min = false, has_max = false;
      for (const auto& [tk, tv] : sub.as_table()) {
        const std::string tfull = full + "." + tk;
        const double d = number(tv, tfull);
        if (!std::isfinite(d) || std::fabs(d) > 1e6) fail(tv, tfull, "must be within +-1e6");
        if (tk == "min") {
          t.min_mm = d;
          has_min = true;
        } else if (tk == "max") {
          t.max_mm = d;
          has_max = true;
        } else {
          fail(tv, tfull, "unknown key (expected min and max)");
        }
      }
      if (!has_min || !has_max) fail(sub, full, "give both min and max");
      if (!(t.min_mm < t.max_mm)) fail(sub, full, "min must be below max");
      t.enabled = true;
      out[static_cast<size_t>(a)] = t;
    }
  }

  MachineConfig read(const toml::value& root) {
    MachineConfig c;
    for (const auto& [k, v] : root.as_table()) {
      if (k == "steps_per_mm") {
        axes(v, k, c.steps_per_mm);
      } else if (k == "max_feed_mm_min") {
        axes(v, k, c.max_feed_mm_min);
      } else if (k == "clk_hz") {
        c.clk_hz = unsigned_int(v, k, 1'000'000'000'000ULL);
        if (c.clk_hz == 0) fail(v, k, "must be > 0");
      } else if (k == "baud") {
        c.baud = static_cast<uint32_t>(unsigned_int(v, k, 100'000'000));
        if (c.baud == 0) fail(v, k, "must be > 0");
      } else if (k == "port") {
        c.port = string(v, k);
      } else if (k == "protocol") {
        c.protocol = string(v, k);
        if (!valid_protocol_name(c.protocol)) fail(v, k, "expected \"auto\", \"v1\" or \"v2\"");
      } else if (k == "rapid_feed_mm_min") {
        c.rapid_feed_mm_min = positive(v, k);
      } else if (k == "default_feed_mm_min") {
        c.default_feed_mm_min = positive(v, k);
      } else if (k == "arc_tolerance_mm") {
        c.arc_tolerance_mm = positive(v, k);
      } else if (k == "ack_timeout_s") {
        c.ack_timeout_s = positive(v, k);
      } else if (k == "retransmit_timeout_s") {
        c.retransmit_timeout_s = positive(v, k);
      } else if (k == "laser_s_max") {
        c.laser_s_max = positive(v, k);
      } else if (k == "laser_s_min") {
        c.laser_s_min = number(v, k);
      } else if (k == "feed_override") {
        c.feed_override_pct = positive(v, k);
      } else if (k == "dwell_time") {
        c.dwell_time_pct = positive(v, k);
      } else if (k == "hold_decel_mm_s2") {
        c.hold_decel_mm_s2 = positive(v, k);
      } else if (k == "max_accel_mm_s2") {
        axes(v, k, c.max_accel_mm_s2);
      } else if (k == "junction_deviation_mm") {
        c.junction_deviation_mm = number(v, k);
        if (!(c.junction_deviation_mm >= 0.0) || c.junction_deviation_mm > 1e3) {
          fail(v, k, "must be >= 0 and <= 1000");
        }
      } else if (k == "lookahead_segments") {
        c.lookahead_segments = static_cast<uint32_t>(unsigned_int(v, k, 1'000'000));
        if (c.lookahead_segments == 0) fail(v, k, "must be >= 1");
      } else if (k == "motion") {
        c.motion = string(v, k);
        if (!valid_motion_name(c.motion)) fail(v, k, "expected \"profile\" or \"constant\"");
      } else if (k == "fourth_axis") {
        const std::string n = string(v, k);
        if (n != "E" && n != "A") fail(v, k, "expected \"E\" (extruder) or \"A\" (rotary)");
        c.fourth_axis = n[0];
      } else if (k == "native_arcs") {
        c.native_arcs = boolean(v, k);
      } else if (k == "laser_requires_m3") {
        c.laser_requires_m3 = boolean(v, k);
      } else if (k == "step_timing") {
        if (!v.is_table()) fail(v, k, "expected a table");
        for (const auto& [tk, tv] : v.as_table()) {
          const std::string full = k + "." + tk;
          const auto clocks = static_cast<uint32_t>(unsigned_int(tv, full, 0xFFFFFFFFu));
          if (tk == "step_high") {
            c.step_timing.step_high = clocks;
          } else if (tk == "step_low") {
            c.step_timing.step_low = clocks;
          } else if (tk == "dir_setup") {
            c.step_timing.dir_setup = clocks;
          } else if (tk == "dir_hold") {
            c.step_timing.dir_hold = clocks;
          } else {
            fail(tv, full, "unknown key");
          }
          if (clocks == 0) fail(tv, full, "must be >= 1 clock");
        }
      } else if (k == "travel") {
        travel(v, k, c.travel);
      } else if (k == "gcode") {
        if (!v.is_table()) fail(v, k, "expected a table");
        for (const auto& [gk, gv] : v.as_table()) {
          const std::string full = k + "." + gk;
          if (gk == "dialect") {
            c.gcode.dialect = string(gv, full);
            if (c.gcode.dialect != "auto" && !gcode::parse_dialect(c.gcode.dialect))
              fail(gv, full, "expected \"auto\", \"grbl\", \"linuxcnc\", \"marlin\" or \"reprap\"");
          } else if (gk == "tool_table") {
            c.gcode.tool_table = string(gv, full);
          } else if (gk == "tool_change") {
            const std::string t = string(gv, full);
            if (t != "pause" && t != "ignore") fail(gv, full, "expected \"pause\" or \"ignore\"");
            c.gcode.tool_change_pause = t == "pause";
          } else if (gk == "optional_stop") {
            c.gcode.optional_stop = boolean(gv, full);
          } else if (gk == "block_delete") {
            c.gcode.block_delete = boolean(gv, full);
          } else {
            fail(gv, full, "unknown key");
          }
        }
      } else if (k == "homing") {
        homing(v, k, c.homing);
      } else if (k == "heater") {  // host/src/heat/heater_config.cpp
        heat::read_heater_toml(v, c.heaters, name_);
      } else {
        fail(v, k, "unknown key");
      }
    }
    return c;
  }

 private:
  double positive(const toml::value& v, const std::string& key) {
    const double d = number(v, key);
    if (!(d > 0.0) || d > 1e9) fail(v, key, "must be > 0");
    return d;
  }
  std::string name_;
};

MachineConfig parse_stream(std::istream& in, const std::string& name) {
  toml::value root;
  try {
    root = toml::parse(in, name);
  } catch (const std::exception& e) {
    throw Error(name, 0, 0, fmt::format("TOML syntax: {}", e.what()));
  }
  MachineConfig c = Reader(name).read(root);
  validate(c, name);
  return c;
}

}  // namespace

bool valid_protocol_name(const std::string& name) {
  return name == "auto" || name == "v1" || name == "v2";
}

bool valid_motion_name(const std::string& name) {
  return name == "profile" || name == "constant";
}

MachineConfig load_machine_config(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, 0, 0, "cannot open configuration file");
  MachineConfig c = parse_stream(f, path);
  // Files the configuration names are relative to the configuration's folder.
  if (!c.gcode.tool_table.empty() && std::filesystem::path(c.gcode.tool_table).is_relative())
    c.gcode.tool_table = (std::filesystem::path(path).parent_path() / c.gcode.tool_table)
                             .lexically_normal()
                             .string();
  return c;
}

MachineConfig parse_machine_config(const std::string& text, const std::string& name) {
  std::istringstream s(text);
  return parse_stream(s, name);
}

void validate(const MachineConfig& c, const std::string& name) {
  for (int a = 0; a < kAxes; ++a) {
    if (!(c.steps_per_mm[static_cast<size_t>(a)] > 0.0)) {
      throw Error(name, 0, 0,
                  fmt::format("steps_per_mm.{} must be > 0", kAxisNames[static_cast<size_t>(a)]));
    }
  }
  if (!valid_protocol_name(c.protocol)) {
    throw Error(name, 0, 0, "protocol: expected \"auto\", \"v1\" or \"v2\"");
  }
  if (!(c.laser_s_max > 0.0)) throw Error(name, 0, 0, "laser_s_max must be > 0");
  if (!(c.laser_s_min >= 0.0 && c.laser_s_min < c.laser_s_max))
    throw Error(name, 0, 0, "laser_s_min must be >= 0 and below laser_s_max");
  if (!(c.retransmit_timeout_s > 0.0)) throw Error(name, 0, 0, "retransmit_timeout_s must be > 0");
  if (c.clk_hz == 0 || c.baud == 0) throw Error(name, 0, 0, "clk_hz and baud must be > 0");
  if (!(c.feed_override_pct > 0.0)) throw Error(name, 0, 0, "feed_override must be > 0");
  for (int a = 0; a < kAxes; ++a) {
    if (!(c.max_accel_mm_s2[static_cast<size_t>(a)] > 0.0)) {
      throw Error(
          name, 0, 0,
          fmt::format("max_accel_mm_s2.{} must be > 0", kAxisNames[static_cast<size_t>(a)]));
    }
  }
  if (!(c.hold_decel_mm_s2 >= 0.0)) throw Error(name, 0, 0, "hold_decel_mm_s2 must be > 0");
  if (!(c.junction_deviation_mm >= 0.0)) {
    throw Error(name, 0, 0, "junction_deviation_mm must be >= 0");
  }
  if (c.lookahead_segments == 0) throw Error(name, 0, 0, "lookahead_segments must be >= 1");
  if (!valid_motion_name(c.motion)) {
    throw Error(name, 0, 0, "motion: expected \"profile\" or \"constant\"");
  }
  for (int a = 0; a < kAxes; ++a) {
    const Travel& t = c.travel[static_cast<size_t>(a)];
    if (t.enabled && !(t.min_mm < t.max_mm)) {
      throw Error(name, 0, 0,
                  fmt::format("travel.{}: min must be below max",
                              static_cast<char>(std::tolower(kAxisNames[static_cast<size_t>(a)]))));
    }
  }
}

}  // namespace fpgacnc::config
