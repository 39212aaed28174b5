// The plan stage of the host pipeline (G-code -> plan -> pack -> stream, docs/architecture.md):
// the planner's Plan (planner.h: steps, feeds, arcs as chords) and, for motion = "profile", the
// look-ahead's blocks (lookahead.h, docs/motion.md: trapezoid profiles in the device's
// fixed-point units, native ARC blocks for the arcs that qualify). The v2 packer
// (protocol/v2_job.h) turns a MotionPlan into frames; it plans nothing itself.
#pragma once

#include <optional>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::plan {

using ArcWalk = decltype(MotionLimits::arc_walk);

struct MotionPlan {
  // The planner's output, kept by the caller (it must outlive the MotionPlan): NUMERATORS and,
  // for motion = "constant", the segments the packer times at their feed.
  const Plan& plan;
  // motion = "profile": every item of `plan` in the look-ahead's order (profiles, dwells,
  // heater commands, pauses, outputs, messages). Unset: motion = "constant".
  std::optional<ProfilePlan> profiles;
};

// Plans `plan` for cfg.motion: "profile" runs the look-ahead (plan_profiles) with the limits of
// `cfg`; arcs in XY go out as ARC blocks when `arc_walk` is given, or when cfg.native_arcs and
// the reference walk is built in (reference_arc_walk), else as chords. "constant": nothing to
// plan. Throws std::invalid_argument naming the segment and line of a block the device cannot
// take.
MotionPlan plan_motion(const Plan& plan, const config::MachineConfig& cfg,
                       const ArcWalk& arc_walk = {});
MotionPlan plan_motion(Plan&&, const config::MachineConfig&, const ArcWalk& = {}) = delete;

}  // namespace fpgacnc::plan
