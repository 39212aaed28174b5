#include "fpgacnc/plan/lookahead.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace fpgacnc::plan {
namespace {

using i128 = __int128;
constexpr i128 kOne = i128{1} << kFracBits;
constexpr uint64_t kMaxClocks = uint64_t{1} << 62;

int64_t iabs(int64_t v) {
  return v < 0 ? -v : v;
}

// Smallest i in [1, hi] with g(i) >= t, or 0 when g(hi) < t. g must be non-decreasing.
template <class G>
uint64_t first_reaching(uint64_t hi, i128 t, G g) {
  if (hi == 0 || g(hi) < t) return 0;
  uint64_t lo = 1;
  while (lo < hi) {
    const uint64_t mid = lo + (hi - lo) / 2;
    if (g(mid) >= t) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return lo;
}

uint64_t ceil_div(i128 a, i128 b) {
  if (a <= 0) return 0;
  const i128 q = (a + b - 1) / b;
  if (q > static_cast<i128>(kMaxClocks)) throw std::invalid_argument("segment never ends");
  return static_cast<uint64_t>(q);
}

// ceil(sqrt(x)) for x >= 0 (x < 2^100).
uint64_t isqrt_ceil(i128 x) {
  if (x <= 0) return 0;
  auto r = static_cast<uint64_t>(std::sqrt(static_cast<long double>(x)));
  while (static_cast<i128>(r) * r > x) --r;
  while (static_cast<i128>(r) * r < x) ++r;
  return r;
}

}  // namespace

const char* profile_field_error(const ProfileFields& f) {
  if (f.n_dom < 1 || f.n_dom > kMaxProfileSteps) return "n_dom outside 1..2^24-1";
  if (f.v_cruise > kMaxVCruise) return "V_cruise >= 2^47";
  if (f.v_entry > f.v_cruise) return "V_entry > V_cruise";
  if (f.v_exit > f.v_cruise) return "V_exit > V_cruise";
  if (f.v_exit < 1) return "V_exit < 1";
  if (f.a < 1 && f.v_entry < 1) return "A = 0 and V_entry = 0";
  return nullptr;
}

namespace {
Recurrence to_recurrence(const ProfileFields& f) {
  return Recurrence{f.n_dom, f.v_entry, f.v_cruise, f.v_exit, f.a, f.d};
}
}  // namespace

ProfileRun simulate_profile(const ProfileFields& f, bool record_knots) {
  if (const char* e = profile_field_error(f)) {
    throw std::invalid_argument(fmt::format("profile fields: {}", e));
  }
  return simulate_recurrence(to_recurrence(f), record_knots);
}

ProfileRun simulate_recurrence(const Recurrence& f, bool record_knots) {
  if (f.n_end < 1 || f.n_end > kMaxArcCost || f.v_cruise > kMaxArcV || f.a > kMaxArcA ||
      f.v_entry > f.v_cruise || f.v_exit > f.v_cruise || f.v_exit < 1 ||
      (f.a < 1 && f.v_entry < 1)) {
    throw std::invalid_argument("recurrence fields out of range");
  }
  ProfileRun r;
  const i128 n_end = static_cast<i128>(f.n_end) * kOne;
  const i128 d_start = static_cast<i128>(std::min<uint64_t>(f.d, f.n_end)) * kOne;
  const auto a = static_cast<int64_t>(f.a);
  const auto vc = static_cast<int64_t>(f.v_cruise);
  const auto ve = static_cast<int64_t>(f.v_exit);
  int64_t v = static_cast<int64_t>(f.v_entry);
  i128 u = 0;
  uint64_t c = 0;
  auto knot = [&](uint64_t clk, int64_t vv) {
    if (record_knots) r.knots.emplace_back(clk, static_cast<uint64_t>(vv));
  };
  auto peak = [&](int64_t vv) { r.v_peak = std::max(r.v_peak, static_cast<uint64_t>(vv)); };
  auto finish = [&](uint64_t clocks, int64_t v_last) {
    if (clocks > kMaxClocks) throw std::invalid_argument("segment never ends");
    r.clocks = clocks;
    r.v_last = static_cast<uint64_t>(v_last);
    knot(clocks - 1, v_last);
    return r;
  };
  for (int guard = 0; guard < 16; ++guard) {
    peak(v);
    knot(c, v);          // V used from clock c on
    if (u >= d_start) {  // decelerating: V <- max(V - A, V_exit)
      if (v > ve && a > 0) {
        const auto jcap = static_cast<uint64_t>((v - ve + a - 1) / a);
        auto g = [&](uint64_t i) {
          const i128 ii = i;
          return u + ii * v - static_cast<i128>(a) * ii * (ii - 1) / 2;
        };
        const uint64_t i = first_reaching(jcap, n_end, g);
        if (i) return finish(c + i, v - static_cast<int64_t>(i - 1) * a);
        u = g(jcap);
        c += jcap;
        knot(c - 1, v - static_cast<int64_t>(jcap - 1) * a);
        v = ve;
      } else if (v < ve) {  // one clock at V, then V_exit
        u += v;
        ++c;
        if (u >= n_end) return finish(c, v);
        v = ve;
      } else {  // constant at V (V == V_exit, or A == 0)
        if (v < 1) throw std::invalid_argument("segment never ends");
        return finish(c + ceil_div(n_end - u, v), v);
      }
    } else {  // accelerating / cruising: V <- min(V + A, V_cruise)
      if (v < vc && a > 0) {
        const auto jcap = static_cast<uint64_t>((vc - v + a - 1) / a);
        auto g = [&](uint64_t i) {
          const i128 ii = i;
          return u + ii * v + static_cast<i128>(a) * ii * (ii - 1) / 2;
        };
        const uint64_t i = first_reaching(jcap, std::min(d_start, n_end), g);
        if (i) {
          u = g(i);
          c += i;
          const int64_t used = v + static_cast<int64_t>(i - 1) * a;
          peak(used);
          if (u >= n_end) return finish(c, used);
          knot(c - 1, used);
          v = std::max(used - a, ve);
        } else {
          u = g(jcap);
          c += jcap;
          knot(c - 1, v + static_cast<int64_t>(jcap - 1) * a);
          v = vc;
        }
      } else {  // constant at V until U >= D * 2^48
        if (v < 1) throw std::invalid_argument("segment never ends");
        const uint64_t i = ceil_div(std::min(d_start, n_end) - u, v);
        u += static_cast<i128>(i) * v;
        c += i;
        if (c > kMaxClocks) throw std::invalid_argument("segment never ends");
        if (u >= n_end) return finish(c, v);
        knot(c - 1, v);
        v = std::max(v - a, ve);
      }
    }
  }
  throw std::logic_error("simulate_profile: too many phases");
}

ProfileRun simulate_profile_naive(const ProfileFields& f) {
  if (const char* e = profile_field_error(f)) {
    throw std::invalid_argument(fmt::format("profile fields: {}", e));
  }
  ProfileRun r;
  const i128 n_end = static_cast<i128>(f.n_dom) * kOne;
  const i128 d_start = static_cast<i128>(f.d) * kOne;
  const auto a = static_cast<int64_t>(f.a);
  int64_t v = static_cast<int64_t>(f.v_entry);
  i128 u = 0;
  for (uint64_t c = 1;; ++c) {
    r.v_peak = std::max(r.v_peak, static_cast<uint64_t>(v));
    u += v;
    if (u >= n_end) {
      r.clocks = c;
      r.v_last = static_cast<uint64_t>(v);
      return r;
    }
    if (u >= d_start) {
      v = std::max(v - a, static_cast<int64_t>(f.v_exit));
    } else {
      v = std::min(v + a, static_cast<int64_t>(f.v_cruise));
    }
    if (c > (uint64_t{1} << 40)) throw std::invalid_argument("naive: too long");
  }
}

MotionLimits motion_limits(const config::MachineConfig& cfg) {
  MotionLimits m;
  for (size_t i = 0; i < 4; ++i) {
    m.v_max[i] = cfg.max_feed_mm_min[i] / 60.0;
    m.a_max[i] = cfg.max_accel_mm_s2[i];
    m.steps_per_mm[i] = cfg.steps_per_mm[i];
  }
  m.junction_deviation = cfg.junction_deviation_mm;
  m.window = std::max<uint32_t>(cfg.lookahead_segments, 1);
  m.clk_hz = cfg.clk_hz;
  m.min_period = std::max<uint32_t>(cfg.step_timing.step_high, 1) +
                 std::max<uint32_t>(cfg.step_timing.step_low, 1);
  return m;
}

double junction_speed(const std::array<double, 4>& u_prev, const std::array<double, 4>& u_next,
                      double delta, const std::array<double, 4>& a_max) {
  double cos_theta = 0.0;  // grbl: theta = angle between -u_prev and u_next (pi = straight on)
  for (size_t i = 0; i < 4; ++i) cos_theta -= u_prev[i] * u_next[i];
  if (cos_theta > 0.999999) return 0.0;  // reversal
  if (cos_theta < -0.999999) return std::numeric_limits<double>::infinity();
  std::array<double, 4> ju{};
  double norm = 0.0;
  for (size_t i = 0; i < 4; ++i) {
    ju[i] = u_next[i] - u_prev[i];
    norm += ju[i] * ju[i];
  }
  norm = std::sqrt(norm);
  double a_j = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < 4; ++i) {
    const double c = std::fabs(ju[i]) / norm;
    if (c > 1e-12) a_j = std::min(a_j, a_max[i] / c);
  }
  const double s = std::sqrt(0.5 * (1.0 - cos_theta));  // sin(theta/2)
  if (!(delta > 0.0)) return 0.0;
  return std::sqrt(a_j * delta * s / (1.0 - s));
}

Lookahead::Lookahead(const MotionLimits& lim) : lim_(lim) {
  lim_.window = std::max<size_t>(lim_.window, 1);
}

void Lookahead::set_block_rates(Block& b, double n_units, double vc, double acc, uint64_t v_cap,
                                uint64_t a_max) {
  Profile& p = b.p;
  const double clk = static_cast<double>(lim_.clk_hz);
  const double one = std::ldexp(1.0, kFracBits);
  const double len = p.length_mm;
  b.scale_v = n_units / len / clk * one;   // LSB per mm/s
  const double scale_a = b.scale_v / clk;  // LSB per mm/s^2
  b.v_cap = v_cap;
  vc = std::min(vc, static_cast<double>(v_cap) / b.scale_v);
  const double a_lsb = std::floor(acc * scale_a);
  uint64_t a_int;
  if (a_lsb < 1.0) {
    a_int = 1;
    ++stats_.a_clamped;
  } else {
    a_int = static_cast<uint64_t>(std::min(a_lsb, static_cast<double>(a_max)));
  }
  p.rec.a = a_int;
  p.rec.n_end = static_cast<uint64_t>(n_units);
  p.accel = static_cast<double>(a_int) / scale_a;
  p.v_cruise = vc;
  // Stop speed: the rate one path unit of acceleration gives, sqrt(2 A) in real units.
  b.v_stop = isqrt_ceil(static_cast<i128>(a_int) << (kFracBits + 1));
  p.v_stop = static_cast<double>(b.v_stop) / b.scale_v;
  p.lsb_mm_s = 1.0 / b.scale_v;
  // Speed changes are planned over L minus a margin of 2 V_cruise (units per clock) + 2^-16
  // units: the clock staircase covers up to about one V of distance differently from the
  // continuous ramp (docs/motion.md).
  const double mu = 2.0 * vc * b.scale_v / one + std::ldexp(1.0, -16);
  b.l_eff = len * std::max(0.0, n_units - mu) / n_units;
}

void Lookahead::push(const Segment& s, size_t segment_index) {
  int64_t n_dom = 0;
  for (size_t a = 0; a < 4; ++a) n_dom = std::max(n_dom, iabs(s.steps[a]));
  if (n_dom == 0) return;
  const int64_t parts = (n_dom + kMaxProfileSteps - 1) / kMaxProfileSteps;
  if (parts > 1) ++stats_.split_moves;
  for (int64_t k = 1; k <= parts; ++k) {
    Block b;
    Profile& p = b.p;
    p.segment_index = segment_index;
    p.source_line = s.source_line;
    p.code = s.code;
    p.rapid = s.rapid;
    p.spindle_s = s.spindle_s;
    p.split = parts > 1;
    int64_t n = 0;
    std::array<double, 4> d{};
    for (size_t a = 0; a < 4; ++a) {
      const i128 t = s.steps[a];
      p.steps[a] = static_cast<int64_t>(t * k / parts - t * (k - 1) / parts);
      n = std::max(n, iabs(p.steps[a]));
      d[a] = static_cast<double>(p.steps[a]) / lim_.steps_per_mm[a];
    }
    if (n == 0) continue;
    const double lxyz = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double feed;  // mm/s path
    if (s.exec_feed_mm_min > 0.0) {
      feed = s.exec_feed_mm_min / 60.0;
    } else {  // step-file segment: the v1 feed word is the dominant X/Y axis feed
      const double dom = std::max(std::fabs(d[0]), std::fabs(d[1]));
      feed = dom > 0.0 ? s.feed_v1 / 60.0 * lxyz / dom : s.feed_v1 / 60.0;
    }
    if (lxyz > 0.0) {
      p.length_mm = lxyz;
      for (size_t a = 0; a < 3; ++a) b.unit[a] = d[a] / lxyz;
    } else {
      p.length_mm = std::fabs(d[3]);
      b.unit[3] = d[3] > 0 ? 1.0 : -1.0;
    }
    b.unit_out = b.unit;
    const double len = p.length_mm;
    double vc = feed;
    double acc = std::numeric_limits<double>::infinity();
    for (size_t a = 0; a < 4; ++a) {
      if (p.steps[a] == 0) continue;
      const double r = std::fabs(d[a]) / len;  // axis speed / path speed
      vc = std::min(vc, lim_.v_max[a] / r);
      const double a_axis =
          s.accel_mm_s2[a] > 0.0 ? std::min(lim_.a_max[a], s.accel_mm_s2[a]) : lim_.a_max[a];
      acc = std::min(acc, a_axis / r);
    }
    if (s.path_accel_mm_s2 > 0.0) acc = std::min(acc, s.path_accel_mm_s2);
    b.junction_deviation = s.junction_deviation_mm > 0.0
                               ? std::min(s.junction_deviation_mm, lim_.junction_deviation)
                               : lim_.junction_deviation;
    b.exact_stop = s.exact_stop;
    const uint64_t v_cap =
        std::min<uint64_t>(kMaxVCruise, (uint64_t{1} << kFracBits) / lim_.min_period);
    set_block_rates(b, static_cast<double>(n), vc, acc, v_cap, kMaxA);
    p.fields.n_dom = static_cast<uint32_t>(n);
    add_block(std::move(b));
  }
}

bool Lookahead::push_arc(const gcode::Move& m, const std::vector<Segment>& chords,
                         size_t first_index) {
  if (!lim_.arc_walk || chords.empty()) return false;
  // The walk's (u, v) plane and helix axis w (ARC flags bits 3:2).
  const gcode::PlaneAxes pa = gcode::plane_axes(m.plane);
  const auto U = static_cast<size_t>(pa.u), V = static_cast<size_t>(pa.v),
             W = static_cast<size_t>(pa.w);
  const auto& spm = lim_.steps_per_mm;
  if (spm[U] != spm[V]) return false;  // a circle in mm is an ellipse on the step lattice
  const Segment& first = chords.front();
  const Segment& last = chords.back();
  Steps4 start{};
  for (size_t a = 0; a < 4; ++a) start[a] = first.target[a] - first.steps[a];
  const int64_t dx = last.target[U] - start[U], dy = last.target[V] - start[V];
  const int64_t dz = last.target[W] - start[W], de = last.target[3] - start[3];
  if (de != 0) return false;  // ARC carries no E
  const int64_t cx = std::llround(m.center[0] * spm[U]), cy = std::llround(m.center[1] * spm[V]);
  const int64_t i = cx - start[U], j = cy - start[V];
  const bool full = dx == 0 && dy == 0;
  if (full != m.full_circle) return false;  // the end rounds onto the start: no native arc
  constexpr int64_t kLim = int64_t{1} << 22;
  if ((i == 0 && j == 0) || (dx == i && dy == j)) return false;
  if (iabs(i) >= kLim || iabs(j) >= kLim || iabs(dx - i) >= kLim || iabs(dy - j) >= kLim) {
    return false;
  }
  if (iabs(dz) > std::numeric_limits<int32_t>::max()) return false;
  const double r0 = std::hypot(static_cast<double>(i), static_cast<double>(j));
  const double r1 = std::hypot(static_cast<double>(dx - i), static_cast<double>(dy - j));
  if (std::fabs(r1 - r0) > 2.0) return false;  // inconsistent arc: chords
  const bool cw = m.motion == gcode::Motion::kArcCw;
  ArcFields af;
  af.code = cw ? 2 : 3;
  af.plane = static_cast<uint8_t>(m.plane);
  af.i = static_cast<int32_t>(i);
  af.j = static_cast<int32_t>(j);
  af.dx = static_cast<int32_t>(dx);
  af.dy = static_cast<int32_t>(dy);
  af.dz = static_cast<int32_t>(dz);
  const auto walk = lim_.arc_walk(af);
  if (!walk || walk->second < 1 || walk->second > kMaxArcCost) return false;
  af.n_ramp = walk->first;
  af.c_total = walk->second;

  // Geometry relative to the centre: start p0 = (-i, -j), end p1 = (dx - i, dy - j).
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  const double a0 = std::atan2(static_cast<double>(-j), static_cast<double>(-i));
  const double a1 = std::atan2(static_cast<double>(dy - j), static_cast<double>(dx - i));
  double sweep;
  if (full) {
    sweep = kTwoPi;
  } else {
    sweep = cw ? a0 - a1 : a1 - a0;
    if (sweep <= 0.0) sweep += kTwoPi;
  }
  const double lxy_steps = 0.5 * (r0 + r1) * sweep;  // spiral: mean radius
  const double lxy = lxy_steps / spm[U];             // mm
  const double dz_mm = static_cast<double>(dz) / spm[W];
  Block b;
  Profile& p = b.p;
  p.segment_index = first_index;
  p.source_line = m.line;
  p.code = first.code == 0 ? 0 : af.code;
  p.spindle_s = first.spindle_s;
  p.arc = true;
  p.arc_fields = af;
  p.steps = {};
  p.steps[U] = dx;
  p.steps[V] = dy;
  p.steps[W] = dz;
  p.length_mm = std::hypot(lxy, dz_mm);
  const double len = p.length_mm;
  const double fxy = lxy / len;  // XY speed / path speed
  auto tangent = [&](double px, double py, std::array<double, 4>& u) {
    const double r = std::hypot(px, py);
    const double tx = cw ? py / r : -py / r, ty = cw ? -px / r : px / r;
    u = {};
    u[U] = tx * fxy;
    u[V] = ty * fxy;
    u[W] = dz_mm / len;
  };
  tangent(static_cast<double>(-i), static_cast<double>(-j), b.unit);
  tangent(static_cast<double>(dx - i), static_cast<double>(dy - j), b.unit_out);
  const double feed =
      first.exec_feed_mm_min > 0.0 ? first.exec_feed_mm_min / 60.0 : first.feed_v1 / 60.0;
  // The tangent sweeps every XY direction: the XY speed and acceleration are held to the
  // smaller X/Y limit; the centripetal acceleration v_xy^2 / R to half of it and the tangential
  // to sqrt(3)/2 of it (their vector sum stays within the limit).
  const double a_xy = std::min(lim_.a_max[U], lim_.a_max[V]);
  const double r_mm = std::min(r0, r1) / spm[U];
  double vc = std::min(
      {feed, std::min(lim_.v_max[U], lim_.v_max[V]) / fxy, std::sqrt(0.5 * a_xy * r_mm) / fxy});
  double acc = 0.5 * std::sqrt(3.0) * a_xy / fxy;
  if (dz != 0) {
    const double fz = std::fabs(dz_mm) / len;
    vc = std::min(vc, lim_.v_max[W] / fz);
    acc = std::min(acc, lim_.a_max[W] / fz);
  }
  // Step rates: an XY lattice move steps each axis at most once, so the move rate is at most
  // the tangential rate in steps per clock: keep it below 1 / min_period and 1/8 (the walk needs 4
  // clocks a move, protocol.md host rule); Z likewise.
  const double clk = static_cast<double>(lim_.clk_hz);
  const double max_steps_per_clock = std::min(0.125, 1.0 / lim_.min_period);
  vc = std::min(vc, max_steps_per_clock * clk / spm[U] / fxy);
  if (dz != 0) vc = std::min(vc, max_steps_per_clock * clk / spm[W] * len / std::fabs(dz_mm));
  set_block_rates(b, static_cast<double>(af.c_total), vc, acc, kMaxArcV, kMaxArcA);
  ++stats_.arcs;
  add_block(std::move(b));
  return true;
}

void Lookahead::add_block(Block b) {
  const std::array<double, 4>* prev_unit = nullptr;
  double prev_vc = 0.0;
  bool prev_exact = false;
  if (!buf_.empty()) {
    prev_unit = &buf_.back().unit_out;
    prev_vc = buf_.back().p.v_cruise;
    prev_exact = buf_.back().exact_stop;
  } else if (last_unit_) {
    prev_unit = &*last_unit_;
    prev_vc = last_vc_;
    prev_exact = last_exact_;
  }
  if (prev_unit && !prev_exact) {
    const double jd = b.junction_deviation > 0.0 ? b.junction_deviation : lim_.junction_deviation;
    const double vj = junction_speed(*prev_unit, b.unit, jd, lim_.a_max);
    b.v_junction_max = std::min({vj, prev_vc, b.p.v_cruise});
  } else {
    b.v_junction_max = 0.0;
  }
  buf_.push_back(std::move(b));
  while (buf_.size() > lim_.window) {
    const auto exits = plan_exits(buf_);
    const Block& f = buf_.front();
    out_.push_back(finalize(f, prev_exit_, exits[0], false, stats_));
    prev_exit_ = exits[0];
    last_unit_ = f.unit_out;
    last_vc_ = f.p.v_cruise;
    last_exact_ = f.exact_stop;
    buf_.pop_front();
  }
}

std::vector<double> Lookahead::plan_exits(const std::deque<Block>& buf) const {
  const size_t n = buf.size();
  std::vector<double> emax(n);
  double next = 0.0;  // the window ends in a stop
  for (size_t k = n; k-- > 0;) {
    const Block& b = buf[k];
    emax[k] = std::min(
        {b.v_junction_max, b.p.v_cruise, std::sqrt(next * next + 2.0 * b.p.accel * b.l_eff)});
    next = emax[k];
  }
  std::vector<double> exits(n);
  double entry = std::min(prev_exit_, emax.empty() ? 0.0 : emax[0]);
  for (size_t k = 0; k < n; ++k) {
    const Block& b = buf[k];
    const double lim_next = k + 1 < n ? emax[k + 1] : 0.0;
    exits[k] = std::min(lim_next, std::sqrt(entry * entry + 2.0 * b.p.accel * b.l_eff));
    entry = exits[k];
  }
  return exits;
}

Profile Lookahead::finalize(const Block& b, double v_entry, double v_exit, bool stop_after,
                            ProfileStats& st) const {
  Profile p = b.p;
  p.v_entry = v_entry;
  p.v_exit = v_exit;
  p.stop_after = stop_after;
  const double sv = b.scale_v;
  // Rounding: every rate DOWN (never faster than planned); a 1e-12 relative shrink keeps a
  // product that lands a hair above an integer from rounding up.
  auto lsb = [&](double v) {
    const double x = std::floor(v * sv * (1.0 - 1e-12));
    return x <= 0.0 ? uint64_t{0} : static_cast<uint64_t>(std::min(x, 9e18));
  };
  Recurrence& f = p.rec;
  uint64_t vc = std::clamp<uint64_t>(lsb(p.v_cruise), 1, b.v_cap);
  const uint64_t v_stop = std::min<uint64_t>(std::max<uint64_t>(b.v_stop, 1), vc);
  const uint64_t v0 = std::min(lsb(v_entry), vc);
  const uint64_t ve = std::min(std::max(lsb(v_exit), v_stop), vc);
  const long double a = static_cast<long double>(f.a);
  const long double one = std::ldexp(1.0L, kFracBits);
  const long double span = static_cast<long double>(f.n_end) * one;
  const long double v0l = static_cast<long double>(v0), vel = static_cast<long double>(ve);
  const long double vcl = static_cast<long double>(vc);
  const long double tri = (2.0L * a * span + v0l * v0l + vel * vel) / 2.0L;
  // Peak of the trapezoid: the cruise rate, or where the acceleration and deceleration ramps
  // meet (never below the entry: a segment that must decelerate all along peaks at V_entry).
  const long double vp2 = std::max(std::min(vcl * vcl, tri), v0l * v0l);
  uint64_t d;
  if (vp2 <= vel * vel) {  // accelerate (or hold) up to V_exit: no deceleration
    vc = ve;
    d = f.n_end;
  } else {  // deceleration from the peak to V_exit starts at D (rounded down: early enough)
    const long double dec = (vp2 - vel * vel) / (2.0L * a * one);
    const long double dd = std::floor(static_cast<long double>(f.n_end) - dec);
    d = dd <= 0 ? 0 : static_cast<uint64_t>(std::min<long double>(dd, f.n_end));
  }
  f.v_entry = v0;
  f.v_cruise = vc;
  f.v_exit = ve;
  f.d = d;
  ProfileRun run = simulate_recurrence(f);
  if (run.v_last > ve) {  // decelerate earlier: largest D whose exit rate is <= V_exit
    ++st.d_adjusted;
    uint64_t lo = 0, hi = d;  // exit(hi) too fast
    f.d = 0;
    if (simulate_recurrence(f).v_last > ve) {
      ++st.exit_overshoot;
      hi = 0;
    }
    while (hi - lo > 1) {
      const uint64_t mid = lo + (hi - lo) / 2;
      f.d = mid;
      if (simulate_recurrence(f).v_last > ve) {
        hi = mid;
      } else {
        lo = mid;
      }
    }
    f.d = lo;
    run = simulate_recurrence(f);
  }
  if (!p.arc) {
    p.fields.v_entry = f.v_entry;
    p.fields.v_cruise = f.v_cruise;
    p.fields.v_exit = f.v_exit;
    p.fields.a = static_cast<uint32_t>(f.a);
    p.fields.d = static_cast<uint32_t>(f.d);
    p.fields.n_dom = static_cast<uint32_t>(f.n_end);
  }
  p.clocks = run.clocks;
  p.v_last = run.v_last;
  ++st.blocks;
  st.total_clocks += run.clocks;
  return p;
}

void Lookahead::stop() {
  if (buf_.empty()) {
    prev_exit_ = 0.0;
    last_unit_.reset();
    return;
  }
  const auto exits = plan_exits(buf_);
  for (size_t k = 0; k < buf_.size(); ++k) {
    const bool last = k + 1 == buf_.size();
    out_.push_back(finalize(buf_[k], prev_exit_, last ? 0.0 : exits[k], last, stats_));
    prev_exit_ = exits[k];
  }
  buf_.clear();
  prev_exit_ = 0.0;
  last_unit_.reset();
}

std::vector<Profile> Lookahead::take() {
  std::vector<Profile> r;
  r.swap(out_);
  return r;
}

std::vector<Profile> Lookahead::preview() const {
  std::vector<Profile> r;
  ProfileStats scratch;
  const auto exits = plan_exits(buf_);
  double entry = prev_exit_;
  for (size_t k = 0; k < buf_.size(); ++k) {
    const bool last = k + 1 == buf_.size();
    r.push_back(finalize(buf_[k], entry, last ? 0.0 : exits[k], last, scratch));
    entry = exits[k];
  }
  return r;
}

ProfilePlan plan_profiles(const Plan& plan, const config::MachineConfig& cfg) {
  return plan_profiles(plan, motion_limits(cfg));
}

ProfilePlan plan_profiles(const Plan& plan, const MotionLimits& lim) {
  ProfilePlan out;
  Lookahead la(lim);
  // Items that wait for the profiles of the segments before them: (first segment after, item).
  std::deque<std::pair<size_t, ProfileItem>> held;
  auto release = [&](size_t before_segment) {
    while (!held.empty() && held.front().first <= before_segment) {
      out.items.push_back(std::move(held.front().second));
      held.pop_front();
    }
  };
  auto drain = [&] {
    for (auto& p : la.take()) {
      release(p.segment_index);
      out.items.emplace_back(std::move(p));
    }
  };
  size_t seg_index = 0;
  uint64_t dwell_clocks = 0;
  std::vector<Segment> chords;  // of the arc being collected
  size_t chords_first = 0;
  auto flush_arc = [&] {
    if (chords.empty()) return;
    const uint32_t id = chords.front().arc_id;
    if (!la.push_arc(plan.arcs.at(id - 1), chords, chords_first)) {
      if (lim.arc_walk) ++out.stats.arcs_as_chords;
      for (size_t k = 0; k < chords.size(); ++k) la.push(chords[k], chords_first + k);
    }
    chords.clear();
    drain();
  };
  auto stop_here = [&] {
    la.stop();
    ++out.stats.forced_stops;
    drain();
    release(SIZE_MAX);
  };
  for (const auto& item : plan.items) {
    if (const auto* s = std::get_if<Segment>(&item)) {
      try {
        if (!chords.empty() && s->arc_id != chords.front().arc_id) flush_arc();
        if (lim.arc_walk && s->arc_id != 0 && s->arc_id <= plan.arcs.size()) {
          if (chords.empty()) chords_first = seg_index;
          chords.push_back(*s);
        } else {
          la.push(*s, seg_index);
        }
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(
            fmt::format("segment {} (line {}): {}", seg_index, s->source_line, e.what()));
      }
      ++seg_index;
      drain();
      continue;
    }
    flush_arc();
    if (const auto* d = std::get_if<Dwell>(&item)) {
      stop_here();
      dwell_clocks +=
          static_cast<uint64_t>(std::llround(d->seconds * static_cast<double>(lim.clk_hz)));
      out.items.emplace_back(*d);
    } else if (const auto* h = std::get_if<HeaterCommand>(&item)) {
      if (h->mcode == 109 || h->mcode == 190) stop_here();
      held.emplace_back(seg_index, *h);
    } else if (const auto* p = std::get_if<gcode::Pause>(&item)) {
      stop_here();  // the machine is at rest when the operator is asked
      out.items.emplace_back(*p);
    } else if (const auto* o = std::get_if<gcode::Output>(&item)) {
      held.emplace_back(seg_index, *o);
    } else if (const auto* m = std::get_if<gcode::Message>(&item)) {
      held.emplace_back(seg_index, *m);
    }
  }
  flush_arc();
  la.stop();
  drain();
  release(SIZE_MAX);
  const ProfileStats& ls = la.stats();
  out.stats.arcs = ls.arcs;
  out.stats.blocks = ls.blocks;
  out.stats.split_moves = ls.split_moves;
  out.stats.a_clamped = ls.a_clamped;
  out.stats.d_adjusted = ls.d_adjusted;
  out.stats.exit_overshoot = ls.exit_overshoot;
  out.stats.total_clocks = ls.total_clocks + dwell_clocks;
  return out;
}

}  // namespace fpgacnc::plan
