#include "fpgacnc/link/cycle_move.h"

#include <variant>

#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::link {

void push_cycle_move(V2Session& s, const config::MachineConfig& cfg, const gcode::Move& m,
                     const char* source) {
  plan::Planner planner(cfg, plan::PlanOptions{}, source);
  plan::Lookahead la(plan::motion_limits(cfg));
  planner.add(m);
  size_t idx = 0;
  for (auto& item : planner.take_items())
    if (const auto* seg = std::get_if<plan::Segment>(&item)) la.push(*seg, idx++);
  la.stop();
  for (const auto& p : la.take()) s.push({protocol::v2::profile_frame(p, cfg), true});
}

}  // namespace fpgacnc::link
