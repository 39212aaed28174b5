#include "fpgacnc/simboard/plot.h"
#include "fpgacnc/svg.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <variant>

namespace fpgacnc::simboard {
namespace {

struct Pt {
  double x, y;
};

struct Bounds {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0;
  double x1 = -std::numeric_limits<double>::infinity(), y1 = x1;
  void add(double x, double y) {
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  bool empty() const { return !(x0 <= x1); }
};

// Executed path: polylines in mm, each with its laser state.
struct Run {
  bool laser;
  std::vector<Pt> pts;
};

// Walks the edges; a point is kept when it is `tol_steps` away from the last kept point, at
// every laser change and at the end, so the SVG stays small for millions of steps.
std::vector<Run> executed_runs(std::span<const models::Edge> edges, std::array<double, 2> spm,
                               double tol_steps, Bounds* bounds) {
  std::vector<Run> runs;
  int64_t x = 0, y = 0, kx = 0, ky = 0;
  uint32_t dir = 0;
  bool laser = false;
  runs.push_back(Run{false, {Pt{0, 0}}});
  auto mm = [&](int64_t sx, int64_t sy) {
    return Pt{static_cast<double>(sx) / spm[0], static_cast<double>(sy) / spm[1]};
  };
  auto keep = [&] {
    runs.back().pts.push_back(mm(x, y));
    kx = x;
    ky = y;
  };
  for (const models::Edge& e : edges) {
    if (e.signal >= models::kDir0 && e.signal < models::kDir0 + models::kBoardAxes) {
      const uint32_t bit = 1u << (e.signal - models::kDir0);
      dir = e.value ? (dir | bit) : (dir & ~bit);
    } else if (e.signal < 2 && e.value) {
      const int64_t d = (dir >> e.signal) & 1u ? 1 : -1;
      (e.signal == 0 ? x : y) += d;
      if (bounds) bounds->add(static_cast<double>(x) / spm[0], static_cast<double>(y) / spm[1]);
      const double dx = static_cast<double>(x - kx), dy = static_cast<double>(y - ky);
      if (dx * dx + dy * dy >= tol_steps * tol_steps) keep();
    } else if (e.signal == models::kLaser && static_cast<bool>(e.value) != laser) {
      if (x != kx || y != ky) keep();
      laser = e.value;
      runs.push_back(Run{laser, {mm(x, y)}});
    }
  }
  if (x != kx || y != ky) keep();
  return runs;
}

bool on_path(const std::string& exe) {
  const char* p = std::getenv("PATH");
  if (!p) return false;
  std::string path = p;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = path.find(':', start);
    const std::string dir = path.substr(start, end == std::string::npos ? end : end - start);
    if (!dir.empty() && ::access((dir + "/" + exe).c_str(), X_OK) == 0) return true;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return false;
}

}  // namespace

std::vector<CommandedSegment> commanded_path(const plan::Plan& plan,
                                             const config::MachineConfig& cfg) {
  std::vector<CommandedSegment> out;
  double x = 0, y = 0;
  for (const auto& item : plan.items) {
    const auto* s = std::get_if<plan::Segment>(&item);
    if (!s) continue;
    const double nx = static_cast<double>(s->target[0]) / cfg.steps_per_mm[0];
    const double ny = static_cast<double>(s->target[1]) / cfg.steps_per_mm[1];
    if (nx != x || ny != y) out.push_back(CommandedSegment{x, y, nx, ny, s->code != 0});
    x = nx;
    y = ny;
  }
  return out;
}

void check_plot_path(const std::string& path) {
  const bool png = path.size() > 4 && path.compare(path.size() - 4, 4, ".png") == 0;
  if (png && !on_path("rsvg-convert")) {
    throw std::runtime_error(fmt::format(
        "{}: error: PNG output needs rsvg-convert on PATH (Debian package librsvg2-bin); "
        "write an .svg instead",
        path));
  }
}

void write_plot_svg(const std::string& path, std::span<const models::Edge> edges,
                    std::span<const CommandedSegment> commanded, const PlotOptions& o) {
  check_plot_path(path);
  const bool png = path.size() > 4 && path.compare(path.size() - 4, 4, ".png") == 0;
  const std::string svg_path = png ? path.substr(0, path.size() - 4) + ".svg" : path;

  Bounds b;
  b.add(0, 0);
  for (const auto& c : commanded) {
    b.add(c.x0, c.y0);
    b.add(c.x1, c.y1);
  }
  executed_runs(edges, o.steps_per_mm, std::numeric_limits<double>::infinity(), &b);
  double wx = b.x1 - b.x0, wy = b.y1 - b.y0;
  if (wx <= 0) wx = 1;
  if (wy <= 0) wy = 1;
  const double ml = 70, mr = 20, mt = 120, mb = 60;  // margins, px (title, legend on top)
  const double pw = o.width_px - ml - mr;
  double ph = o.height_px - mt - mb;
  const double scale = std::min(pw / wx, ph / wy);  // px per mm, same on both axes
  ph = wy * scale;                                  // the canvas fits the drawing's aspect
  const double height_px = mt + ph + mb;
  const double ox = ml + (pw - wx * scale) / 2, oy = mt;
  auto X = [&](double mm) { return ox + (mm - b.x0) * scale; };
  auto Y = [&](double mm) { return oy + (b.y1 - mm) * scale; };
  // Keep a point every 0.4 px of the executed path.
  const double tol_steps = 0.4 / scale * std::min(o.steps_per_mm[0], o.steps_per_mm[1]);
  const auto runs = executed_runs(edges, o.steps_per_mm, std::max(tol_steps, 1.0), nullptr);

  std::string s;
  auto out = std::back_inserter(s);
  fmt::format_to(out,
                 "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" "
                 "viewBox=\"0 0 {0} {1}\" font-family=\"sans-serif\" font-size=\"12\">\n"
                 "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
                 "<text x=\"{2}\" y=\"24\" font-size=\"16\">{3}</text>\n",
                 o.width_px, height_px, ml, svg::escape(o.title));
  // Axes with ticks in mm.
  const double ax0 = X(b.x0), ax1 = X(b.x1), ay0 = Y(b.y0), ay1 = Y(b.y1);
  fmt::format_to(out,
                 "<g stroke=\"#888\" stroke-width=\"1\" fill=\"none\">"
                 "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\"/></g>\n",
                 ax0, ay1, ax1 - ax0, ay0 - ay1);
  const double step = svg::nice_step(std::max(wx, wy), 8);
  s += "<g stroke=\"#ddd\" stroke-width=\"0.5\">\n";
  std::string labels;
  for (double v = std::ceil(b.x0 / step) * step; v <= b.x1 + 1e-9; v += step) {
    fmt::format_to(out, "<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\"/>\n",
                   X(v), ay0, ay1);
    fmt::format_to(std::back_inserter(labels),
                   "<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">{:g}</text>\n", X(v),
                   ay0 + 16, std::abs(v) < 1e-9 ? 0.0 : v);
  }
  for (double v = std::ceil(b.y0 / step) * step; v <= b.y1 + 1e-9; v += step) {
    fmt::format_to(out, "<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{2:.2f}\" y2=\"{1:.2f}\"/>\n",
                   ax0, Y(v), ax1);
    fmt::format_to(std::back_inserter(labels),
                   "<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\">{:g}</text>\n", ax0 - 6,
                   Y(v) + 4, std::abs(v) < 1e-9 ? 0.0 : v);
  }
  s += "</g>\n" + labels;
  fmt::format_to(out,
                 "<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">X (mm)</text>\n"
                 "<text x=\"18\" y=\"{:.2f}\" text-anchor=\"middle\" "
                 "transform=\"rotate(-90 18 {:.2f})\">Y (mm)</text>\n",
                 (ax0 + ax1) / 2, ay0 + 40, (ay0 + ay1) / 2, (ay0 + ay1) / 2);

  // Commanded path: wide light strokes underneath; cutting solid, rapid/laser-off dashed.
  for (int pass = 0; pass < 2; ++pass) {
    const bool cutting = pass == 1;
    fmt::format_to(out,
                   "<g fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-linecap=\"round\"{}>"
                   "\n<path d=\"",
                   cutting ? "#9ecae1" : "#bbbbbb", cutting ? 4 : 1.5,
                   cutting ? "" : " stroke-dasharray=\"6 4\"");
    for (const auto& c : commanded) {
      if (c.cutting != cutting) continue;
      fmt::format_to(out, "M{:.2f} {:.2f}L{:.2f} {:.2f}", X(c.x0), Y(c.y0), X(c.x1), Y(c.y1));
    }
    s += "\"/></g>\n";
  }
  // Executed path from the STEP/DIR edges: laser on red solid, laser off dark dotted.
  for (const auto& r : runs) {
    if (r.pts.size() < 2) continue;
    fmt::format_to(out, "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"{} points=\"",
                   r.laser ? "#d62728" : "#333333", r.laser ? 1.2 : 0.8,
                   r.laser ? "" : " stroke-dasharray=\"1.5 2\"");
    for (const Pt& p : r.pts) fmt::format_to(out, "{:.2f},{:.2f} ", X(p.x), Y(p.y));
    s += "\"/>\n";
  }
  // Legend.
  const double lx = o.width_px - mr - 250, ly = 34;
  fmt::format_to(
      out,
      "<g font-size=\"11\"><rect x=\"{0}\" y=\"{1}\" width=\"245\" height=\"74\" "
      "fill=\"white\" fill-opacity=\"0.85\" stroke=\"#888\"/>\n"
      "<line x1=\"{2}\" y1=\"{3}\" x2=\"{4}\" y2=\"{3}\" stroke=\"#9ecae1\" "
      "stroke-width=\"4\"/><text x=\"{5}\" y=\"{6}\">commanded, cutting (laser on)</text>\n"
      "<line x1=\"{2}\" y1=\"{7}\" x2=\"{4}\" y2=\"{7}\" stroke=\"#bbbbbb\" "
      "stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/><text x=\"{5}\" y=\"{8}\">"
      "commanded, rapid / laser off</text>\n"
      "<line x1=\"{2}\" y1=\"{9}\" x2=\"{4}\" y2=\"{9}\" stroke=\"#d62728\" "
      "stroke-width=\"1.2\"/><text x=\"{5}\" y=\"{10}\">executed (STEP/DIR), laser "
      "on</text>\n"
      "<line x1=\"{2}\" y1=\"{11}\" x2=\"{4}\" y2=\"{11}\" stroke=\"#333\" "
      "stroke-width=\"0.8\" stroke-dasharray=\"1.5 2\"/><text x=\"{5}\" y=\"{12}\">"
      "executed, laser off</text></g>\n",
      lx, ly, lx + 8, ly + 14, lx + 40, lx + 48, ly + 18, ly + 30, ly + 34, ly + 46, ly + 50,
      ly + 62, ly + 66);
  s += "</svg>\n";

  std::ofstream f(svg_path, std::ios::binary);
  if (!f) throw std::runtime_error(fmt::format("{}: error: cannot create file", svg_path));
  f.write(s.data(), static_cast<std::streamsize>(s.size()));
  f.close();
  if (!f) throw std::runtime_error(fmt::format("{}: error: write error", svg_path));
  if (png) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::execlp("rsvg-convert", "rsvg-convert", "-o", path.c_str(), svg_path.c_str(),
               static_cast<char*>(nullptr));
      ::_exit(127);
    }
    int status = 0;
    if (pid < 0 || ::waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
      throw std::runtime_error(
          fmt::format("{}: error: rsvg-convert failed to convert {}", path, svg_path));
    }
  }
}

}  // namespace fpgacnc::simboard
