// fpgacnc marlin [--config F] [--port DEV | --model tlm|rtl] [--listen tcp:HOST:PORT] [--no-pty]:
// Marlin's host protocol for printers (docs/marlin.md) on a new pseudo-terminal (its path is the
// first line on stdout) and on TCP, with the FPGA behind it: a real port, or the simulated board
// (default: the twins; --model rtl for the Verilated board with its heaters' thermal plants and
// e-stop). Serves until SIGINT or SIGTERM.
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "fpgacnc/marlin/engine.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

struct MarlinArgs {
  CommonOptions common;
  BoardChoice board;
  SenderChoice senders;
};

void run_marlin(const MarlinArgs& args) {
  const config::MachineConfig cfg = load_config(args.common);
  SenderSide senders(args.senders);
  // First line: the pty path (scripts read it), before the board prints its own line.
  fmt::print("{}\n", args.senders.no_pty ? std::string("-") : senders.pty_path());
  if (!senders.tcp_where().empty()) fmt::print("marlin on tcp {}\n", senders.tcp_where());

  BoardBehind board = open_board_behind(cfg, args.board);
  marlin::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  eo.limit_switches = board.limit_switches;
  eo.estop_press = board.estop_press;
  std::string behind = board.description;
  if (board.rtl) {
    if (auto clk = simboard::plant_clock(*board.link)) {
      eo.v2.plant_time = std::move(clk);
      eo.v2.heater_poll = std::chrono::milliseconds(5);
    }
  } else if (args.board.port.empty()) {
    behind = "the simulated board (tlm: no heater plants, no e-stop input)";
  }
  fmt::print("Marlin front end for {}\n", behind);
  std::fflush(stdout);

  marlin::Engine engine(*board.link, cfg, eo);
  engine.connect();
  const std::string banner = engine.take_output();  // to each sender when it opens the port

  serve(
      senders, engine, [&](Peer& p) { p.pending += banner; }, board.pull_off);
  const auto& s = engine.stats();
  fmt::print("marlin: {} commands, {} resends asked, {} frames, {} busy lines\n", s.lines,
             s.resends, s.frames, s.busy);
}

}  // namespace

void register_marlin(CLI::App& app) {
  auto args = std::make_shared<MarlinArgs>();
  auto* sub = app.add_subcommand(
      "marlin",
      "Serve Marlin's host protocol (printers: OctoPrint, Pronterface, Repetier-Host) on a new pty "
      "(its path is the first line on stdout) and on TCP, with the FPGA behind it");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  add_board_options(sub, args->board,
                    "simulated board: tlm (the SystemC twins, default; no heater plants) or rtl "
                    "(the Verilated cnc_core with its thermal plants and e-stop)");
  add_sender_options(sub, args->senders);
  sub->callback([args] {
    check_sender_choice(args->senders, "marlin");
    run_marlin(*args);
  });
}

}  // namespace fpgacnc::cli
