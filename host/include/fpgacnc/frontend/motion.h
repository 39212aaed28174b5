// What the sender front ends (`fpgacnc grbl`: grbl/engine.h, `fpgacnc marlin`: marlin/engine.h)
// share on the FPGA side: the session's first frames, the parser and planner started where the
// machine is, and the v2 frames of what the look-ahead and the planner give them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/dialect.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::frontend {

// CONFIG_AXIS (the configuration's step timing) for every axis the device has.
void push_config_axes(link::V2Session& session, const protocol::v2::Ident& ident,
                      const config::MachineConfig& cfg);

// Runs `lines` (G-code of `dialect`) through the interpreter and the planner and drops what the
// planner made of them: the machine is there already. First the parser and planner are moved to
// `steps` (a G53 G0 to the machine position), as grbl's gc_sync_position.
void sync_to(const plan::Steps4& steps, const config::MachineConfig& cfg, gcode::Dialect dialect,
             gcode::Params& params, gcode::Interpreter& interp, plan::Planner& planner,
             const std::vector<std::string>& lines = {});

// The LINE_PROFILE frame of a finished look-ahead profile (laser power from its S).
protocol::v2::Frame profile_frame(const plan::Profile& p, const config::MachineConfig& cfg);

// DWELL frames for a dwell of `seconds` (several when longer than one frame's 32-bit clocks).
std::vector<protocol::v2::Frame> dwell_frames(double seconds, uint64_t clk_hz);

}  // namespace fpgacnc::frontend
