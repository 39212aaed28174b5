// Command-line glue for the simulated board, called by the fpgacnc tool (host/cli):
//   fpgacnc board [--config F] [--fst F] [--edges F.csv]
//   fpgacnc stream FILE (no --port) [--plot out.svg|.png] [--fst out.fst] [--edges out.csv]
#pragma once

#include <memory>
#include <string>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::simboard {

struct BoardCommandArgs {
  std::string config_path;  // machine configuration (clock, baud, step timing)
  std::string fst_path;     // FST waveform ("" = none)
  std::string edges_csv;    // edge list written at the end ("" = none)
};

// `fpgacnc board`: starts the simulated board in its own thread, prints
// "simulated board on /dev/pts/N (115200 baud)", serves any serial client until SIGINT or
// SIGTERM, then prints its figures (and writes the edge list). Returns the exit status.
int run_board_command(const BoardCommandArgs& args);

// Outputs of a stream to the in-process board.
struct SimOutputs {
  std::string plot_path;  // executed vs commanded path, .svg (or .png with rsvg-convert)
  std::string fst_path;   // FST waveform
  std::string edges_csv;  // edge list
};

// `fpgacnc stream` without --port: starts the simulated board in-process and returns a Link
// (a SerialLink on the board's pty, owning the board). Throws BoardError for a configuration
// the board cannot model (clock other than 50 MHz, baud other than 115200).
std::unique_ptr<link::Link> make_default_link(const config::MachineConfig& cfg,
                                              const SimOutputs& outputs);

// After a stream over a link made by make_default_link: stops the board, prints its figures
// (cycles, clocks/s, edges, net steps per axis from the edges vs the plan's final target) and
// writes the requested outputs. Returns false (and does nothing) for any other link.
bool report_board_run(link::Link& link, const plan::Plan& plan, const config::MachineConfig& cfg,
                      const SimOutputs& outputs);

}  // namespace fpgacnc::simboard
