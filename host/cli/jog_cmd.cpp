// fpgacnc jog [--config F] [--port DEV | --model tlm|rtl] --feed F [--to] [--inch] AXIS...: one
// jog (docs/grbl.md "Jogging"), through the grbl front end's `$J=` in-process: by a distance
// (default) or to machine coordinates (--to), the laser and spindle off; Ctrl-C is the jog cancel
// (the board decelerates with its hold ramp and stops on the path). Prints where it stopped.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/grbl/settings.h"
#include "interrupt_guard.h"
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

struct JogArgs {
  CommonOptions common;
  BoardChoice board;
  double feed = 0.0;
  bool to = false;
  bool inch = false;
  std::vector<std::string> axes;  // "X10", "Y-2.5"
};

// "X10" / "x=10" -> "X10"; throws naming the word otherwise.
std::string jog_word(const std::string& w) {
  std::string s;
  for (char c : w)
    if (c != '=') s += c;
  if (s.size() < 2 || std::string("XYZxyz").find(s[0]) == std::string::npos)
    throw std::invalid_argument(
        fmt::format("jog: '{}' is not an axis and a value (X10, Y-2.5)", w));
  size_t used = 0;
  try {
    (void)std::stod(s.substr(1), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() - 1)
    throw std::invalid_argument(fmt::format("jog: '{}': the value is not a number", w));
  s[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

void run_jog(const JogArgs& args) {
  std::string line =
      fmt::format("$J={} {}", args.inch ? "G20" : "G21", args.to ? "G53 G90" : "G91");
  for (const auto& w : args.axes) line += " " + jog_word(w);
  line += fmt::format(" F{:g}", args.feed);

  const config::MachineConfig cfg = load_config(args.common);
  BoardBehind board = open_board_behind(cfg, args.board);
  grbl::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  eo.limit_switches = board.limit_switches;
  grbl::Engine engine(*board.link, cfg, grbl::settings_from_config(cfg), eo);
  engine.connect();
  engine.take_output();
  if (!engine.motion_available())
    throw std::runtime_error(fmt::format(
        "jog: {} has no motion rate (MOTION): a jog could not be cancelled", board.description));

  InterruptGuard interrupts;
  engine.receive(line + "\n");
  std::string out, answer;
  bool cancelled = false;
  for (;;) {
    engine.step(std::chrono::milliseconds(10));
    out += engine.take_output();
    if (answer.empty()) {
      for (size_t nl; answer.empty() && (nl = out.find('\n')) != std::string::npos;) {
        std::string l = out.substr(0, nl);
        out.erase(0, nl + 1);
        if (!l.empty() && l.back() == '\r') l.pop_back();
        if (l == "ok" || l.rfind("error:", 0) == 0) answer = l;
      }
      if (answer.rfind("error:", 0) == 0) {
        throw std::invalid_argument(
            fmt::format("jog: `{}` refused: grbl {} (docs/grbl.md \"Errors\")", line, answer));
      }
    }
    if (interrupts.take() > 0 && !cancelled) {
      engine.receive("\x85");
      cancelled = true;
      fmt::print("jog cancel: decelerating\n");
      std::fflush(stdout);
    }
    if (!answer.empty() && !engine.busy() && engine.state() == grbl::State::kIdle) break;
  }
  // A STATUS after the stop: the position is the board's step counters.
  engine.receive("?");
  while (engine.busy()) engine.step(std::chrono::milliseconds(10));
  const auto p = engine.mpos();
  fmt::print("{} at MPos X {:.3f} Y {:.3f} Z {:.3f} (mm, the board's step counters)\n",
             cancelled ? "jog cancelled" : "jog done", p[0], p[1], p[2]);
}

}  // namespace

void register_jog(CLI::App& app) {
  auto args = std::make_shared<JogArgs>();
  auto* sub = app.add_subcommand(
      "jog",
      "Jog by a distance (or --to machine coordinates) at --feed, as grbl's $J=; Ctrl-C cancels "
      "with a controlled stop");
  sub->add_option("axes", args->axes, "axis words: X10 Y-2.5 (mm, or inches with --inch)")
      ->required();
  sub->add_option("--feed,-F", args->feed, "feed, mm/min (in/min with --inch)")
      ->required()
      ->check(CLI::PositiveNumber);
  sub->add_flag("--to", args->to, "move to machine coordinates (G53) instead of by a distance");
  sub->add_flag("--inch", args->inch, "the values are inches");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  add_board_options(sub, args->board, "simulated board: tlm (the SystemC twins, default) or rtl");
  sub->add_flag("--realtime", args->board.realtime,
                "tlm: simulated time follows the wall clock while the board is busy");
  sub->callback([args] { run_jog(*args); });
}

}  // namespace fpgacnc::cli
