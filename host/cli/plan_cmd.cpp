// fpgacnc plan FILE [--config F] [--csv OUT] [--hex OUT] [--v2-hex OUT] [--feed-override PCT]
//                   [--motion profile|constant] [--times] [--speed-svg OUT [--zoom T0 T1]]
//                   [--board-edges E.csv]
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>

#include "commands.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/plan/speed_plot.h"
#include "fpgacnc/plan/stepfile.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::cli {
namespace {

struct PlanArgs {
  std::string input;
  std::string csv_out;
  std::string hex_out;
  std::string v2_hex_out;
  std::string motion;  // "" = from the configuration
  bool times = false;
  std::string speed_svg;
  std::vector<double> zoom{0.0, 10.0};
  std::string board_edges;  // simulated board edge CSV to overlay on the speed plot
  bool quiet = false;
  CommonOptions common;
};

void print_summary(const plan::Plan& p, const config::MachineConfig& cfg) {
  const auto& s = p.stats;
  fmt::print(
      "summary: {} segments ({} rapid, {} cutting, {} arc chords), {} dwells, {} heater "
      "commands (recorded, not sent by v1 or v2)\n",
      s.segments, s.rapid_segments, s.cutting_segments, s.arc_chords, s.dwells, s.heater_commands);
  fmt::print(
      "path length {:.3f} mm, estimated time {:.1f} s (no acceleration), feed override "
      "{}%\n",
      s.path_length_mm, s.estimated_time_s, cfg.feed_override_pct);
  fmt::print("v1 init numerators X {} Y {}\n", p.numerator[0], p.numerator[1]);
  fmt::print(
      "warnings: {} feeds clamped to [1, 65535], {} feeds limited by axis max, {} moves "
      "split (> INT32_MAX steps), {} Z/E-only moves not driven by v1\n",
      s.feed_clamped, s.feed_limited, s.split_moves, s.ze_only_moves);
  print_gcode_report(p);
  if (p.input.modal_arc_as_line || p.input.arc_radius_mismatch) {
    fmt::print(
        "input warnings: {} modal G2/G3 lines without I/J/R run as straight lines, {} arcs "
        "whose end radius differs from the start radius (planned as spirals)\n",
        p.input.modal_arc_as_line, p.input.arc_radius_mismatch);
  }
  print_final_position(p);
}

// Constant-feed v2 speeds: every LINE at length / T, as the device runs it (zero gap).
plan::SpeedSeries constant_speed_series(const protocol::v2::Job& j,
                                        const config::MachineConfig& cfg) {
  plan::SpeedSeries s;
  s.name = "v2 constant feed (LINE)";
  s.color = "#2e86c1";
  const double clk = static_cast<double>(cfg.clk_hz);
  uint64_t t0 = 0;
  for (const auto& jf : j.frames) {
    if (jf.t == 0) continue;
    double v = 0.0;
    if (jf.frame.type == static_cast<uint8_t>(protocol::v2::Type::Line)) {
      const auto l = protocol::v2::decode_line(jf.frame);
      double l2 = 0.0, le = 0.0;
      for (size_t a = 0; a < l.steps.size(); ++a) {
        const double d = l.steps[a] / cfg.steps_per_mm[a];
        if (a < 3) l2 += d * d;
        if (a == 3) le = std::fabs(d);
      }
      const double len = l2 > 0 ? std::sqrt(l2) : le;
      v = len / (jf.t / clk);
    }
    s.pts.emplace_back(t0 / clk, v);
    t0 += jf.t;
    s.pts.emplace_back(t0 / clk, v);
  }
  return s;
}

// Path speed measured from a simulated board's STEP edges (fpgacnc stream --edges F.csv): X/Y/Z
// positions from the STEP rises and DIR levels, speed over 1 ms windows. Time 0 is aligned with
// the plan: the first STEP rise is put at the first dominant step of the first profile.
plan::SpeedSeries board_speed_series(const std::string& path, const config::MachineConfig& cfg,
                                     const plan::ProfilePlan& pp) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(fmt::format("{}: error: cannot open file", path));
  std::string line;
  std::getline(f, line);  // header: cycle,time_s,signal,value
  std::array<int, 3> dir{-1, -1, -1};
  std::array<int64_t, 3> pos{};
  std::vector<std::pair<uint64_t, std::array<int64_t, 3>>> pts;
  while (std::getline(f, line)) {
    const auto c1 = line.find(',');
    const auto c2 = line.find(',', c1 + 1);
    const auto c3 = line.find(',', c2 + 1);
    if (c3 == std::string::npos) continue;
    const uint64_t cyc = std::stoull(line.substr(0, c1));
    const std::string sig = line.substr(c2 + 1, c3 - c2 - 1);
    const int val = std::stoi(line.substr(c3 + 1));
    if (sig.size() != 6 || (sig[5] != 'x' && sig[5] != 'y' && sig[5] != 'z')) continue;
    const size_t a = static_cast<size_t>(sig[5] == 'x' ? 0 : sig[5] == 'y' ? 1 : 2);
    if (sig.rfind("dir_", 0) == 0) dir[a] = val ? 1 : -1;
    if (sig.rfind("step_", 0) == 0 && val == 1) {
      pos[a] += dir[a];
      pts.emplace_back(cyc, pos);
    }
  }
  plan::SpeedSeries s;
  s.name = "simulated board (STEP edges; windows of >= 1 ms and 16 steps)";
  s.color = "#27ae60";
  if (pts.empty()) return s;
  uint64_t first_tick = 0;  // first dominant step of the first profile, clocks
  for (const auto& it : pp.items) {
    if (const auto* p = std::get_if<plan::Profile>(&it)) {
      plan::Recurrence r = p->rec;
      r.n_end = 1;
      r.v_exit = r.v_cruise;
      r.d = 1;
      first_tick = plan::simulate_recurrence(r).clocks;
      break;
    }
  }
  const double clk = static_cast<double>(cfg.clk_hz);
  const double t0 = static_cast<double>(pts.front().first) - static_cast<double>(first_tick);
  // Windows of at least 1 ms and 16 STEP events (a slow move has few steps per ms).
  const uint64_t win = cfg.clk_hz / 1000;
  size_t k = 0;
  while (k + 1 < pts.size()) {
    const size_t k0 = k;
    while (k + 1 < pts.size() && (k - k0 < 16 || pts[k].first - pts[k0].first < win)) ++k;
    const double dt = static_cast<double>(pts[k].first - pts[k0].first);
    if (dt <= 0) break;
    double d2 = 0.0;
    for (size_t a = 0; a < 3; ++a) {
      const double d =
          static_cast<double>(pts[k].second[a] - pts[k0].second[a]) / cfg.steps_per_mm[a];
      d2 += d * d;
    }
    const double v = std::sqrt(d2) / (dt / clk);
    s.pts.emplace_back((static_cast<double>(pts[k0].first) - t0) / clk, v);
    s.pts.emplace_back((static_cast<double>(pts[k].first) - t0) / clk, v);
  }
  return s;
}

// Job time estimates (seconds) at the same feeds: v1 stop-and-wait (each move at its v1 feed
// word, T = floor(NUMERATOR_dom / feed) * n_dom over X/Y, plus kV1OverheadClocks115200 per move
// for the packet, the ACK and the host turnaround; dwells added), v2 constant feed (sum of LINE
// and DWELL T, zero gap), v2 planned (sum of the exact LINE_PROFILE clock counts and DWELL T).
struct JobTimes {
  double v1_s = 0.0, v2_constant_s = 0.0, v2_profile_s = 0.0;
  uint64_t v1_moves = 0, v2_lines = 0, v2_profiles = 0;
  uint64_t v1_clocks = 0, v2_constant_clocks = 0, v2_profile_clocks = 0;
};
constexpr uint64_t kV1OverheadClocks115200 = 51'981;  // host/README.md, measured

JobTimes job_times(const plan::Plan& p, const config::MachineConfig& cfg) {
  const uint64_t v1_overhead_clocks = kV1OverheadClocks115200;
  JobTimes t;
  const double clk = static_cast<double>(cfg.clk_hz);
  uint64_t v1 = 0;
  for (const auto& item : p.items) {
    if (const auto* s = std::get_if<plan::Segment>(&item)) {
      const bool x_dom = std::llabs(s->steps[0]) >= std::llabs(s->steps[1]);
      const int64_t n = std::max(std::llabs(s->steps[0]), std::llabs(s->steps[1]));
      const uint32_t num = p.numerator[x_dom ? 0 : 1];
      v1 += static_cast<uint64_t>(num / std::max<uint16_t>(s->feed_v1, 1)) *
                static_cast<uint64_t>(n) +
            v1_overhead_clocks;
      ++t.v1_moves;
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      v1 += static_cast<uint64_t>(std::llround(d->seconds * clk));
    }
  }
  t.v1_clocks = v1;
  config::MachineConfig c = cfg;
  c.motion = "constant";
  const protocol::v2::PackOptions motion_only{.heaters = false};
  const auto jc = protocol::v2::pack_job(plan::plan_motion(p, c), c, motion_only);
  c.motion = "profile";
  const auto jp = protocol::v2::pack_job(plan::plan_motion(p, c), c, motion_only);
  t.v2_lines = jc.lines;
  t.v2_profiles = jp.profiles;
  t.v2_constant_clocks = jc.total_t;
  t.v2_profile_clocks = jp.total_t;
  t.v1_s = static_cast<double>(v1) / clk;
  t.v2_constant_s = static_cast<double>(jc.total_t) / clk;
  t.v2_profile_s = static_cast<double>(jp.total_t) / clk;
  return t;
}

void print_times(const plan::Plan& p, const config::MachineConfig& cfg) {
  const auto t = job_times(p, cfg);
  fmt::print(
      "job time, same feeds ({}; accel X {} Y {} Z {} E {} mm/s^2, junction deviation {} mm, "
      "window {}):\n",
      p.source, cfg.max_accel_mm_s2[0], cfg.max_accel_mm_s2[1], cfg.max_accel_mm_s2[2],
      cfg.max_accel_mm_s2[3], cfg.junction_deviation_mm, cfg.lookahead_segments);
  fmt::print("  {:<42} {:>8} {:>14} {:>12}\n", "mode", "frames", "clocks", "seconds");
  fmt::print("  {:<42} {:>8} {:>14} {:>12.3f}\n",
             fmt::format("v1 stop-and-wait, X/Y only (+{} clk/move)", kV1OverheadClocks115200),
             t.v1_moves, t.v1_clocks, t.v1_s);
  fmt::print("  {:<42} {:>8} {:>14} {:>12.3f}\n", "v2 constant feed (LINE, zero gap)", t.v2_lines,
             t.v2_constant_clocks, t.v2_constant_s);
  fmt::print("  {:<42} {:>8} {:>14} {:>12.3f}\n", "v2 planned (LINE_PROFILE, zero gap)",
             t.v2_profiles, t.v2_profile_clocks, t.v2_profile_s);
  if (p.stats.ze_only_moves) {
    fmt::print("  (v1 does not drive Z/E: its {} Z/E-only moves take only the per-move overhead)\n",
               p.stats.ze_only_moves);
  }
}

void run_plan(const PlanArgs& a) {
  config::MachineConfig cfg = load_config(a.common);
  if (!a.motion.empty()) cfg.motion = a.motion;
  plan::PlanOptions po;
  po.feed_override_pct = cfg.feed_override_pct;
  const plan::Plan p = plan::plan_input_file(a.input, cfg, po);
  // Packing validates every segment for v1 (and v2 when asked) before anything is written.
  const auto bytes = protocol::v1::job_bytes(p);
  std::optional<protocol::v2::Job> job2;
  // The motion frames only: heater commands are listed, not checked (no heaters needed to plan).
  if (!a.v2_hex_out.empty() || cfg.motion == "profile")
    job2 = protocol::v2::pack_job(plan::plan_motion(p, cfg), cfg, {.heaters = false});
  if (!a.quiet) {
    size_t idx = 0;
    std::string out;
    for (const auto& item : p.items) {
      if (const auto* s = std::get_if<plan::Segment>(&item)) {
        out += fmt::format("{:6} line {:6} code {} steps X {:9} Y {:9} Z {:7} E {:7} feed {}\n",
                           idx++, s->source_line, s->code, s->steps[0], s->steps[1], s->steps[2],
                           s->steps[3], s->feed_v1);
      } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
        out += fmt::format("     - line {:6} dwell {:.3f} s\n", d->source_line, d->seconds);
      } else if (const auto* h = std::get_if<plan::HeaterCommand>(&item)) {
        out += fmt::format("     - line {:6} heater M{} S{} (not sent by v1)\n", h->source_line,
                           h->mcode, h->s);
      }
      if (out.size() > (1 << 16)) {
        std::fwrite(out.data(), 1, out.size(), stdout);
        out.clear();
      }
    }
    std::fwrite(out.data(), 1, out.size(), stdout);
  }
  print_summary(p, cfg);
  if (!a.csv_out.empty()) plan::write_step_file(a.csv_out, p, cfg);
  if (!a.hex_out.empty()) {
    std::ofstream f(a.hex_out);
    if (!f) throw std::runtime_error(fmt::format("{}: error: cannot create file", a.hex_out));
    // One packet per line: the init packet, then each motion packet.
    size_t pos = 0;
    auto line = [&](size_t n) {
      for (size_t i = 0; i < n; ++i) f << (i ? " " : "") << fmt::format("{:02X}", bytes[pos + i]);
      f << '\n';
      pos += n;
    };
    line(protocol::v1::kInitSize);
    while (pos < bytes.size()) line(protocol::v1::kMotionSize);
    if (!f) throw std::runtime_error(fmt::format("{}: error: write error", a.hex_out));
  }
  if (a.times) print_times(p, cfg);
  if (!a.speed_svg.empty()) {
    config::MachineConfig c = cfg;
    c.motion = "constant";
    const auto jc = protocol::v2::pack_job(plan::plan_motion(p, c), c, {.heaters = false});
    const auto pp = plan::plan_profiles(p, cfg);
    const std::string title = fmt::format(
        "{}: path speed against time (accel X/Y {}/{} mm/s^2, junction deviation {} mm)",
        std::filesystem::path(p.source).filename().string(), cfg.max_accel_mm_s2[0],
        cfg.max_accel_mm_s2[1], cfg.junction_deviation_mm);
    std::vector<plan::SpeedSeries> series;
    if (!a.board_edges.empty()) series.push_back(board_speed_series(a.board_edges, cfg, pp));
    series.push_back(constant_speed_series(jc, cfg));
    series.push_back(plan::profile_speed_series(pp, cfg.clk_hz));
    const std::string svg = plan::speed_svg(series, title, a.zoom[0], a.zoom[1]);
    std::ofstream f(a.speed_svg);
    f << svg;
    if (!f) throw std::runtime_error(fmt::format("{}: error: cannot write file", a.speed_svg));
  }
  if (job2) {
    const auto& j = *job2;
    if (j.profiles) {
      const auto& ps = j.profile_stats;
      fmt::print(
          "v2 planned: {} LINE_PROFILE frames ({} SHORT), {} DWELL frames, {} moves split "
          "(n_dom >= 2^24), {} ARC frames ({} arcs as chords), {} forced stops, {} D lowered by "
          "the exact check, {} exits above plan, {} A raised to 1 LSB; {} wire bytes; job time "
          "{} clocks = {:.6f} s (incl. {} DIR reversal pauses, {} clocks)\n",
          j.profiles, j.short_lines, j.dwells, ps.split_moves, j.arcs, ps.arcs_as_chords,
          ps.forced_stops, ps.d_adjusted, ps.exit_overshoot, ps.a_clamped, j.wire_bytes, j.total_t,
          static_cast<double>(j.total_t) / static_cast<double>(cfg.clk_hz), j.reversal_gaps,
          j.reversal_gap_clocks);
    } else {
      fmt::print(
          "v2: {} LINE frames ({} SHORT), {} DWELL frames, {} moves split, {} segments raised "
          "to the STEP rate; {} wire bytes; job time without gaps {:.3f} s\n",
          j.lines, j.short_lines, j.dwells, j.split_moves, j.t_raised, j.wire_bytes,
          static_cast<double>(j.total_t) / static_cast<double>(cfg.clk_hz));
    }
    if (a.v2_hex_out.empty()) return;
    std::ofstream f(a.v2_hex_out);
    if (!f) throw std::runtime_error(fmt::format("{}: error: cannot create file", a.v2_hex_out));
    // One frame per line, as sent to a device whose next_seq is 0: CONFIG_AXIS x4, NUMERATORS,
    // LINE/DWELL, RELEASE.
    for (const auto& fr : protocol::v2::session_frames(j, 0, config::kAxes)) {
      f << protocol::v2::hex(fr) << '\n';
    }
    if (!f) throw std::runtime_error(fmt::format("{}: error: write error", a.v2_hex_out));
  }
}

}  // namespace

void register_plan(CLI::App& app) {
  auto args = std::make_shared<PlanArgs>();
  auto* sub = app.add_subcommand("plan", "Plan a G-code file (or step-file CSV) into v1 segments");
  sub->add_option("FILE", args->input, "G-code file or step-file CSV")->required();
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--csv", args->csv_out, "write the segments as a step-file CSV");
  sub->add_option("--hex", args->hex_out, "write the v1 byte stream as hex, one packet a line");
  sub->add_option("--v2-hex", args->v2_hex_out,
                  "write the v2 frames as hex, one frame a line (SEQ from 0: config, "
                  "NUMERATORS, LINE/DWELL, RELEASE)");
  add_gcode_options(sub, args->common);
  sub->add_option("--feed-override", args->common.feed_override_pct, "feed override percent")
      ->check(CLI::Range(1.0, 1000.0));
  sub->add_option("--motion", args->motion,
                  "v2 motion: profile (look-ahead planned LINE_PROFILE) or constant (LINE); "
                  "default from the configuration")
      ->check(CLI::IsMember({"profile", "constant"}));
  sub->add_flag("--times", args->times,
                "print the job time of v1 stop-and-wait, v2 constant feed and v2 planned");
  sub->add_option("--speed-svg", args->speed_svg,
                  "write an SVG of path speed against time (planned and constant feed)");
  sub->add_option("--board-edges", args->board_edges,
                  "overlay the speed measured from a simulated board's edge CSV (stream --edges)");
  sub->add_option("--zoom", args->zoom, "zoom window of the speed plot, seconds (T0 T1)")
      ->expected(2);
  sub->add_flag("-q,--quiet", args->quiet, "print only the summary");
  sub->callback([args] { run_plan(*args); });
}

}  // namespace fpgacnc::cli
