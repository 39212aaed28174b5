#include "fpgacnc/plan/motion_plan.h"

namespace fpgacnc::plan {

MotionPlan plan_motion(const Plan& plan, const config::MachineConfig& cfg,
                       const ArcWalk& arc_walk) {
  MotionPlan mp{plan, std::nullopt};
  if (cfg.motion != "profile") return mp;
  MotionLimits lim = motion_limits(cfg);
  lim.arc_walk = arc_walk;
  if (!lim.arc_walk && cfg.native_arcs) lim.arc_walk = reference_arc_walk();
  mp.profiles = plan_profiles(plan, lim);
  return mp;
}

}  // namespace fpgacnc::plan
