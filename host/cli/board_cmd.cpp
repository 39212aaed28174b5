// fpgacnc board [--model tlm|rtl] [--realtime] [--config F] [--fst F] [--edges F.csv]
//               [--line-* ...]: a simulated board alone on a pseudo-terminal; prints its
// /dev/pts/N path and serves any serial client until Ctrl-C / SIGTERM; SIGUSR1 / SIGUSR2 press /
// release the e-stop (--model rtl), --endstop places simulated endstops (rtl), --control PATH
// listens on a control socket (hold / start buttons, e-stop, limit switches, state; keys h, s, e
// on a terminal). `tlm` (default): the
// SystemC twins of cnc_core (twins::TwinBoard, event-driven, proven edge-for-edge equal to the
// RTL); `rtl`: the Verilated cnc_core (SimBoard: heaters, line faults, FST waveforms). Also the
// hooks that put a board behind `stream` without --port, and `stream --model both`.
#include <fmt/format.h>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/twins/pty_lockstep.h"
#include "fpgacnc/twins/twin_board.h"

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
           std::string(o.help) + " (--model rtl)")
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

// What the twin board cannot do, as an error naming the option.
void check_tlm_options(const std::string& what, bool fst, bool line_faults) {
  if (fst) {
    throw std::invalid_argument(
        fmt::format("{}: --fst needs the Verilated board (--model rtl): the twins have no "
                    "waveform",
                    what));
  }
  if (line_faults) {
    throw std::invalid_argument(
        fmt::format("{}: --line-* fault injection needs the Verilated board (--model rtl)", what));
  }
}

std::unique_ptr<twins::TwinBoard> make_twin_board(const config::MachineConfig& cfg, bool realtime,
                                                  bool record_tx = false) {
  twins::TwinBoardOptions o = twins::TwinBoard::options_from_config(cfg);
  o.realtime = realtime;
  o.record_tx = record_tx;
  return std::make_unique<twins::TwinBoard>(o);
}

void print_lockstep(const twins::LockstepRun& r, double clk_hz) {
  const auto& s = r.stats;
  const auto n = models::net_steps(r.edges);
  fmt::print(
      "{} board: {} cycles ({:.3f} s of machine time) in {:.2f} s wall ({:.2f} M clocks/s), {} "
      "batches, {} answer bytes, {} edges (TX included), {} moves done, net steps X {} Y {} Z {} "
      "E {}\n",
      r.model, s.cycles, static_cast<double>(s.cycles) / clk_hz, r.wall_s,
      r.wall_s > 0 ? static_cast<double>(s.cycles) / r.wall_s / 1e6 : 0.0, r.batches,
      r.received.size(), r.edges.size(), s.moves_done, n[0], n[1], n[2], n[3]);
  std::fflush(stdout);
}

// `stream --model both`: the lockstep host (pty_lockstep.h) through both ptys.
void compare_boards(const plan::Plan& p, const config::MachineConfig& cfg,
                    const SimOutputOptions& o) {
  check_tlm_options("--model both", !o.fst_path.empty(), !o.line_faults.empty());
  if (o.realtime) throw std::invalid_argument("--model both: --realtime is for --model tlm");
  const std::string proto = cfg.protocol == "auto" ? "v2" : cfg.protocol;
  twins::HostScript script;
  if (proto == "v1") {
    script.v1 = twins::job_packets(protocol::v1::pack_job(p), cfg.clk_hz, o.max_moves);
  } else {
    script.v2 = twins::job_script(
        protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg, {.heaters = false}), o.max_moves);
    // The twins report idle heaters in STATUS, the Verilated board its plants: no STATUS.
    script.v2->status_at_end = false;
  }
  const std::string moves = o.max_moves == SIZE_MAX
                                ? std::string("the whole job")
                                : fmt::format("the first {} moves", o.max_moves);
  fmt::print(
      "{}: {} with protocol {} through the pty into the twin board (tlm), then the Verilated "
      "board (rtl); lockstep host: each batch written when the board is idle for the host\n",
      p.source, moves, proto);
  std::fflush(stdout);
  const auto limit = std::chrono::milliseconds(600'000);
  const double clk = static_cast<double>(cfg.clk_hz);
  auto tlm_board = make_twin_board(cfg, false, true);
  const auto tlm = twins::run_lockstep(*tlm_board, script, cfg.clk_hz, cfg.baud, limit);
  if (!tlm_board->error().empty()) throw std::runtime_error(tlm_board->error());
  print_lockstep(tlm, clk);
  simboard::BoardOptions ro = simboard::SimBoard::options_from_config(cfg);
  ro.record_tx = true;
  simboard::SimBoard rtl_board(ro);
  const auto rtl = twins::run_lockstep(rtl_board, script, cfg.clk_hz, cfg.baud, limit);
  print_lockstep(rtl, clk);
  const std::string d = twins::compare_lockstep(rtl, tlm, clk, cfg.baud);
  if (!d.empty()) {
    fmt::print("rtl vs tlm behind the pty: DIFFER: {}\n", d);
    throw std::runtime_error("the twin board and the Verilated board differ");
  }
  fmt::print(
      "rtl vs tlm behind the pty: identical ({} edges with every answer bit on TX, {} answer "
      "bytes at the same clocks, same bytes read by the host); twin board {:.0f}x faster\n",
      rtl.edges.size(), rtl.received.size(), tlm.wall_s > 0 ? rtl.wall_s / tlm.wall_s : 0.0);
}

}  // namespace

StreamHooks simboard_stream_hooks() {
  StreamHooks h;
  h.compare_boards = compare_boards;
  h.open_default_link = [](const config::MachineConfig& cfg, const SimOutputOptions& o) {
    const simboard::SimOutputs outs{o.plot_path, o.fst_path, o.edges_csv};
    if (o.model == "tlm") {
      check_tlm_options("--model tlm", !o.fst_path.empty(), !o.line_faults.empty());
      return simboard::make_board_link(make_twin_board(cfg, o.realtime), cfg.baud, outs);
    }
    if (o.realtime) {
      throw std::invalid_argument(
          "--realtime needs --model tlm: the Verilated board runs slower than real time");
    }
    simboard::LineFaults faults;
    for (const auto& [name, value] : o.line_faults) apply_line_fault(faults, name, value);
    return simboard::make_default_link(cfg, outs, faults);
  };
  h.add_sim_options = [](CLI::App& sub, SimOutputOptions& o) {
    add_line_fault_options(sub, [&o](const std::string& name, const std::string& v) {
      o.line_faults.emplace_back(name, v);
    });
  };
  // Heaters: plant time of the Verilated board (scaled thermal time) and a STATUS poll that
  // keeps up with it (docs/heater.md "Simulated board"). The twin board has no heaters.
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
  struct Args {
    simboard::BoardCommandArgs board;
    std::vector<std::string> endstops;
    simboard::SwitchNoise noise;
    std::string probe_plate;
    std::string model = "tlm";
    bool realtime = false;
  };
  auto args = std::make_shared<Args>();
  auto* sub = app.add_subcommand(
      "board",
      "Run a simulated board on a pseudo-terminal until Ctrl-C: the SystemC twins (tlm, default) "
      "or the Verilated cnc_core (rtl)");
  sub->add_option("--model", args->model,
                  "tlm: the SystemC twins of cnc_core (default; fast, event-driven, edge-for-edge "
                  "equal to the RTL; no heaters, no line faults, no e-stop); rtl: the Verilated "
                  "cnc_core (about 1.6 M clocks/s; heaters, --line-*, --fst, e-stop by SIGUSR1 / "
                  "SIGUSR2, limit switches, feed hold and cycle start buttons by --control)")
      ->check(CLI::IsMember({"tlm", "rtl"}));
  sub->add_flag("--realtime", args->realtime,
                "tlm: simulated time follows the wall clock while the board is busy (a 5-minute "
                "job takes 5 minutes; STATUS shows true progress)");
  sub->add_option("--config", args->board.config_path, "machine configuration (TOML): step timing");
  sub->add_option("--fst", args->board.fst_path, "write an FST waveform of the core (rtl)");
  sub->add_option("--edges", args->board.edges_csv,
                  "write the STEP/DIR/LASER edge list (CSV) at exit");
  sub->add_option("--endstop", args->endstops,
                  "rtl: a simulated endstop, AXIS-SIDE=MM (x-max=200, z-min=-5): the switch is "
                  "pressed while the axis is at or beyond MM (machine position from reset); "
                  "SIGHUP pulls the carriages off their endstops by hand (repeatable)")
      ->type_name("AXIS-SIDE=MM");
  sub->add_option("--endstop-bounce", args->noise.bounce_clks,
                  "rtl: each endstop change bounces: 2 to 6 more toggles of its pin within this "
                  "many clocks (default 0: clean)")
      ->type_name("CLOCKS");
  sub->add_option("--endstop-jitter", args->noise.jitter_steps,
                  "rtl: each actuation of an endstop trips up to this many steps before or "
                  "after its position (uniform; default 0)")
      ->type_name("STEPS")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--endstop-seed", args->noise.seed, "rtl: seed of the bounce and jitter")
      ->type_name("N");
  sub->add_option("--probe-plate", args->probe_plate,
                  "rtl: a simulated probe plate, AXIS-SIDE=MM (z-min=-2: the probe touches while "
                  "Z is at or below -2 mm, machine position from reset; x-max=5: at or above)")
      ->type_name("AXIS-SIDE=MM");
  sub->add_option("--control", args->board.control_path,
                  "listen on a Unix-domain control socket at PATH (removed at exit): one command "
                  "a line, answered 'ok ...' or 'error: ...': hold, start (rtl: the feed hold "
                  "and cycle start buttons), estop on|off, limit AXIS min|max on|off (rtl), "
                  "probe on|off (rtl), state, help (docs/protocol.md \"The simulated board\")")
      ->type_name("PATH");
  add_line_fault_options(*sub, [args](const std::string& name, const std::string& v) {
    apply_line_fault(args->board.line_faults, name, v);
  });
  sub->callback([args] {
    config::MachineConfig cfg;
    if (!args->board.config_path.empty())
      cfg = config::load_machine_config(args->board.config_path);
    std::unique_ptr<simboard::Board> board;
    if (args->model == "tlm") {
      check_tlm_options("fpgacnc board --model tlm", !args->board.fst_path.empty(),
                        args->board.line_faults.any());
      if (!args->endstops.empty() || args->noise.bounce_clks || args->noise.jitter_steps)
        throw std::invalid_argument(
            "fpgacnc board: --endstop*: the twin board has no limit switches; use --model rtl");
      if (!args->probe_plate.empty())
        throw std::invalid_argument(
            "fpgacnc board: --probe-plate: the twin board (tlm) models neither the probe input "
            "nor the trigger; use --model rtl");
      board = make_twin_board(cfg, args->realtime);
    } else {
      if (args->realtime) {
        throw std::invalid_argument(
            "fpgacnc board: --realtime needs --model tlm (the Verilated board runs slower than "
            "real time)");
      }
      simboard::BoardOptions o = simboard::SimBoard::options_from_config(cfg);
      o.fst_path = args->board.fst_path;
      o.line_faults = args->board.line_faults;
      for (const auto& e : args->endstops)
        o.endstops.push_back(simboard::parse_endstop_option(e, cfg));
      o.switch_noise = args->noise;
      if (!args->probe_plate.empty())
        o.probe_plate = simboard::parse_probe_plate_option(args->probe_plate, cfg);
      board = std::make_unique<simboard::SimBoard>(o);
    }
    const int rc = simboard::run_board_command(args->board, *board, cfg.baud);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace fpgacnc::cli
