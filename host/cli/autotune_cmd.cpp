// fpgacnc autotune [--heater bed|hotend] [--setpoint C] [--relay-v V] [--hysteresis C]
//                  [--cycles N] [--max-time S] [--port DEV] [--config F] [--plot OUT.svg]
//                  [--csv OUT.csv]
//
// Relay test on one heater through the link (fpgacnc/heat/autotune_link.h): the device runs the
// channel in ON_OFF mode between 0 and --relay-v volts around --setpoint; the host records the
// temperature from STATUS, measures the oscillation period Pu and amplitude a, computes the
// critical gain Ku = 4 d / (pi a) (d = relay-v / 2) and prints PID gains (Ziegler-Nichols, the
// reference bed's relay rule, ...). Without --port the simulated board (thermal plant models)
// is used; its plant seconds are scaled (docs/heater.md, "Simulated board").
#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <memory>

#include "commands.h"
#include "fpgacnc/heat/autotune_link.h"
#include "fpgacnc/heat/heater_plot.h"
#include "fpgacnc/link/serial_link.h"

namespace fpgacnc::cli {
namespace {

struct AutotuneArgs {
  std::string heater = "bed";
  double setpoint = -1.0;  // negative: 60 (bed) / 200 (hot end)
  double relay_v = -1.0;   // negative: 12 V (bed, the reference test) / supply (hot end)
  double hysteresis = 0.0625;
  int cycles = 4;
  int skip = 2;
  double max_time = 3600.0;
  std::string port;
  std::string plot;
  std::string csv;
  CommonOptions common;
  SimOutputOptions sim;
};

void run_autotune(const AutotuneArgs& a, const StreamHooks& hooks) {
  config::MachineConfig cfg = load_config(a.common);
  const uint8_t ch = a.heater == "hotend" ? heat::kHotend : heat::kBed;
  const auto& hc = cfg.heaters.ch[ch];
  heat::AutotuneLinkOptions o;
  o.channel = ch;
  o.relay.setpoint_c = a.setpoint > 0 ? a.setpoint : (ch == heat::kBed ? 60.0 : 200.0);
  o.relay.u_high = a.relay_v > 0 ? a.relay_v : (ch == heat::kBed ? 12.0 : hc.supply_v);
  o.relay.u_low = 0.0;
  o.relay.hysteresis_c = a.hysteresis;
  o.relay.cycles = a.cycles;
  o.relay.skip_cycles = a.skip;
  o.max_plant_s = a.max_time;
  const std::string port = a.port.empty() ? cfg.port : a.port;
  if (port.empty() && cfg.heaters.watchdog_s > 0.0 && cfg.heaters.watchdog_s < 60.0) {
    cfg.heaters.watchdog_s = 60.0;  // simulated board: see stream_cmd.cpp
  }
  std::unique_ptr<link::Link> lk;
  if (port.empty()) {
    lk = hooks.open_default_link(cfg, a.sim);
    if (hooks.configure_v2) {
      link::StreamV2Options so;
      hooks.configure_v2(*lk, so);
      o.plant_time = so.plant_time;
      o.poll = std::min(o.poll, so.heater_poll);
    }
  } else {
    lk = std::make_unique<link::SerialLink>(port, cfg.baud);
  }
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  bool last_on = false;
  size_t switches = 0;
  o.on_sample = [&](const heat::RelaySample& s, const protocol::v2::HeaterStatus&) {
    const bool on = s.u > 0.0;
    if (on != last_on) {
      ++switches;
      if (tty) {
        fmt::print(stderr, "\r t {:7.1f} s  {} {:6.2f} degC  relay {}  ({} switches) ", s.t_s,
                   a.heater, s.temp_c, on ? "on " : "off", switches);
      }
    }
    last_on = on;
  };
  fmt::print("autotune: {} heater, relay 0/{:g} V around {:g} degC on {}\n", a.heater,
             o.relay.u_high, o.relay.setpoint_c, lk->name());
  std::fflush(stdout);
  const auto r = heat::run_relay_test(*lk, cfg, o);
  if (tty) fmt::print(stderr, "\n");
  fmt::print("{}", heat::format_autotune(r.result, o.relay, "V"));
  fmt::print("{} samples over {:.0f} s of plant time ({:.1f} s wall)\n", r.samples.size(),
             r.plant_s, r.wall_s);
  fmt::print(
      "configure with: [heater.{}] kp = {:.2f}, ti_s = {:.1f}, td_s = {:.1f} (reference "
      "rule)\n",
      a.heater, heat::propose_gains(r.result.ku, r.result.period_s)[1].kp,
      heat::propose_gains(r.result.ku, r.result.period_s)[1].ti_s,
      heat::propose_gains(r.result.ku, r.result.period_s)[1].td_s);
  if (!a.csv.empty()) {
    std::ofstream f(a.csv);
    f << "t_s,temp_c,u_v,setpoint_c\n";
    for (size_t i = 0; i < r.samples.size(); ++i) {
      f << fmt::format("{:.3f},{:.4f},{:.3f},{:.4f}\n", r.samples[i].t_s, r.samples[i].temp_c,
                       r.samples[i].u, r.setpoints[i]);
    }
    fmt::print("samples written to {}\n", a.csv);
  }
  if (!a.plot.empty()) {
    heat::HeaterTrace tr;
    tr.name = a.heater;
    for (size_t i = 0; i < r.samples.size(); ++i) {
      tr.t_s.push_back(r.samples[i].t_s);
      tr.temp_c.push_back(r.samples[i].temp_c);
      tr.setpoint_c.push_back(r.setpoints[i]);
      tr.duty.push_back(r.samples[i].u / hc.supply_v);
    }
    heat::write_heater_svg(
        a.plot, {tr},
        fmt::format("Relay autotune: {} heater, 0/{:g} V around {:g} degC", a.heater,
                    o.relay.u_high, o.relay.setpoint_c),
        fmt::format("Pu {:.1f} s, a {:.3f} degC, Ku {:.2f} V/degC (time: plant seconds)",
                    r.result.period_s, r.result.amplitude_c, r.result.ku));
    fmt::print("plot written to {}\n", a.plot);
  }
}

}  // namespace

void register_autotune(CLI::App& app, StreamHooks hooks) {
  auto args = std::make_shared<AutotuneArgs>();
  auto* sub = app.add_subcommand(
      "autotune",
      "Relay test on a heater (v2 device): critical period and gain, proposed PID gains");
  sub->add_option("--heater", args->heater, "bed (default) or hotend")
      ->check(CLI::IsMember({"bed", "hotend"}));
  sub->add_option("--setpoint", args->setpoint, "relay setpoint degC (default 60 bed, 200 hot end)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--relay-v", args->relay_v,
                  "relay high output, volts of the heater supply (default 12 bed as the reference "
                  "test, supply_v hot end)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--hysteresis", args->hysteresis, "relay hysteresis degC (default 0.0625)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--cycles", args->cycles, "cycles measured (default 4)")
      ->check(CLI::Range(1, 100));
  sub->add_option("--skip", args->skip, "first cycles left out (default 2)")
      ->check(CLI::Range(0, 100));
  sub->add_option("--max-time", args->max_time, "give up after this much plant time, s (3600)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--port", args->port, "serial port (default: the simulated board)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--plot", args->plot, "temperature and relay output plot (.svg)");
  sub->add_option("--csv", args->csv, "samples as CSV (t_s,temp_c,u_v,setpoint_c)");
  sub->callback([args, hooks = std::move(hooks)] { run_autotune(*args, hooks); });
}

}  // namespace fpgacnc::cli
