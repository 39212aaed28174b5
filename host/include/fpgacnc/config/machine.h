// Machine configuration: loaded from a TOML file (see host/machine.example.toml).
// Defaults match the original laboratory machine (DE1-SoC at 50 MHz, 1/32 microstep GT2 belt,
// 20-tooth pulley: 160 steps/mm on X and Y; 400 steps/mm on a T8 lead-screw Z; 100 steps/mm on E).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/error.h"
#include "fpgacnc/heat/heater_config.h"

namespace fpgacnc::config {

enum Axis : int { kX = 0, kY = 1, kZ = 2, kE = 3 };
inline constexpr int kAxes = 4;
inline constexpr std::array<char, kAxes> kAxisNames{'X', 'Y', 'Z', 'E'};

struct StepTiming {  // in clocks of clk_hz
  uint32_t step_high = 100;
  uint32_t step_low = 100;
  uint32_t dir_setup = 200;
  uint32_t dir_hold = 200;
};

// Soft limits of one axis: its travel in machine coordinates (mm; degrees for an A axis). A move
// whose end (an arc: whose extent) leaves [min_mm, max_mm] is refused before anything is sent
// (docs/machine.md "Soft limits"). Off (enabled = false) unless the configuration gives it.
struct Travel {
  bool enabled = false;
  double min_mm = 0.0;
  double max_mm = 0.0;
};

// [homing]: the homing cycle (docs/machine.md "Homing and probing (host)"; grbl's $22..$27).
struct Homing {
  bool enabled = false;              // $22: `$H` allowed (and required at power-up in grbl)
  uint32_t dir_invert_mask = 0;      // $23: bit a set = axis a homes toward its min switch
  double locate_feed_mm_min = 25.0;  // $24
  double seek_feed_mm_min = 500.0;   // $25
  double debounce_ms = 250.0;        // $26: kept for senders; the FPGA filters the switches
  double pulloff_mm = 1.0;           // $27
  // The axes homed together, in order (grbl's HOMING_CYCLE_0, _1: Z, then X and Y); bit a =
  // axis a. Only axes with a switch on their homing side take part.
  std::vector<uint32_t> cycles{0b100, 0b011};
  // Each axis's travel for the seek (1.5 x) and the position of machine zero (toward min:
  // -max_travel + pull-off); grbl's $130..$132. 0: [travel] max - min, else 200 mm.
  std::array<double, 3> max_travel_mm{0.0, 0.0, 0.0};
};

struct MachineConfig {
  std::array<double, kAxes> steps_per_mm{160.0, 160.0, 400.0, 100.0};
  std::array<double, kAxes> max_feed_mm_min{12000.0, 12000.0, 600.0, 3000.0};
  uint64_t clk_hz = 50'000'000;
  uint32_t baud = 115200;
  std::string port;  // "" = none given
  // "auto" (v2 if the device answers HELLO with IDENT within 300 ms, else v1), "v1" or "v2".
  std::string protocol = "auto";
  double rapid_feed_mm_min = 3000.0;
  double default_feed_mm_min = 1000.0;  // feed before the first F word
  double arc_tolerance_mm = 0.01;       // max chord sagitta
  StepTiming step_timing;
  double ack_timeout_s = 10.0;        // v1: per move; v2: no answer at all from the device
  double retransmit_timeout_s = 0.3;  // v2: go-back-N when nothing is acknowledged this long
  double laser_s_max = 1000.0;        // v2: S word giving laser power 255 (GRBL's $30 default)
  // v2: S word at the bottom of the power map (grbl's $31): S in (0, min] gives power 1, S in
  // [min, max] power (S - min) / (max - min) * 255 rounded (at least 1), the spindle_pwm duty.
  double laser_s_min = 0.0;
  double feed_override_pct = 100.0;
  // G4 dwells last this percentage of their programmed time (100 = as written); with
  // feed_override, a configuration that compresses a whole job in time
  // (examples/demo-machine.toml).
  double dwell_time_pct = 100.0;
  // true: G1/G2/G3 cut only while M3/M4 is active with S>0 (or no S given);
  // false: original v1 semantics, every G1/G2/G3 is laser-on.
  bool laser_requires_m3 = true;
  // Motion planning (protocol v2; docs/motion.md). Per-axis acceleration limit, mm/s^2.
  std::array<double, kAxes> max_accel_mm_s2{1000.0, 1000.0, 100.0, 1000.0};
  double junction_deviation_mm = 0.01;  // grbl's $11
  // Feed hold: the deceleration to rest (mm/s^2, every axis); 0 = each axis's max_accel_mm_s2.
  // Sets the MOTION ramp (link::machine_hold_ramp, docs/timing.md "Feed hold and overrides").
  double hold_decel_mm_s2 = 0.0;
  uint32_t lookahead_segments = 64;  // planner window W (>= 1); 64 = device FIFO depth
  // v2 motion: "profile" (LINE_PROFILE frames, look-ahead planned trapezoids) or "constant"
  // (LINE frames, constant feed per segment, no acceleration). v1 always moves at constant feed.
  std::string motion = "profile";
  // motion = "profile": send G2/G3 in XY as ARC frames (the device's circular DDA) where the
  // arc qualifies (docs/motion.md "Native arcs on the host"), chords otherwise; false: chords.
  bool native_arcs = true;
  // The fourth step channel: "E" (an extruder, mm) or "A" (a rotary axis: steps_per_mm.a is
  // steps per degree, max_feed_mm_min.a degrees per minute, max_accel_mm_s2.a degrees/s^2).
  char fourth_axis = 'E';
  // [travel]: soft limits per axis (x, y, z, e or a = { min = ..., max = ... }); absent: none.
  std::array<Travel, kAxes> travel{};
  // [gcode]: how G-code files are read (docs/gcode.md).
  struct GCode {
    std::string dialect = "auto";   // "auto" (detected per file), grbl, linuxcnc, marlin, reprap
    std::string tool_table;         // LinuxCNC-format tool table for G43 H and M6 prompts
    bool tool_change_pause = true;  // M6 stops at rest and asks for the tool
    bool optional_stop = false;     // M1 pauses like M0
    bool block_delete = false;      // lines starting with '/' are skipped
  } gcode;
  Homing homing;
  // [heater.hotend], [heater.bed]: heater channels (fpgacnc/heat/heater_config.h).
  heat::HeaterSet heaters;
};

// Thrown for an unreadable file, a syntax error, an unknown key or a wrong type/value.
// what(): "FILE:LINE:COL: error: key 'a.b': MESSAGE".
class Error : public SourceError {
 public:
  using SourceError::SourceError;
};

// Loads a TOML file; keys absent from the file keep their defaults.
MachineConfig load_machine_config(const std::string& path);
// Same from TOML text (name used in error messages).
MachineConfig parse_machine_config(const std::string& text, const std::string& name);
// Checks ranges (positive steps/mm, feeds, clk, baud, protocol name, travel min < max); throws
// Error naming `name`. Protocol names: "auto", "v1", "v2".
bool valid_protocol_name(const std::string& name);
// Motion names: "profile", "constant".
bool valid_motion_name(const std::string& name);
void validate(const MachineConfig& cfg, const std::string& name);

}  // namespace fpgacnc::config
