// The host pipeline's last stages as the tests drive them: plan (plan_motion), pack (pack_job,
// heater commands included), stream (stream_v2_job); the report's final position is the plan's.
#pragma once

#include <optional>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::test {

// The motion frames of `p`: plan, then pack without heater commands (the tests' boards and
// checks that have no heater plants).
inline protocol::v2::Job pack_motion(const plan::Plan& p, const config::MachineConfig& cfg,
                                     const plan::ArcWalk& arc_walk = {}) {
  return protocol::v2::pack_job(plan::plan_motion(p, cfg, arc_walk), cfg, {.heaters = false});
}

inline link::StreamV2Report stream_plan(link::Link& link, const plan::Plan& p,
                                        const config::MachineConfig& cfg,
                                        const link::StreamV2Options& options,
                                        std::optional<protocol::v2::Ident> ident = std::nullopt) {
  const protocol::v2::Job job = protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg);
  link::StreamV2Report r = link::stream_v2_job(link, job, options, ident);
  r.final_steps = p.final_steps;
  r.final_mm = p.final_mm;
  return r;
}

}  // namespace fpgacnc::test
