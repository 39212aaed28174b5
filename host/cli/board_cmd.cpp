// fpgacnc board [--config F] [--fst F] [--edges F.csv]: the simulated board (Verilated
// cnc_core behind a pseudo-terminal) alone; prints its /dev/pts/N path and serves any serial
// client until Ctrl-C / SIGTERM. Also the hooks that put the board behind `stream` without
// --port.
#include "fpgacnc/simboard/cli_board.h"

#include "commands.h"

namespace fpgacnc::cli {

StreamHooks simboard_stream_hooks() {
  StreamHooks h;
  h.open_default_link = [](const config::MachineConfig& cfg, const SimOutputOptions& o) {
    return simboard::make_default_link(cfg, {o.plot_path, o.fst_path, o.edges_csv});
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
  sub->callback([args] {
    const int rc = simboard::run_board_command(*args);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace fpgacnc::cli
