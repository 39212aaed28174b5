// Small helpers shared by the SVG writers (path plot, speed plot, heater plot).
#pragma once

#include <cmath>
#include <string>

namespace fpgacnc::svg {

// A "nice" axis tick step for `range`: 1, 2 or 5 times a power of ten, about `ticks` ticks.
inline double nice_step(double range, int ticks) {
  const double raw = range / ticks;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

// Text escaped for an SVG/XML text node or attribute.
inline std::string escape(const std::string& s) {
  std::string o;
  for (const char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else if (c == '\'')
      o += "&apos;";
    else
      o += c;
  }
  return o;
}

}  // namespace fpgacnc::svg
