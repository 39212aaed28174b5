// The integer reference walk of the circular DDA (models/include/fpgacnc/models/arc_walk.h, the
// arc twin) as the planner's MotionLimits::arc_walk: N_RAMP and C_TOTAL of an ARC frame.
#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/plan/lookahead.h"

namespace fpgacnc::plan {

decltype(MotionLimits::arc_walk) reference_arc_walk() {
  return [](const ArcFields& f) -> std::optional<std::pair<uint32_t, uint64_t>> {
    ::fpgacnc::models::arc::Geometry g;
    g.i = f.i;
    g.j = f.j;
    g.dx = f.dx;
    g.dy = f.dy;
    g.ccw = f.code == 3;
    const auto p = ::fpgacnc::models::arc::plan(g);
    if (!p.ok) return std::nullopt;
    return std::make_pair(p.n_ramp, p.c_total);
  };
}

}  // namespace fpgacnc::plan
