// Command-line glue for the simulated boards (any simboard::Board: the Verilated SimBoard or the
// twins' TwinBoard, chosen by host/cli), called by the fpgacnc tool:
//   fpgacnc board [--model tlm|rtl] [--config F] [--fst F] [--edges F.csv]
//   fpgacnc stream FILE (no --port) [--model tlm|rtl] [--plot out.svg|.png] [--fst out.fst]
//                  [--edges out.csv]
// and, for the Verilated board, the line fault options (parse_line_fault_option).
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/simboard/line_faults.h"
#include "fpgacnc/simboard/sim_board.h"

namespace fpgacnc::simboard {

struct BoardCommandArgs {
  std::string config_path;   // machine configuration (clock, baud, step timing)
  std::string fst_path;      // FST waveform ("" = none)
  std::string edges_csv;     // edge list written at the end ("" = none)
  LineFaults line_faults;    // serial line fault injection (default none)
  std::string control_path;  // control socket (Unix-domain stream socket; "" = none)
};

// One line of the board's control protocol (docs/protocol.md "The simulated board": hold,
// start, estop on|off, limit AXIS min|max on|off, state, help) applied to `board`; returns the
// answer without its newline: "ok ..." or "error: <why>" naming the word it could not take.
std::string board_control_command(Board& board, std::string_view line);

// Line fault options shared by `fpgacnc board` and `fpgacnc stream` (simulated board):
//   --line-ber P[,Q]        bit error rate, P host->board (per UART bit) and Q board->host (per
//                           data bit); one value sets both
//   --line-drop P           probability a host byte is dropped
//   --line-dup P            probability a host byte is duplicated
//   --line-lose-frames P    probability a whole device frame is lost (lost ACKs)
//   --line-stall CYCLE:CLOCKS  hold the host->board line from simulated cycle CYCLE for CLOCKS
//                           clocks (50 MHz: 200 ms = 10000000); bN:CLOCKS holds it before the
//                           N-th byte on the line (0-based); repeatable
//   --line-seed N           seed of the fault generator (default 1)
struct LineFaultOption {
  const char* name;  // "--line-ber"
  const char* value_name;
  const char* help;
};
std::span<const LineFaultOption> line_fault_options();
// Applies one option (`name` with or without the leading "--") to `faults`. Returns false when
// `name` is not a line fault option; throws std::invalid_argument naming the option for a bad
// value (not a number, probability outside [0, 1], stall of 0 clocks).
bool parse_line_fault_option(std::string_view name, std::string_view value, LineFaults& faults);

// --endstop AXIS-SIDE=MM (x-max=200, z-min=-5): a simulated endstop of the Verilated board at MM
// (steps from `cfg`'s steps/mm). Throws std::invalid_argument naming the option for a bad value.
Endstop parse_endstop_option(std::string_view value, const config::MachineConfig& cfg);
// --probe-plate AXIS-SIDE=MM (z-min=-2: the probe touches while Z is at or below -2 mm; x-max=5:
// at or above 5 mm): a simulated probe plate of the Verilated board (steps from `cfg`'s
// steps/mm). Throws std::invalid_argument naming the option for a bad value.
ProbePlate parse_probe_plate_option(std::string_view value, const config::MachineConfig& cfg);
// --limit-switches x-min,x-max,...: the switches a real board wires (its LIMIT_ENABLE), as
// STATUS's switch bits (bit a min of axis a, bit 8 + a max); "" = none. Throws
// std::invalid_argument naming the option for an unknown name.
uint16_t parse_limit_switches_option(std::string_view value);

// `fpgacnc board`: starts `board` (not started yet) in its own thread, prints
// "simulated board (MODEL) on /dev/pts/N (115200 baud)", serves any serial client until SIGINT
// or SIGTERM, then prints its figures (and writes the edge list). SIGUSR1 presses the board's
// e-stop input, SIGUSR2 releases it (Board::set_estop; a board without one prints why and goes
// on); SIGHUP pulls the carriages off their simulated endstops (SimBoard::pull_off_endstops).
// With args.control_path it listens on a Unix-domain stream socket there (printed after the pty
// line, removed at exit; a path that exists and is not a stale socket is an error before the
// board starts) and answers board_control_command() for each line of each client. When stdin is
// a terminal, keys press the buttons: h feed hold, s cycle start, e e-stop toggle. Returns the
// exit status.
int run_board_command(const BoardCommandArgs& args, Board& board, uint32_t baud);
// The figures of a board (cycles, machine time, clocks/s, bytes, edges, moves; line faults and
// heaters for the Verilated board).
void print_board_figures(const Board& board);

// Outputs of a stream to the in-process board.
struct SimOutputs {
  std::string plot_path;  // executed vs commanded path, .svg (or .png with rsvg-convert)
  std::string fst_path;   // FST waveform
  std::string edges_csv;  // edge list
};

// `fpgacnc stream` without --port: starts the simulated board in-process and returns a Link
// (a SerialLink on the board's pty, owning the board). Throws BoardError for a configuration
// the board cannot model (clock other than 50 MHz, baud other than 115200). `line_faults`:
// fault injection on the simulated line (parse_line_fault_option), none by default.
std::unique_ptr<link::Link> make_default_link(const config::MachineConfig& cfg,
                                              const SimOutputs& outputs,
                                              const LineFaults& line_faults = {});
// The same for any board (not started yet; started here): a BoardLink on its pty.
std::unique_ptr<link::Link> make_board_link(std::unique_ptr<Board> board, uint32_t baud,
                                            const SimOutputs& outputs);

// After a stream over a link made by make_default_link or make_board_link: stops the board, prints
// its figures (cycles, clocks/s, edges, injected line faults, net steps per axis from the edges vs
// the plan's final target) and writes the requested outputs. Returns false (and does nothing) for
// any other link.
bool report_board_run(link::Link& link, const plan::Plan& plan, const config::MachineConfig& cfg,
                      const SimOutputs& outputs);

// Heaters: for a link to a Verilated SimBoard, the board's plant clock (plant
// seconds, SimBoard::plant_seconds) and the board itself; empty / null for any other link
// (the twin board has no heaters).
std::function<double()> plant_clock(link::Link& link);
SimBoard* board_of(link::Link& link);
// The board behind a link made by make_default_link / make_board_link; null for any other link.
Board* any_board_of(link::Link& link);

}  // namespace fpgacnc::simboard
