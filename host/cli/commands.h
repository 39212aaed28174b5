// fpgacnc subcommands: one file per subcommand, each registering itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::cli {

// Options shared by subcommands that read a machine configuration.
struct CommonOptions {
  std::string config_path;          // --config
  double feed_override_pct = -1.0;  // --feed-override (negative: from config)
  std::string dialect;              // --dialect (empty: from config)
  std::string tool_table;           // --tool-table (empty: from config)
};

// The interpreter's part of a report: dialect and why, pauses/outputs/messages, warnings.
void print_gcode_report(const plan::Plan& p);
// "final position: steps X .. Y .. Z .. E|A ..; mm ..." of a plan.
void print_final_position(const plan::Plan& p);

// --dialect and --tool-table (the G-code options every command that reads G-code takes).
void add_gcode_options(CLI::App* sub, CommonOptions& opt);

// Loads the configuration (defaults when no --config) and applies command-line overrides.
config::MachineConfig load_config(const CommonOptions& opt);

void register_plan(CLI::App& app);

// Options of `stream` that only the simulated board can honour (--plot, --fst, --edges, and the
// line fault options --line-*, kept as (name, value) and applied by the board hooks).
struct SimOutputOptions {
  std::string plot_path;
  std::string fst_path;
  std::string edges_csv;
  std::vector<std::pair<std::string, std::string>> line_faults;
  // Which simulated board: "tlm" (the SystemC twins, twins::TwinBoard), "rtl" (the Verilated
  // cnc_core, SimBoard; also what "" means), "both" (stream: the lockstep comparison).
  std::string model;
  bool realtime = false;        // tlm: simulated time follows the wall clock
  size_t max_moves = SIZE_MAX;  // --model both: the first N moves (v2: motion frames)
  bool any() const {
    return !plot_path.empty() || !fst_path.empty() || !edges_csv.empty() || !line_faults.empty();
  }
};

// Hook for `stream` without --port: returns the link to use (e.g. start the simulated board).
// The default throws "no --port given and no simulated board built in".
using OpenDefaultLink = std::function<std::unique_ptr<link::Link>(const config::MachineConfig&,
                                                                  const SimOutputOptions&)>;
// Called after a successful stream over the default link (board figures, plot).
using AfterDefaultStream = std::function<void(
    link::Link&, const plan::Plan&, const config::MachineConfig&, const SimOutputOptions&)>;
// Adds options of the default link to a subcommand (the simulated board's --line-* options).
using AddSimOptions = std::function<void(CLI::App&, SimOutputOptions&)>;
// Heaters: adjusts the v2 options for a default link (the simulated board gives its
// plant clock and a faster STATUS poll; host/simboard scales thermal time).
using ConfigureDefaultV2 = std::function<void(link::Link&, link::StreamV2Options&)>;
// `stream --model both`: the job (the first max_moves moves) through the pty into the twin board
// and into the Verilated board with the lockstep host; throws when they differ.
using CompareBoards =
    std::function<void(const plan::Plan&, const config::MachineConfig&, const SimOutputOptions&)>;
struct StreamHooks {
  CompareBoards compare_boards;
  OpenDefaultLink open_default_link;
  AfterDefaultStream after_default_stream;
  AddSimOptions add_sim_options;
  ConfigureDefaultV2 configure_v2;
};
StreamHooks default_stream_hooks();
// Hooks that run the simulated board in-process (host/simboard).
StreamHooks simboard_stream_hooks();
void register_stream(CLI::App& app, StreamHooks hooks);

// fpgacnc board [--model tlm|rtl] [--realtime] [--config F] [--fst F] [--edges F.csv]: the
// simulated board alone on a pty.
void register_board(CLI::App& app);

// fpgacnc grbl [--port DEV | --model tlm|rtl] [--listen tcp:HOST:PORT] [--settings F]: grbl
// 1.1's protocol on a pty and TCP with the FPGA behind it (host/cli/grbl_cmd.cpp).
void register_grbl(CLI::App& app);

// fpgacnc jog [--port DEV | --model tlm|rtl] --feed F [--to] [--inch] X10 Y-2: one jog through
// the grbl front end's $J=, Ctrl-C the jog cancel (host/cli/jog_cmd.cpp).
void register_jog(CLI::App& app);

// fpgacnc grbl-bench [--moves N] [--feed F] [--baud B]: sender-side throughput of `fpgacnc grbl`
// on the simulated board (host/cli/grbl_bench_cmd.cpp).
void register_grbl_bench(CLI::App& app);

// fpgacnc marlin [--port DEV | --model tlm|rtl]: Marlin's host protocol on a pty with the FPGA
// behind it (host/cli/marlin_cmd.cpp).
void register_marlin(CLI::App& app);

// fpgacnc sim FILE [--model tlm|rtl|both]: a whole job on the twins or the Verilated RTL
// (host/cli/sim_cmd.cpp, built with systemc/).
void register_sim(CLI::App& app);

// fpgacnc autotune [--heater bed|hotend] [--setpoint C] [--relay-v V] ... [--port DEV]: relay
// test on a heater, proposes PID gains (host/cli/autotune_cmd.cpp). Without --port: the hooks'
// default link (the simulated board).
void register_autotune(CLI::App& app, StreamHooks hooks);

// fpgacnc home [--config F] [--port DEV --limit-switches LIST | --endstop AXIS-SIDE=MM]: the
// homing cycle ([homing]), the latched switch positions printed (host/cli/home_cmd.cpp).
void register_home(CLI::App& app);
// fpgacnc probe --axis A --dist MM --feed F [--away] [--no-error] [--port DEV | --probe-plate
// AXIS-SIDE=MM]: one probing move (G38.2 .. G38.5), the latched position printed
// (host/cli/probe_cmd.cpp).
void register_probe(CLI::App& app);

// fpgacnc status [--port DEV] [--config F]: one STATUS decoded (state, faults, the hard-limit
// alarm and switches, positions, counters; host/cli/status_cmd.cpp). Without --port: the hooks'
// default link (the simulated board).
void register_status(CLI::App& app, StreamHooks hooks);

}  // namespace fpgacnc::cli
