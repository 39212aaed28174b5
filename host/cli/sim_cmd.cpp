// fpgacnc sim FILE [--model tlm|rtl|both] [--protocol v1|v2] [--config F] [--feed-override PCT]
//                  [--plot OUT] [--edges OUT.csv] [--max-moves N]
//
// Runs a whole job without a port: on the virtual platform (`tlm`: the SystemC twins of
// cnc_core, systemc/) or on the Verilated RTL (`rtl`), with the same host schedule (v1
// stop-and-wait, or a v2 streaming session: HELLO, CONFIG_AXIS, NUMERATORS, LINE/DWELL under
// the sliding window, STATUS_QUERY, RELEASE), and prints the simulated board's report (cycles,
// clocks/s, edges, moves, net steps against the plan) and plot. `both` runs the two and compares
// them event by event. The protocol defaults to the configuration's (`auto` means v2 here: the
// simulated board speaks both).
#include <fmt/format.h>

#include <memory>

#include "commands.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/simboard/plot.h"
#include "fpgacnc/twins/compare.h"
#include "fpgacnc/twins/rtl_runner.h"
#include "fpgacnc/twins/virtual_board.h"

// libsystemc's own main() calls sc_main(); fpgacnc has its own main() and calls sc_start()
// directly, so this one only satisfies the link.
int sc_main(int, char*[]) {
  return 1;
}

namespace fpgacnc::cli {
namespace {

struct SimArgs {
  std::string input;
  std::string model = "tlm";
  std::string protocol;
  CommonOptions common;
  std::string plot_path;
  std::string edges_csv;
  size_t max_moves = SIZE_MAX;
};

void report(const std::string& model, const twins::RunResult& r, const plan::Plan& plan,
            const config::MachineConfig& cfg, double clk_hz) {
  const double cps = r.wall_s > 0 ? static_cast<double>(r.end_cycle) / r.wall_s : 0.0;
  fmt::print(
      "simulated board ({}): {} cycles ({:.3f} s of machine time), {:.2f} M clocks/s ({:.3f} s "
      "wall), {} packets sent, {} ACKs, {} edges, {} moves done\n",
      model, r.end_cycle, static_cast<double>(r.end_cycle) / clk_hz, cps / 1e6, r.wall_s,
      r.packets_sent, r.acks.size(), r.edges.size(), r.moves_done);
  if (r.frame_errors || r.timeouts || r.violations || r.overruns)
    fmt::print(
        "simulated board ({}): {} framing errors, {} packet timeouts, {} overruns, {} step timing "
        "violations\n",
        model, r.frame_errors, r.timeouts, r.overruns, r.violations);
  if (r.device_frames)
    fmt::print(
        "v2 ({}): {} device frames, {} NAKs, {} frames retransmitted, {} segments done, {} "
        "segments started with zero idle clocks, {} clamped\n",
        model, r.device_frames, r.naks, r.retransmitted, r.segments_done, r.zero_gap, r.clamped);
  if (!r.error.empty()) fmt::print("simulated board ({}): host error: {}\n", model, r.error);
  const auto pulses = models::step_pulses(r.edges);
  fmt::print("step pulses ({}): X {} Y {} Z {} E {}\n", model, pulses[0], pulses[1], pulses[2],
             pulses[3]);
  const auto n = models::net_steps(r.edges);
  const bool ok = n[0] == plan.final_steps[0] && n[1] == plan.final_steps[1];
  fmt::print(
      "net steps from the edges ({}): X {} Y {} (planned final target X {} Y {}: {}); position "
      "counters X {} Y {}\n",
      model, n[0], n[1], plan.final_steps[0], plan.final_steps[1],
      ok ? "match" : "MISMATCH (partial run?)", r.position[0], r.position[1]);
  (void)cfg;
}

void run_sim(const SimArgs& a) {
  if (a.model != "tlm" && a.model != "rtl" && a.model != "both")
    throw std::invalid_argument("--model must be tlm, rtl or both");
  config::MachineConfig cfg = load_config(a.common);
  if (!a.plot_path.empty()) simboard::check_plot_path(a.plot_path);
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const plan::Plan p = plan::plan_input_file(a.input, cfg, po);
  print_gcode_report(p);
  std::string proto = a.protocol.empty() ? cfg.protocol : a.protocol;
  if (proto == "auto") proto = "v2";
  if (proto != "v1" && proto != "v2") throw std::invalid_argument("--protocol must be v1 or v2");
  twins::CoreParams params;
  params.clk_hz = cfg.clk_hz;
  params.baud = cfg.baud;
  params.watchdog_clks = cfg.clk_hz / 10;
  for (auto& t : params.timing)
    t = twins::AxisTiming{cfg.step_timing.step_high, cfg.step_timing.step_low,
                          cfg.step_timing.dir_setup, cfg.step_timing.dir_hold};
  twins::HostScript script;
  if (proto == "v1") {
    const protocol::v1::Job job = protocol::v1::pack_job(p);
    script.v1 = twins::job_packets(job, cfg.clk_hz, a.max_moves);
    fmt::print("sim {}: {} motion packets{}, model {}, protocol v1\n", a.input,
               script.v1.size() - 1,
               a.max_moves != SIZE_MAX ? fmt::format(" (first {})", a.max_moves) : "", a.model);
  } else {
    // The twins' job script carries the motion frames (the virtual board has no heater plants).
    const protocol::v2::Job job =
        protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg, {.heaters = false});
    script.v2 = twins::job_script(job, a.max_moves);
    fmt::print(
        "sim {}: {} LINE/DWELL frames{} (sum of T {} clocks for the whole job), model {}, "
        "protocol v2\n",
        a.input, job.frames.size() - 1,
        a.max_moves != SIZE_MAX ? fmt::format(" (first {})", a.max_moves) : "", job.total_t,
        a.model);
  }
  std::fflush(stdout);

  std::unique_ptr<twins::RunResult> rtl, tlm;
  if (a.model != "tlm") {
    rtl = std::make_unique<twins::RunResult>(twins::run_on_rtl(params, script));
    report("rtl", *rtl, p, cfg, static_cast<double>(cfg.clk_hz));
  }
  if (a.model != "rtl") {
    tlm = std::make_unique<twins::RunResult>(twins::run_on_twins(params, script));
    report("tlm", *tlm, p, cfg, static_cast<double>(cfg.clk_hz));
  }
  if (rtl && tlm) {
    const std::string d = twins::compare_runs(*rtl, *tlm);
    const double speed = (static_cast<double>(tlm->end_cycle) / tlm->wall_s) /
                         (static_cast<double>(rtl->end_cycle) / rtl->wall_s);
    fmt::print(
        "rtl vs tlm: {}; virtual platform {:.0f}x the Verilated RTL's clocks/s\n",
        d.empty() ? "identical (edges, ACKs, block events, positions, duration)" : "DIFFER: " + d,
        speed);
    if (!d.empty()) throw std::runtime_error("rtl and tlm runs differ");
  }
  const twins::RunResult& r = tlm ? *tlm : *rtl;
  if (!r.error.empty()) throw std::runtime_error("sim: " + r.error);
  if (!a.plot_path.empty()) {
    simboard::PlotOptions o;
    o.steps_per_mm = {cfg.steps_per_mm[0], cfg.steps_per_mm[1]};
    o.title = fmt::format("{} on the simulated board ({})", p.source, tlm ? "tlm" : "rtl");
    simboard::write_plot_svg(a.plot_path, r.edges, simboard::commanded_path(p, cfg), o);
    fmt::print("plot written to {}\n", a.plot_path);
  }
  if (!a.edges_csv.empty()) {
    models::write_edges_csv(a.edges_csv, r.edges, static_cast<double>(cfg.clk_hz));
    fmt::print("edges written to {}\n", a.edges_csv);
  }
}

}  // namespace

void register_sim(CLI::App& app) {
  auto args = std::make_shared<SimArgs>();
  auto* sub = app.add_subcommand(
      "sim", "Run a job on the virtual platform (SystemC twins) or the Verilated RTL, no port");
  sub->add_option("FILE", args->input, "G-code file or step-file CSV")->required();
  sub->add_option("--model", args->model, "tlm (twins, fast), rtl (Verilated cnc_core) or both")
      ->check(CLI::IsMember({"tlm", "rtl", "both"}));
  sub->add_option("--protocol", args->protocol,
                  "v1 (stop-and-wait) or v2 (streaming; default, and what `auto` means here)")
      ->check(CLI::IsMember({"v1", "v2", "auto"}));
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  add_gcode_options(sub, args->common);
  sub->add_option("--feed-override", args->common.feed_override_pct, "feed override percent")
      ->check(CLI::Range(1.0, 1000.0));
  sub->add_option("--plot", args->plot_path, "executed vs commanded path plot (.svg or .png)");
  sub->add_option("--edges", args->edges_csv, "write the STEP/DIR/LASER edge list (CSV)");
  sub->add_option("--max-moves", args->max_moves, "run only the first N moves");
  sub->callback([args] { run_sim(*args); });
}

}  // namespace fpgacnc::cli
