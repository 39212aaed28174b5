// Corpus arcs through the circular DDA (CTest label cosim): every G2/G3 of the G-code corpus
// (host interpreter, machine mm) is put on the lattice as the host does (160 and 157.48 steps/mm on
// X, Y and Z; position = the rounded end of the previous move), planned
// with arc::plan, and run through the Verilated rtl/motion/arc_dda.v and the reference: the RTL
// must match the reference edge for edge and end exactly on the rounded G-code end point (X, Y and
// the helix's Z). Arcs whose rounded radii differ by more than 2 steps are counted (the host cuts
// them into chords). The simulated speed is 0.05 steps per clock (the feed is not simulated: the
// check is the geometry). Usage: arc_corpus_rtl [corpus dir]. Exit status 1 on any failure.
#include "common/arc_rtl.h"
// clang-format off
#include <fmt/format.h>
// clang-format on

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

#include "fpgacnc/gcode/interpreter.h"

namespace arc = fpgacnc::models::arc;
namespace gc = fpgacnc::gcode;

int main(int argc, char* argv[]) {
  const std::string dir = argc > 1 ? argv[1] : FPGACNC_CORPUS_DIR;
  constexpr double kV = 0.05;
  fpgacnc::tb::ArcRtl rtl;
  int failures = 0;
  std::vector<std::filesystem::path> paths;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".gcode") paths.push_back(e.path());
  std::sort(paths.begin(), paths.end());
  // 160 steps/mm (the demo machine: corpus coordinates land on the lattice) and 157.48 steps/mm
  // (4000 per inch: start, centre and end are rounded, the rounded radii differ)
  for (const double spm : {160.0, 157.48}) {
    const auto lat = [spm](double mm) { return static_cast<int64_t>(std::llround(mm * spm)); };
    int files = 0, arcs = 0, chords = 0;
    double worst_dr = 0;
    for (const auto& path : paths) {
      gc::Program prog;
      try {
        prog = gc::parse_file(path.string());
      } catch (const std::exception& ex) {
        fmt::print("skip {}: {}\n", path.filename().string(), ex.what());
        continue;
      }
      ++files;
      int file_arcs = 0;
      for (const gc::Command& c : prog.commands) {
        const auto* m = std::get_if<gc::Move>(&c);
        if (!m || (m->motion != gc::Motion::kArcCw && m->motion != gc::Motion::kArcCcw)) continue;
        const int64_t sx = lat(m->start[0]), sy = lat(m->start[1]), sz = lat(m->start[2]);
        const int64_t ex = lat(m->end[0]), ey = lat(m->end[1]), ez = lat(m->end[2]);
        arc::Frame f;
        f.g.ccw = m->motion == gc::Motion::kArcCcw;
        f.g.i = static_cast<int32_t>(lat(m->center[0]) - sx);
        f.g.j = static_cast<int32_t>(lat(m->center[1]) - sy);
        f.g.dx = static_cast<int32_t>(ex - sx);
        f.g.dy = static_cast<int32_t>(ey - sy);
        f.dz = static_cast<int32_t>(ez - sz);
        if (f.g.dx == 0 && f.g.dy == 0 && !m->full_circle) continue;  // sent as a LINE of its Z
        const double r0 = std::hypot(double(f.g.i), double(f.g.j));
        const double r1 = std::hypot(double(f.g.dx) - f.g.i, double(f.g.dy) - f.g.j);
        if ((f.g.i == 0 && f.g.j == 0) || std::fabs(r1 - r0) > 2.0) {
          if (std::getenv("ARC_VERBOSE"))
            fmt::print("chords: {} line {} R0 {:.2f} R1 {:.2f}\n", path.filename().string(),
                       m->line, r0, r1);
          ++chords;
          continue;
        }
        worst_dr = std::max(worst_dr, std::fabs(r1 - r0));
        const arc::Plan p = arc::plan(f.g);
        const std::string what =
            fmt::format("{} line {}: I={} J={} DX={} DY={} DZ={}", path.filename().string(),
                        m->line, f.g.i, f.g.j, f.g.dx, f.g.dy, f.dz);
        if (!p.ok) {
          fmt::print("FAIL {}: the walk does not land on the end point\n", what);
          ++failures;
          continue;
        }
        f.n_ramp = p.n_ramp;
        f.c_total = p.c_total;
        const double len = 0.5 * (r0 + r1) * arc::sweep(f.g);
        const double k = double(f.c_total) / len;
        f.v_entry = f.v_cruise = f.v_exit =
            static_cast<uint64_t>(std::llround(kV * k * std::ldexp(1.0, 48)));
        f.a = 1;
        f.d = f.c_total;
        const arc::RunResult ref = arc::run(f);
        const arc::RunResult got = rtl.run(f, ref.end_clock + 16);
        bool same = got.events.size() == ref.events.size() && !got.err && !ref.err;
        for (size_t q = 0; same && q < ref.events.size(); ++q) {
          const arc::Event &a = ref.events[q], &b = got.events[q];
          same = a.clock == b.clock && a.dx == b.dx && a.dy == b.dy && a.dz == b.dz;
        }
        if (!same || got.x != f.g.dx || got.y != f.g.dy || got.z != f.dz) {
          fmt::print("FAIL {}: RTL ended at ({}, {}, {}) err {}, edges {} the reference's\n", what,
                     got.x, got.y, got.z, got.err, same ? "equal" : "differ from");
          ++failures;
        }
        ++arcs;
        ++file_arcs;
      }
      if (file_arcs) fmt::print("{}: {} arcs end exactly\n", path.filename().string(), file_arcs);
    }
    fmt::print(
        "[arc] corpus at {} steps/mm: {} files, {} arcs through the RTL (end points exact: {}), {} "
        "cut "
        "into chords (|R1 - R0| > 2 steps), worst |R1 - R0| sent {:.3f} steps\n",
        spm, files, arcs, failures == 0 ? "all" : "NOT all", chords, worst_dr);
  }
  return failures ? 1 : 0;
}
