// fpgacnc probe --axis X|Y|Z --dist MM --feed MM_MIN [--away] [--no-error] [--config F]
// [--port DEV | --probe-plate AXIS-SIDE=MM]: one probing move (link::ProbeCycle, docs/machine.md
// "Homing and probing (host)") from where the machine is, on a real board or on the Verilated
// simulated board with a simulated probe plate; prints the position latched at the probe's edge
// and where the machine stopped. G38.2 by default; --away probes for the release (G38.4),
// --no-error makes a miss a result instead of a failure (G38.3 / G38.5).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "fpgacnc/frontend/motion.h"
#include "fpgacnc/link/probe.h"
#include "fpgacnc/link/v2_session.h"
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

struct ProbeArgs {
  CommonOptions common;
  BoardChoice board;
  std::string axis;
  double dist = 0.0;
  double feed = 0.0;
  bool away = false;
  bool no_error = false;
};

// "X 0.0000, Y 0.0000, Z -2.0000 mm (steps 0, 0, -800)"
std::string probe_position(const std::vector<int32_t>& steps, const config::MachineConfig& cfg) {
  std::string mm, st;
  for (size_t a = 0; a < 3 && a < steps.size(); ++a) {
    mm += fmt::format("{}{} {:.4f}", a ? ", " : "", config::kAxisNames[a],
                      static_cast<double>(steps[a]) / cfg.steps_per_mm[a]);
    st += fmt::format("{}{}", a ? ", " : "", steps[a]);
  }
  return fmt::format("{} mm (steps {})", mm, st);
}

void run_probe(const ProbeArgs& args) {
  const config::MachineConfig cfg = load_config(args.common);
  const std::string axes = "xyzXYZ";
  if (args.axis.size() != 1 || axes.find(args.axis[0]) == std::string::npos)
    throw std::invalid_argument(
        fmt::format("fpgacnc probe: --axis {}: expected x, y or z", args.axis));
  const size_t axis = axes.find(args.axis[0]) % 3;
  if (!(std::isfinite(args.dist) && args.dist != 0.0))
    throw std::invalid_argument("fpgacnc probe: --dist: a distance other than 0 (mm)");
  if (!(std::isfinite(args.feed) && args.feed > 0.0))
    throw std::invalid_argument("fpgacnc probe: --feed: a feed > 0 (mm/min)");
  if (args.board.port.empty() && args.board.model != "rtl")
    throw std::invalid_argument(
        "fpgacnc probe: the twin board has no probe input or trigger; use --model rtl (the "
        "default)");
  BoardBehind board = open_board_behind(cfg, args.board);
  link::Link& lk = *board.link;
  const link::StreamV2Options opt = link::stream_v2_options(cfg);
  link::StreamV2Report rep;
  const protocol::v2::Ident ident = link::handshake_v2(lk, opt, rep, std::nullopt);
  if (ident.n_axes <= axis)
    throw std::runtime_error(fmt::format("fpgacnc probe: the board has {} axes: no {}",
                                         ident.n_axes, config::kAxisNames[axis]));
  std::unique_ptr<link::V2Session> session;
  auto open = [&]() -> link::V2Session& {
    session = std::make_unique<link::V2Session>(lk, opt, ident, rep);
    session->start();
    return *session;
  };
  // The first session sets the board up (MOTION's ramp: the stop after the contact; CONFIG_AXIS
  // and the travel) and tells where the machine is.
  {
    link::V2Session& s = open();
    s.configure_motion(link::machine_motion(cfg, ident.n_axes));
    frontend::push_config_axes(s, ident, cfg);
    s.drain();
  }
  const auto& start = session->last_status().position;
  link::ProbeRequest req;
  for (size_t a = 0; a < 3 && a < start.size(); ++a)
    req.target_mm[a] = static_cast<double>(start[a]) / cfg.steps_per_mm[a];
  req.target_mm[axis] += args.dist;
  req.feed_mm_min = args.feed;
  req.toward = !args.away;
  req.error_on_miss = !args.no_error;
  const char* code = req.toward ? (req.error_on_miss ? "G38.2" : "G38.3")
                                : (req.error_on_miss ? "G38.4" : "G38.5");
  fmt::print("probing on {}: {} {:+.4f} mm at {:g} mm/min for the {} ({})\n", board.description,
             config::kAxisNames[axis], args.dist, args.feed, req.toward ? "contact" : "release",
             code);
  std::fflush(stdout);
  link::ProbeCycle cycle(lk, cfg, ident, req, open);
  while (!cycle.step(std::chrono::milliseconds(5))) {
  }
  const link::ProbeResult& r = cycle.result();
  if (r.alarm) throw std::runtime_error(fmt::format("{} (grbl ALARM:{})", r.message, r.alarm));
  if (r.found) {
    fmt::print("{}: latched at {}\n", req.toward ? "contact" : "release",
               probe_position(r.latched, cfg));
    const int64_t past = static_cast<int64_t>(r.final_position[axis]) - r.latched[axis];
    fmt::print("stopped at {}: {} steps ({:.4f} mm) past the latch along {}\n",
               probe_position(r.final_position, cfg), past < 0 ? -past : past,
               static_cast<double>(past < 0 ? -past : past) / cfg.steps_per_mm[axis],
               config::kAxisNames[axis]);
  } else {
    fmt::print("no {} within the move: stopped at {}\n", req.toward ? "contact" : "release",
               probe_position(r.final_position, cfg));
  }
}

}  // namespace

void register_probe(CLI::App& app) {
  auto args = std::make_shared<ProbeArgs>();
  args->board.model = "rtl";
  auto* sub = app.add_subcommand(
      "probe",
      "One probing move (G38.2; --away: G38.4) on a --port or the Verilated simulated board with "
      "--probe-plate; prints the latched position and where the machine stopped");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--axis", args->axis, "the axis to move: x, y or z")->required();
  sub->add_option("--dist", args->dist, "distance from the machine's position, mm (signed)")
      ->required();
  sub->add_option("--feed", args->feed, "probing feed, mm/min")->required();
  sub->add_flag("--away", args->away,
                "probe away from the contact: stop at the release (G38.4 / G38.5)");
  sub->add_flag("--no-error", args->no_error,
                "no contact (release) within the move is a result, not an error (G38.3 / G38.5)");
  add_board_options(sub, args->board,
                    "simulated board: rtl (the Verilated cnc_core with the probe input, default)");
  sub->callback([args] { run_probe(*args); });
}

}  // namespace fpgacnc::cli
