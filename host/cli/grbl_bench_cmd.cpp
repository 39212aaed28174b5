// fpgacnc grbl-bench [--moves N] [--feed F] [--step MM] [--baud B] [--model tlm|rtl]
//                    [--config F]: sender-side throughput of the grbl front end (docs/grbl.md,
// "Throughput"). A character-counting sender streams N short laser moves (G1 of --step mm along
// X, S power changing every move, M4 laser mode) into the engine over a modelled serial line of
// --baud (10 bits per byte, both directions: lines to the engine, answers back), timed on the
// simulated board's clock (link time), never the wall clock. Prints what the line could carry
// (moves/s), what the sender delivered, what the FPGA executed (first laser-on to last
// laser-off), and the executor's idle clocks between segments: every low interval of the LASER
// pin between the first segment's start and the last segment's end (the pin is high while a
// segment with power > 0 runs, and stays high when the next segment starts on the edge the
// previous one ends). Exit status 1 when any gap was seen.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/grbl/settings.h"
#include "fpgacnc/models/edges.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace fpgacnc::cli {
namespace {

using Time = link::Link::Time;

struct BenchArgs {
  CommonOptions common;
  std::string model = "tlm";
  size_t moves = 1000;
  double feed = 3000.0;  // mm/min
  double step = 0.1;     // mm per move
  uint32_t baud = 115200;
  uint32_t board_baud = 0;  // host <-> FPGA link; 0: the configuration's
};

// One line on the modelled serial line: the time its last byte has arrived.
struct OnLine {
  Time at;
  std::string text;
  bool move;
};

int run_bench(const BenchArgs& a) {
  if (a.moves < 2) throw std::invalid_argument("grbl-bench: --moves must be at least 2");
  if (!(a.feed > 0.0)) throw std::invalid_argument("grbl-bench: --feed must be > 0");
  if (!(a.step > 0.0)) throw std::invalid_argument("grbl-bench: --step must be > 0");
  if (a.baud == 0) throw std::invalid_argument("grbl-bench: --baud must be > 0");
  config::MachineConfig cfg = load_config(a.common);
  if (a.board_baud != 0) cfg.baud = a.board_baud;

  std::unique_ptr<link::Link> lk;
  if (a.model == "tlm") {
    lk = simboard::make_board_link(
        std::make_unique<twins::TwinBoard>(twins::TwinBoard::options_from_config(cfg)), cfg.baud,
        {});
  } else {
    lk = simboard::make_default_link(cfg, {});
  }
  auto* bl = dynamic_cast<simboard::BoardLink*>(lk.get());
  if (!bl) throw std::logic_error("grbl-bench: the simulated board has no BoardLink");

  grbl::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  grbl::Engine engine(*lk, cfg, grbl::settings_from_config(cfg), eo);
  engine.connect();
  engine.take_output();

  // The sender's job: laser mode on, then the moves, S changing every move (a greyscale row).
  std::vector<std::string> lines = {"G21 G90", fmt::format("M4 S0 F{:g}", a.feed)};
  const size_t first_move = lines.size();
  for (size_t i = 1; i <= a.moves; ++i)
    lines.push_back(fmt::format("G1 X{:.3f} S{}", static_cast<double>(i) * a.step,
                                400 + static_cast<int>((i * 37) % 600)));
  lines.push_back("M5");
  size_t move_bytes = 0;
  for (size_t i = first_move; i < first_move + a.moves; ++i) move_bytes += lines[i].size() + 1;

  // 10 bits per byte (8N1) at `baud`, in link time.
  const Time byte_time =
      std::chrono::duration_cast<Time>(std::chrono::duration<double>(10.0 / a.baud));
  std::deque<OnLine> to_engine;  // on the line, sender -> engine
  std::deque<Time> answers;      // ok / error on the line, engine -> sender
  std::deque<size_t> in_flight;  // bytes of lines not yet answered (character counting)
  size_t bytes_in_flight = 0, next = 0, oks = 0, errors = 0;
  Time tx_free{0}, rx_free{0};
  Time first_delivered{-1}, last_delivered{0};
  std::string partial;
  const Time limit = lk->now() + std::chrono::seconds(3600);

  for (;;) {
    const Time now = lk->now();
    if (now > limit) throw std::runtime_error("grbl-bench: no end after an hour of board time");
    while (!answers.empty() && answers.front() <= now) {
      answers.pop_front();
      bytes_in_flight -= in_flight.front();
      in_flight.pop_front();
    }
    while (next < lines.size() && bytes_in_flight + lines[next].size() + 1 <= grbl::kRxBuffer) {
      const size_t n = lines[next].size() + 1;
      tx_free = std::max(tx_free, now) + static_cast<Time::rep>(n) * byte_time;
      const bool move = next >= first_move && next < first_move + a.moves;
      to_engine.push_back({tx_free, lines[next] + "\n", move});
      in_flight.push_back(n);
      bytes_in_flight += n;
      ++next;
    }
    while (!to_engine.empty() && to_engine.front().at <= now) {
      if (to_engine.front().move) {
        if (first_delivered < Time::zero()) first_delivered = to_engine.front().at;
        last_delivered = to_engine.front().at;
      }
      engine.receive(to_engine.front().text);
      to_engine.pop_front();
    }
    engine.step(std::chrono::milliseconds(0));
    partial += engine.take_output();
    for (size_t nl; (nl = partial.find('\n')) != std::string::npos;) {
      const std::string l = partial.substr(0, nl + 1);
      partial.erase(0, nl + 1);
      const bool ok = l.rfind("ok", 0) == 0;
      if (!ok && l.rfind("error:", 0) != 0) continue;  // [MSG:...] and the like
      (ok ? oks : errors)++;
      rx_free = std::max(rx_free, lk->now()) + static_cast<Time::rep>(l.size()) * byte_time;
      answers.push_back(rx_free);
    }
    const bool sender_done = next == lines.size() && to_engine.empty() && answers.empty();
    if (sender_done && !engine.busy()) break;
    // Board time runs to the next event on the serial line, at most 1 ms on (answers from the
    // board are read at least that often while it moves).
    Time until = lk->now() + std::chrono::milliseconds(1);
    if (!to_engine.empty()) until = std::min(until, to_engine.front().at);
    if (!answers.empty()) until = std::min(until, answers.front());
    lk->wait_until(until);
  }
  bl->wait_idle(std::chrono::milliseconds(1000));

  const simboard::Board& board = bl->any_board();
  const double clk = board.clk_hz();
  const auto edges = board.edges();
  const auto on = models::high_intervals(edges, models::kLaser, board.cycle());
  uint64_t gaps = 0, idle = 0, longest = 0;
  for (size_t i = 1; i < on.size(); ++i) {
    const uint64_t g = on[i].begin - on[i - 1].end;
    ++gaps;
    idle += g;
    longest = std::max(longest, g);
  }
  const double exec_s =
      on.empty() ? 0.0 : static_cast<double>(on.back().end - on.front().begin) / clk;
  const double avg_line = static_cast<double>(move_bytes) / static_cast<double>(a.moves);
  const double line_cap = a.baud / 10.0 / avg_line;
  const double deliver_s = std::chrono::duration<double>(last_delivered - first_delivered).count();
  const double delivered = deliver_s > 0 ? static_cast<double>(a.moves - 1) / deliver_s : 0.0;
  const double motion = a.feed / 60.0 / a.step;  // moves/s at the programmed feed
  const double executed = exec_s > 0 ? static_cast<double>(a.moves) / exec_s : 0.0;
  const auto& st = engine.stats();
  const auto bs = board.stats();
  // The host -> FPGA link: bytes the board read per move (frames, polls, retransmissions).
  const double link_bytes = static_cast<double>(bs.bytes_in) / static_cast<double>(a.moves);
  const double link_cap = cfg.baud / 10.0 / link_bytes;

  fmt::print(
      "grbl-bench ({}): {} moves of {:g} mm at F{:g} (laser M4, S per move), character counting "
      "into the 128-byte buffer at {} baud ({:.1f} bytes per move line)\n",
      board.model(), a.moves, a.step, a.feed, a.baud, avg_line);
  fmt::print(
      "bench: grbl sender line capacity {:.0f} moves/s; sender delivered {:.0f} moves/s; motion at "
      "F{:g} needs {:.0f} moves/s; FPGA executed {:.0f} moves/s ({:.3f} s laser on to off)\n",
      line_cap, delivered, a.feed, motion, executed, exec_s);
  fmt::print(
      "bench: host -> FPGA link at {} baud: {:.1f} bytes per move (LINE_PROFILE frames, status "
      "polls), {:.0f} moves/s\n",
      cfg.baud, link_bytes, link_cap);
  if (link_cap < motion)
    fmt::print(
        "bench: the host -> FPGA link limits: it carries {:.0f} moves/s, below the {:.0f} moves/s "
        "the feed asks for\n",
        link_cap, motion);
  if (line_cap < motion)
    fmt::print(
        "bench: the {} baud line limits: it carries {:.0f} moves/s, below the {:.0f} moves/s the "
        "feed asks for\n",
        a.baud, line_cap, motion);
  fmt::print(
      "bench: executor idle clocks between segments after the first: {} in {} gaps (longest {}); "
      "{} ok, {} errors; look-ahead planned to a stop {} times (the last at the end of the job)\n",
      idle, gaps, longest, oks, errors, st.flushes);
  if (gaps == 0 && errors == 0 && on.size() == 1) {
    fmt::print("bench: zero gaps: the FPGA ran all {} moves back to back\n", a.moves);
    return 0;
  }
  if (on.empty()) fmt::print("bench: the laser never came on\n");
  if (gaps > 0)
    fmt::print(
        "bench: NOT zero gaps: the board's queue ran dry {} times (the sender delivered {:.0f} "
        "moves/s, the FPGA link carries {:.0f}, the feed needs {:.0f})\n",
        gaps, delivered, link_cap, motion);
  return 1;
}

}  // namespace

void register_grbl_bench(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  auto* sub = app.add_subcommand(
      "grbl-bench",
      "Throughput of `fpgacnc grbl`: a character-counting sender streams short laser moves over "
      "a modelled serial line (simulated time) into the simulated board; prints moves/s and the "
      "executor's gaps (exit 1 on a gap)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--model", args->model, "simulated board: tlm (default) or rtl")
      ->check(CLI::IsMember({"tlm", "rtl"}));
  sub->add_option("--moves", args->moves, "number of moves (default 1000)");
  sub->add_option("--feed", args->feed, "feed, mm/min (default 3000)");
  sub->add_option("--step", args->step, "move length, mm (default 0.1)");
  sub->add_option("--baud", args->baud, "sender <-> front end line, baud (default 115200)");
  sub->add_option("--board-baud", args->board_baud,
                  "host <-> FPGA link, baud (default: the configuration's, 115200)");
  sub->callback([args] {
    const int rc = run_bench(*args);
    std::fflush(stdout);
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace fpgacnc::cli
