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
  const gcode::PlaneAxes pa = gcode::plane_axes(m.plane);
  const auto u = static_cast<size_t>(pa.u), v = static_cast<size_t>(pa.v);
  const double cx = m.center[0], cy = m.center[1];
  const double r0 = std::hypot(m.start[u] - cx, m.start[v] - cy);
  const double r1 = std::hypot(m.end[u] - cx, m.end[v] - cy);
  const double a0 = std::atan2(m.start[v] - cy, m.start[u] - cx);
  const double a1 = std::atan2(m.end[v] - cy, m.end[u] - cx);
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
  sweep += (cw ? -kTwoPi : kTwoPi) * m.extra_turns;
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
    for (size_t i = 0; i < 4; ++i) p[i] = m.start[i] + (m.end[i] - m.start[i]) * f;
    p[u] = cx + r * std::cos(a);
    p[v] = cy + r * std::sin(a);
    pts.push_back(p);
  }
  pts.push_back(m.end);
  return pts;
}

namespace {

// Soft-limit test of one axis value, in steps.
std::optional<TravelViolation> outside(int axis, double mm, bool in_arc,
                                       const config::MachineConfig& cfg) {
  const auto a = static_cast<size_t>(axis);
  const config::Travel& t = cfg.travel[a];
  if (!t.enabled) return std::nullopt;
  const double spm = cfg.steps_per_mm[a];
  const long long v = std::llround(mm * spm);
  if (v > std::llround(t.max_mm * spm)) return TravelViolation{axis, true, in_arc, mm, t.max_mm};
  if (v < std::llround(t.min_mm * spm)) return TravelViolation{axis, false, in_arc, mm, t.min_mm};
  return std::nullopt;
}

}  // namespace

std::optional<TravelViolation> check_travel(const gcode::Move& m,
                                            const config::MachineConfig& cfg) {
  const bool arc = m.motion == gcode::Motion::kArcCw || m.motion == gcode::Motion::kArcCcw;
  if (arc) {
    const gcode::PlaneAxes pa = gcode::plane_axes(m.plane);
    const auto u = static_cast<size_t>(pa.u), v = static_cast<size_t>(pa.v);
    const config::Travel& tu = cfg.travel[u];
    const config::Travel& tv = cfg.travel[v];
    if (tu.enabled || tv.enabled) {
      const double cx = m.center[0], cy = m.center[1];
      const double r0 = std::hypot(m.start[u] - cx, m.start[v] - cy);
      const double r1 = std::hypot(m.end[u] - cx, m.end[v] - cy);
      const double a0 = std::atan2(m.start[v] - cy, m.start[u] - cx);
      const double a1 = std::atan2(m.end[v] - cy, m.end[u] - cx);
      const bool cw = m.motion == gcode::Motion::kArcCw;
      constexpr double kTwoPi = 2.0 * std::numbers::pi;
      constexpr double kQuarter = std::numbers::pi / 2.0;
      double sweep;
      if (m.full_circle) {
        sweep = cw ? -kTwoPi : kTwoPi;
      } else {
        sweep = a1 - a0;
        if (cw && sweep >= 0.0) sweep -= kTwoPi;
        if (!cw && sweep <= 0.0) sweep += kTwoPi;
      }
      sweep += (cw ? -kTwoPi : kTwoPi) * m.extra_turns;
      // Quarter-turn directions k * pi/2 strictly inside the sweep, in the order the arc meets
      // them: the first and last four (the radius changes linearly along a spiral).
      const double dir = cw ? -1.0 : 1.0;
      const double s0 = dir * a0 / kQuarter, s1 = dir * (a0 + sweep) / kQuarter;
      const long long k_first = static_cast<long long>(std::floor(s0)) + 1;
      const long long k_last = static_cast<long long>(std::ceil(s1)) - 1;
      for (long long k = k_first; k <= k_last; ++k) {
        if (k - k_first >= 4 && k_last - k >= 4) {
          k = k_last - 4;
          continue;
        }
        const double ang = dir * static_cast<double>(k) * kQuarter;
        const double f = (ang - a0) / sweep;
        const double r = r0 + (r1 - r0) * f;
        if (auto o = outside(pa.u, cx + r * std::cos(ang), true, cfg)) return o;
        if (auto o = outside(pa.v, cy + r * std::sin(ang), true, cfg)) return o;
      }
    }
  }
  for (int a = 0; a < config::kAxes; ++a) {
    if (auto o = outside(a, m.end[static_cast<size_t>(a)], false, cfg)) return o;
  }
  return std::nullopt;
}

std::optional<TravelViolation> check_travel_steps(const Steps4& position,
                                                  const config::MachineConfig& cfg) {
  for (size_t a = 0; a < 4; ++a) {
    const config::Travel& t = cfg.travel[a];
    if (!t.enabled) continue;
    const double spm = cfg.steps_per_mm[a];
    const double mm = static_cast<double>(position[a]) / spm;
    const int axis = static_cast<int>(a);
    if (position[a] > std::llround(t.max_mm * spm))
      return TravelViolation{axis, true, false, mm, t.max_mm};
    if (position[a] < std::llround(t.min_mm * spm))
      return TravelViolation{axis, false, false, mm, t.min_mm};
  }
  return std::nullopt;
}

std::string describe(const TravelViolation& v, char fourth_axis) {
  const char name =
      v.axis == config::kE ? fourth_axis : config::kAxisNames[static_cast<size_t>(v.axis)];
  const char* unit = name == 'A' ? "deg" : "mm";
  return fmt::format("{} reaches {:.3f} {}{}, {:.3f} {} {} its {} {:.3f} {}", name, v.value_mm,
                     unit, v.in_arc ? " inside the arc" : "", std::fabs(v.value_mm - v.limit_mm),
                     unit, v.above_max ? "beyond" : "below", v.above_max ? "max" : "min",
                     v.limit_mm, unit);
}

Planner::Planner(const config::MachineConfig& cfg, PlanOptions options, std::string source)
    : cfg_(cfg), opt_(options), source_(std::move(source)) {
  plan_.numerator = {v1_numerator(cfg.clk_hz, cfg.steps_per_mm[0]),
                     v1_numerator(cfg.clk_hz, cfg.steps_per_mm[1])};
}

void Planner::add(const gcode::Command& command) {
  if (const auto* m = std::get_if<gcode::Move>(&command)) {
    add_move(*m);
  } else if (const auto* d = std::get_if<gcode::Dwell>(&command)) {
    const double seconds = d->seconds * cfg_.dwell_time_pct / 100.0;
    plan_.items.emplace_back(Dwell{seconds, d->line});
    ++plan_.stats.dwells;
    plan_.stats.estimated_time_s += seconds;
  } else if (const auto* h = std::get_if<gcode::Heater>(&command)) {
    plan_.items.emplace_back(
        HeaterCommand{h->mcode, h->s.value_or(0.0), h->s.has_value(), h->line});
    ++plan_.stats.heater_commands;
  } else if (const auto* p = std::get_if<gcode::Pause>(&command)) {
    plan_.items.emplace_back(*p);
    ++plan_.stats.pauses;
  } else if (const auto* o = std::get_if<gcode::Output>(&command)) {
    plan_.items.emplace_back(*o);
    ++plan_.stats.outputs;
  } else if (const auto* msg = std::get_if<gcode::Message>(&command)) {
    plan_.items.emplace_back(*msg);
    ++plan_.stats.messages;
  } else if (const auto* l = std::get_if<gcode::Limits>(&command)) {
    add_limits(*l);
  } else if (const auto* pr = std::get_if<gcode::Probe>(&command)) {
    // A probe's end is the board's: the front end runs it (link::ProbeCycle), never the plan.
    throw gcode::Error(source_, pr->line, 0,
                       "a probe move (G38.2 .. G38.5) is run by the probing cycle, not planned");
  }
}

// M201/M203/M204/M205: for the rest of the job, never above the machine's limits.
void Planner::add_limits(const gcode::Limits& l) {
  auto lower = [&](double& slot, double value, double machine) {
    if (value <= 0.0) return;
    if (machine > 0.0 && value > machine) {
      ++plan_.stats.limits_clamped;
      value = machine;
    }
    slot = value;
  };
  for (size_t a = 0; a < 4; ++a) {
    lower(job_accel_[a], l.accel_mm_s2[a], cfg_.max_accel_mm_s2[a]);
    lower(job_max_feed_[a], l.max_feed_mm_min[a], cfg_.max_feed_mm_min[a]);
  }
  lower(job_path_accel_, l.path_accel_mm_s2, 0.0);
  lower(job_jd_, l.junction_deviation_mm, cfg_.junction_deviation_mm);
}

void Planner::add_move(const gcode::Move& m) {
  if (const auto v = check_travel(m, cfg_)) {
    throw TravelError(
        source_, m.line, *v,
        fmt::format("{} leaves the travel (soft limits, [travel]): {}",
                    m.motion == gcode::Motion::kArcCw || m.motion == gcode::Motion::kArcCcw
                        ? "arc"
                        : "move",
                    describe(*v, cfg_.fourth_axis)));
  }
  move_ = &m;
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
    for (size_t k = 0; k < pts.size(); ++k) {
      last_piece_ = k + 1 == pts.size();
      add_straight(pts[k], code, feed, rapid, m.line, s_word);
    }
    last_piece_ = true;
    arc_id_ = 0;
  } else {
    add_straight(m.end, code, feed, rapid, m.line, s_word);
  }
  move_ = nullptr;
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
      const double cap = job_max_feed_[a] > 0.0 ? job_max_feed_[a] : cfg_.max_feed_mm_min[a];
      if (comp > cap * (1.0 + 1e-12)) {
        eff *= cap / comp;
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
    s.rapid = rapid;
    s.source_line = line;
    s.feed_mm_min = feed;
    s.exec_feed_mm_min = eff;
    s.spindle_s = spindle_s;
    s.arc_id = arc_id_;
    s.accel_mm_s2 = job_accel_;
    s.path_accel_mm_s2 = job_path_accel_;
    s.junction_deviation_mm = job_jd_;
    if (move_) {
      if (move_->path_tolerance_mm > 0.0 &&
          (s.junction_deviation_mm == 0.0 || move_->path_tolerance_mm < s.junction_deviation_mm))
        s.junction_deviation_mm = std::min(move_->path_tolerance_mm, cfg_.junction_deviation_mm);
      s.exact_stop = move_->exact_stop && k == parts && last_piece_;
    }
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
  plan_.fourth_axis = cfg_.fourth_axis;
  for (size_t a = 0; a < 4; ++a) {
    plan_.final_mm[a] = static_cast<double>(pos_[a]) / cfg_.steps_per_mm[a];
  }
  return std::move(plan_);
}

std::vector<PlanItem> Planner::take_items() {
  std::vector<PlanItem> out = std::move(plan_.items);
  plan_.items.clear();
  return out;
}

gcode::Options gcode_options(const config::MachineConfig& cfg) {
  gcode::Options go;
  go.default_feed_mm_min = cfg.default_feed_mm_min;
  go.arc_tolerance_mm = cfg.arc_tolerance_mm;
  if (cfg.gcode.dialect != "auto") {
    go.dialect = gcode::parse_dialect(cfg.gcode.dialect);
    go.dialect_source = "configuration [gcode] dialect =";
  }
  go.tool_table = cfg.gcode.tool_table;
  go.tool_change_pause = cfg.gcode.tool_change_pause;
  go.fourth_axis = cfg.fourth_axis;
  go.optional_stop = cfg.gcode.optional_stop;
  go.block_delete = cfg.gcode.block_delete;
  return go;
}

Plan plan_program(const gcode::Program& program, const config::MachineConfig& cfg,
                  PlanOptions options) {
  Planner p(cfg, options, program.file_name);
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
  Planner p(cfg, options, path);
  const gcode::Options go = gcode_options(cfg);
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
