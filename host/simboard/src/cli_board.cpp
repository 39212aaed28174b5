#include "fpgacnc/simboard/cli_board.h"

#include <fmt/format.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "fpgacnc/simboard/plot.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace fpgacnc::simboard {
namespace {

void print_sim_extras(const SimBoard& b, const BoardStats& s) {
  if (b.options().line_faults.any()) {
    fmt::print("simulated board: line faults ({}): {}\n", b.options().line_faults.describe(),
               describe(s.line));
  }
  const ThermalStats t = b.thermal();
  if (t.ticks) {
    fmt::print(
        "simulated board heaters: {} sample ticks = {} plant seconds (1 per {} clocks); hot end "
        "{:.1f} degC, bed {:.1f} degC; ADC timing violations {}{}\n",
        t.ticks, t.ticks, SimBoard::kSampleClks, t.plant_c[0], t.plant_c[1], t.adc_violations,
        t.adc_violations ? " (" + t.adc_first_violation + ")" : std::string());
  }
}

constexpr LineFaultOption kLineFaultOptions[] = {
    {"--line-ber", "P[,Q]",
     "bit error rate on the simulated line: P host->board (per UART bit), Q board->host (per "
     "data bit); one value sets both"},
    {"--line-drop", "P", "probability that a host->board byte is dropped"},
    {"--line-dup", "P", "probability that a host->board byte is duplicated"},
    {"--line-lose-frames", "P", "probability that a whole device frame (ACK, ...) is lost"},
    {"--line-stall", "CYCLE:CLOCKS",
     "hold the host->board line from simulated cycle CYCLE for CLOCKS clocks (bN:CLOCKS: before "
     "the N-th byte on the line); repeatable"},
    {"--line-seed", "N", "seed of the line fault generator (default 1)"},
};

[[noreturn]] void bad_value(std::string_view name, std::string_view value, std::string_view why) {
  throw std::invalid_argument(fmt::format("--{}: invalid value '{}': {}", name, value, why));
}

uint64_t parse_u64(std::string_view name, std::string_view v) {
  uint64_t x = 0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size()) {
    bad_value(name, v, "expected a non-negative integer");
  }
  return x;
}

double parse_probability(std::string_view name, std::string_view v) {
  double x = 0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size()) {
    bad_value(name, v, "expected a number");
  }
  if (!(x >= 0.0 && x <= 1.0)) bad_value(name, v, "a probability must be in [0, 1]");
  return x;
}

}  // namespace

void print_board_figures(const Board& b) {
  const BoardStats s = b.stats();
  fmt::print(
      "simulated board ({}): {} cycles ({:.3f} s of machine time), {:.2f} M clocks/s ({:.2f} s "
      "simulating, {:.2f} s wall), {} bytes in, {} bytes out, {} edges, {} moves done\n",
      b.model(), s.cycles, static_cast<double>(s.cycles) / b.clk_hz(), s.clocks_per_s / 1e6,
      s.sim_wall_s, s.wall_s, s.bytes_in, s.bytes_out, s.edges, s.moves_done);
  if (const auto* sim = dynamic_cast<const SimBoard*>(&b)) print_sim_extras(*sim, s);
  if (s.frame_errors || s.timeouts || s.violations) {
    fmt::print(
        "simulated board: {} framing errors, {} packet timeouts, {} step timing violations\n",
        s.frame_errors, s.timeouts, s.violations);
  }
}

std::span<const LineFaultOption> line_fault_options() {
  return kLineFaultOptions;
}

bool parse_line_fault_option(std::string_view name, std::string_view value, LineFaults& f) {
  if (name.starts_with("--")) name.remove_prefix(2);
  if (name == "line-ber") {
    const size_t comma = value.find(',');
    if (comma == std::string_view::npos) {
      f.ber_to_board = f.ber_to_host = parse_probability(name, value);
    } else {
      f.ber_to_board = parse_probability(name, value.substr(0, comma));
      f.ber_to_host = parse_probability(name, value.substr(comma + 1));
    }
  } else if (name == "line-drop") {
    f.drop = parse_probability(name, value);
  } else if (name == "line-dup") {
    f.dup = parse_probability(name, value);
  } else if (name == "line-lose-frames") {
    f.lose_frames = parse_probability(name, value);
  } else if (name == "line-seed") {
    f.seed = parse_u64(name, value);
  } else if (name == "line-stall") {
    const size_t colon = value.find(':');
    if (colon == std::string_view::npos) bad_value(name, value, "expected CYCLE:CLOCKS");
    LineStall s;
    std::string_view at = value.substr(0, colon);
    if (at.starts_with('b')) {
      s.trigger = LineStall::Trigger::kBytes;
      at.remove_prefix(1);
    }
    s.at = parse_u64(name, at);
    s.clocks = parse_u64(name, value.substr(colon + 1));
    if (s.clocks == 0) bad_value(name, value, "a stall must last at least 1 clock");
    f.stalls.push_back(s);
  } else {
    return false;
  }
  return true;
}

Endstop parse_endstop_option(std::string_view v, const config::MachineConfig& cfg) {
  const size_t eq = v.find('=');
  const std::string sw(v.substr(0, eq));
  const std::string axes = "xyz";
  const bool ok_name = sw.size() == 5 && axes.find(sw[0]) != std::string::npos &&
                       (sw.substr(1) == "-min" || sw.substr(1) == "-max");
  const std::string num(eq == std::string_view::npos ? std::string_view() : v.substr(eq + 1));
  char* end = nullptr;
  const double mm = std::strtod(num.c_str(), &end);
  if (!ok_name || num.empty() || *end || !std::isfinite(mm)) {
    throw std::invalid_argument(
        fmt::format("--endstop {}: expected AXIS-SIDE=MM with AXIS x, y or z and SIDE min or max "
                    "(e.g. x-max=200)",
                    v));
  }
  Endstop e;
  e.axis = static_cast<int>(axes.find(sw[0]));
  e.max_side = sw.substr(1) == "-max";
  e.position =
      static_cast<int64_t>(std::llround(mm * cfg.steps_per_mm[static_cast<size_t>(e.axis)]));
  return e;
}

uint16_t parse_limit_switches_option(std::string_view value) {
  uint16_t bits = 0;
  size_t b = 0;
  while (b < value.size()) {
    size_t e = value.find(',', b);
    if (e == std::string_view::npos) e = value.size();
    const std::string sw(value.substr(b, e - b));
    const std::string axes = "xyz";
    if (sw.size() != 5 || axes.find(sw[0]) == std::string::npos ||
        (sw.substr(1) != "-min" && sw.substr(1) != "-max")) {
      throw std::invalid_argument(fmt::format(
          "--limit-switches {}: '{}' is not a switch (x-min, x-max, y-min, y-max, z-min, z-max)",
          value, sw));
    }
    bits = static_cast<uint16_t>(bits | (1u << (axes.find(sw[0]) + (sw[2] == 'a' ? 8 : 0))));
    b = e + 1;
  }
  return bits;
}

int run_board_command(const BoardCommandArgs& args, Board& board, uint32_t baud) {
  // SIGINT/SIGTERM (stop) and SIGUSR1/SIGUSR2 (e-stop) are taken with sigwait() here; block them
  // before the board thread starts so that it inherits the mask and they always reach this thread.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);
  sigaddset(&set, SIGUSR2);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  board.start();
  fmt::print("simulated board ({}) on {} ({} baud)\n", board.model(), board.path(), baud);
  if (!args.fst_path.empty()) fmt::print("FST waveform: {}\n", args.fst_path);
  if (args.line_faults.any()) fmt::print("line faults: {}\n", args.line_faults.describe());
  fmt::print(
      "Ctrl-C (SIGINT) or SIGTERM stops it; SIGUSR1 presses the e-stop, SIGUSR2 releases it "
      "(kill -USR1 {}); SIGHUP pulls the carriages off their endstops\n",
      static_cast<long>(getpid()));
  std::fflush(stdout);
  int sig = 0;
  for (;;) {
    sigwait(&set, &sig);
    if (sig == SIGHUP) {
      // The operator pulls the carriages off their simulated endstops
      // (SimBoard::pull_off_endstops).
      auto* sb = dynamic_cast<SimBoard*>(&board);
      const int n = sb ? sb->pull_off_endstops() : 0;
      fmt::print("SIGHUP: {} endstop(s) released by hand at board cycle {}\n", n, board.cycle());
      std::fflush(stdout);
      continue;
    }
    if (sig != SIGUSR1 && sig != SIGUSR2) break;
    // The e-stop pin (cnc_core's estop input) follows the signal until the next one; the core
    // synchronizes and latches it on its next clocks (docs/protocol.md "The simulated board").
    const bool pressed = sig == SIGUSR1;
    try {
      board.set_estop(pressed);
      fmt::print("e-stop {} at board cycle {}\n", pressed ? "pressed" : "released", board.cycle());
    } catch (const BoardError& e) {
      fmt::print("e-stop ignored: {}\n", e.what());
    }
    std::fflush(stdout);
  }
  board.stop();
  fmt::print("\nstopped by {}\n", sig == SIGINT ? "SIGINT" : "SIGTERM");
  print_board_figures(board);
  const auto edges = board.edges();
  const auto n = models::net_steps(edges);
  fmt::print("net steps from the edges: X {} Y {} Z {} E {}\n", n[0], n[1], n[2], n[3]);
  if (!args.edges_csv.empty()) {
    models::write_edges_csv(args.edges_csv, edges, board.clk_hz());
    fmt::print("edges written to {}\n", args.edges_csv);
  }
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
  return 0;
}

std::unique_ptr<link::Link> make_default_link(const config::MachineConfig& cfg,
                                              const SimOutputs& outputs,
                                              const LineFaults& line_faults) {
  if (!outputs.plot_path.empty()) check_plot_path(outputs.plot_path);
  BoardOptions o = SimBoard::options_from_config(cfg);
  o.fst_path = outputs.fst_path;
  o.line_faults = line_faults;
  if (o.line_faults.any()) fmt::print("line faults: {}\n", o.line_faults.describe());
  return make_board_link(std::make_unique<SimBoard>(o), o.baud, outputs);
}

std::unique_ptr<link::Link> make_board_link(std::unique_ptr<Board> board, uint32_t baud,
                                            const SimOutputs& outputs) {
  if (!outputs.plot_path.empty()) check_plot_path(outputs.plot_path);
  auto lk = std::make_unique<BoardLink>(std::move(board), baud);
  fmt::print("simulated board ({}) on {} ({} baud)\n", lk->any_board().model(),
             lk->any_board().path(), baud);
  std::fflush(stdout);
  return lk;
}

Board* any_board_of(link::Link& lk) {
  auto* bl = dynamic_cast<BoardLink*>(&lk);
  return bl ? &bl->any_board() : nullptr;
}

std::function<double()> plant_clock(link::Link& lk) {
  SimBoard* b = board_of(lk);
  if (!b) return {};
  return [b] { return b->plant_seconds(); };
}

SimBoard* board_of(link::Link& lk) {
  return dynamic_cast<SimBoard*>(any_board_of(lk));
}

bool report_board_run(link::Link& lk, const plan::Plan& plan, const config::MachineConfig& cfg,
                      const SimOutputs& outputs) {
  auto* bl = dynamic_cast<BoardLink*>(&lk);
  if (!bl) return false;
  Board& b = bl->any_board();
  // The last answer has reached the host; the board goes idle within a few clocks after it.
  if (!bl->wait_idle(std::chrono::milliseconds(1000)))
    fmt::print("simulated board: not idle 1 s of board time after the last answer\n");
  b.stop();
  print_board_figures(b);
  const auto edges = b.edges();
  const auto n = models::net_steps(edges);
  // v2 drives all four axes; v1 carries X and Y only, so Z/E that never stepped while the plan
  // moves them are reported as not driven rather than as a mismatch.
  const bool xy_ok = n[0] == plan.final_steps[0] && n[1] == plan.final_steps[1];
  const bool ze_ok = n[2] == plan.final_steps[2] && n[3] == plan.final_steps[3];
  const auto pulses = models::step_pulses(edges);
  const bool ze_idle = pulses[2] == 0 && pulses[3] == 0;
  const char* verdict = !xy_ok    ? "MISMATCH"
                        : ze_ok   ? "match"
                        : ze_idle ? "X/Y match; Z and E not driven (protocol v1)"
                                  : "MISMATCH";
  fmt::print(
      "net steps from the edges: X {} Y {} Z {} E {} (planned final target X {} Y {} Z {} E {}: "
      "{})\n",
      n[0], n[1], n[2], n[3], plan.final_steps[0], plan.final_steps[1], plan.final_steps[2],
      plan.final_steps[3], verdict);
  if (!outputs.plot_path.empty()) {
    PlotOptions po;
    po.steps_per_mm = {cfg.steps_per_mm[0], cfg.steps_per_mm[1]};
    po.title = fmt::format("{} on the simulated board ({})", plan.source, b.model());
    write_plot_svg(outputs.plot_path, edges, commanded_path(plan, cfg), po);
    fmt::print("plot written to {}\n", outputs.plot_path);
  }
  if (!outputs.fst_path.empty()) fmt::print("FST waveform written to {}\n", outputs.fst_path);
  if (!outputs.edges_csv.empty()) {
    models::write_edges_csv(outputs.edges_csv, edges, b.clk_hz());
    fmt::print("edges written to {}\n", outputs.edges_csv);
  }
  return true;
}

}  // namespace fpgacnc::simboard
