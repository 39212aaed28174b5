// grbl 1.1's `$` settings (docs/grbl.md, "Settings") over the machine configuration: the values
// a sender reads with `$$` and writes with `$N=value`, the startup lines `$N0=` / `$N1=` and the
// `$I=` build string, kept in a text file of `$N=value` lines.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>

#include "fpgacnc/config/machine.h"

namespace fpgacnc::grbl {

struct Settings {
  std::map<int, double> values;        // every setting number listed by `$$`
  std::array<std::string, 2> startup;  // $N0, $N1
  std::string info;                    // $I= user string
};

// The settings a sender sees for `cfg` (steps/mm, rates, accelerations, junction deviation, arc
// tolerance, step pulse, laser S maximum; the rest at grbl's defaults).
Settings settings_from_config(const config::MachineConfig& cfg);
// `cfg` with the settings applied (the machine configuration the planner uses).
config::MachineConfig apply_settings(const config::MachineConfig& cfg, const Settings& s);

// Checks `$N=value` against grbl's rules; returns 0 and stores it, or grbl's error code:
// 3 unknown setting (also a feature the board lacks: hard limits `$21=1` and homing `$22=1`
// unless `hard_limits`: the board has limit switches), 4 negative value (or 0 for a value the
// planner or the homing cycle divides by or moves), 6 step pulse under 3 us. $20 and $22 are
// stored as 0 or 1.
int set_value(Settings& s, int number, double value, bool hard_limits = false);

// `$N=value` lines in number order, as `$$` prints them.
std::string format_settings(const Settings& s);

// The settings file: `$N=value`, `$N0=line`, `$N1=line`, `$I=text` lines ('#' comments).
// load: nullopt when the file does not exist; throws fpgacnc::SourceError naming FILE:LINE for a
// malformed line. save: writes the whole file (a temporary file renamed over it).
std::optional<Settings> load_settings(const std::string& path, const Settings& defaults);
void save_settings(const std::string& path, const Settings& s);
// Default file: $XDG_CONFIG_HOME/fpgacnc/grbl-settings.txt, else
// $HOME/.config/fpgacnc/grbl-settings.txt.
std::string default_settings_path();

}  // namespace fpgacnc::grbl
