// fpgacnc grbl [--config F] [--port DEV | --model tlm|rtl] [--listen tcp:HOST:PORT]
//              [--settings FILE] [--realtime] [--no-pty]: grbl 1.1's protocol (docs/grbl.md)
// on a new pseudo-terminal (its path is the first line on stdout) and on TCP, with the FPGA
// behind it: a real port, or the simulated board (default: the twins). Serves until SIGINT or
// SIGTERM.
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/grbl/settings.h"
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

struct Args {
  CommonOptions common;
  BoardChoice board;
  SenderChoice senders;
  std::string settings;
};

void run(const Args& args) {
  const config::MachineConfig cfg = load_config(args.common);
  const std::string settings_path =
      args.settings.empty() ? grbl::default_settings_path() : args.settings;
  const grbl::Settings defaults = grbl::settings_from_config(cfg);
  const grbl::Settings settings = grbl::load_settings(settings_path, defaults).value_or(defaults);

  SenderSide senders(args.senders);
  // First line: the pty path (scripts read it), before the board prints its own line.
  fmt::print("{}\n", args.senders.no_pty ? std::string("-") : senders.pty_path());
  if (!senders.tcp_where().empty()) fmt::print("grbl on tcp {}\n", senders.tcp_where());

  BoardBehind board = open_board_behind(cfg, args.board);
  grbl::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  eo.settings_path = settings_path;
  eo.estop_press = board.estop_press;
  eo.estop_release = board.estop_release;
  eo.limit_switches = board.limit_switches;
  eo.probe = board.probe;
  const std::string& behind = board.description;
  fmt::print("grbl 1.1 front end for {}; settings {}\n", behind, settings_path);
  std::fflush(stdout);

  grbl::Engine engine(*board.link, cfg, settings, eo);
  engine.connect();
  engine.take_output();  // the banner goes to each sender when it connects

  serve(
      senders, engine, [&](Peer&) { engine.opened(); }, board.pull_off);
  const auto& s = engine.stats();
  fmt::print(
      "grbl: {} lines ({} ok, {} errors), {} status reports, {} frames, {} flushes, {} "
      "soft resets\n",
      s.lines, s.oks, s.errors, s.reports, s.frames, s.flushes, s.resets);
}

}  // namespace

void register_grbl(CLI::App& app) {
  auto args = std::make_shared<Args>();
  auto* sub = app.add_subcommand(
      "grbl",
      "Serve grbl 1.1's protocol on a new pty (its path is the first line on stdout) and on TCP, "
      "with the FPGA behind it (a real --port, or the simulated board)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  add_board_options(sub, args->board,
                    "simulated board: tlm (the SystemC twins, default) or rtl (the Verilated "
                    "cnc_core: soft reset mid-job presses its e-stop)");
  add_sender_options(sub, args->senders);
  sub->add_option("--settings", args->settings,
                  "grbl $ settings file (default $XDG_CONFIG_HOME/fpgacnc/grbl-settings.txt or "
                  "~/.config/fpgacnc/grbl-settings.txt)");
  sub->add_flag("--realtime", args->board.realtime,
                "tlm: simulated time follows the wall clock while the board is busy");
  sub->add_option("--speed", args->board.speed,
                  "with --realtime: simulated seconds per wall second (default 1)");
  sub->callback([args] {
    check_sender_choice(args->senders, "grbl");
    run(*args);
  });
}

}  // namespace fpgacnc::cli
