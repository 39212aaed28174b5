// Temperature-and-duty plot of heater channels against (plant) time, as SVG: top panel the
// measured temperature (solid) and the setpoint (dashed), bottom panel the heater duty in percent.
// Used by `fpgacnc stream --heater-plot` (what the user sees in STATUS during a job) and
// `fpgacnc autotune --plot`.
#pragma once

#include <string>
#include <vector>

namespace fpgacnc::heat {

struct HeaterTrace {
  std::string name;                                   // "bed", "hotend"
  std::vector<double> t_s, temp_c, setpoint_c, duty;  // duty 0..1
};

// Throws std::runtime_error when the file cannot be written or there is nothing to plot.
void write_heater_svg(const std::string& path, const std::vector<HeaterTrace>& traces,
                      const std::string& title, const std::string& subtitle);

}  // namespace fpgacnc::heat
