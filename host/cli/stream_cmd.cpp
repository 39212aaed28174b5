// fpgacnc stream FILE [--port DEV] [--config F] [--baud N] [--timeout S] [--feed-override PCT]
//                     [--plot OUT.svg] [--fst OUT.fst] [--edges OUT.csv]
//
// Hook: without --port, StreamHooks::open_default_link is called (main.cpp plugs in the
// simulated board, see board_cmd.cpp); the plain default throws. --plot/--fst/--edges need the
// simulated board.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>

#include "commands.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/plan/planner.h"

namespace fpgacnc::cli {
namespace {

struct StreamArgs {
  std::string input;
  std::string port;
  uint32_t baud = 0;        // 0: from config
  double timeout_s = -1.0;  // negative: from config
  CommonOptions common;
  SimOutputOptions sim;
};

// Progress bar on stderr (only when stderr is a terminal): moves done/total, rate, ETA.
class ProgressBar {
 public:
  ProgressBar() : enabled_(::isatty(STDERR_FILENO) == 1), t0_(clock::now()) {}
  void update(size_t done, size_t total) {
    if (!enabled_) return;
    const auto now = clock::now();
    if (done != total && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double el = std::chrono::duration<double>(now - t0_).count();
    const double rate = el > 0 ? static_cast<double>(done) / el : 0.0;
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
    constexpr int kWidth = 30;
    const int fill = total ? static_cast<int>(kWidth * done / total) : kWidth;
    fmt::print(stderr, "\r[{:=<{}}{: <{}}] {}/{} moves  {:.1f} moves/s  ETA {:.0f} s ", "", fill,
               "", kWidth - fill, done, total, rate, eta);
    if (done == total) fmt::print(stderr, "\n");
  }

 private:
  using clock = std::chrono::steady_clock;
  bool enabled_;
  clock::time_point t0_;
  clock::time_point last_{};
};

void run_stream(const StreamArgs& a, const StreamHooks& hooks) {
  config::MachineConfig cfg = load_config(a.common);
  if (a.baud) cfg.baud = a.baud;
  if (a.timeout_s > 0) cfg.ack_timeout_s = a.timeout_s;
  std::string port = a.port.empty() ? cfg.port : a.port;
  if (!port.empty() && a.sim.any()) {
    throw link::Error(
        "--plot, --fst and --edges need the simulated board: give no --port (and no port in "
        "the configuration)");
  }

  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  // Plan (and, inside stream_v1, pack) the whole job before opening anything.
  const plan::Plan p = plan::plan_input_file(a.input, cfg, po);

  std::unique_ptr<link::Link> lk;
  if (port.empty()) {
    lk = hooks.open_default_link(cfg, a.sim);
  } else {
    lk = std::make_unique<link::SerialLink>(port, cfg.baud);
  }
  ProgressBar bar;
  link::StreamOptions so;
  so.ack_timeout = std::chrono::milliseconds(std::llround(cfg.ack_timeout_s * 1000.0));
  so.progress = [&bar](size_t d, size_t t) { bar.update(d, t); };
  const link::StreamReport r = link::stream_v1(*lk, p, so);
  fmt::print(
      "streamed {} over {}: {} moves, {} acks, {} warnings (unexpected bytes), {} dwells, "
      "{} bytes in {:.2f} s\n",
      a.input, lk->name(), r.moves, r.acks, r.warnings, r.dwells, r.bytes_written,
      r.elapsed.count());
  if (r.skipped_heater) fmt::print("{} heater commands not sent (v1 has none)\n", r.skipped_heater);
  if (r.ze_only) fmt::print("{} Z/E-only moves not driven by v1 (sent as 0,0 steps)\n", r.ze_only);
  fmt::print("final position: steps X {} Y {} Z {} E {}; mm X {:.4f} Y {:.4f} Z {:.4f} E {:.4f}\n",
             r.final_steps[0], r.final_steps[1], r.final_steps[2], r.final_steps[3], r.final_mm[0],
             r.final_mm[1], r.final_mm[2], r.final_mm[3]);
  if (port.empty() && hooks.after_default_stream) hooks.after_default_stream(*lk, p, cfg, a.sim);
}

}  // namespace

StreamHooks default_stream_hooks() {
  StreamHooks h;
  h.open_default_link = [](const config::MachineConfig&,
                           const SimOutputOptions&) -> std::unique_ptr<link::Link> {
    throw link::Error("no --port given and no simulated board built in");
  };
  return h;
}

void register_stream(CLI::App& app, StreamHooks hooks) {
  auto args = std::make_shared<StreamArgs>();
  auto* sub = app.add_subcommand("stream", "Stream a job to the controller with protocol v1");
  sub->add_option("FILE", args->input, "G-code file or step-file CSV")->required();
  sub->add_option("--port", args->port, "serial port (/dev/ttyUSB0, COM3, /dev/pts/N)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--baud", args->baud, "baud rate (default from config: 115200)")
      ->check(CLI::Range(1u, 100'000'000u));
  sub->add_option("--timeout", args->timeout_s, "ACK timeout in seconds (default 10)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--feed-override", args->common.feed_override_pct, "feed override percent")
      ->check(CLI::Range(1.0, 1000.0));
  sub->add_option("--plot", args->sim.plot_path,
                  "simulated board: plot of the executed vs commanded path (.svg, or .png with "
                  "rsvg-convert)");
  sub->add_option("--fst", args->sim.fst_path, "simulated board: FST waveform of the core");
  sub->add_option("--edges", args->sim.edges_csv, "simulated board: STEP/DIR/LASER edge list CSV");
  sub->callback([args, hooks = std::move(hooks)] { run_stream(*args, hooks); });
}

}  // namespace fpgacnc::cli
