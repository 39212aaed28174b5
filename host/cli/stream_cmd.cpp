// fpgacnc stream FILE [--port DEV] [--config F] [--protocol auto|v1|v2] [--baud N] [--timeout S]
//                     [--retransmit-timeout S] [--feed-override PCT]
//                     [--model tlm|rtl|both] [--realtime] [--max-moves N]
//                     [--plot OUT.svg] [--fst OUT.fst] [--edges OUT.csv] [--line-* ...]
//                     [--heater-plot OUT.svg]
//
// Without --port the job goes through a pseudo-terminal into a simulated board: `tlm` (default)
// the SystemC twins (twins::TwinBoard), `rtl` the Verilated cnc_core (SimBoard); `both` streams
// the first --max-moves moves with the lockstep host into both and fails unless their edges,
// answer bytes and answer clocks are identical.
//
// Protocol: auto (default) sends HELLO and uses v2 when an IDENT comes back within 300 ms, else
// waits 150 ms more (the device watchdog drops the HELLO bytes) and uses v1.
// Hook: without --port, StreamHooks::open_default_link is called (main.cpp plugs in the
// simulated board, see board_cmd.cpp); the plain default throws. --plot/--fst/--edges and the
// line fault options need the simulated board.
#include <fmt/format.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "commands.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/heat/heater_plot.h"
#include "fpgacnc/link/hold_control.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "interrupt_guard.h"

namespace fpgacnc::cli {
namespace {

struct StreamArgs {
  std::string input;
  std::string port;
  uint32_t baud = 0;        // 0: from config
  double timeout_s = -1.0;  // negative: from config
  double retransmit_s = -1.0;
  std::string protocol;  // "": from config
  CommonOptions common;
  SimOutputOptions sim;
  std::string heater_plot;          // temperature and duty against time (.svg)
  std::string pause_mode = "auto";  // --pause: auto, prompt, continue, stop
};

// Progress bar on stderr (only when stderr is a terminal): moves done/total, rate, ETA.
class ProgressBar {
 public:
  explicit ProgressBar(std::string unit = "moves")
      : enabled_(::isatty(STDERR_FILENO) == 1), t0_(clock::now()), unit_(std::move(unit)) {}
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
    fmt::print(stderr, "\r[{:=<{}}{: <{}}] {}/{} {}  {:.1f} {}/s  ETA {:.0f} s {}", "", fill, "",
               kWidth - fill, done, total, unit_, rate, unit_, eta, extra_);
    done_ = done;
    total_ = total;
    if (done == total) fmt::print(stderr, "\n");
  }
  // Ends the bar's line before other output (a pause prompt, a message).
  void finish_line() {
    if (enabled_ && done_ != total_) fmt::print(stderr, "\n");
  }
  // Heaters: temperatures shown after the bar, redrawn at most every 100 ms.
  void set_extra(std::string extra) {
    extra_ = std::move(extra);
    if (done_ != total_) update(done_, total_);
  }

 private:
  using clock = std::chrono::steady_clock;
  bool enabled_;
  clock::time_point t0_;
  clock::time_point last_{};
  std::string unit_;
  std::string extra_;
  size_t done_ = 0, total_ = 1;
};

// Keys on a terminal: stdin in non-canonical mode without echo (signals still on: Ctrl-C is
// SIGINT), read without waiting; the terminal's mode back on destruction and around questions.
class TerminalKeys {
 public:
  TerminalKeys() : on_(::isatty(STDIN_FILENO) == 1) {
    if (on_ && ::tcgetattr(STDIN_FILENO, &saved_) != 0) on_ = false;
    if (on_) raw();
  }
  ~TerminalKeys() { cooked(); }
  TerminalKeys(const TerminalKeys&) = delete;
  TerminalKeys& operator=(const TerminalKeys&) = delete;
  bool on() const { return on_; }
  std::string read_keys() {
    std::string out;
    if (!on_) return out;
    char buf[16];
    for (;;) {
      const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
      if (n <= 0) break;
      out.append(buf, static_cast<size_t>(n));
    }
    return out;
  }
  void raw() {
    if (!on_) return;
    termios t = saved_;
    t.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
    t.c_cc[VMIN] = 0;
    t.c_cc[VTIME] = 0;
    ::tcsetattr(STDIN_FILENO, TCSANOW, &t);
  }
  void cooked() {
    if (on_) ::tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }

 private:
  bool on_;
  termios saved_{};
};

void run_stream(const StreamArgs& a, const StreamHooks& hooks) {
  config::MachineConfig cfg = load_config(a.common);
  if (a.baud) cfg.baud = a.baud;
  if (a.timeout_s > 0) cfg.ack_timeout_s = a.timeout_s;
  if (a.retransmit_s > 0) cfg.retransmit_timeout_s = a.retransmit_s;
  if (!a.protocol.empty()) cfg.protocol = a.protocol;
  config::validate(cfg, "command line");
  std::string port = a.port.empty() ? cfg.port : a.port;
  if (!port.empty() && (a.sim.any() || !a.sim.model.empty() || a.sim.realtime)) {
    throw link::Error(
        "--plot, --fst, --edges, --line-*, --model and --realtime need the simulated board: give "
        "no --port (and no port in the configuration)");
  }
  SimOutputOptions sim = a.sim;
  if (sim.model.empty()) sim.model = "tlm";
  if (sim.max_moves != SIZE_MAX && sim.model != "both") {
    throw std::invalid_argument("--max-moves is for --model both");
  }

  if (port.empty() && cfg.heaters.watchdog_s > 0.0 && cfg.heaters.watchdog_s < 60.0) {
    // Simulated board: 60 plant seconds (~0.1 s of board time) for the heater watchdog, whose
    // STATUS_QUERY feeding is paced by the host's wall clock (docs/heater.md, "Simulated board").
    cfg.heaters.watchdog_s = 60.0;
  }
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  // Plan and pack the whole job before opening anything: an error writes no byte.
  const plan::Plan p = plan::plan_input_file(a.input, cfg, po);
  print_gcode_report(p);
  if (port.empty() && sim.model == "both") {
    if (!hooks.compare_boards) throw link::Error("--model both: no simulated boards built in");
    hooks.compare_boards(p, cfg, sim);
    return;
  }
  std::optional<protocol::v2::Job> job2;
  const heat::HeaterJob* heaters = nullptr;
  std::optional<protocol::v1::Job> job1;
  std::string v1_error;
  if (cfg.protocol != "v1") {
    // Plan, then pack (M104/M109/M140/M190 checked: line:col errors).
    job2 = protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg);
    heaters = &job2->heaters;
  }
  if (cfg.protocol == "v1") {
    job1 = protocol::v1::pack_job(p);
  } else if (cfg.protocol == "auto") {
    try {  // only an error if auto falls back to v1
      job1 = protocol::v1::pack_job(p);
    } catch (const std::invalid_argument& e) {
      v1_error = e.what();
    }
  }

  if (port.empty() && sim.model == "tlm" && heaters && heaters->any()) {
    throw std::invalid_argument(fmt::format(
        "{}: heater commands (M104/M109/M140/M190) need the Verilated board with its heater "
        "plants: --model rtl (the tlm board has no heaters)",
        a.input));
  }
  std::unique_ptr<link::Link> lk;
  if (port.empty()) {
    lk = hooks.open_default_link(cfg, sim);
  } else {
    lk = std::make_unique<link::SerialLink>(port, cfg.baud);
  }
  link::StreamV2Options o2 = link::stream_v2_options(cfg);
  const link::ProtocolChoice choice = link::select_protocol(*lk, cfg.protocol, o2);
  if (cfg.protocol == "auto") {
    fmt::print("protocol: {} ({} after {:.0f} ms)\n", choice.protocol,
               choice.ident ? "IDENT answered HELLO" : "no IDENT answer to HELLO",
               choice.probe_time.count() * 1000.0);
  }

  if (choice.protocol == "v2") {
    ProgressBar bar("frames");
    // Feed hold and overrides (README.md "Feed hold and overrides while streaming"): keys on a
    // terminal, SIGINT always.
    o2.motion = link::machine_motion(cfg);
    InterruptGuard interrupts;
    TerminalKeys keys;
    link::HoldControl::Io hio;
    hio.say = [&bar](const std::string& l) {
      bar.finish_line();
      fmt::print("{}\n", l);
      std::fflush(stdout);
    };
    if (keys.on()) {
      using Answer = link::HoldControl::Io::Answer;
      hio.ask = [&bar, &keys](const std::string& where) {
        bar.finish_line();
        fmt::print(
            "held at {}, at rest on the path. Enter or r Enter: resume; s Enter: stop the job "
            "here (the board drops what it has queued, its position kept; the frames not yet "
            "sent are dropped); k Enter: stop sending, the board keeps its queue, held\n",
            where);
        std::fflush(stdout);
        keys.cooked();
        std::string answer;
        const bool got = static_cast<bool>(std::getline(std::cin, answer));
        keys.raw();
        if (!got) {  // end of input or a second Ctrl-C: stop
          std::cin.clear();
          return Answer::kStop;
        }
        if (answer.empty() || answer[0] == 'r' || answer[0] == 'R') return Answer::kResume;
        if (answer[0] == 'k' || answer[0] == 'K') return Answer::kKeep;
        return Answer::kStop;
      };
    }
    link::HoldControl hold(cfg, hio);
    o2.on_poll = [&](link::V2Session& s) {
      for (const char c : keys.read_keys()) hold.key(c);
      for (int n = interrupts.take(); n > 0; --n) hold.interrupt();
      return hold.poll(s);
    };
    if (keys.on()) {
      fmt::print(
          "keys: ! or space feed hold, ~ or c resume, f / F feed -10 / +10 %, r rapid 100 / 50 / "
          "25 %; Ctrl-C holds and asks\n");
    } else {
      fmt::print("SIGINT: feed hold, then the job stops at rest (no terminal to ask)\n");
    }
    std::fflush(stdout);
    o2.progress = [&bar](size_t d, size_t t) { bar.update(d, t); };
    if (port.empty() && hooks.configure_v2) hooks.configure_v2(*lk, o2);
    // Pauses (M0/M1, M6, M600): at rest, ask the operator (a terminal), go on (a simulated
    // board without a terminal) or stop (a real machine without a terminal).
    std::string mode = a.pause_mode;
    if (mode == "auto") mode = isatty(STDIN_FILENO) ? "prompt" : port.empty() ? "continue" : "stop";
    o2.on_pause = [&bar, &keys, mode](const gcode::Pause& pz) {
      bar.finish_line();
      if (mode == "continue") {
        fmt::print("pause at line {}: {} (--pause continue: going on)\n", pz.line, pz.prompt);
        return true;
      }
      if (mode == "stop") return false;
      fmt::print(
          "pause at line {}: {}. The machine is at rest. Enter: go on, q Enter: stop the job\n",
          pz.line, pz.prompt);
      std::fflush(stdout);
      keys.cooked();
      std::string answer;
      const bool got = static_cast<bool>(std::getline(std::cin, answer));
      keys.raw();
      if (!got) return false;
      return answer.empty() || (answer[0] != 'q' && answer[0] != 'Q');
    };
    o2.on_message = [&bar](const gcode::Message& m) {
      if (m.kind == gcode::Message::Kind::kProgress) return;  // the progress bar shows it
      bar.finish_line();
      fmt::print("line {}: {}\n", m.line, m.text);
    };
    // Heater samples for the progress line and --heater-plot (plant time).
    std::vector<heat::HeaterTrace> traces(heat::kChannels);
    for (size_t c = 0; c < heat::kChannels; ++c) traces[c].name = heat::kChannelNames[c];
    const auto t0 = std::chrono::steady_clock::now();
    auto plant_now = [&]() {
      return o2.plant_time
                 ? o2.plant_time()
                 : std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    const double p0 = plant_now();
    o2.on_status = [&](const protocol::v2::Status& st) {
      if (st.heaters.empty()) return;
      bar.set_extra(heat::format_heaters(st));
      if (a.heater_plot.empty() || !heaters) return;
      const double t = plant_now() - p0;
      for (size_t c = 0; c < st.heaters.size() && c < heat::kChannels; ++c) {
        if (!heaters->used[c]) continue;
        traces[c].t_s.push_back(t);
        traces[c].temp_c.push_back(st.heaters[c].temp_c());
        traces[c].setpoint_c.push_back(st.heaters[c].setpoint_c());
        traces[c].duty.push_back(st.heaters[c].duty());
      }
    };
    auto write_heater_plot = [&]() {
      if (a.heater_plot.empty() || !heaters || !heaters->any()) return;
      std::vector<heat::HeaterTrace> used;
      for (size_t c = 0; c < heat::kChannels; ++c) {
        if (heaters->used[c]) used.push_back(traces[c]);
      }
      heat::write_heater_svg(
          a.heater_plot, used, fmt::format("{}: heaters as STATUS reports them", a.input),
          fmt::format("{} on {}; time in plant seconds", a.input,
                      port.empty() ? std::string("the simulated board (1 plant s = 102 400 clocks)")
                                   : lk->name()));
      fmt::print("heater plot written to {}\n", a.heater_plot);
    };
    link::StreamV2Report r;
    try {
      r = link::stream_v2_job(*lk, *job2, o2, choice.ident);
      r.final_steps = p.final_steps;
      r.final_mm = p.final_mm;
    } catch (const link::Error&) {
      try {
        write_heater_plot();  // up to the error: shows what happened
      } catch (const std::exception&) {
      }
      throw;
    }
    write_heater_plot();
    if (r.stopped) {
      bar.finish_line();
      const std::string at = hold.where(r.status_end);
      fmt::print("{}", link::format_report(r));
      if (hold.cancelled()) {
        throw link::Error(fmt::format(
            "{}: job stopped by the operator; the device is at {}, at rest ({} frames not sent, "
            "{} dropped by the device: MOTION CANCEL)",
            lk->name(), at, r.unsent, r.queued));
      }
      throw link::Error(fmt::format(
          "{}: job stopped by the operator; the device is at {} ({} frames not sent, {} left "
          "queued on the device{})",
          lk->name(), at, r.unsent, r.queued,
          (r.status_end.state & protocol::v2::kStateHold) ? ", held" : ""));
    }
    if (r.motion == 0) {
      fmt::print("feed hold and overrides: not available (the device refused MOTION)\n");
    }
    fmt::print(
        "streamed {} over {} with protocol v2: {} segments as {} LINE, {} LINE_PROFILE, {} ARC "
        "and {} DWELL frames, {} bytes in {:.2f} s\n",
        a.input, lk->name(), job2->segments, r.lines, r.profiles, r.arcs, r.dwells, r.bytes_written,
        r.elapsed.count());
    fmt::print("{}", link::format_report(r));
    if (r.skipped_heater) fmt::print("{} heater commands not sent\n", r.skipped_heater);
    if (r.pauses) fmt::print("{} pauses\n", r.pauses);
    if (job2->outputs)
      fmt::print("{} OUTPUT frames (coolant, fan, digital outputs) in step with the motion\n",
                 job2->outputs);
    if (r.t_raised) {
      fmt::print("{} segments faster than the STEP timing allows: slowed to it\n", r.t_raised);
    }
    print_final_position(p);
    if (port.empty() && hooks.after_default_stream) hooks.after_default_stream(*lk, p, cfg, sim);
    if (!r.position_ok) {
      throw link::Error(fmt::format(
          "{}: the device position changed by other than the plan's target (see 'device "
          "moved' above)",
          lk->name()));
    }
    return;
  }

  if (!job1) throw std::invalid_argument(v1_error);
  ProgressBar bar;
  link::StreamOptions so;
  so.ack_timeout = std::chrono::milliseconds(std::llround(cfg.ack_timeout_s * 1000.0));
  so.progress = [&bar](size_t d, size_t t) { bar.update(d, t); };
  const link::StreamReport r = link::stream_v1(*lk, p, so);
  fmt::print(
      "streamed {} over {} with protocol v1: {} moves, {} acks, {} warnings (unexpected bytes), "
      "{} dwells, {} bytes in {:.2f} s\n",
      a.input, lk->name(), r.moves, r.acks, r.warnings, r.dwells, r.bytes_written,
      r.elapsed.count());
  if (r.skipped_heater) fmt::print("{} heater commands not sent (v1 has none)\n", r.skipped_heater);
  if (r.ze_only) fmt::print("{} Z/E-only moves not driven by v1 (sent as 0,0 steps)\n", r.ze_only);
  print_final_position(p);
  if (port.empty() && hooks.after_default_stream) hooks.after_default_stream(*lk, p, cfg, sim);
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
  auto* sub = app.add_subcommand(
      "stream", "Stream a job to the controller (protocol v2 when it answers HELLO, else v1)");
  sub->add_option("FILE", args->input, "G-code file or step-file CSV")->required();
  sub->add_option("--port", args->port, "serial port (/dev/ttyUSB0, COM3, /dev/pts/N)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--baud", args->baud, "baud rate (default from config: 115200)")
      ->check(CLI::Range(1u, 100'000'000u));
  sub->add_option("--protocol", args->protocol,
                  "auto (default from config: v2 if the device answers HELLO within 300 ms, "
                  "else v1), v1 or v2")
      ->check(CLI::IsMember({"auto", "v1", "v2"}));
  sub->add_option("--timeout", args->timeout_s,
                  "v1: ACK timeout per move; v2: no answer at all; seconds (default 10)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--retransmit-timeout", args->retransmit_s,
                  "v2: resend from the device's next_seq when nothing is acknowledged this long, "
                  "seconds (default 0.3)")
      ->check(CLI::PositiveNumber);
  add_gcode_options(sub, args->common);
  sub->add_option("--feed-override", args->common.feed_override_pct, "feed override percent")
      ->check(CLI::Range(1.0, 1000.0));
  sub->add_option("--model", args->sim.model,
                  "simulated board (no --port): tlm (default) the SystemC twins of cnc_core, "
                  "event-driven and edge-for-edge equal to the RTL (no heaters, no --line-*, no "
                  "--fst); rtl the Verilated cnc_core (about 1.6 M clocks/s); both: the first "
                  "--max-moves moves into both with the lockstep host, compared")
      ->check(CLI::IsMember({"tlm", "rtl", "both"}));
  sub->add_flag("--realtime", args->sim.realtime,
                "tlm: simulated time follows the wall clock while the board is busy (a 5-minute "
                "job takes 5 minutes)");
  sub->add_option("--max-moves", args->sim.max_moves,
                  "--model both: only the first N moves (v2: motion frames)");
  sub->add_option("--plot", args->sim.plot_path,
                  "simulated board: plot of the executed vs commanded path (.svg, or .png with "
                  "rsvg-convert)");
  sub->add_option("--fst", args->sim.fst_path, "simulated board: FST waveform of the core");
  sub->add_option("--edges", args->sim.edges_csv, "simulated board: STEP/DIR/LASER edge list CSV");
  sub->add_option("--pause", args->pause_mode,
                  "at M0/M1/M6/M600: prompt (ask on the terminal), continue, stop, or auto "
                  "(prompt on a terminal; else continue on a simulated board, stop on a port)")
      ->check(CLI::IsMember({"auto", "prompt", "continue", "stop"}));
  sub->add_option("--heater-plot", args->heater_plot,
                  "v2 with heaters: temperature, setpoint and duty of the heaters used against "
                  "time as STATUS reports them (.svg)");
  if (hooks.add_sim_options) hooks.add_sim_options(*sub, args->sim);
  sub->callback([args, hooks = std::move(hooks)] { run_stream(*args, hooks); });
}

}  // namespace fpgacnc::cli
