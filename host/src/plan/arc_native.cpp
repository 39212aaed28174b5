// The integer reference walk of the circular DDA (systemc/include/fpgacnc/twins/arc_walk.h, the
// arc twin) as the planner's MotionLimits::arc_walk: N_RAMP and C_TOTAL of an ARC frame.
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/twins/arc_walk.h"

namespace fpgacnc::plan {

decltype(MotionLimits::arc_walk) reference_arc_walk() {
  return [](const ArcFields& f) -> std::optional<std::pair<uint32_t, uint64_t>> {
    ::fpgacnc::twins::arc::Geometry g;
    g.i = f.i;
    g.j = f.j;
    g.dx = f.dx;
    g.dy = f.dy;
    g.ccw = f.code == 3;
    const auto p = ::fpgacnc::twins::arc::plan(g);
    if (!p.ok) return std::nullopt;
    return std::make_pair(p.n_ramp, p.c_total);
  };
}

}  // namespace fpgacnc::plan
