// fpgacnc: command-line host. Subcommands live in one file each and register here.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"fpgacnc: FPGA CNC controller host (plan and stream G-code jobs)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "fpgacnc 0.1.0");

  fpgacnc::cli::register_plan(app);
  // Without --port, `stream` runs the simulated board in-process (board_cmd.cpp).
  fpgacnc::cli::register_stream(app, fpgacnc::cli::simboard_stream_hooks());
  fpgacnc::cli::register_board(app);
  fpgacnc::cli::register_grbl(app);
  fpgacnc::cli::register_jog(app);
  fpgacnc::cli::register_grbl_bench(app);
  fpgacnc::cli::register_marlin(app);
  fpgacnc::cli::register_sim(app);
  fpgacnc::cli::register_autotune(app, fpgacnc::cli::simboard_stream_hooks());
  fpgacnc::cli::register_status(app, fpgacnc::cli::simboard_stream_hooks());
  fpgacnc::cli::register_home(app);
  fpgacnc::cli::register_probe(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fflush(stdout);
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  }
  return 0;
}
