#include "fpgacnc/frontend/motion.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fpgacnc/gcode/reader.h"

namespace fpgacnc::frontend {
namespace v2 = protocol::v2;

void push_config_axes(link::V2Session& session, const v2::Ident& ident,
                      const config::MachineConfig& cfg) {
  const auto& t = cfg.step_timing;
  for (uint8_t a = 0; a < ident.n_axes && a < config::kAxes; ++a) {
    session.push({v2::config_axis(
        0, a, static_cast<uint16_t>(t.step_high), static_cast<uint16_t>(t.step_low),
        static_cast<uint16_t>(t.dir_setup), static_cast<uint16_t>(t.dir_hold))});
  }
  // Soft limits (docs/machine.md): every axis, so that turning them off reaches the device too.
  for (uint8_t a = 0; a < ident.n_axes && a < config::kAxes; ++a) {
    const config::Travel& tr = cfg.travel[a];
    const double spm = cfg.steps_per_mm[a];
    const auto steps = [&](double mm) {
      return static_cast<int32_t>(std::clamp(std::round(mm * spm), -2147483648.0, 2147483647.0));
    };
    session.push({v2::config_travel(0, a, tr.enabled, tr.enabled ? steps(tr.min_mm) : 0,
                                    tr.enabled ? steps(tr.max_mm) : 0)});
  }
}

void sync_to(const plan::Steps4& steps, const config::MachineConfig& cfg, gcode::Dialect dialect,
             gcode::Params& params, gcode::Interpreter& interp, plan::Planner& planner,
             const std::vector<std::string>& lines) {
  std::string sync = "G21 G90 G53 G0";
  for (size_t a = 0; a < 3; ++a) {
    sync += fmt::format(" {}{:.9f}", config::kAxisNames[a],
                        static_cast<double>(steps[a]) / cfg.steps_per_mm[a]);
  }
  std::vector<std::string> all{sync};
  all.insert(all.end(), lines.begin(), lines.end());
  const auto& syntax = gcode::dialect_rules(dialect).syntax;
  for (const auto& line : all) {
    if (line.empty()) continue;
    gcode::Reader reader("sync", line, syntax, params);
    gcode::Block b;
    std::vector<gcode::Command> cmds;
    while (reader.next(b)) interp.execute(b, cmds);
    for (const auto& c : cmds) planner.add(c);
    planner.take_items();
  }
}

}  // namespace fpgacnc::frontend
