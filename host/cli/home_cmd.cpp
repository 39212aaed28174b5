// fpgacnc home [--config F] [--port DEV --limit-switches LIST | --endstop AXIS-SIDE=MM ...]: the
// homing cycle (link::HomingCycle, docs/machine.md "Homing and probing (host)") on a real board
// or on the Verilated simulated board with simulated endstops; prints each switch's latched
// position and the machine position it leaves. Runs whatever [homing] enabled says (it is the
// explicit request); the cycles, feeds, pull-off and directions come from [homing].
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "fpgacnc/frontend/motion.h"
#include "fpgacnc/link/homing.h"
#include "fpgacnc/link/v2_session.h"
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

namespace v2 = protocol::v2;

struct Args {
  CommonOptions common;
  BoardChoice board;
};

void run(const Args& args) {
  const config::MachineConfig cfg = load_config(args.common);
  BoardChoice choice = args.board;
  if (choice.port.empty() && choice.model != "rtl")
    throw std::invalid_argument(
        "fpgacnc home: the twin board has no limit switches; use --model rtl (the default)");
  BoardBehind board = open_board_behind(cfg, choice);
  if (!board.limit_switches) {
    throw std::invalid_argument(
        "fpgacnc home: the board has no limit switches (--limit-switches with --port)");
  }
  link::Link& lk = *board.link;
  const link::StreamV2Options opt = link::stream_v2_options(cfg);
  link::StreamV2Report rep;
  const v2::Ident ident = link::handshake_v2(lk, opt, rep, std::nullopt);
  std::unique_ptr<link::V2Session> session;
  bool first = true;
  // The first session sets the board up (MOTION rates and ramp, CONFIG_AXIS); the later ones of
  // the cycle only open (the board keeps both).
  auto open = [&]() -> link::V2Session& {
    session = std::make_unique<link::V2Session>(lk, opt, ident, rep);
    session->start();
    if (first) {
      session->configure_motion(link::machine_motion(cfg, ident.n_axes));
      frontend::push_config_axes(*session, ident, cfg);
      first = false;
    }
    return *session;
  };
  v2::Status wired;
  wired.switches = board.limit_switches;
  // describe_limits says "switches: X max, ..." for the switches set.
  fmt::print("homing on {} ({})\n", board.description, v2::describe_limits(wired, ident.n_axes));
  std::fflush(stdout);
  link::HomingCycle cycle(lk, cfg, ident, board.limit_switches, open);
  while (!cycle.step(std::chrono::milliseconds(5))) {
  }
  const link::HomingResult& r = cycle.result();
  if (session) {
    // The machine's soft limits again (the cycle switched the device's off), then at rest.
    link::V2Session& s = open();
    frontend::push_config_axes(s, ident, cfg);
    s.drain();
  }
  if (!r.ok) throw std::runtime_error(fmt::format("{} (grbl ALARM:{})", r.message, r.alarm));
  for (const auto& h : r.axes) {
    const double spm = cfg.steps_per_mm[h.axis];
    fmt::print(
        "{} {}: switch latched at step {} ({:.4f} mm; device counter {}), set to {:.4f} mm\n",
        config::kAxisNames[h.axis], h.max_side ? "max" : "min", h.latched,
        static_cast<double>(h.latched) / spm, h.latched_raw, static_cast<double>(h.home) / spm);
  }
  const v2::Status& st = session->last_status();
  std::string pos;
  for (size_t a = 0; a < st.position.size() && a < config::kAxes; ++a)
    pos += fmt::format("{}{} {:.4f}", pos.empty() ? "" : ", ", config::kAxisNames[a],
                       static_cast<double>(st.position[a]) / cfg.steps_per_mm[a]);
  fmt::print("homed: machine position {} mm\n", pos);
}

}  // namespace

void register_home(CLI::App& app) {
  auto args = std::make_shared<Args>();
  args->board.model = "rtl";
  auto* sub = app.add_subcommand(
      "home",
      "Run the homing cycle ([homing] of the configuration) on a --port or the Verilated "
      "simulated board with --endstop; prints the latched switch positions");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  add_board_options(sub, args->board,
                    "simulated board: rtl (the Verilated cnc_core with limit switches, default)");
  sub->callback([args] { run(*args); });
}

}  // namespace fpgacnc::cli
