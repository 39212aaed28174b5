#include "fpgacnc/plan/planner.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "fpgacnc/plan/stepfile.h"

namespace fpgacnc::plan {
namespace {

constexpr int64_t kMaxPacketSteps = std::numeric_limits<int32_t>::max();

bool is_cutting(const gcode::Move& m, const config::MachineConfig& cfg) {
  if (m.motion == gcode::Motion::kRapid) return false;
  if (!cfg.laser_requires_m3) return true;
  return m.spindle_on && (!m.spindle_s || *m.spindle_s > 0.0);
}

}  // namespace

uint32_t v1_numerator(uint64_t clk_hz, double steps_per_mm) {
  if (!(steps_per_mm > 0.0)) throw std::invalid_argument("steps_per_mm must be > 0");
  const uint64_t num = clk_hz * 60;
  double q;
  if (steps_per_mm == std::floor(steps_per_mm) && steps_per_mm < 1e15) {
    q = static_cast<double>(num / static_cast<uint64_t>(steps_per_mm));
  } else {
    q = std::floor(static_cast<double>(num) / steps_per_mm);
  }
  if (q < 1.0 || q > static_cast<double>(std::numeric_limits<uint32_t>::max())) {
    throw std::invalid_argument(
        fmt::format("v1 numerator clk_hz*60/steps_per_mm = {} does not fit in 32 bits", q));
  }
  return static_cast<uint32_t>(q);
}

std::vector<gcode::Vec4> arc_chord_points(const gcode::Move& m, double tolerance_mm) {
  const double cx = m.center[0], cy = m.center[1];
  const double r0 = std::hypot(m.start[0] - cx, m.start[1] - cy);
  const double r1 = std::hypot(m.end[0] - cx, m.end[1] - cy);
  const double a0 = std::atan2(m.start[1] - cy, m.start[0] - cx);
  const double a1 = std::atan2(m.end[1] - cy, m.end[0] - cx);
  const bool cw = m.motion == gcode::Motion::kArcCw;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double sweep;
  if (m.full_circle) {
    sweep = cw ? -kTwoPi : kTwoPi;
  } else {
    sweep = a1 - a0;
    if (cw && sweep >= 0.0) sweep -= kTwoPi;
    if (!cw && sweep <= 0.0) sweep += kTwoPi;
  }
  const double rmax = std::max(r0, r1);
  double max_angle = kTwoPi / 3.0;  // never fewer than 3 chords for a full circle
  if (tolerance_mm > 0.0 && tolerance_mm < rmax) {
    max_angle = std::min(max_angle, 2.0 * std::acos(1.0 - tolerance_mm / rmax));
  }
  const double want = std::ceil(std::fabs(sweep) / max_angle);
  if (!(want < 1e7)) {
    throw std::invalid_argument("arc needs more than 1e7 chords: arc tolerance too small");
  }
  const int n = std::max(1, static_cast<int>(want));
  std::vector<gcode::Vec4> pts;
  pts.reserve(static_cast<size_t>(n));
  for (int k = 1; k < n; ++k) {
    const double f = static_cast<double>(k) / n;
    const double a = a0 + sweep * f;
    const double r = r0 + (r1 - r0) * f;
    gcode::Vec4 p;
    p[0] = cx + r * std::cos(a);
    p[1] = cy + r * std::sin(a);
    p[2] = m.start[2] + (m.end[2] - m.start[2]) * f;
    p[3] = m.start[3] + (m.end[3] - m.start[3]) * f;
    pts.push_back(p);
  }
  pts.push_back(m.end);
  return pts;
}

Planner::Planner(const config::MachineConfig& cfg, PlanOptions options) : cfg_(cfg), opt_(options) {
  plan_.numerator = {v1_numerator(cfg.clk_hz, cfg.steps_per_mm[0]),
                     v1_numerator(cfg.clk_hz, cfg.steps_per_mm[1])};
}

void Planner::add(const gcode::Command& command) {
  if (const auto* m = std::get_if<gcode::Move>(&command)) {
    add_move(*m);
  } else if (const auto* d = std::get_if<gcode::Dwell>(&command)) {
    plan_.items.emplace_back(Dwell{d->seconds, d->line});
    ++plan_.stats.dwells;
    plan_.stats.estimated_time_s += d->seconds;
  } else if (const auto* h = std::get_if<gcode::Heater>(&command)) {
    plan_.items.emplace_back(
        HeaterCommand{h->mcode, h->s.value_or(0.0), h->s.has_value(), h->line});
    ++plan_.stats.heater_commands;
  }
}

void Planner::add_move(const gcode::Move& m) {
  const bool cutting = is_cutting(m, cfg_);
  const uint8_t code = cutting ? static_cast<uint8_t>(m.motion) : 0;
  const bool rapid = m.motion == gcode::Motion::kRapid;
  const double feed = rapid ? cfg_.rapid_feed_mm_min : m.feed_mm_min;
  const double s_word = m.spindle_s ? *m.spindle_s : -1.0;
  if (m.motion == gcode::Motion::kArcCw || m.motion == gcode::Motion::kArcCcw) {
    const auto pts = arc_chord_points(m, cfg_.arc_tolerance_mm);
    plan_.stats.arc_chords += pts.size();
    plan_.arcs.push_back(m);
    arc_id_ = static_cast<uint32_t>(plan_.arcs.size());
    for (const auto& p : pts) add_straight(p, code, feed, rapid, m.line, s_word);
    arc_id_ = 0;
  } else {
    add_straight(m.end, code, feed, rapid, m.line, s_word);
  }
}

void Planner::add_straight(const gcode::Vec4& target_mm, uint8_t code, double feed, bool rapid,
                           int line, double spindle_s) {
  Steps4 target;
  Steps4 delta;
  int64_t maxabs = 0;
  for (size_t a = 0; a < 4; ++a) {
    target[a] = std::llround(target_mm[a] * cfg_.steps_per_mm[a]);
    delta[a] = target[a] - pos_[a];
    maxabs = std::max(maxabs, delta[a] < 0 ? -delta[a] : delta[a]);
  }
  if (maxabs == 0) return;  // nothing to move after rounding

  // Effective feed: override (not for rapids), then limited by each axis's max feed.
  double eff = rapid ? feed : feed * opt_.feed_override_pct / 100.0;
  double len3 = 0.0;
  for (size_t a = 0; a < 3; ++a) {
    const double d = static_cast<double>(delta[a]) / cfg_.steps_per_mm[a];
    len3 += d * d;
  }
  len3 = std::sqrt(len3);
  if (len3 > 0.0) {
    bool limited = false;
    for (size_t a = 0; a < 3; ++a) {
      const double d = std::fabs(static_cast<double>(delta[a]) / cfg_.steps_per_mm[a]);
      const double comp = eff * d / len3;
      if (comp > cfg_.max_feed_mm_min[a] * (1.0 + 1e-12)) {
        eff *= cfg_.max_feed_mm_min[a] / comp;
        limited = true;
      }
    }
    if (limited) ++plan_.stats.feed_limited;
  }

  const int64_t parts = (maxabs + kMaxPacketSteps - 1) / kMaxPacketSteps;
  if (parts > 1) ++plan_.stats.split_moves;
  const Steps4 origin = pos_;
  for (int64_t k = 1; k <= parts; ++k) {
    Segment s;
    s.code = code;
    s.source_line = line;
    s.feed_mm_min = feed;
    s.exec_feed_mm_min = eff;
    s.spindle_s = spindle_s;
    s.arc_id = arc_id_;
    for (size_t a = 0; a < 4; ++a) {
      const auto part = static_cast<int64_t>(static_cast<__int128>(delta[a]) * k / parts);
      s.target[a] = origin[a] + part;
      s.steps[a] = s.target[a] - pos_[a];
    }
    const double dx = static_cast<double>(s.steps[0]) / cfg_.steps_per_mm[0];
    const double dy = static_cast<double>(s.steps[1]) / cfg_.steps_per_mm[1];
    const double dz = static_cast<double>(s.steps[2]) / cfg_.steps_per_mm[2];
    const double lxy = std::hypot(dx, dy);
    s.length_mm = std::sqrt(dx * dx + dy * dy + dz * dz);
    double fd = eff;
    if (lxy > 0.0) {
      const bool x_dom = std::llabs(s.steps[0]) >= std::llabs(s.steps[1]);
      fd = eff * std::fabs(x_dom ? dx : dy) / lxy;
    } else {
      ++plan_.stats.ze_only_moves;
    }
    const long long r = std::llround(fd);
    if (r < 1 || r > 65535) ++plan_.stats.feed_clamped;
    s.feed_v1 = static_cast<uint16_t>(std::clamp<long long>(r, 1, 65535));
    ++plan_.stats.segments;
    if (code == 0) {
      ++plan_.stats.rapid_segments;
    } else {
      ++plan_.stats.cutting_segments;
    }
    plan_.stats.path_length_mm += s.length_mm;
    if (eff > 0.0) plan_.stats.estimated_time_s += s.length_mm / eff * 60.0;
    pos_ = s.target;
    plan_.items.emplace_back(s);
  }
}

Plan Planner::finish() {
  plan_.final_steps = pos_;
  for (size_t a = 0; a < 4; ++a) {
    plan_.final_mm[a] = static_cast<double>(pos_[a]) / cfg_.steps_per_mm[a];
  }
  return std::move(plan_);
}

Plan plan_program(const gcode::Program& program, const config::MachineConfig& cfg,
                  PlanOptions options) {
  Planner p(cfg, options);
  for (const auto& c : program.commands) p.add(c);
  Plan plan = p.finish();
  plan.source = program.file_name;
  plan.input = program.stats;
  return plan;
}

Plan plan_gcode_file(const std::string& path, const config::MachineConfig& cfg,
                     PlanOptions options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw gcode::Error(path, 0, 0, "cannot open file");
  Planner p(cfg, options);
  gcode::Options go;
  go.default_feed_mm_min = cfg.default_feed_mm_min;
  const gcode::Stats in =
      gcode::parse_stream(f, path, go, [&](const gcode::Command& c) { p.add(c); });
  Plan plan = p.finish();
  plan.input = in;
  plan.source = path;
  return plan;
}

Plan plan_input_file(const std::string& path, const config::MachineConfig& cfg,
                     PlanOptions options) {
  if (looks_like_step_file(path)) return read_step_file(path, cfg);
  return plan_gcode_file(path, cfg, options);
}

}  // namespace fpgacnc::plan
