// What the sender front ends (`fpgacnc grbl`: grbl/engine.h, `fpgacnc marlin`: marlin/engine.h)
// share on the FPGA side: the session's first frames and the parser and planner started where
// the machine is. Each line then goes plan (the planner and a plan::Lookahead) -> pack (the v2
// packer's profile_frame / dwell_frames / output_frame, protocol/v2_job.h) -> stream (a
// link::V2Session).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/dialect.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::frontend {

// CONFIG_AXIS (the configuration's step timing) and CONFIG_TRAVEL (its [travel]: soft limits on
// or off) for every axis the device has.
void push_config_axes(link::V2Session& session, const protocol::v2::Ident& ident,
                      const config::MachineConfig& cfg);

// Runs `lines` (G-code of `dialect`) through the interpreter and the planner and drops what the
// planner made of them: the machine is there already. First the parser and planner are moved to
// `steps` (G21 G90 G53 G0 to the machine position, as grbl's gc_sync_position: the parser is
// left in G21, G90 and G0; `lines` restore other modes).
void sync_to(const plan::Steps4& steps, const config::MachineConfig& cfg, gcode::Dialect dialect,
             gcode::Params& params, gcode::Interpreter& interp, plan::Planner& planner,
             const std::vector<std::string>& lines = {});

}  // namespace fpgacnc::frontend
