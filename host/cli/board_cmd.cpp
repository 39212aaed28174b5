// fpgacnc board [--config F] [--fst F] [--edges F.csv] [--line-* ...]: the simulated board
// (Verilated cnc_core behind a pseudo-terminal) alone; prints its /dev/pts/N path and serves any
// serial client until Ctrl-C / SIGTERM. Also the hooks that put the board behind `stream` without
// --port.
#include "fpgacnc/simboard/cli_board.h"

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"

namespace fpgacnc::cli {

namespace {

// Registers every --line-* option of the simulated board; each value is handed to `apply`
// (repeatable options such as --line-stall give one call per occurrence).
void add_line_fault_options(CLI::App& sub,
                            std::function<void(const std::string&, const std::string&)> apply) {
  for (const auto& o : simboard::line_fault_options()) {
    const std::string name = o.name;
    sub.add_option_function<std::vector<std::string>>(
           name,
           [apply, name](const std::vector<std::string>& values) {
             for (const auto& v : values) apply(name, v);
           },
           o.help)
        ->type_name(o.value_name)
        ->group("Simulated line faults");
  }
}

void apply_line_fault(simboard::LineFaults& f, const std::string& name, const std::string& v) {
  try {
    simboard::parse_line_fault_option(name, v, f);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(name, e.what());
  }
}

}  // namespace

StreamHooks simboard_stream_hooks() {
  StreamHooks h;
  h.open_default_link = [](const config::MachineConfig& cfg, const SimOutputOptions& o) {
    simboard::LineFaults faults;
    for (const auto& [name, value] : o.line_faults) apply_line_fault(faults, name, value);
    return simboard::make_default_link(cfg, {o.plot_path, o.fst_path, o.edges_csv}, faults);
  };
  h.add_sim_options = [](CLI::App& sub, SimOutputOptions& o) {
    add_line_fault_options(sub, [&o](const std::string& name, const std::string& v) {
      o.line_faults.emplace_back(name, v);
    });
  };
  // Heaters: plant time of the simulated board (scaled thermal time) and a STATUS poll that
  // keeps up with it (issue 7, docs/heater.md "Simulated board").
  h.configure_v2 = [](link::Link& lk, link::StreamV2Options& o) {
    if (auto clk = simboard::plant_clock(lk)) {
      o.plant_time = std::move(clk);
      o.heater_poll = std::chrono::milliseconds(5);
    }
  };
  h.after_default_stream = [](link::Link& lk, const plan::Plan& p, const config::MachineConfig& cfg,
                              const SimOutputOptions& o) {
    simboard::report_board_run(lk, p, cfg, {o.plot_path, o.fst_path, o.edges_csv});
  };
  return h;
}

void register_board(CLI::App& app) {
  auto args = std::make_shared<simboard::BoardCommandArgs>();
  auto* sub = app.add_subcommand(
      "board", "Run the simulated board (Verilated cnc_core) on a pseudo-terminal until Ctrl-C");
  sub->add_option("--config", args->config_path, "machine configuration (TOML): step timing");
  sub->add_option("--fst", args->fst_path, "write an FST waveform of the core");
  sub->add_option("--edges", args->edges_csv, "write the STEP/DIR/LASER edge list (CSV) at exit");
  add_line_fault_options(*sub, [args](const std::string& name, const std::string& v) {
    apply_line_fault(args->line_faults, name, v);
  });
  sub->callback([args] {
    const int rc = simboard::run_board_command(*args);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace fpgacnc::cli
