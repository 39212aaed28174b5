// The arc helper's integer reference walk (systemc/include/fpgacnc/twins/arc_walk.h) as the
// planner's MotionLimits::arc_walk: N_RAMP and C_TOTAL of an ARC frame. Built without it (the
// header not in the tree yet) the function is empty and arcs stay chords.
#include "fpgacnc/plan/lookahead.h"

#if __has_include("fpgacnc/twins/arc_walk.h")
#include "fpgacnc/twins/arc_walk.h"
#define FPGACNC_HAVE_ARC_WALK 1
#else
#define FPGACNC_HAVE_ARC_WALK 0
#endif

namespace fpgacnc::plan {

bool have_reference_arc_walk() {
  return FPGACNC_HAVE_ARC_WALK != 0;
}

decltype(MotionLimits::arc_walk) reference_arc_walk() {
#if FPGACNC_HAVE_ARC_WALK
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
#else
  return {};
#endif
}

}  // namespace fpgacnc::plan
