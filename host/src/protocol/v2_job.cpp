#include "fpgacnc/protocol/v2_job.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>

namespace fpgacnc::protocol::v2 {
namespace {

// Pauses, messages and outputs keep their place in the frame list (Job::events); outputs also
// become OUTPUT frames (consecutive ones merged into one frame).
template <typename Item, typename Push>
bool record_event(Job& job, const Item& item, size_t next_segment, Push&& push) {
  if (const auto* o = std::get_if<gcode::Output>(&item)) {
    job.events.push_back(JobEvent{job.frames.size(), *o});
    if (!job.frames.empty() && job.frames.back().frame.type == static_cast<uint8_t>(Type::Output) &&
        job.frames.back().segment_index == next_segment) {
      OutputSet set = decode_output(job.frames.back().frame);
      add_output(set, *o);
      job.frames.back().frame = output_frame(0, set);
      return true;
    }
    OutputSet set;
    add_output(set, *o);
    JobFrame jf;
    jf.frame = output_frame(0, set);
    jf.segment_index = next_segment;
    jf.source_line = o->line;
    push(std::move(jf));
    ++job.outputs;
    return true;
  }
  if (const auto* p = std::get_if<gcode::Pause>(&item)) {
    job.events.push_back(JobEvent{job.frames.size(), *p});
    ++job.pauses;
  } else if (const auto* m = std::get_if<gcode::Message>(&item)) {
    job.events.push_back(JobEvent{job.frames.size(), *m});
    ++job.messages;
  } else {
    return false;
  }
  return true;
}

constexpr uint64_t kMaxT = std::numeric_limits<uint32_t>::max();
constexpr int64_t kMaxSteps = std::numeric_limits<int32_t>::max();

int64_t iabs(int64_t v) {
  return v < 0 ? -v : v;
}

// Segment time in clocks before the min-period raise (may exceed 32 bits).
double segment_clocks(const plan::Segment& s, const plan::Plan& plan,
                      const config::MachineConfig& cfg) {
  const double clk = static_cast<double>(cfg.clk_hz);
  if (s.exec_feed_mm_min > 0.0) {
    double len2 = 0.0;
    for (size_t a = 0; a < 3; ++a) {
      const double d = static_cast<double>(s.steps[a]) / cfg.steps_per_mm[a];
      len2 += d * d;
    }
    double len = std::sqrt(len2);
    double feed = s.exec_feed_mm_min;
    if (len == 0.0) {  // E alone
      len = std::fabs(static_cast<double>(s.steps[3]) / cfg.steps_per_mm[3]);
      feed = std::min(feed, cfg.max_feed_mm_min[3]);
    }
    return std::round(len / feed * 60.0 * clk);
  }
  // Step-file segment: v1 timing of the dominant of X, Y (X on a tie).
  const bool x_dom = iabs(s.steps[0]) >= iabs(s.steps[1]);
  const int64_t n = std::max(iabs(s.steps[0]), iabs(s.steps[1]));
  const uint32_t num = plan.numerator[x_dom ? 0 : 1];
  const uint64_t p = num / std::max<uint16_t>(s.feed_v1, 1);
  return static_cast<double>(p) * static_cast<double>(n);
}

uint16_t u16_timing(uint32_t v, const char* what) {
  if (v > 0xFFFF) {
    throw std::invalid_argument(fmt::format(
        "step_timing.{} = {} clocks does not fit a CONFIG_AXIS frame (max 65535)", what, v));
  }
  return static_cast<uint16_t>(v);
}

// The k of a segment: axes up to the last moving one, at least 2 (X, Y).
// A G4 dwell as DWELL frames of at most kMaxT clocks each (split when longer).
std::vector<JobFrame> job_dwell_frames(const plan::Dwell& d, uint32_t clk_hz,
                                       size_t segment_index) {
  const double clocks = std::round(d.seconds * static_cast<double>(clk_hz));
  if (!std::isfinite(clocks) || clocks < 0.0 || clocks > 1e15) {
    throw std::invalid_argument(
        fmt::format("dwell (line {}): {} s out of range", d.source_line, d.seconds));
  }
  std::vector<JobFrame> out;
  uint64_t left = static_cast<uint64_t>(clocks);
  const bool split = left > kMaxT;
  while (left > 0) {
    const uint64_t t = std::min(left, kMaxT);
    JobFrame jf;
    jf.frame = dwell(0, static_cast<uint32_t>(t));
    jf.segment_index = segment_index;
    jf.source_line = d.source_line;
    jf.t = static_cast<uint32_t>(t);
    jf.split = split;
    out.push_back(std::move(jf));
    left -= t;
  }
  return out;
}

size_t frame_axes(const plan::Steps4& steps) {
  size_t k = 2;
  for (size_t a = 0; a < 4; ++a) {
    if (steps[a] != 0) k = std::max(k, a + 1);
  }
  return k;
}

// An ARC segment lasts the walk's last-move clock c_last (Profile::clocks) + 2 ticks
// (docs/timing.md).
constexpr uint64_t kArcExtraTicks = 2;

// A heater command met between the frames: `heater` packs it (or counts it as skipped).
using HeaterHook = std::function<void(const plan::HeaterCommand&, size_t next_segment)>;

void pack_profiles(const plan::ProfilePlan& pp, const config::MachineConfig& cfg, Job& job,
                   const std::function<void(JobFrame)>& push, const HeaterHook& heater) {
  job.profile_stats = pp.stats;
  size_t seg_seen = 0;
  size_t last_seg = SIZE_MAX;
  // Reversal gaps (docs/timing.md, "Profiled segments"): a profiled segment with an axis whose
  // direction differs from its DIR pin takes the HOLD/SETUP path: run from
  // R = max(A + 1, max_a(L_a + hold)) + setup, A = the previous segment's end, L_a = the last STEP
  // of axis a (every moving axis steps on its segment's last tick). The first segment starts
  // from idle (not counted). DIR pins reset to 0 (negative). After an ARC, X/Y DIR are unknown:
  // no gap counted for them (the arc block's own DIR handling is the arc helper's).
  const int64_t hold = std::max<uint32_t>(cfg.step_timing.dir_hold, 1);
  const int64_t setup = std::max<uint32_t>(cfg.step_timing.dir_setup, 1);
  std::array<int, 4> dir{-1, -1, -1, -1};  // -1, +1, 0 = unknown
  std::array<int64_t, 4> last_step{};
  last_step.fill(std::numeric_limits<int64_t>::min() / 4);
  int64_t now = 0;  // clock of the current segment's start, relative to the first one's
  bool first = true;
  // arc_plane: -1 for a line; else the ARC's plane (its u and v axes reverse within the arc).
  auto advance = [&](const plan::Steps4& steps, uint64_t clocks, int arc_plane) {
    const bool arc = arc_plane >= 0;
    const gcode::PlaneAxes pa = gcode::plane_axes(static_cast<gcode::Plane>(arc ? arc_plane : 0));
    int64_t d_edge = std::numeric_limits<int64_t>::min();
    bool rev = false;
    for (size_t a = 0; a < 4; ++a) {
      if (steps[a] == 0) continue;
      const int sgn = steps[a] > 0 ? 1 : -1;
      if (dir[a] != 0 && sgn != dir[a]) {
        rev = true;
        d_edge = std::max(d_edge, last_step[a] + hold);
      }
    }
    if (rev && !first) {
      const int64_t r = std::max(now + 1, d_edge) + setup;
      job.reversal_gap_clocks += static_cast<uint64_t>(r - now);
      ++job.reversal_gaps;
      now = r;
    }
    first = false;
    now += static_cast<int64_t>(clocks);
    for (size_t a = 0; a < 4; ++a) {
      if (steps[a] == 0) continue;
      const bool in_plane = arc && (static_cast<int>(a) == pa.u || static_cast<int>(a) == pa.v);
      dir[a] = in_plane ? 0 : (steps[a] > 0 ? 1 : -1);
      last_step[a] = now;
    }
  };
  for (const auto& item : pp.items) {
    if (const auto* p = std::get_if<plan::Profile>(&item)) {
      if (p->code > 3) {
        throw std::invalid_argument(fmt::format("segment {} (line {}): motion code {} not valid",
                                                p->segment_index, p->source_line, p->code));
      }
      plan::Segment s;
      s.code = p->code;
      s.spindle_s = p->spindle_s;
      if (p->arc) {
        // The ARC segment lasts c_last + 2 clocks (p->clocks is c_last, the clock of the walk's
        // last move: rtl/motion/segment_executor.v issues its step request one clock after it, on
        // the segment's last tick, and the last STEP rises on the segment's last edge).
        const uint64_t arc_ticks = p->clocks + kArcExtraTicks;
        JobFrame jf;
        jf.frame = arc_frame(0, laser_power(s, cfg), p->arc_fields, p->rec);
        jf.segment_index = p->segment_index;
        jf.source_line = p->source_line;
        jf.t = static_cast<uint32_t>(std::min<uint64_t>(arc_ticks, kMaxT));
        jf.axes = 3;
        jf.profile = true;
        for (size_t a = 0; a < 3; ++a) job.target[a] += p->steps[a];
        job.total_t += arc_ticks;
        advance(p->steps, arc_ticks, p->arc_fields.plane);
        ++job.arcs;
        job.max_axes =
            std::max<size_t>(job.max_axes, p->steps[2] != 0 || p->arc_fields.plane != 0 ? 3 : 2);
        if (p->segment_index != last_seg) {
          ++seg_seen;
          last_seg = p->segment_index;
        }
        push(std::move(jf));
        continue;
      }
      const size_t k = frame_axes(p->steps);
      for (size_t a = 0; a < 4; ++a) job.target[a] += p->steps[a];
      JobFrame jf;
      jf.frame = profile_frame(*p, cfg);
      jf.segment_index = p->segment_index;
      jf.source_line = p->source_line;
      jf.t = static_cast<uint32_t>(std::min<uint64_t>(p->clocks, kMaxT));
      jf.axes = static_cast<uint8_t>(k);
      jf.split = p->split;
      jf.profile = true;
      if (jf.frame.payload[0] & kLineShort) ++job.short_lines;
      job.total_t += p->clocks;
      advance(p->steps, p->clocks, -1);
      ++job.profiles;
      job.max_axes = std::max(job.max_axes, k);
      if (p->segment_index != last_seg) {
        ++seg_seen;
        last_seg = p->segment_index;
      }
      push(std::move(jf));
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      for (JobFrame& jf : job_dwell_frames(*d, cfg.clk_hz, seg_seen)) {
        job.total_t += jf.t;
        advance(plan::Steps4{}, jf.t, -1);
        ++job.dwells;
        push(std::move(jf));
      }
    } else if (!record_event(job, item, seg_seen, push)) {
      heater(std::get<plan::HeaterCommand>(item), seg_seen);
    }
  }
  job.total_t += job.reversal_gap_clocks;
  job.segments = seg_seen;
  job.split_moves = pp.stats.split_moves;
}

// motion = "constant": one LINE frame per planned segment (split when too long).
void pack_constant(const plan::Plan& plan, const config::MachineConfig& cfg, Job& job,
                   const std::function<void(JobFrame)>& push, const HeaterHook& heater) {
  size_t seg_index = 0;
  for (const auto& item : plan.items) {
    if (const auto* s = std::get_if<plan::Segment>(&item)) {
      if (s->code > 3) {
        throw std::invalid_argument(fmt::format("segment {} (line {}): motion code {} not valid",
                                                seg_index, s->source_line, s->code));
      }
      int64_t n_dom = 0;
      size_t k = 2;
      for (size_t a = 0; a < 4; ++a) {
        n_dom = std::max(n_dom, iabs(s->steps[a]));
        if (s->steps[a] != 0) k = std::max(k, a + 1);
      }
      const double t_feed = segment_clocks(*s, plan, cfg);
      if (!std::isfinite(t_feed) || t_feed < 0.0 || t_feed > 1e18) {
        throw std::invalid_argument(
            fmt::format("segment {} (line {}): duration of {} clocks out of range", seg_index,
                        s->source_line, t_feed));
      }
      const uint64_t t_min = static_cast<uint64_t>(n_dom) * job.min_period;
      uint64_t t_total = static_cast<uint64_t>(t_feed);
      if (t_total < t_min) {  // the feed asks for more than the step rate allows
        t_total = t_min;
        ++job.t_raised;
      }
      const uint8_t power = laser_power(*s, cfg);

      // Smallest number of equal parts whose T and steps all fit.
      uint64_t parts =
          std::max<uint64_t>({1, (t_total + kMaxT - 1) / kMaxT,
                              static_cast<uint64_t>((n_dom + kMaxSteps - 1) / kMaxSteps)});
      std::vector<std::pair<uint64_t, std::array<int64_t, 4>>> pieces;
      for (;; ++parts) {
        if (parts > 1'000'000) {
          throw std::invalid_argument(fmt::format(
              "segment {} (line {}): cannot be split into LINE frames", seg_index, s->source_line));
        }
        pieces.clear();
        bool ok = true;
        for (uint64_t p = 1; p <= parts && ok; ++p) {
          std::array<int64_t, 4> steps{};
          int64_t nd = 0;
          for (size_t a = 0; a < 4; ++a) {
            const __int128 d = s->steps[a];
            steps[a] = static_cast<int64_t>(d * p / parts - d * (p - 1) / parts);
            nd = std::max(nd, iabs(steps[a]));
          }
          const __int128 tt = t_total;
          uint64_t t = static_cast<uint64_t>(tt * p / parts - tt * (p - 1) / parts);
          t = std::max<uint64_t>(t, static_cast<uint64_t>(nd) * job.min_period);
          if (t > kMaxT || nd > kMaxSteps) ok = false;
          pieces.emplace_back(t, steps);
        }
        if (ok) break;
      }
      if (pieces.size() > 1) ++job.split_moves;
      for (const auto& [t, steps] : pieces) {
        std::array<int32_t, 4> s32{};
        for (size_t a = 0; a < 4; ++a) {
          s32[a] = static_cast<int32_t>(steps[a]);
          job.target[a] += steps[a];
        }
        JobFrame jf;
        jf.frame = line(0, frame_code(s->code, s->rapid), power, static_cast<uint32_t>(t),
                        std::span<const int32_t>(s32.data(), k));
        jf.segment_index = seg_index;
        jf.source_line = s->source_line;
        jf.t = static_cast<uint32_t>(t);
        jf.axes = static_cast<uint8_t>(k);
        jf.split = pieces.size() > 1;
        if (jf.frame.payload[0] & kLineShort) ++job.short_lines;
        job.total_t += t;
        ++job.lines;
        job.max_axes = std::max(job.max_axes, k);
        push(std::move(jf));
      }
      ++job.segments;
      ++seg_index;
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      for (JobFrame& jf : job_dwell_frames(*d, cfg.clk_hz, seg_index)) {
        job.total_t += jf.t;
        ++job.dwells;
        push(std::move(jf));
      }
    } else if (!record_event(job, item, seg_index, push)) {
      heater(std::get<plan::HeaterCommand>(item), seg_index);
    }
  }
}

}  // namespace

void add_output(OutputSet& set, const gcode::Output& o) {
  switch (o.kind) {
    case gcode::Output::Kind::kFlood:
      set.flood = o.value != 0.0;
      break;
    case gcode::Output::Kind::kMist:
      set.mist = o.value != 0.0;
      break;
    case gcode::Output::Kind::kFan:
      set.fan = static_cast<uint8_t>(std::clamp(std::lround(o.value * 255.0), 0L, 255L));
      break;
    case gcode::Output::Kind::kDigital:
      if (o.index >= 0 && static_cast<size_t>(o.index) < kDigitalOutputs)
        set.dout[static_cast<size_t>(o.index)] = o.value != 0.0;
      break;
    case gcode::Output::Kind::kLaserMode:
      set.laser_dyn = o.value != 0.0;
      break;
  }
}

uint8_t laser_power(const plan::Segment& s, const config::MachineConfig& cfg) {
  if (s.code == 0) return 0;
  if (s.spindle_s < 0.0) return 255;
  if (s.spindle_s <= 0.0) return 0;
  const double scaled =
      (s.spindle_s - cfg.laser_s_min) / (cfg.laser_s_max - cfg.laser_s_min) * 255.0;
  long long p = std::llround(std::clamp(scaled, 0.0, 255.0));
  if (p == 0 && s.spindle_s > 0.0) p = 1;
  return static_cast<uint8_t>(p);
}

Frame arc_frame(uint8_t seq, uint8_t power, const plan::ArcFields& g, const plan::Recurrence& r) {
  Arc a;
  a.code = g.code;
  a.power = power;
  a.plane = static_cast<ArcPlane>(g.plane);
  a.i = g.i;
  a.j = g.j;
  a.dx = g.dx;
  a.dy = g.dy;
  a.dz = g.dz;
  a.n_ramp = g.n_ramp;
  a.c_total = g.c_total;
  a.v_entry = r.v_entry;
  a.v_cruise = r.v_cruise;
  a.v_exit = r.v_exit;
  a.accel = r.a;
  a.decel_at = r.d;
  return arc(seq, a);  // the codec's builder: its field rules, then the payload
}

LineProfile to_line_profile(uint8_t code, uint8_t power, const plan::ProfileFields& f,
                            std::span<const int32_t> steps) {
  LineProfile lp;
  lp.code = code;
  lp.power = power;
  lp.v_entry = f.v_entry;
  lp.v_cruise = f.v_cruise;
  lp.v_exit = f.v_exit;
  lp.accel = f.a;
  lp.decel_at = f.d;
  lp.steps.assign(steps.begin(), steps.end());
  return lp;
}

Frame profile_frame(const plan::Profile& p, const config::MachineConfig& cfg) {
  plan::Segment s;
  s.code = p.code;
  s.spindle_s = p.spindle_s;
  std::array<int32_t, 4> s32{};
  for (size_t a = 0; a < 4; ++a) s32[a] = static_cast<int32_t>(p.steps[a]);
  return line_profile(0,
                      to_line_profile(frame_code(p.code, p.rapid), laser_power(s, cfg), p.fields,
                                      std::span<const int32_t>(s32.data(), frame_axes(p.steps))));
}

std::vector<Frame> dwell_frames(double seconds, uint64_t clk_hz) {
  std::vector<Frame> out;
  const double clocks = std::round(seconds * static_cast<double>(clk_hz));
  uint64_t left = clocks > 0 && clocks < 1e15 ? static_cast<uint64_t>(clocks) : 0;
  while (left > 0) {
    const uint64_t t = std::min<uint64_t>(left, kMaxT);
    out.push_back(dwell(0, static_cast<uint32_t>(t)));
    left -= t;
  }
  return out;
}

uint32_t min_period(const config::StepTiming& t) {
  return std::max<uint32_t>(t.step_high, 1) + std::max<uint32_t>(t.step_low, 1);
}

namespace {

// A job with CONFIG_AXIS for the 4 axes and its first frame, NUMERATORS.
Job start_job(const plan::Plan& plan, const config::MachineConfig& cfg) {
  Job job;
  const auto& st = cfg.step_timing;
  const uint16_t sh = u16_timing(st.step_high, "step_high");
  const uint16_t sl = u16_timing(st.step_low, "step_low");
  const uint16_t ds = u16_timing(st.dir_setup, "dir_setup");
  const uint16_t dh = u16_timing(st.dir_hold, "dir_hold");
  for (uint8_t a = 0; a < config::kAxes; ++a)
    job.config.push_back(config_axis(0, a, sh, sl, ds, dh));
  for (uint8_t a = 0; a < config::kAxes; ++a) {
    const config::Travel& t = cfg.travel[a];
    if (!t.enabled) continue;
    const auto steps = [&](double mm) {
      const double s = std::round(mm * cfg.steps_per_mm[a]);
      if (!(std::fabs(s) <= 2147483647.0))
        throw std::invalid_argument(
            fmt::format("[travel] {}: {} mm is {} steps, beyond a CONFIG_TRAVEL field (int32)",
                        static_cast<char>(std::tolower(config::kAxisNames[a])), mm, s));
      return static_cast<int32_t>(s);
    };
    job.travel.push_back(config_travel(0, a, true, steps(t.min_mm), steps(t.max_mm)));
  }
  for (const auto& f : job.config) job.wire_bytes += kOverhead + f.payload.size();
  for (const auto& f : job.travel) job.wire_bytes += kOverhead + f.payload.size();
  job.min_period = min_period(st);
  job.numerator = plan.numerator;
  job.clk_hz = cfg.clk_hz;
  JobFrame jf;
  jf.frame = numerators(0, plan.numerator[0], plan.numerator[1]);
  job.wire_bytes += kOverhead + jf.frame.payload.size();
  job.frames.push_back(std::move(jf));
  return job;
}

// A heater command's place: before the first frame of the segment or dwell that follows it,
// and so before the OUTPUT frames already packed for that segment (`next_segment`), after the
// heater frames before them. Events at or after that place move with the frames.
void place_heater(Job& job, const plan::HeaterCommand& h, size_t next_segment, int index) {
  size_t at = job.frames.size();
  while (at > 1 && job.frames[at - 1].fifo &&
         job.frames[at - 1].frame.type == static_cast<uint8_t>(Type::Output) &&
         job.frames[at - 1].segment_index == next_segment) {
    --at;
  }
  JobFrame jf;
  jf.fifo = false;
  jf.heater = index;
  jf.segment_index = next_segment;
  jf.source_line = h.source_line;
  job.frames.insert(job.frames.begin() + static_cast<std::ptrdiff_t>(at), std::move(jf));
  for (auto& e : job.events) {
    if (e.before_frame >= at) ++e.before_frame;
  }
}

}  // namespace

Job pack_job(const plan::MotionPlan& planned, const config::MachineConfig& cfg,
             const PackOptions& options) {
  Job job = start_job(planned.plan, cfg);
  auto push = [&job](JobFrame jf) {
    job.wire_bytes += kOverhead + jf.frame.payload.size();
    job.frames.push_back(std::move(jf));
  };
  int heaters = 0;
  const HeaterHook heater = [&](const plan::HeaterCommand& h, size_t next_segment) {
    if (!options.heaters) {
      ++job.skipped_heater;
      return;
    }
    place_heater(job, h, next_segment, heaters++);
  };
  if (planned.profiles) {
    pack_profiles(*planned.profiles, cfg, job, push, heater);
  } else {
    pack_constant(planned.plan, cfg, job, push, heater);
  }
  if (heaters > 0) {
    // Validated after the motion (its errors first), in program order: the k-th placeholder
    // is the k-th heater command.
    job.heaters = heat::make_heater_job(planned.plan, cfg);
    for (auto& jf : job.frames) {
      if (jf.heater < 0) continue;
      const heat::HeaterAction& a = job.heaters.actions.at(static_cast<size_t>(jf.heater));
      jf.frame = heater_setpoint(0, a.channel, a.target_q4);
    }
    std::vector<JobFrame> setup;
    for (const Frame& f : job.heaters.setup) {
      JobFrame jf;
      jf.frame = f;
      jf.fifo = false;
      setup.push_back(std::move(jf));
    }
    job.frames.insert(job.frames.begin(), setup.begin(), setup.end());
    for (auto& e : job.events) e.before_frame += setup.size();
    job.heater_frames = setup.size() + static_cast<size_t>(heaters);
  }
  job.fifo_frames = job.frames.size() - job.heater_frames;
  return job;
}

std::vector<std::vector<uint8_t>> session_frames(const Job& job, uint8_t first_seq,
                                                 size_t device_axes) {
  std::vector<std::vector<uint8_t>> out;
  uint8_t seq = first_seq;
  for (size_t a = 0; a < job.config.size() && a < device_axes; ++a) {
    Frame f = job.config[a];
    f.seq = seq++;
    out.push_back(encode(f));
  }
  for (const auto& jf : job.frames) {
    Frame f = jf.frame;
    f.seq = seq++;
    out.push_back(encode(f));
  }
  out.push_back(encode(release(seq)));
  return out;
}

}  // namespace fpgacnc::protocol::v2
