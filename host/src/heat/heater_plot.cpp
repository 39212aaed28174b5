#include "fpgacnc/heat/heater_plot.h"
#include "fpgacnc/svg.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace fpgacnc::heat {

void write_heater_svg(const std::string& path, const std::vector<HeaterTrace>& traces,
                      const std::string& title, const std::string& subtitle) {
  double t_max = 0.0, y_min = 1e300, y_max = -1e300;
  size_t points = 0;
  for (const auto& tr : traces) {
    for (size_t i = 0; i < tr.t_s.size(); ++i) {
      t_max = std::max(t_max, tr.t_s[i]);
      y_min = std::min({y_min, tr.temp_c[i], tr.setpoint_c[i] > 0 ? tr.setpoint_c[i] : y_min});
      y_max = std::max({y_max, tr.temp_c[i], tr.setpoint_c[i]});
      ++points;
    }
  }
  if (points < 2 || !(t_max > 0.0)) throw std::runtime_error("heater plot: no samples to plot");
  y_min = std::floor(y_min / 10.0) * 10.0;
  y_max = std::ceil((y_max + 1.0) / 10.0) * 10.0;
  const double W = 900, H = 560, L = 70, R = 20, T1 = 60, H1 = 300, T2 = 400, H2 = 110;
  const double pw = W - L - R;
  auto X = [&](double t) { return L + t / t_max * pw; };
  auto Y1 = [&](double c) { return T1 + H1 - (c - y_min) / (y_max - y_min) * H1; };
  auto Y2 = [&](double d) { return T2 + H2 - d * H2; };
  static const char* kColors[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd"};

  std::string s;
  s += fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
      "fill=\"white\"/>\n",
      W, H);
  s += fmt::format("<text x=\"{}\" y=\"22\" font-size=\"16\">{}</text>\n", L, svg::escape(title));
  s += fmt::format("<text x=\"{}\" y=\"40\" fill=\"#555\">{}</text>\n", L, svg::escape(subtitle));
  // Axes and grid.
  const double ts = svg::nice_step(t_max, 10);
  for (double t = 0; t <= t_max + 1e-9; t += ts) {
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#eee\"/>"
        "<line x1=\"{0:.1f}\" y1=\"{3}\" x2=\"{0:.1f}\" y2=\"{4}\" stroke=\"#eee\"/>"
        "<text x=\"{0:.1f}\" y=\"{5}\" text-anchor=\"middle\">{6:g}</text>\n",
        X(t), T1, T1 + H1, T2, T2 + H2, T2 + H2 + 16, t);
  }
  const double ys = svg::nice_step(y_max - y_min, 8);
  for (double c = y_min; c <= y_max + 1e-9; c += ys) {
    s += fmt::format(
        "<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#eee\"/>"
        "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5:g}</text>\n",
        L, Y1(c), L + pw, L - 6, Y1(c) + 4, c);
  }
  for (double d : {0.0, 0.5, 1.0}) {
    s += fmt::format(
        "<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#eee\"/>"
        "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5:g}</text>\n",
        L, Y2(d), L + pw, L - 6, Y2(d) + 4, d * 100);
  }
  s += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n", L, T1,
      pw, H1);
  s += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n", L, T2,
      pw, H2);
  s += fmt::format(
      "<text x=\"18\" y=\"{0}\" transform=\"rotate(-90 18 {0})\" text-anchor=\"middle\">"
      "temperature degC</text>\n",
      T1 + H1 / 2);
  s += fmt::format(
      "<text x=\"18\" y=\"{0}\" transform=\"rotate(-90 18 {0})\" text-anchor=\"middle\">duty "
      "%</text>\n",
      T2 + H2 / 2);
  s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">time s</text>\n", L + pw / 2,
                   T2 + H2 + 34);
  // Traces.
  for (size_t k = 0; k < traces.size(); ++k) {
    const auto& tr = traces[k];
    if (tr.t_s.empty()) continue;
    const char* col = kColors[k % 4];
    std::string temp, set, duty;
    for (size_t i = 0; i < tr.t_s.size(); ++i) {
      temp += fmt::format("{}{:.1f},{:.1f}", i ? " " : "", X(tr.t_s[i]), Y1(tr.temp_c[i]));
      set += fmt::format("{}{:.1f},{:.1f}", i ? " " : "", X(tr.t_s[i]),
                         Y1(std::max(tr.setpoint_c[i], y_min)));
      // Duty as a step function (held until the next sample).
      if (i) duty += fmt::format(" {:.1f},{:.1f}", X(tr.t_s[i]), Y2(tr.duty[i - 1]));
      duty += fmt::format("{}{:.1f},{:.1f}", i ? " " : "", X(tr.t_s[i]), Y2(tr.duty[i]));
    }
    s += fmt::format(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.2\" "
        "stroke-dasharray=\"6 4\"/>\n",
        set, col);
    s += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.8\"/>\n",
                     temp, col);
    s += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1\"/>\n",
                     duty, col);
    s += fmt::format(
        "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"{3}\" stroke-width=\"2\"/>"
        "<text x=\"{4}\" y=\"{5}\">{6} temperature (dashed: setpoint)</text>\n",
        L + 10, T1 + 16 + 16 * k, L + 34, col, L + 40, T1 + 20 + 16 * k, svg::escape(tr.name));
  }
  s += "</svg>\n";
  std::ofstream f(path);
  if (!f) throw std::runtime_error(fmt::format("{}: cannot write the heater plot", path));
  f << s;
}

}  // namespace fpgacnc::heat
