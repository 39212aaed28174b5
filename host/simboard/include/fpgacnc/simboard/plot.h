// Plot of a job: the XY path the board actually executed (rebuilt from the recorded STEP/DIR
// edges, steps -> mm) drawn over the commanded path (the host plan's segments). Own SVG writer,
// no dependency; a .png path is written as SVG and converted with rsvg-convert when it is on
// PATH (otherwise a clear error).
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/models/edges.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::simboard {

// One commanded straight move in mm (XY), cutting = laser on (codes 1..3; solid) or not
// (rapid / laser off; dashed).
struct CommandedSegment {
  double x0, y0, x1, y1;
  bool cutting;
};

// The plan's segments as XY lines in mm, starting at the origin (as the board does).
std::vector<CommandedSegment> commanded_path(const plan::Plan& plan,
                                             const config::MachineConfig& cfg);

struct PlotOptions {
  std::array<double, 2> steps_per_mm{160.0, 160.0};  // X, Y
  std::string title = "fpgacnc simulated board";
  double width_px = 900.0;
  double height_px = 900.0;
};

// Throws the error write_plot_svg would give for a .png path without rsvg-convert on PATH (to
// fail before a job is streamed rather than after).
void check_plot_path(const std::string& path);

// Writes the plot. `edges` are the board's recorded edges (STEP/DIR/LASER). Throws
// std::runtime_error naming the file (cannot create, or .png without rsvg-convert).
void write_plot_svg(const std::string& path, std::span<const models::Edge> edges,
                    std::span<const CommandedSegment> commanded, const PlotOptions& options);

}  // namespace fpgacnc::simboard
