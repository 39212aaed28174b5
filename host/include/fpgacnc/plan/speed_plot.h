// Speed-against-time plot (SVG) of a job: the path speed the user sees, from the planned
// profiles (exact hardware recurrence, plan::simulate_profile knots) and optionally other series
// (constant-feed segments, speeds measured from STEP edges).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "fpgacnc/plan/lookahead.h"

namespace fpgacnc::plan {

struct SpeedSeries {
  std::string name;
  std::string color;                           // SVG colour
  std::vector<std::pair<double, double>> pts;  // (time s, path speed mm/s), time ascending
};

// Path speed of the planned job: per profile the knots of the exact recurrence, V / scale
// (mm/s), dwells at 0 mm/s. Time 0 = first clock of the first segment.
SpeedSeries profile_speed_series(const ProfilePlan& pp, uint64_t clk_hz);

// SVG with two panels: the whole job (per-pixel min/max envelope) and a zoom on
// [zoom_t0, zoom_t1] seconds showing every knot. `title` goes on top.
std::string speed_svg(const std::vector<SpeedSeries>& series, const std::string& title,
                      double zoom_t0, double zoom_t1);

}  // namespace fpgacnc::plan
