// One move of a host cycle (link::HomingCycle, link::ProbeCycle): planned alone, from rest to
// rest, with the machine's limits (plan::Planner, plan::Lookahead), and pushed on a session as
// LINE_PROFILE frames that count for `complete()`.
#pragma once

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/v2_session.h"

namespace fpgacnc::link {

// `m` in mm from the machine's position now (the planner starts at 0); `source` names the cycle in
// the planner's messages ("homing", "probe").
void push_cycle_move(V2Session& s, const config::MachineConfig& cfg, const gcode::Move& m,
                     const char* source);

}  // namespace fpgacnc::link
