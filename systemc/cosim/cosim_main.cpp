// RTL/twin co-simulation (CTest label cosim; docs/systemc.md "Co-simulation").
//
// The Verilated C++ model of cnc_core (Vcnc_core_cosim, built with BAUD = 3 000 000 and
// WATCHDOG_CLKS = 20 000 to keep UART time short) clocked by a loop, and the virtual board made
// of the twins (one SystemC elaboration) with the same parameters. Both run the same list of
// jobs, the RTL first; each job is a stop-and-wait byte stream (host_schedule.h) with its own step
// timing. After the run every job's results are compared event by event (compare.h): pin edges
// with their cycles at system level, and per block the decoder's packet_done, the executor's
// seg_start/seg_done, the ACK start edges on tx, counters and positions. The first difference
// is printed with its cycle and the exit status is 1.
//
// Jobs: `--seeds` random jobs of `--segments` random segments each (random step timing per job,
// random numerators, codes, steps, feeds, a watchdog timeout and mid-stream init packets), and
// the first `--corpus-moves` moves of jsdc-laser.gcode and Circle_Diamond_Square_Calibration.gcode
// packed by the host (feeds and dwells at `--corpus-feed-override` percent).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <systemc>

#include "arc_stimulus.h"
#include "cosim_args.h"
#include "cosim_rtl.h"

#include "fpgacnc/config/machine.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/twins/compare.h"
#include "fpgacnc/twins/v2_frames.h"
#include "fpgacnc/twins/virtual_board.h"

using namespace fpgacnc::twins;
namespace spec = fpgacnc::spec;
namespace arc = fpgacnc::models::arc;

namespace {

// STEP high or low of 0 is treated as 1 clock by step_pulse, but cnc_core's minimum period adds
// the raw values, so a 0 makes the period one clock too short for the pulse generator: steps
// then come late (violations) and DIR can change on the edge of a late STEP rise. Reported to
// the RTL owner; the twins follow the specification there, not the one-deep pending register.
// Off by default (0 becomes 1, same random sequence); `--zero-pulse 1` turns it back on.
bool g_zero_pulse = false;
uint32_t pulse(uint32_t v) {
  return g_zero_pulse ? v : std::max<uint32_t>(v, 1);
}

using Job = CosimJob;

uint32_t pick(std::mt19937_64& g, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
}

AxisTiming random_timing(std::mt19937_64& g) {
  const uint32_t r = std::array<uint32_t, 4>{4, 40, 200, 600}[pick(g, 0, 3)];
  auto v = [&](uint32_t lo) { return pick(g, 0, 19) == 0 ? 0u : pick(g, lo, r); };
  return AxisTiming{pulse(v(1)), pulse(v(1)), v(0), v(0)};
}

Job random_job(uint64_t seed, size_t segments) {
  using namespace fpgacnc::protocol::v1;
  std::mt19937_64 g(seed);
  Job j;
  j.name = fmt::format("random seed {}", seed);
  j.segments = segments;
  if (pick(g, 0, 4) != 0)
    for (auto& t : j.timing) t = random_timing(g);
  auto init = [&] {
    const auto b = pack_init(pick(g, 500, 400'000), pick(g, 500, 400'000));
    return HostPacket{{b.begin(), b.end()}, false, 1};
  };
  j.script.v1.push_back(init());
  auto steps = [&]() -> int32_t {
    const uint32_t kind = pick(g, 0, 9);
    int32_t m = kind == 0  ? 0
                : kind < 5 ? static_cast<int32_t>(pick(g, 0, 12))
                           : static_cast<int32_t>(pick(g, 0, 100));
    return pick(g, 0, 1) ? -m : m;
  };
  for (size_t i = 0; i < segments; ++i) {
    const uint32_t what = pick(g, 0, 99);
    if (what == 0) {  // a new init between moves
      j.script.v1.push_back(init());
    } else if (what == 1) {  // a truncated packet, then silence past the watchdog
      std::vector<uint8_t> part;
      for (uint32_t k = pick(g, 1, 10); k > 0; --k)
        part.push_back(static_cast<uint8_t>(pick(g, 0, 254)));
      j.script.v1.push_back(HostPacket{part, false, pick(g, 1, 100)});
      j.script.v1.push_back(HostPacket{{}, false, 0});
      j.script.v1.back().gap = 0;
    }
    const int32_t sx = steps(), sy = steps();
    uint16_t feed = static_cast<uint16_t>(pick(g, 1, 65535));
    if (pick(g, 0, 29) == 0) feed = 0;
    int32_t fx = sx, fy = sy;
    if (feed == 0) {  // 62 500 clocks a step: keep it short
      fx = sx % 3;
      fy = sy % 3;
    }
    // Motion codes 0..3: other first bytes are noise to the v1/v2 decoder (docs/protocol.md
    // "Telling v1 from v2"); the truncated packets above bring noise bytes.
    const auto b = pack_motion(static_cast<uint8_t>(pick(g, 0, 3)), fx, fy, feed);
    int64_t gap = pick(g, 1, 40);
    if (what == 1) gap += 20'000 + pick(g, 0, 500);  // past the watchdog
    j.script.v1.push_back(HostPacket{{b.begin(), b.end()}, true, gap});
  }
  // Empty packets (used above as placeholders) carry no frames: drop them.
  std::erase_if(j.script.v1, [](const HostPacket& p) { return p.bytes.empty(); });
  return j;
}

constexpr double kCorpusRapid = 60'000.0;  // mm/min, and the X and Y max feeds

// A corpus file planned at a feed override, its dwells shortened by the same factor: the
// sequence of segments and dwells the RTL and the twins compare is the job's, in less board time
// (jsdc-laser's G4 P0.5 alone is 25 M clocks at 100 %).
fpgacnc::plan::Plan plan_at_override(const std::string& path, fpgacnc::config::MachineConfig cfg,
                                     double feed_override) {
  cfg.dwell_time_pct = 100.0 * 100.0 / feed_override;
  return fpgacnc::plan::plan_input_file(path, cfg, {feed_override});
}

Job corpus_job(const std::string& path, size_t max_moves, double feed_override) {
  fpgacnc::config::MachineConfig cfg;
  // Short rapids and fast feeds, less RTL time (jsdc-laser's first move, 52 mm at F1500, is 2.6 M
  // clocks at 4000 %).
  cfg.rapid_feed_mm_min = kCorpusRapid;
  cfg.max_feed_mm_min[0] = cfg.max_feed_mm_min[1] = kCorpusRapid;
  const auto plan = plan_at_override(path, cfg, feed_override);
  const auto packed = fpgacnc::protocol::v1::pack_job(plan);
  Job j;
  j.name = fmt::format("{} (first {} moves, feeds and dwells at {}%, rapids {} mm/min)", path,
                       max_moves, feed_override, kCorpusRapid);
  j.script.v1 = job_packets(packed, 50'000'000, max_moves);
  j.segments = j.script.v1.size() - 1;
  return j;
}

// A random v2 session: CONFIG_AXIS for every axis (the cfg port's timing, or new timing applied
// while the board is idle), NUMERATORS, then `segments` FIFO frames: LINEs on 1..4 axes (SHORT
// and int32, codes 0..3, power 0..255, T at, above and below n_dom * min_period: clamped),
// LINEs without steps, zero-length LINEs, DWELLs, NUMERATORS, CONFIG_AXIS with new timing
// mid-stream (active once the board is quiet); mostly back to back (the FIFO
// fills and the window closes), some gaps (the FIFO runs dry); a few frames corrupted once (NAK
// BAD_CRC, go-back-N), line noise between frames, frames cut short followed by silence past the
// watchdog (NAK TIMEOUT); some jobs ignore the credit (NAK FIFO_FULL, duplicates).
bool g_v2_profiles = true;         // LINE_PROFILE frames in the random v2 sessions
uint64_t g_v2_profile_frames = 0;  // how many were generated
bool g_v2_arcs = true;             // ARC frames in the random v2 sessions
uint64_t g_v2_arc_frames = 0, g_v2_bad_arcs = 0;
// OUTPUT frames in the random v2 sessions: drawn from a generator of their own, so the other
// frames of a session are the same with or without them. After about one frame in five an OUTPUT
// with a random mask, levels (bit 7: the laser's M3 / M4 mode, so the spindle_pwm pin's duty
// follows the rate and the profiles at times) and fan duty (0, 1..254 or 255); the session ends
// with one turning everything off (M9 M107 M65 P0..3), so the fan's PWM stops and the job can end.
bool g_v2_outputs = true;
uint64_t g_v2_output_frames = 0;

// ARC planes (flags bits 3:2): XY, ZX, YZ at random (`--v2-arc-planes 0`: XY only), drawn from
// the OUTPUT frames' generator so that the arcs themselves are the same.
bool g_v2_arc_planes = true;
std::array<uint64_t, 3> g_v2_plane_arcs{};

// MOTION frames (feed hold, resume, feed and rapid rates) in the random v2 sessions, drawn from a
// generator of their own (the other frames of a session are the same without them): before about
// one frame in eight, as side frames (no credit needed, host_schedule.h), after 1..20 000 clocks
// one of: a HOLD and, 1..2 000 clocks (often still ramping down) or 2 000..60 000 clocks later,
// its RESUME; new feed / rapid rates (1 % .. 100 %; below 20 % back to at least 20 % within
// 20 000 clocks, to bound the RTL time); rarely a MOTION that breaks a field rule (NAK BAD_FIELD);
// in half of the sessions (`--v2-cancels`) one in six of them a CANCEL (the session goes on with
// the frames after it; those sessions have no OUTPUT frames: the twins do not model the abort
// clearing the outputs).
// Rates are Q1.15, a third at 100 %; ramps 2^20 .. 2^32 - 1 per 256 clocks. A session that got
// any ends with a MOTION back to 100 %.
bool g_v2_holds = true, g_v2_cancels = true;
uint64_t g_v2_motion_frames = 0, g_v2_holds_sent = 0, g_v2_bad_motions = 0, g_v2_cancels_sent = 0;
// The feed hold and cycle-start buttons in the random v2 sessions (`--v2-buttons`; a generator of
// their own): in about half of them a hold press 20 000..1 000 000 clocks in and a cycle-start
// press 1..400 000 clocks after it, each held for the filter's 50 000 clocks (cnc_core's
// LIMIT_FILTER_CLKS) plus 0..20 000; in a quarter of those a press too short for the filter too.
bool g_v2_buttons = true;
uint64_t g_v2_presses = 0, g_v2_short_presses = 0;
uint16_t g_v2_min_rate = 0x8000;

void add_motions(std::mt19937_64& g, V2Item& it, bool cancels) {
  using namespace fpgacnc::twins::v2;
  auto rate = [&]() -> uint16_t {
    const auto r = static_cast<uint16_t>(pick(g, 0, 2) == 0 ? 0x8000 : pick(g, 328, 0x8000));
    g_v2_min_rate = std::min(g_v2_min_rate, r);
    return r;
  };
  auto ramp = [&]() -> uint32_t {
    if (pick(g, 0, 9) == 0) return 0xFFFF'FFFFu;
    const uint32_t e = pick(g, 20, 31);
    return pick(g, 1u << e, e == 31 ? 0xFFFF'FFFEu : (2u << e) - 1);
  };
  auto side = [&](uint8_t flags, uint16_t feed, uint16_t rapid, uint32_t rp, int64_t gap) {
    it.side.push_back(V2Side{spec::kTypeMotion, motion_payload(flags, feed, rapid, rp), gap});
    ++g_v2_motion_frames;
  };
  const auto hold = static_cast<uint8_t>(spec::kMotionHold);
  const auto resume = static_cast<uint8_t>(spec::kMotionResume);
  const int64_t gap = pick(g, 1, 20'000);
  if (cancels && pick(g, 0, 5) == 0) {  // a CANCEL: hold, then the queue dropped at rest
    side(static_cast<uint8_t>(spec::kMotionCancel), rate(), rate(), ramp(), gap);
    ++g_v2_cancels_sent;
    return;
  }
  const uint32_t what = pick(g, 0, 19);
  if (what < 10) {  // a hold and its resume
    side(hold, rate(), rate(), ramp(), gap);
    const int64_t held = pick(g, 0, 1) ? pick(g, 1, 2'000) : pick(g, 2'000, 60'000);
    side(resume, rate(), rate(), ramp(), held);
    ++g_v2_holds_sent;
  } else if (what < 19) {  // new rates
    const uint16_t f = rate(), r = rate();
    side(0, f, r, ramp(), gap);
    if (std::min(f, r) < 0x8000 / 5)
      side(0, static_cast<uint16_t>(pick(g, 0x8000 / 5, 0x8000)),
           static_cast<uint16_t>(pick(g, 0x8000 / 5, 0x8000)), ramp(), pick(g, 1, 20'000));
  } else {  // a field rule broken: reserved flag bit 3, HOLD with RESUME, a rate or the ramp 0
    const uint32_t k = pick(g, 0, 3);
    side(k == 0   ? 0x08
         : k == 1 ? 3
                  : 0,
         k == 2 ? uint16_t{0} : uint16_t{0x8001}, 0x8000, k == 3 ? 0u : ramp(), gap);
    if (k < 2) it.side.back().payload[1] = 0x40;  // a good feed rate: only the flags are wrong
    ++g_v2_bad_motions;
  }
}

// An ARC frame within the host's rules (arc_stimulus.h, defaults: R = 2..30 steps, cruise at
// 1 201..2 400 clocks per step, one in ten with C_TOTAL + 1), in `plane`.
std::vector<uint8_t> random_arc_payload(std::mt19937_64& g, uint8_t power, uint8_t plane) {
  bool bad = false;
  const arc::Frame f = random_arc_frame(g, ArcStimulus{}, &bad);
  if (bad) ++g_v2_bad_arcs;
  ++g_v2_arc_frames;
  ++g_v2_plane_arcs[plane];
  return v2::arc_payload(static_cast<uint8_t>((f.g.ccw ? 3 : 2) | plane << 2), power, f);
}

Job random_v2_job(uint64_t seed, size_t segments, uint64_t watchdog) {
  using namespace fpgacnc::twins::v2;
  std::mt19937_64 g(seed * 0x9E37'79B9'7F4A'7C15ull + 2);
  std::mt19937_64 go(seed * 0x9E37'79B9'7F4A'7C15ull + 3);  // OUTPUT frames
  std::mt19937_64 gm(seed * 0x9E37'79B9'7F4A'7C15ull + 4);  // MOTION frames
  std::mt19937_64 gb(seed * 0x9E37'79B9'7F4A'7C15ull + 5);  // buttons
  std::mt19937_64 gc(seed * 0x9E37'79B9'7F4A'7C15ull + 6);  // sessions with CANCEL
  const bool cancels = g_v2_holds && g_v2_cancels && pick(gc, 0, 1) == 0;
  bool motions = false;
  Job j;
  j.segments = segments;
  if (pick(g, 0, 4) != 0)
    for (auto& t : j.timing) t = random_timing(g);
  if (g_v2_buttons && pick(gb, 0, 1) == 0) {
    const Cycle f = spec::kDefaultLimitFilterClks;
    const Cycle hold_at = pick(gb, 20'000, 1'000'000);
    auto& bp = j.script.buttons;
    bp.push_back(ButtonPress{0, hold_at, f + pick(gb, 0, 20'000)});
    bp.push_back(ButtonPress{1, hold_at + pick(gb, 1, 400'000), f + pick(gb, 0, 20'000)});
    g_v2_presses += 2;
    if (pick(gb, 0, 3) == 0) {
      bp.push_back(ButtonPress{static_cast<int>(pick(gb, 0, 1)), pick(gb, 20'000, 1'500'000),
                               pick(gb, 1, static_cast<uint32_t>(f - 1))});
      ++g_v2_short_presses;
    }
    std::stable_sort(bp.begin(), bp.end(),
                     [](const ButtonPress& a, const ButtonPress& b) { return a.from < b.from; });
  }
  V2Script sc;
  sc.ignore_credit = pick(g, 0, 3) == 0;
  j.name = fmt::format("v2 random seed {}{}", seed, sc.ignore_credit ? " (ignoring credit)" : "");
  std::array<AxisTiming, kAxes> tm = j.timing;
  if (pick(g, 0, 2) == 0)
    for (auto& t : tm) t = random_timing(g);
  for (uint8_t a = 0; a < kAxes; ++a)
    sc.items.push_back(V2Item{kConfigAxis, config_axis_payload(a, tm[a])});
  CoreParams p;
  p.timing = tm;
  const uint32_t minp = p.min_period();
  auto numerators = [&] {
    return V2Item{kNumerators, numerators_payload(pick(g, 500, 400'000), pick(g, 500, 400'000))};
  };
  sc.items.push_back(numerators());
  for (size_t i = 0; i < segments; ++i) {
    V2Item it{kLine, {}};
    const uint32_t kind = pick(g, 0, 19);
    const auto code = static_cast<uint8_t>(pick(g, 0, 3));
    const auto power = static_cast<uint8_t>(pick(g, 0, 4) == 0 ? 0 : pick(g, 1, 255));
    if (kind == 0 && pick(g, 0, 3) == 0) {  // new step timing for an axis, mid-stream
      it = V2Item{kConfigAxis, config_axis_payload(static_cast<uint8_t>(pick(g, 0, kAxes - 1)),
                                                   random_timing(g))};
    } else if (kind == 0) {
      it = V2Item{kDwell, dwell_payload(pick(g, 0, 3) == 0 ? 0 : pick(g, 1, 20'000))};
    } else if (kind == 1) {
      it = numerators();
    } else if (kind == 8 && g_v2_arcs) {
      const auto plane = static_cast<uint8_t>(g_v2_arc_planes ? pick(go, 0, 2) : 0);
      it = V2Item{kArc, random_arc_payload(g, power, plane)};
    } else if (kind >= 4 && kind <= 7 && g_v2_profiles) {
      // LINE_PROFILE on 1..4 axes (n_a <= 12): cruise at 1 201..2 400 clocks per step (above any
      // random_timing's minimum period, also after a CONFIG_AXIS mid-stream: the STEP timing
      // holds, as the host plans it), entry and exit from cruise/8 up, A reaching cruise within
      // 1..2*n_dom steps (or tiny), D from the stopping rule or random.
      const double two48 = std::ldexp(1.0, 48);
      std::vector<int32_t> st(static_cast<size_t>(pick(g, 1, kAxes)));
      uint32_t n = 0;
      for (auto& x : st) {
        const uint32_t v = pick(g, 0, 2) == 0 ? 0 : pick(g, 1, pick(g, 0, 1) ? 3 : 12);
        x = pick(g, 0, 1) ? -static_cast<int32_t>(v) : static_cast<int32_t>(v);
        n = std::max(n, v);
      }
      if (n == 0) st[0] = n = 1;
      ProfileParams pr;
      pr.v_cruise = static_cast<uint64_t>(two48 / pick(g, 1201, 2400));
      auto from8 = [&] { return pr.v_cruise / 8 + pick(g, 0, 7) * (pr.v_cruise / 8); };
      pr.v_entry = pick(g, 0, 2) == 0 ? pr.v_cruise : std::min(pr.v_cruise, from8());
      pr.v_exit = pick(g, 0, 2) == 0 ? pr.v_cruise : std::min(pr.v_cruise, from8());
      const double vc = static_cast<double>(pr.v_cruise), vx = static_cast<double>(pr.v_exit);
      const double l = std::ldexp(static_cast<double>(pick(g, 1, 2 * n)), 48);
      pr.accel = pick(g, 0, 5) == 0
                     ? pick(g, 1, 2000)
                     : static_cast<uint32_t>(std::clamp(vc * vc / (2 * l), 1.0, 4e9));
      const double stop = (vc * vc - vx * vx) / (2.0 * pr.accel) / two48;
      pr.decel_at = pick(g, 0, 3) == 0 ? pick(g, 0, n + 1)
                                       : static_cast<uint32_t>(std::max(0.0, n - std::ceil(stop)));
      it = V2Item{kLineProfile, line_profile_payload(code, power, pr, st, pick(g, 0, 3) != 0)};
      ++g_v2_profile_frames;
    } else if (kind <= 3) {  // zero-length, or T ticks without steps
      const int32_t none[2] = {0, 0};
      it.payload = line_payload(code, power, kind == 2 ? 0 : pick(g, 1, 5000), none, true);
    } else {
      const int k = static_cast<int>(pick(g, 1, kAxes));
      // (40 000 steps, int32 on the wire, only with a fast minimum period: RTL time)
      const uint32_t m =
          std::array<uint32_t, 4>{3, 12, 60, minp <= 10 ? 40'000u : 300u}[pick(g, 0, 3)];
      std::vector<int32_t> st(static_cast<size_t>(k));
      uint32_t n = 0;
      for (auto& x : st) {
        const uint32_t v = pick(g, 0, 2) == 0 ? 0 : pick(g, 0, m);
        x = pick(g, 0, 1) ? -static_cast<int32_t>(v) : static_cast<int32_t>(v);
        n = std::max(n, v);
      }
      uint64_t t;
      const uint32_t how = pick(g, 0, 9);
      if (how == 0)
        t = pick(g, 0, std::max<uint32_t>(minp, 2) - 1) * static_cast<uint64_t>(n);  // clamped
      else
        t = static_cast<uint64_t>(pick(g, minp, 4 * minp)) * n + (n ? pick(g, 0, n - 1) : 0);
      bool fits = true;
      for (int32_t x : st) fits = fits && x >= -32768 && x <= 32767;
      it.payload =
          line_payload(code, power, static_cast<uint32_t>(std::min<uint64_t>(t, 2'000'000)), st,
                       fits && pick(g, 0, 4) != 0);
    }
    const uint32_t gap = pick(g, 0, 19);
    it.gap = gap < 17 ? 1 : gap < 19 ? pick(g, 1, 3000) : pick(g, 1, 30'000);
    it.corrupt = pick(g, 0, 32) == 0;
    const uint32_t pre = pick(g, 0, 59);
    if (pre == 0) {  // line noise between frames (never a SYNC)
      for (uint32_t b = pick(g, 1, 5); b > 0; --b)
        it.pre.push_back(static_cast<uint8_t>(pick(g, 0, 254) == 0xA5 ? 0x5A : pick(g, 0, 254)));
    } else if (pre == 1) {  // a frame cut short, then silence past the watchdog
      it.pre = {kSync, static_cast<uint8_t>(pick(g, 6, 20)), static_cast<uint8_t>(pick(g, 0, 255)),
                kLine};
      it.pre.resize(pick(g, 1, 6));
      it.pre_gap = static_cast<int64_t>(watchdog) + pick(g, 1, 500);
    }
    if (g_v2_holds && pick(gm, 0, 7) == 0) {
      add_motions(gm, it, cancels);
      motions = true;
    }
    sc.items.push_back(std::move(it));
    if (g_v2_outputs && !cancels && pick(go, 0, 4) == 0) {
      auto mask = static_cast<uint8_t>(pick(go, 1, 0xFF));
      const auto value = static_cast<uint8_t>(pick(go, 0, 0xFF) & mask & ~0x04u);
      const uint32_t dk = pick(go, 0, 3);
      const auto duty = static_cast<uint8_t>((mask & 0x04) == 0 ? 0
                                             : dk == 0          ? 0
                                             : dk == 1          ? 255
                                                                : pick(go, 1, 254));
      V2Item o{kOutput, {mask, value, duty}};
      o.gap = pick(go, 0, 3) == 0 ? pick(go, 1, 3000) : 1;
      o.corrupt = pick(go, 0, 32) == 0;
      sc.items.push_back(std::move(o));
      ++g_v2_output_frames;
    }
  }
  if (g_v2_outputs && !cancels) {
    sc.items.push_back(V2Item{kOutput, {0x7F, 0, 0}});
    ++g_v2_output_frames;
  }
  if (motions) {  // back to 100 % before the last frame
    sc.items.back().side.push_back(
        V2Side{spec::kTypeMotion, motion_payload(0, 0x8000, 0x8000, 0xFFFF'FFFFu), 1});
    ++g_v2_motion_frames;
  }
  j.script.v2 = std::move(sc);
  return j;
}

Job corpus_v2_job(const std::string& path, size_t max_frames, double feed_override) {
  fpgacnc::config::MachineConfig cfg;
  cfg.rapid_feed_mm_min = 12'000.0;
  const auto plan = plan_at_override(path, cfg, feed_override);
  const auto packed = fpgacnc::protocol::v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg,
                                                      {.heaters = false});
  Job j;
  j.name = fmt::format("{} as v2 frames (first {} LINE/DWELL, feeds and dwells at {}%)", path,
                       max_frames, feed_override);
  j.script.v2 = job_script(packed, max_frames);
  j.segments = j.script.v2->items.size();
  return j;
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t seed = 1, seeds = 20, v2_seeds = 20;
  size_t segments = 100, corpus_moves = 12, v2_corpus_frames = 200;
  double corpus_override = 4000.0;
  std::string corpus_dir = FPGACNC_CORPUS_DIR, examples_dir = FPGACNC_EXAMPLES_DIR;
  fpgacnc::cosim::Options opts("cosim");
  opts.flag("--zero-pulse", &g_zero_pulse).u64("--seed", &seed).u64("--seeds", &seeds);
  opts.size("--segments", &segments).size("--corpus-moves", &corpus_moves);
  opts.u64("--v2-seeds", &v2_seeds).size("--v2-corpus-frames", &v2_corpus_frames);
  opts.real("--corpus-feed-override", &corpus_override);
  opts.flag("--v2-profiles", &g_v2_profiles);
  opts.flag("--v2-arcs", &g_v2_arcs);
  opts.flag("--v2-outputs", &g_v2_outputs);
  opts.flag("--v2-cancels", &g_v2_cancels);
  opts.flag("--v2-arc-planes", &g_v2_arc_planes);
  opts.flag("--v2-holds", &g_v2_holds);
  opts.flag("--v2-buttons", &g_v2_buttons);
  if (!opts.parse(argc, argv)) return 2;
  seed = opts.seed(seed, seeds);

  std::vector<Job> jobs;
  for (uint64_t s = 0; s < seeds; ++s) jobs.push_back(random_job(seed + s, segments));
  if (corpus_moves > 0) {
    jobs.push_back(corpus_job(examples_dir + "/jsdc-laser.gcode", corpus_moves, corpus_override));
    jobs.push_back(corpus_job(corpus_dir + "/Circle_Diamond_Square_Calibration.gcode", corpus_moves,
                              corpus_override));
  }
  for (uint64_t s = 0; s < v2_seeds; ++s) jobs.push_back(random_v2_job(seed + s, segments, 20'000));
  if (v2_corpus_frames > 0)
    jobs.push_back(
        corpus_v2_job(examples_dir + "/jsdc-laser.gcode", v2_corpus_frames, corpus_override));

  CoreParams p;
  p.baud = 3'000'000;
  p.watchdog_clks = 20'000;
  const auto t0 = std::chrono::steady_clock::now();
  // The twins first (they take a fraction of the time): each job's twin end bounds the RTL's
  // run of it, so an RTL job that never ends is a difference named by its job, not a hang.
  VirtualBoard twins("twins", p, true);
  twins.record_outputs(true);
  std::vector<RunResult> twin_results;
  for (const Job& j : jobs)
    twins.add_job(
        TwinJob{j.script, j.timing, [&](RunResult&& r) { twin_results.push_back(std::move(r)); }});
  sc_core::sc_start();
  std::vector<Cycle> twin_ends;
  for (const RunResult& r : twin_results) twin_ends.push_back(r.end_cycle);
  const std::vector<RunResult> rtl_results = run_cosim_rtl(p, jobs, twin_ends);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  int bad = 0;
  uint64_t total_segments = 0, total_edges = 0, total_cycles = 0;
  double rtl_wall = 0, twin_wall = 0;
  for (size_t i = 0; i < jobs.size(); ++i) {
    if (i >= rtl_results.size() || i >= twin_results.size()) {
      fmt::print("FAIL {}: not run\n", jobs[i].name);
      ++bad;
      continue;
    }
    const RunResult& a = rtl_results[i];
    const RunResult& b = twin_results[i];
    const std::string diff = compare_runs(a, b);
    total_segments += jobs[i].segments;
    total_edges += a.edges.size();
    total_cycles += static_cast<uint64_t>(a.end_cycle);
    rtl_wall += a.wall_s;
    twin_wall += b.wall_s;
    if (!diff.empty()) ++bad;
    const std::string v2 =
        jobs[i].script.v2
            ? fmt::format(
                  " ({} device frames, {} NAKs, {} retransmitted, {} segments done, {} "
                  "zero-gap starts)",
                  a.device_frames, a.naks, a.retransmitted, a.segments_done, b.zero_gap)
            : "";
    fmt::print("{} {}: {} answers, {} edges, {} clocks, {} timeouts{}{}{}\n",
               diff.empty() ? "ok  " : "FAIL", jobs[i].name, a.acks.size(), a.edges.size(),
               a.end_cycle, a.timeouts, v2, diff.empty() ? "" : ": first difference: ", diff);
  }
  fmt::print(
      "cosim: {} LINE_PROFILE, {} ARC ({} with C_TOTAL off by one; XY {}, ZX {}, YZ {}) and {} "
      "OUTPUT frames in the random v2 sessions\n",
      g_v2_profile_frames, g_v2_arc_frames, g_v2_bad_arcs, g_v2_plane_arcs[0], g_v2_plane_arcs[1],
      g_v2_plane_arcs[2], g_v2_output_frames);
  uint64_t runs = 0, motions = 0, flushed = 0;
  std::array<uint64_t, 4> motion_in{};
  for (const RunResult& r : twin_results) {
    runs += static_cast<uint64_t>(r.runs);
    flushed += r.flushed;
    motions += r.motion_from.size();
    for (size_t k = 0; k < 4; ++k) motion_in[k] += r.motion_in[k];
  }
  fmt::print(
      "cosim: {} MOTION frames ({} holds with their resumes, {} CANCELs, {} breaking a rule, "
      "lowest rate {:.1f} %); {} accepted, taking effect in a LINE {}, PROFILE {}, ARC {}, no "
      "segment {}; {} entries dropped by a CANCEL's flush; twin runs {} for {} jobs\n",
      g_v2_motion_frames, g_v2_holds_sent, g_v2_cancels_sent, g_v2_bad_motions,
      100.0 * g_v2_min_rate / 0x8000, motions, motion_in[0], motion_in[1], motion_in[2],
      motion_in[3], flushed, runs, twin_results.size());
  fmt::print("cosim: {} button presses (hold and cycle start), {} of them too short to pass\n",
             g_v2_presses + g_v2_short_presses, g_v2_short_presses);
  fmt::print(
      "cosim: {} jobs, {} segments, {} edges, {} clocks compared; rtl {:.2f} s ({:.2f} M "
      "clocks/s), twins {:.3f} s; wall {:.2f} s; {}\n",
      jobs.size(), total_segments, total_edges, total_cycles, rtl_wall,
      static_cast<double>(total_cycles) / rtl_wall / 1e6, twin_wall, wall,
      bad ? fmt::format("{} jobs DIFFER", bad) : std::string("all identical"));
  return bad ? 1 : 0;
}
