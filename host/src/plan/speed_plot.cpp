#include "fpgacnc/plan/speed_plot.h"
#include "fpgacnc/svg.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace fpgacnc::plan {

SpeedSeries profile_speed_series(const ProfilePlan& pp, uint64_t clk_hz) {
  SpeedSeries s;
  s.name = "v2 planned (LINE_PROFILE)";
  s.color = "#c0392b";
  const double clk = static_cast<double>(clk_hz);
  uint64_t t0 = 0;  // clocks
  for (const auto& item : pp.items) {
    if (const auto* p = std::get_if<Profile>(&item)) {
      const ProfileRun run = simulate_profile(p->fields, true);
      for (const auto& [c, v] : run.knots) {
        s.pts.emplace_back(static_cast<double>(t0 + c) / clk, static_cast<double>(v) * p->lsb_mm_s);
      }
      t0 += run.clocks;
    } else if (const auto* d = std::get_if<Dwell>(&item)) {
      s.pts.emplace_back(static_cast<double>(t0) / clk, 0.0);
      t0 += static_cast<uint64_t>(std::llround(d->seconds * clk));
      s.pts.emplace_back(static_cast<double>(t0) / clk, 0.0);
    }
  }
  return s;
}

namespace {

struct Panel {
  double x, y, w, h;    // pixels
  double t0, t1, vmax;  // data range
  double px(double t) const { return x + (t - t0) / (t1 - t0) * w; }
  double py(double v) const { return y + h - v / vmax * h; }
};

void axes(std::string& out, const Panel& p, const std::string& label) {
  out += fmt::format(
      "<rect x='{:.1f}' y='{:.1f}' width='{:.1f}' height='{:.1f}' fill='none' stroke='#444'/>\n",
      p.x, p.y, p.w, p.h);
  const double ts = svg::nice_step(p.t1 - p.t0, 8);
  for (double t = std::ceil(p.t0 / ts) * ts; t <= p.t1 + 1e-9; t += ts) {
    out += fmt::format(
        "<line x1='{0:.1f}' y1='{1:.1f}' x2='{0:.1f}' y2='{2:.1f}' stroke='#ddd'/>"
        "<text x='{0:.1f}' y='{3:.1f}' font-size='11' text-anchor='middle'>{4:g}</text>\n",
        p.px(t), p.y, p.y + p.h, p.y + p.h + 14, std::round(t / ts) * ts);
  }
  const double vs = svg::nice_step(p.vmax, 5);
  for (double v = 0; v <= p.vmax + 1e-9; v += vs) {
    out += fmt::format(
        "<line x1='{0:.1f}' y1='{1:.1f}' x2='{2:.1f}' y2='{1:.1f}' stroke='#ddd'/>"
        "<text x='{3:.1f}' y='{4:.1f}' font-size='11' text-anchor='end'>{5:g}</text>\n",
        p.x, p.py(v), p.x + p.w, p.x - 4, p.py(v) + 4, v);
  }
  out += fmt::format(
      "<text x='{:.1f}' y='{:.1f}' font-size='12' text-anchor='middle'>{}</text>\n"
      "<text x='{:.1f}' y='{:.1f}' font-size='12' transform='rotate(-90 {:.1f} {:.1f})' "
      "text-anchor='middle'>path speed, mm/s</text>\n",
      p.x + p.w / 2, p.y + p.h + 30, label, p.x - 40, p.y + p.h / 2, p.x - 40, p.y + p.h / 2);
}

// Per-pixel-column min/max envelope of a piecewise linear series, as a polyline.
std::string envelope(const SpeedSeries& s, const Panel& p) {
  const int cols = static_cast<int>(p.w);
  std::vector<double> lo(static_cast<size_t>(cols), std::numeric_limits<double>::infinity());
  std::vector<double> hi(static_cast<size_t>(cols), -std::numeric_limits<double>::infinity());
  auto add = [&](double t, double v) {
    const int c = std::clamp(static_cast<int>((t - p.t0) / (p.t1 - p.t0) * cols), 0, cols - 1);
    lo[static_cast<size_t>(c)] = std::min(lo[static_cast<size_t>(c)], v);
    hi[static_cast<size_t>(c)] = std::max(hi[static_cast<size_t>(c)], v);
  };
  for (size_t i = 0; i < s.pts.size(); ++i) {
    add(s.pts[i].first, s.pts[i].second);
    if (i + 1 < s.pts.size()) {  // a long linear piece crosses columns: sample it per column
      const auto [ta, va] = s.pts[i];
      const auto [tb, vb] = s.pts[i + 1];
      const double dt = (p.t1 - p.t0) / cols;
      for (double t = ta + dt; t < tb; t += dt) add(t, va + (vb - va) * (t - ta) / (tb - ta));
    }
  }
  std::string pts;
  for (int c = 0; c < cols; ++c) {
    if (!(lo[static_cast<size_t>(c)] <= hi[static_cast<size_t>(c)])) continue;
    pts +=
        fmt::format("{:.1f},{:.1f} {:.1f},{:.1f} ", p.x + c + 0.5, p.py(lo[static_cast<size_t>(c)]),
                    p.x + c + 0.5, p.py(hi[static_cast<size_t>(c)]));
  }
  return pts;
}

std::string zoomed(const SpeedSeries& s, const Panel& p) {
  std::string pts;
  for (size_t i = 0; i < s.pts.size(); ++i) {
    const auto [t, v] = s.pts[i];
    const bool next_in = i + 1 < s.pts.size() && s.pts[i + 1].first >= p.t0;
    if (t > p.t1 && !(i > 0 && s.pts[i - 1].first <= p.t1)) break;
    if (t < p.t0 && !next_in) continue;
    const double tc = std::clamp(t, p.t0, p.t1);
    pts += fmt::format("{:.2f},{:.2f} ", p.px(tc), p.py(v));
  }
  return pts;
}

}  // namespace

std::string speed_svg(const std::vector<SpeedSeries>& series, const std::string& title,
                      double zoom_t0, double zoom_t1) {
  double t_end = 0, vmax = 0;
  for (const auto& s : series) {
    for (const auto& [t, v] : s.pts) {
      t_end = std::max(t_end, t);
      vmax = std::max(vmax, v);
    }
  }
  if (!(t_end > 0)) t_end = 1;
  if (!(vmax > 0)) vmax = 1;
  vmax *= 1.08;
  zoom_t1 = std::min(zoom_t1, t_end);
  if (!(zoom_t1 > zoom_t0)) zoom_t0 = 0, zoom_t1 = t_end;
  const double width = 1100, height = 668 + 18.0 * static_cast<double>(series.size());
  std::string out = fmt::format(
      "<svg xmlns='http://www.w3.org/2000/svg' width='{}' height='{}' "
      "font-family='sans-serif'>\n<rect width='100%' height='100%' fill='white'/>\n"
      "<text x='{}' y='22' font-size='15' text-anchor='middle'>{}</text>\n",
      width, height, width / 2, title);
  const Panel whole{70, 45, 1000, 250, 0, t_end, vmax};
  const Panel zoom{70, 370, 1000, 250, zoom_t0, zoom_t1, vmax};
  axes(out, whole, "time, s (whole job; per-pixel min/max)");
  axes(out, zoom, fmt::format("time, s (zoom {:g} .. {:g} s)", zoom_t0, zoom_t1));
  // Zoom region marker on the whole-job panel.
  out += fmt::format(
      "<rect x='{:.1f}' y='{:.1f}' width='{:.1f}' height='{:.1f}' fill='#f5c542' "
      "fill-opacity='0.25'/>\n",
      whole.px(zoom_t0), whole.y, std::max(1.0, whole.px(zoom_t1) - whole.px(zoom_t0)), whole.h);
  double ly = 660;
  for (const auto& s : series) {
    out += fmt::format(
        "<polyline fill='none' stroke='{}' stroke-width='0.8' points='{}'/>\n"
        "<polyline fill='none' stroke='{}' stroke-width='1.2' points='{}'/>\n",
        s.color, envelope(s, whole), s.color, zoomed(s, zoom));
    out += fmt::format(
        "<line x1='80' y1='{0}' x2='110' y2='{0}' stroke='{1}' stroke-width='3'/>"
        "<text x='118' y='{2}' font-size='12'>{3}</text>\n",
        ly, s.color, ly + 4, s.name);
    ly += 18;
  }
  out += "</svg>\n";
  return out;
}

}  // namespace fpgacnc::plan
