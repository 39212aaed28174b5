#include "fpgacnc/config/machine.h"

#include <fmt/format.h>

#include <stdexcept>

#include "fpgacnc/gcode/dialect.h"

#include "commands.h"

namespace fpgacnc::cli {

config::MachineConfig load_config(const CommonOptions& opt) {
  config::MachineConfig cfg;
  if (!opt.config_path.empty()) cfg = config::load_machine_config(opt.config_path);
  if (opt.feed_override_pct >= 0.0) {
    cfg.feed_override_pct = opt.feed_override_pct;
    config::validate(cfg, "--feed-override");
  }
  if (!opt.dialect.empty()) {
    cfg.gcode.dialect = opt.dialect;
    if (cfg.gcode.dialect != "auto" && !gcode::parse_dialect(cfg.gcode.dialect))
      throw std::invalid_argument("--dialect must be auto, grbl, linuxcnc, marlin or reprap");
  }
  if (!opt.tool_table.empty()) cfg.gcode.tool_table = opt.tool_table;
  return cfg;
}

void print_final_position(const plan::Plan& p) {
  const char f = p.fourth_axis;
  fmt::print(
      "final position: steps X {} Y {} Z {} {} {}; mm X {:.4f} Y {:.4f} Z {:.4f} {} {:.4f}\n",
      p.final_steps[0], p.final_steps[1], p.final_steps[2], f, p.final_steps[3], p.final_mm[0],
      p.final_mm[1], p.final_mm[2], f, p.final_mm[3]);
}

void print_gcode_report(const plan::Plan& p) {
  const auto& in = p.input;
  if (in.dialect.empty()) return;  // a step file
  fmt::print("G-code: dialect {} ({}){}\n", in.dialect, in.dialect_reason,
             in.generator.empty() ? "" : fmt::format(", written by {}", in.generator));
  if (p.stats.pauses || p.stats.outputs || p.stats.messages || in.canned_cycles ||
      in.tool_changes || p.stats.limits_clamped)
    fmt::print(
        "G-code: {} pauses, {} tool changes, {} outputs (coolant, fan, digital), {} messages, {} "
        "canned-cycle holes, {} job limits lowered to the machine's\n",
        p.stats.pauses, in.tool_changes, p.stats.outputs, p.stats.messages, in.canned_cycles,
        p.stats.limits_clamped);
  for (const auto& w : in.warnings)
    fmt::print("G-code warning: {} (line {}{})\n", w.what, w.first_line,
               w.count > 1 ? fmt::format(", {} times", w.count) : "");
}

void add_gcode_options(CLI::App* sub, CommonOptions& opt) {
  sub->add_option("--dialect", opt.dialect,
                  "G-code dialect: auto (detected from the file), grbl, linuxcnc, marlin, reprap");
  sub->add_option("--tool-table", opt.tool_table, "LinuxCNC tool table for G43 H and M6");
}

}  // namespace fpgacnc::cli
