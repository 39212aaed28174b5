#include "fpgacnc/frontend/motion.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "fpgacnc/gcode/reader.h"
#include "fpgacnc/protocol/v2_job.h"

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
}

void sync_to(const plan::Steps4& steps, const config::MachineConfig& cfg, gcode::Dialect dialect,
             gcode::Params& params, gcode::Interpreter& interp, plan::Planner& planner,
             const std::vector<std::string>& lines) {
  std::string sync = "G53 G0";
  bool moved = false;
  for (size_t a = 0; a < 3; ++a) {
    if (steps[a] == 0) continue;
    sync += fmt::format(" {}{:.9f}", config::kAxisNames[a],
                        static_cast<double>(steps[a]) / cfg.steps_per_mm[a]);
    moved = true;
  }
  std::vector<std::string> all;
  if (moved) all.push_back(sync);
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

v2::Frame profile_frame(const plan::Profile& p, const config::MachineConfig& cfg) {
  plan::Segment s;
  s.code = p.code;
  s.spindle_s = p.spindle_s;
  size_t k = 2;
  for (size_t a = 0; a < 4; ++a)
    if (p.steps[a] != 0) k = std::max(k, a + 1);
  std::array<int32_t, 4> s32{};
  for (size_t a = 0; a < 4; ++a) s32[a] = static_cast<int32_t>(p.steps[a]);
  return v2::line_profile(0, v2::to_line_profile(p.code, v2::laser_power(s, cfg), p.fields,
                                                 std::span<const int32_t>(s32.data(), k)));
}

std::vector<v2::Frame> dwell_frames(double seconds, uint64_t clk_hz) {
  std::vector<v2::Frame> out;
  const double clocks = std::round(seconds * static_cast<double>(clk_hz));
  uint64_t left = clocks > 0 && clocks < 1e15 ? static_cast<uint64_t>(clocks) : 0;
  while (left > 0) {
    const uint64_t t = std::min<uint64_t>(left, UINT32_MAX);
    out.push_back(v2::dwell(0, static_cast<uint32_t>(t)));
    left -= t;
  }
  return out;
}

}  // namespace fpgacnc::frontend
