// Look-ahead planner, LINE_PROFILE conversion and the exact time model (docs/motion.md).
// Randomized tests take FPGACNC_SEED (default fixed) and print it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"
#include "stream_plan.h"

namespace pl = fpgacnc::plan;
namespace v2 = fpgacnc::protocol::v2;
using fpgacnc::config::MachineConfig;

namespace {

uint64_t lookahead_seed(uint64_t def) {
  const char* s = std::getenv("FPGACNC_SEED");
  const uint64_t seed = s ? std::strtoull(s, nullptr, 0) : def;
  std::printf("seed %llu (set FPGACNC_SEED to change)\n", static_cast<unsigned long long>(seed));
  return seed;
}

constexpr double kOne = 281474976710656.0;  // 2^48

std::vector<pl::Profile> profiles_of(const pl::ProfilePlan& pp) {
  std::vector<pl::Profile> r;
  for (const auto& it : pp.items) {
    if (const auto* p = std::get_if<pl::Profile>(&it)) r.push_back(*p);
  }
  return r;
}

// Random machine: steps/mm, feeds, accelerations, junction deviation, window.
MachineConfig random_machine(std::mt19937_64& rng) {
  MachineConfig c;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t a = 0; a < 4; ++a) {
    c.steps_per_mm[a] = std::round(20.0 + u(rng) * 800.0);
    c.max_feed_mm_min[a] = 300.0 + u(rng) * 15000.0;
    c.max_accel_mm_s2[a] = 20.0 + u(rng) * 3000.0;
  }
  c.junction_deviation_mm = u(rng) < 0.1 ? 0.0 : u(rng) * 0.1;
  c.lookahead_segments = 1 + static_cast<uint32_t>(u(rng) * 40);
  c.rapid_feed_mm_min = 500.0 + u(rng) * 8000.0;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  return c;
}

// Random segments: mixes of long and tiny moves, straight runs, corners, reversals, E-only.
pl::Plan random_plan(std::mt19937_64& rng, const MachineConfig& c, int count) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::string g = "G90 G21\n";
  double x = 0, y = 0, z = 0, e = 0, ang = 0;
  for (int i = 0; i < count; ++i) {
    const double r = u(rng);
    double len = r < 0.3 ? u(rng) * 0.05 : (r < 0.8 ? u(rng) * 3.0 : u(rng) * 60.0);
    const double t = u(rng);
    if (t < 0.5) {
      ang += (u(rng) - 0.5) * 0.6;  // gentle curve
    } else if (t < 0.8) {
      ang += (u(rng) - 0.5) * 3.5;  // corner
    } else if (t < 0.85) {
      ang += 3.14159265358979;  // reversal
    }
    x += len * std::cos(ang);
    y += len * std::sin(ang);
    std::string line = u(rng) < 0.15 ? "G0" : "G1";
    line += " X" + std::to_string(x) + " Y" + std::to_string(y);
    if (u(rng) < 0.1) {
      z += (u(rng) - 0.5) * 2.0;
      line += " Z" + std::to_string(z);
    }
    if (u(rng) < 0.3) {
      e += u(rng) * 0.5;
      line += " E" + std::to_string(e);
    }
    line += " F" + std::to_string(30.0 + u(rng) * 9000.0);
    g += line + "\n";
    if (u(rng) < 0.03) {  // retract
      e -= 0.5 + u(rng);
      g += "G1 E" + std::to_string(e) + " F2400\n";
    }
    if (u(rng) < 0.01) g += "G4 P" + std::to_string(static_cast<int>(u(rng) * 3)) + "\n";
  }
  return pl::plan_program(fpgacnc::gcode::parse_string(g), c, {});
}

struct Checker {
  const MachineConfig& c;
  pl::MotionLimits lim;
  size_t checked = 0;
  double worst_junction_mismatch_lsb = 0.0;
  double worst_jump_up_clocks = 0.0, worst_jump_down_clocks = 0.0;
  double worst_tail_steps = 0.0;

  explicit Checker(const MachineConfig& cfg) : c(cfg), lim(pl::motion_limits(cfg)) {}

  std::array<double, 4> unit(const pl::Profile& p) const {
    std::array<double, 4> d{}, u{};
    for (size_t a = 0; a < 4; ++a) d[a] = p.steps[a] / c.steps_per_mm[a];
    const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (l > 0) {
      for (size_t a = 0; a < 3; ++a) u[a] = d[a] / l;
    } else {
      u[3] = d[3] > 0 ? 1 : -1;
    }
    return u;
  }

  // Checks one profile alone; returns the scale (LSB per mm/s).
  double check_one(const pl::Profile& p, const std::string& where) {
    const auto& f = p.fields;
    EXPECT_EQ(pl::profile_field_error(f), nullptr) << where;
    int64_t n = 0;
    for (size_t a = 0; a < 4; ++a) n = std::max<int64_t>(n, std::llabs(p.steps[a]));
    EXPECT_EQ(f.n_dom, static_cast<uint64_t>(n)) << where;
    EXPECT_LE(f.d, f.n_dom) << where;
    std::array<double, 4> d{};
    for (size_t a = 0; a < 4; ++a) d[a] = p.steps[a] / c.steps_per_mm[a];
    const double lxyz = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double len = lxyz > 0 ? lxyz : std::fabs(d[3]);
    const double clk = static_cast<double>(c.clk_hz);
    const double sv = static_cast<double>(n) / len / clk * kOne;  // LSB per mm/s
    const double sa = sv / clk;
    // Per-axis limits on the integer values, back in mm/s and mm/s^2.
    const double vmax = static_cast<double>(std::max({f.v_cruise, f.v_entry, f.v_exit}));
    for (size_t a = 0; a < 4; ++a) {
      const double r = std::fabs(d[a]) / len;
      EXPECT_LE(vmax / sv * r, lim.v_max[a] * (1 + 1e-9) + (f.v_cruise <= 1 ? 1 / sv : 0))
          << where << " axis " << a << " speed";
      if (p.fields.a > 1) {
        EXPECT_LE(f.a / sa * r, lim.a_max[a] * (1 + 1e-9)) << where << " axis " << a << " accel";
      }
    }
    // STEP rate: the dominant axis never above one step per min_period clocks.
    EXPECT_LE(static_cast<double>(f.v_cruise) * lim.min_period, kOne) << where;
    const pl::ProfileRun run = pl::simulate_profile(f);
    EXPECT_EQ(run.clocks, p.clocks) << where;
    EXPECT_LE(run.v_peak, f.v_cruise) << where;
    EXPECT_LE(run.v_last, f.v_exit) << where << ": exit faster than planned";
    // Deceleration starts late enough: after the last clock above V_exit at most 2 + V_peak
    // dominant steps remain at V_exit (D rounds down by < 1 step, which also lowers a triangle
    // peak by up to one step of deceleration; the staircase covers up to about V_peak
    // less than the continuous ramp).
    const auto kn = pl::simulate_profile(f, true);
    if (kn.v_peak > f.v_exit) {
      uint64_t since = 0;
      for (const auto& [clk, v] : kn.knots) {
        if (v > f.v_exit) since = clk + 1;
      }
      const double tail_steps = static_cast<double>(kn.clocks - since) * f.v_exit / kOne;
      EXPECT_LE(tail_steps, 2.5) << where << ": tail at V_exit";
      worst_tail_steps = std::max(worst_tail_steps, tail_steps);
    }
    EXPECT_LE(f.v_entry / sv, p.v_entry * (1 + 1e-9)) << where;
    ++checked;
    return sv;
  }

  void check_sequence(const std::vector<pl::Profile>& ps, const pl::Plan& plan) {
    // Junction speeds: exit of k and entry of k+1 at the same path speed within one LSB, both
    // at most the junction deviation limit (unless k ends in its stop speed).
    for (size_t k = 0; k < ps.size(); ++k) {
      const std::string where =
          "profile " + std::to_string(k) + " (line " + std::to_string(ps[k].source_line) + ")";
      const double sv = check_one(ps[k], where);
      if (k + 1 == ps.size()) {
        EXPECT_TRUE(ps[k].stop_after) << where;
      }
      if (ps[k].stop_after) {
        EXPECT_EQ(ps[k].fields.v_exit,
                  std::min<uint64_t>(ps[k].fields.v_cruise,
                                     static_cast<uint64_t>(std::llround(ps[k].v_stop * sv))))
            << where << ": a stop ends at V_stop";
        if (k + 1 < ps.size()) {
          EXPECT_EQ(ps[k + 1].fields.v_entry, 0u) << where << ": start after a stop";
        }
        continue;
      }
      if (k + 1 >= ps.size()) continue;
      const pl::Profile& q = ps[k + 1];
      const double sv2 = check_one(q, where + " next");
      const double vx = ps[k].fields.v_exit / sv, vn = q.fields.v_entry / sv2;
      const double vj =
          pl::junction_speed(unit(ps[k]), unit(q), c.junction_deviation_mm, c.max_accel_mm_s2);
      const double vj_cap = std::min({vj, ps[k].v_cruise, q.v_cruise});
      const bool at_stop_speed =
          ps[k].fields.v_exit ==
          std::min<uint64_t>(ps[k].fields.v_cruise,
                             static_cast<uint64_t>(std::llround(ps[k].v_stop * sv)));
      EXPECT_LE(vn, vj_cap * (1 + 1e-9) + 1e-12) << where << ": entry above the junction limit";
      if (!at_stop_speed) {
        EXPECT_LE(vx, vj_cap * (1 + 1e-9) + 1e-12) << where << ": exit above the junction limit";
        const double lsb = std::max(1 / sv, 1 / sv2);
        EXPECT_LE(std::fabs(vx - vn), lsb * (1 + 1e-6))
            << where << ": exit " << vx << " mm/s vs next entry " << vn << " mm/s";
        worst_junction_mismatch_lsb =
            std::max(worst_junction_mismatch_lsb, std::fabs(vx - vn) / lsb);
      } else {
        EXPECT_LE(vn, ps[k].v_stop * (1 + 1e-9) + 1 / sv2) << where;
      }
    }
    // Total steps unchanged against the constant-feed plan.
    pl::Steps4 want{}, got{};
    for (const auto& it : plan.items) {
      if (const auto* s = std::get_if<pl::Segment>(&it)) {
        for (size_t a = 0; a < 4; ++a) want[a] += s->steps[a];
      }
    }
    for (const auto& p : ps) {
      for (size_t a = 0; a < 4; ++a) got[a] += p.steps[a];
    }
    EXPECT_EQ(got, want);
  }
};

}  // namespace

TEST(ProfileSim, ClosedFormEqualsClockByClock) {
  std::mt19937_64 rng(lookahead_seed(6001));
  std::uniform_int_distribution<uint64_t> any;
  int cases = 0;
  for (int i = 0; i < 3000; ++i) {
    pl::ProfileFields f;
    f.n_dom = 1 + static_cast<uint32_t>(any(rng) % (i % 3 == 0 ? 4 : 400));
    // Speeds 1e-4 .. 0.5 steps/clock keep the clock-by-clock run short.
    auto speed = [&] {
      return static_cast<uint64_t>(
          std::ldexp(1.0, 48 - 1 - static_cast<int>(any(rng) % 12)) *
          (0.5 + 0.5 * std::ldexp(static_cast<double>(any(rng) >> 11), -53)));
    };
    f.v_cruise = std::min<uint64_t>(speed(), pl::kMaxVCruise);
    f.v_entry = any(rng) % 4 == 0 ? 0 : std::min(speed(), f.v_cruise);
    f.v_exit = std::max<uint64_t>(1, std::min(speed(), f.v_cruise));
    if (any(rng) % 5 == 0) f.v_exit = 1 + any(rng) % 1000;  // crawling tail
    f.a = static_cast<uint32_t>(std::ldexp(1.0, 20 + static_cast<int>(any(rng) % 12)) +
                                static_cast<double>(any(rng) % 1000));
    f.d = static_cast<uint32_t>(any(rng) % (f.n_dom + 2));
    if (f.v_exit < 1000 && f.d < f.n_dom) f.d = f.n_dom;  // avoid a 2^38-clock crawl
    const auto fast = pl::simulate_profile(f);
    const auto slow = pl::simulate_profile_naive(f);
    ASSERT_EQ(fast.clocks, slow.clocks) << "case " << i << " n " << f.n_dom << " d " << f.d;
    ASSERT_EQ(fast.v_last, slow.v_last) << "case " << i;
    ASSERT_EQ(fast.v_peak, slow.v_peak) << "case " << i;
    ++cases;
  }
  EXPECT_EQ(cases, 3000);
}

TEST(ProfileSim, RejectsFieldsTheDeviceRejects) {
  pl::ProfileFields f{0, 100, 0, 10, 0, 5};
  EXPECT_STREQ(pl::profile_field_error(f), "V_exit < 1");
  f.v_exit = 1;
  EXPECT_EQ(pl::profile_field_error(f), nullptr);
  f.v_entry = 101;
  EXPECT_NE(pl::profile_field_error(f), nullptr);
  f.v_entry = 0;
  f.a = 0;
  EXPECT_NE(pl::profile_field_error(f), nullptr);
  f.a = 1;
  f.n_dom = 1u << 24;
  EXPECT_NE(pl::profile_field_error(f), nullptr);
  EXPECT_THROW(pl::simulate_profile(f), std::invalid_argument);
}

TEST(Junction, DeviationFormula) {
  const std::array<double, 4> x{1, 0, 0, 0}, y{0, 1, 0, 0}, mx{-1, 0, 0, 0};
  const std::array<double, 4> a{1000, 1000, 100, 1000};
  EXPECT_TRUE(std::isinf(pl::junction_speed(x, x, 0.01, a)));
  EXPECT_EQ(pl::junction_speed(x, mx, 0.01, a), 0.0);
  // 90 degrees: theta = 90, sin(45) = 0.7071; junction vector (-1, 1)/sqrt2 -> a_j = 1000*sqrt2.
  const double s = std::sqrt(0.5);
  const double want = std::sqrt(1000 * std::sqrt(2.0) * 0.01 * s / (1 - s));
  EXPECT_NEAR(pl::junction_speed(x, y, 0.01, a), want, 1e-9);
  EXPECT_EQ(pl::junction_speed(x, y, 0.0, a), 0.0);
}

TEST(Lookahead, RandomMovesRespectLimitsAndJunctions) {
  std::mt19937_64 rng(lookahead_seed(6002));
  size_t total = 0;
  double worst = 0, jump_up = 0, jump_down = 0, tail = 0;
  for (int job = 0; job < 12; ++job) {
    const MachineConfig c = random_machine(rng);
    const pl::Plan plan = random_plan(rng, c, 400);
    const pl::ProfilePlan pp = pl::plan_profiles(plan, c);
    EXPECT_EQ(pp.stats.exit_overshoot, 0u) << "job " << job;
    EXPECT_EQ(pp.stats.a_clamped, 0u) << "job " << job;
    Checker ck(c);
    ck.check_sequence(profiles_of(pp), plan);
    total += ck.checked;
    worst = std::max(worst, ck.worst_junction_mismatch_lsb);
    jump_up = std::max(jump_up, ck.worst_jump_up_clocks);
    jump_down = std::max(jump_down, ck.worst_jump_down_clocks);
    tail = std::max(tail, ck.worst_tail_steps);
    if (HasFailure()) {
      std::printf("failed in job %d (window %u, jd %g)\n", job, c.lookahead_segments,
                  c.junction_deviation_mm);
      return;
    }
  }
  std::printf(
      "%zu profiles checked, worst junction mismatch %.3f LSB; executed speed step at a "
      "junction: up %.3f, down %.3f clocks of acceleration; longest tail at V_exit %.3f "
      "dominant steps\n",
      total, worst, jump_up, jump_down, tail);
}

TEST(Lookahead, EveryPrefixCanStopAndEmittedProfilesAreFinal) {
  std::mt19937_64 rng(lookahead_seed(6003));
  for (int job = 0; job < 3; ++job) {
    MachineConfig c = random_machine(rng);
    c.lookahead_segments = 1 + static_cast<uint32_t>(rng() % 12);
    const pl::Plan plan = random_plan(rng, c, 150);
    const auto full = profiles_of(pl::plan_profiles(plan, c));
    // Same stream, pushed one segment at a time; dwells force a stop.
    pl::Lookahead la(pl::motion_limits(c));
    std::vector<pl::Profile> emitted;
    size_t seg = 0;
    for (const auto& it : plan.items) {
      if (const auto* s = std::get_if<pl::Segment>(&it)) {
        la.push(*s, seg++);
      } else if (std::holds_alternative<pl::Dwell>(it)) {
        la.stop();
      }
      for (auto& p : la.take()) emitted.push_back(std::move(p));
      EXPECT_LE(la.window_size(), c.lookahead_segments);
      // The prefix as planned now ends in a stop: the last tentative block exits at V_stop.
      const auto tail = la.preview();
      if (!tail.empty()) {
        const auto& l = tail.back();
        const double sv = 1 / l.lsb_mm_s;
        EXPECT_TRUE(l.stop_after);
        EXPECT_EQ(l.fields.v_exit,
                  std::min<uint64_t>(l.fields.v_cruise,
                                     static_cast<uint64_t>(std::llround(l.v_stop * sv))))
            << "prefix ending at segment " << seg;
        EXPECT_LE(pl::simulate_profile(l.fields).v_last, l.fields.v_exit);
      }
      // Everything emitted so far is final: identical to the whole-program plan.
      for (size_t k = 0; k < emitted.size(); ++k) {
        ASSERT_LT(k, full.size());
        EXPECT_EQ(emitted[k].fields.v_entry, full[k].fields.v_entry) << "profile " << k;
        EXPECT_EQ(emitted[k].fields.v_exit, full[k].fields.v_exit) << "profile " << k;
        EXPECT_EQ(emitted[k].fields.d, full[k].fields.d) << "profile " << k;
      }
      if (HasFailure()) return;
    }
    la.stop();
    for (auto& p : la.take()) emitted.push_back(std::move(p));
    EXPECT_EQ(emitted.size(), full.size());
  }
}

TEST(Lookahead, DwellAndHeatAndWaitForceStops) {
  MachineConfig c;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  const auto plan = pl::plan_program(
      fpgacnc::gcode::parse_string("G1 X10 F3000\nX20\nG4 P0.5\nX30\nM104 S200\nX40\nM109 S200\n"
                                   "X50\nM3 S100\nX60\nM5\nX70\n"),
      c, {});
  const auto pp = pl::plan_profiles(plan, c);
  std::vector<bool> stops;
  for (const auto& p : profiles_of(pp)) stops.push_back(p.stop_after);
  // X10 X20 | dwell | X30 X40 | M109 | X50 X60 X70 (M104, M3, M5 do not stop)
  EXPECT_EQ(stops, (std::vector<bool>{false, true, false, true, false, false, true}));
  EXPECT_EQ(pp.stats.forced_stops, 2u);
  // Collinear moves at 50 mm/s, 1000 mm/s^2: the junctions run at full feed.
  const auto ps = profiles_of(pp);
  EXPECT_NEAR(ps[0].v_exit, 50.0, 1e-9);
  EXPECT_EQ(ps[0].fields.v_exit, ps[1].fields.v_entry);
}

TEST(Lookahead, LongMoveSplitBelow2To24) {
  MachineConfig c;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  c.steps_per_mm[0] = 10000;
  c.max_feed_mm_min[0] = 1e6;
  const auto plan = pl::plan_program(fpgacnc::gcode::parse_string("G1 X4000 F60000\n"), c, {});
  const auto pp = pl::plan_profiles(plan, c);
  const auto ps = profiles_of(pp);
  ASSERT_EQ(ps.size(), 3u);  // 4e7 steps -> 3 parts < 2^24
  int64_t sum = 0;
  for (const auto& p : ps) {
    EXPECT_LT(p.fields.n_dom, 1u << 24);
    sum += p.steps[0];
  }
  EXPECT_EQ(sum, 40'000'000);
  EXPECT_EQ(pp.stats.split_moves, 1u);
  Checker ck(c);
  ck.check_sequence(ps, plan);
}

TEST(Packer, LineProfileFrameIsTheWorkedExample) {
  // docs/protocol.md worked frame: seq 10, code 1, SHORT, power 255, V_entry 0,
  // V_cruise 18 014 398 509, V_exit 10^9, A 18 014, D 288, X +320, Y -160.
  pl::ProfileFields f;
  f.v_entry = 0;
  f.v_cruise = 18'014'398'509ULL;
  f.v_exit = 1'000'000'000ULL;
  f.a = 18'014;
  f.d = 288;
  const std::array<int32_t, 2> st{320, -160};
  const auto fr = v2::line_profile(10, v2::to_line_profile(1, 255, f, st));
  EXPECT_EQ(v2::hex(v2::encode(fr)),
            "A5 20 0A 12 81 FF 00 00 00 00 00 00 00 04 31 BD E8 2D 00 00 3B 9A CA 00 00 00 46 5E "
            "00 00 01 20 01 40 FF 60 51 62");
  const std::array<int32_t, 3> big{70000, 0, -1};
  const auto fr2 = v2::line_profile(0, v2::to_line_profile(0, 0, f, big));
  EXPECT_EQ(fr2.payload.size(), 28u + 12u);
  EXPECT_EQ(fr2.payload[0], 0x00);
}

TEST(Packer, ProfileJobFromCorpusFiles) {
  MachineConfig c;
  c.motion = "profile";
  size_t planned = 0;
  for (const auto& entry : std::filesystem::directory_iterator(FPGACNC_CORPUS_DIR)) {
    if (entry.path().extension() != ".gcode") continue;
    const std::string name = entry.path().filename().string();
    const std::string path = entry.path().string();
    pl::Plan plan;
    try {
      plan = pl::plan_gcode_file(path, c, {});
    } catch (const fpgacnc::gcode::Error& e) {  // outside the accepted G-code subset
      std::printf("%s: not planned (%s)\n", name.c_str(), e.what());
      EXPECT_NE(name, "jsdc-laser.gcode");
      EXPECT_NE(name, "Circle_Diamond_Square_Calibration.gcode");
      continue;
    }
    ++planned;
    const auto job = v2::pack_job(fpgacnc::plan::plan_motion(plan, c), c, {.heaters = false});
    EXPECT_EQ(job.profile_stats.exit_overshoot, 0u) << name;
    EXPECT_EQ(job.lines, 0u) << name;
    EXPECT_GT(job.profiles, 0u) << name;
    EXPECT_EQ(job.target, plan.final_steps) << name;
    // Tail at V_exit at the end of each stop: the staircase reaches V_exit a little before the
    // end (D rounds down), the rest runs at V_exit.
    const auto pp = pl::plan_profiles(plan, c);
    double worst_tail_ms = 0.0;
    for (const auto& p : profiles_of(pp)) {
      if (!p.stop_after) continue;
      const auto run = pl::simulate_profile(p.fields, true);
      if (run.v_peak <= p.fields.v_exit) continue;  // the whole segment at V_exit: no tail
      uint64_t since = 0;  // first clock at V_exit after the last clock above it
      for (const auto& [clk, v] : run.knots) {
        if (v > p.fields.v_exit) since = clk + 1;
      }
      worst_tail_ms = std::max(worst_tail_ms, (run.clocks - since) / 5e4);
    }
    EXPECT_LT(worst_tail_ms, 10.0) << name;
    std::printf("%s: longest run at V_exit at the end of a stop %.3f ms\n", name.c_str(),
                worst_tail_ms);
    size_t profile_frames = 0;
    for (const auto& jf : job.frames) {
      if (!jf.profile) continue;
      ++profile_frames;
      EXPECT_LE(jf.frame.payload.size(), v2::kMaxPayload);
    }
    EXPECT_EQ(profile_frames, job.profiles + job.arcs) << name;
    c.motion = "constant";
    const auto jc = fpgacnc::test::pack_motion(plan, c);
    c.motion = "profile";
    EXPECT_EQ(jc.profiles, 0u);
    std::printf("%s: %zu LINE_PROFILE frames, %.3f s planned vs %.3f s constant feed\n",
                name.c_str(), job.profiles, job.total_t / 5e7, jc.total_t / 5e7);
  }
  EXPECT_GE(planned, 8u);
}

TEST(MotionConfig, KeysParseValidateAndExampleEqualsDefaults) {
  const auto c = fpgacnc::config::parse_machine_config(
      "motion = \"profile\"\njunction_deviation_mm = 0.05\nlookahead_segments = 16\n"
      "[max_accel_mm_s2]\nx = 500\nz = 50.5\n",
      "t.toml");
  EXPECT_EQ(c.motion, "profile");
  EXPECT_EQ(c.junction_deviation_mm, 0.05);
  EXPECT_EQ(c.lookahead_segments, 16u);
  EXPECT_EQ(c.max_accel_mm_s2[0], 500.0);
  EXPECT_EQ(c.max_accel_mm_s2[1], 1000.0);  // default kept
  EXPECT_EQ(c.max_accel_mm_s2[2], 50.5);
  using fpgacnc::config::Error;
  using fpgacnc::config::parse_machine_config;
  EXPECT_THROW(parse_machine_config("motion = \"trapezoid\"\n", "t"), Error);
  EXPECT_THROW(parse_machine_config("lookahead_segments = 0\n", "t"), Error);
  EXPECT_THROW(parse_machine_config("junction_deviation_mm = -1\n", "t"), Error);
  EXPECT_THROW(parse_machine_config("[max_accel_mm_s2]\ny = 0\n", "t"), Error);
  EXPECT_THROW(parse_machine_config("[max_accel_mm_s2]\nq = 1\n", "t"), Error);
  const auto ex = fpgacnc::config::load_machine_config(FPGACNC_HOST_DIR "/machine.example.toml");
  const MachineConfig d;
  EXPECT_EQ(ex.max_accel_mm_s2, d.max_accel_mm_s2);
  EXPECT_EQ(ex.junction_deviation_mm, d.junction_deviation_mm);
  EXPECT_EQ(ex.lookahead_segments, d.lookahead_segments);
  EXPECT_EQ(ex.motion, d.motion);
  EXPECT_EQ(ex.native_arcs, d.native_arcs);
  EXPECT_TRUE(fpgacnc::config::parse_machine_config("native_arcs = true\n", "t").native_arcs);
  EXPECT_THROW(parse_machine_config("native_arcs = 1\n", "t"), Error);
}

TEST(Packer, ConstantModeUnchangedByTheProfileCode) {
  // motion = "constant" still packs LINE frames (same T as before this change: length/feed).
  MachineConfig c;
  c.motion = "constant";
  c.laser_requires_m3 = false;
  const auto plan =
      pl::plan_program(fpgacnc::gcode::parse_string("G1 X2 Y-1 F1341.64\nG4 P0.001\n"), c, {});
  const auto job = fpgacnc::test::pack_motion(plan, c);
  EXPECT_EQ(job.profiles, 0u);
  ASSERT_EQ(job.lines, 1u);
  // 2.236 mm at 1341.64 mm/min = 0.1 s = 5 000 000 clocks
  EXPECT_NEAR(static_cast<double>(job.frames[1].t), 5e6, 10.0);
  EXPECT_EQ(job.frames[1].frame.type, 0x10);
  c.motion = "profile";
  const auto jp = fpgacnc::test::pack_motion(plan, c);
  ASSERT_EQ(jp.profiles, 1u);
  EXPECT_EQ(jp.frames[1].frame.type, static_cast<uint8_t>(v2::Type::LineProfile));
  EXPECT_EQ(jp.frames[2].frame.type, 0x11);  // DWELL after the stop
  // The profile takes longer than the instant-speed constant feed, by about v/a:
  // 22.36 mm/s at 1000 mm/s^2 (X limits; path accel 1000*L/dx = 1118) -> ~0.02 s more.
  const double extra = (static_cast<double>(jp.frames[1].t) - 5e6) / 5e7;
  EXPECT_GT(extra, 0.015);
  EXPECT_LT(extra, 0.025);
}

namespace {

// A stand-in for the reference walk (fpgacnc/models/arc_walk.h): C_TOTAL ~ R * arc length in steps
// (the cross-product cost), N_RAMP 1. The planner only uses C_TOTAL as its path unit; the device
// checks it against its own walk.
std::optional<std::pair<uint32_t, uint64_t>> fake_walk(const pl::ArcFields& f) {
  const double r0 = std::hypot(f.i, f.j), r1 = std::hypot(f.dx - f.i, f.dy - f.j);
  const double a0 = std::atan2(-f.j, -f.i), a1 = std::atan2(f.dy - f.j, f.dx - f.i);
  double sweep = f.code == 2 ? a0 - a1 : a1 - a0;
  if (sweep <= 0) sweep += 2 * 3.14159265358979;
  const double c = 0.5 * (r0 + r1) * 0.5 * (r0 + r1) * sweep;
  return std::make_pair(uint32_t{1}, static_cast<uint64_t>(std::max(1.0, std::llround(c) * 1.0)));
}

}  // namespace

TEST(Packer, ArcFrameIsTheWorkedExample) {
  // docs/protocol.md "ARC" worked frame: seq 11, G3, power 255, I -100, J 0, DX -100, DY 100,
  // DZ 0, N_RAMP 127, C_TOTAL 15 703, V_cruise 1 125 544 154 615, V_entry = V_exit =
  // 281 386 038 653, A 1 125 544, D 13 828.
  pl::ArcFields g;
  g.code = 3;
  g.i = -100;
  g.j = 0;
  g.dx = -100;
  g.dy = 100;
  g.dz = 0;
  g.n_ramp = 127;
  g.c_total = 15'703;
  pl::Recurrence r{15'703, 281'386'038'653ULL, 1'125'544'154'615ULL, 281'386'038'653ULL, 1'125'544,
                   13'828};
  EXPECT_EQ(v2::hex(v2::encode(v2::arc_frame(11, 255, g, r))),
            "A5 3F 0B 13 03 FF FF FF 9C 00 00 00 FF FF 9C 00 00 64 00 00 00 00 00 00 7F 00 00 "
            "00 00 3D 57 00 00 00 41 83 EA 35 7D 00 00 01 06 0F A8 D5 F7 00 00 00 41 83 EA 35 "
            "7D 00 00 00 11 2C A8 00 00 00 00 36 04 47 F8");
}

TEST(Lookahead, NativeArcsRespectTangentialCentripetalAndJunctionLimits) {
  MachineConfig c;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  const std::string g =
      "G0 X0 Y0\nG1 X10 Y0 F3000\n"
      "G3 X20 Y10 I0 J10\n"           // tangent continues +X: smooth junction
      "G2 X30 Y20 I10 J0\n"           // reverses curvature, tangent +Y at the join
      "G1 X30 Y40\n"                  // the G2 ends heading +X: a 90 degree corner
      "G2 X30 Y40 I5 J0 Z-2 F600\n"   // full helical circle, R = 5 mm
      "G3 X31 Y41 I0.5 J0.5 F3000\n"  // tiny radius (0.707 mm): centripetal limit
      "G1 X0 Y0\n";
  const auto plan = pl::plan_program(fpgacnc::gcode::parse_string(g), c, {});
  pl::MotionLimits lim = pl::motion_limits(c);
  lim.arc_walk = fake_walk;
  const auto pp = pl::plan_profiles(plan, lim);
  EXPECT_EQ(pp.stats.arcs, 4u);
  EXPECT_EQ(pp.stats.arcs_as_chords, 0u);
  EXPECT_EQ(pp.stats.exit_overshoot, 0u);
  const auto ps = profiles_of(pp);
  ASSERT_EQ(ps.size(), 7u);  // G0 X0 Y0 does not move
  pl::Steps4 sum{};
  const double clk = static_cast<double>(c.clk_hz);
  for (size_t k = 0; k < ps.size(); ++k) {
    const auto& p = ps[k];
    for (size_t a = 0; a < 4; ++a) sum[a] += p.steps[a];
    const auto run = pl::simulate_recurrence(p.rec);
    EXPECT_EQ(run.clocks, p.clocks) << k;
    EXPECT_LE(run.v_peak, p.rec.v_cruise) << k;
    EXPECT_LE(run.v_last, p.rec.v_exit) << k;
    const double vc = p.rec.v_cruise * p.lsb_mm_s;  // mm/s along the path
    const double acc = p.rec.a * p.lsb_mm_s * clk;  // mm/s^2
    if (!p.arc) continue;
    const auto& f = p.arc_fields;
    const double r_mm = std::min(std::hypot(f.i, f.j), std::hypot(f.dx - f.i, f.dy - f.j)) / 160;
    const double dz_mm = f.dz / 400.0;
    const double fxy =
        std::sqrt(std::max(0.0, p.length_mm * p.length_mm - dz_mm * dz_mm)) / p.length_mm;
    const double vxy = vc * fxy;
    EXPECT_LE(vxy * vxy / r_mm, 0.5 * 1000 * (1 + 1e-9)) << "arc " << k << " centripetal";
    EXPECT_LE(acc * fxy, 0.5 * std::sqrt(3.0) * 1000 * (1 + 1e-9)) << "arc " << k;
    EXPECT_LE(vxy, 50.0 * (1 + 1e-9)) << "arc " << k << " feed";
    if (f.dz != 0) {
      EXPECT_LE(vc * std::fabs(dz_mm) / p.length_mm, 10.0 * (1 + 1e-9)) << "Z max feed";
    }
  }
  EXPECT_EQ(sum, plan.final_steps);
  // Tangent-continuous joins (line -> G3, G3 -> G2) keep the feed; G2 -> line is a 90 degree
  // corner (junction deviation); the tiny arc is limited by its centripetal acceleration,
  // sqrt(a/2 * R) = sqrt(500 * 0.707) = 18.8 mm/s.
  EXPECT_NEAR(ps[0].v_exit, 50.0, 1e-6);
  EXPECT_NEAR(ps[1].v_exit, 50.0, 1e-6);
  EXPECT_LT(ps[2].v_exit, 10.0);
  EXPECT_NEAR(ps[5].v_cruise, std::sqrt(500 * std::hypot(0.5, 0.5)), 0.05);
  for (size_t k = 0; k + 1 < ps.size(); ++k) {
    const double ex = ps[k].rec.v_exit * ps[k].lsb_mm_s;
    const double en = ps[k + 1].rec.v_entry * ps[k + 1].lsb_mm_s;
    EXPECT_LE(std::fabs(ex - en), std::max(ps[k].lsb_mm_s, ps[k + 1].lsb_mm_s) * 1.000001)
        << "junction " << k;
  }
  // Packed: ARC frames for the arcs, LINE_PROFILE for the lines; constant mode keeps chords.
  const auto job = fpgacnc::test::pack_motion(plan, c, fake_walk);
  EXPECT_EQ(job.arcs, 4u);
  EXPECT_EQ(job.profiles, 3u);
  EXPECT_EQ(job.target, plan.final_steps);
  for (const auto& jf : job.frames) {
    if (jf.frame.type == static_cast<uint8_t>(v2::Type::Arc)) {
      EXPECT_EQ(jf.frame.payload.size(), 63u);
    }
  }
  c.motion = "constant";
  EXPECT_EQ(fpgacnc::test::pack_motion(plan, c, fake_walk).arcs, 0u);
}

TEST(Lookahead, ArcsThatCannotGoNativeStayChords) {
  MachineConfig c;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  pl::MotionLimits lim;
  // Arc with extrusion (ARC has no E) and a spiral whose radii differ by 1 mm (> 2 steps).
  auto plan = pl::plan_program(
      fpgacnc::gcode::parse_string("G1 X10 F3000\nG2 X20 Y0 I5 J0 E1\nG2 X31 Y0 I5 J0\n"), c, {});
  lim = pl::motion_limits(c);
  lim.arc_walk = fake_walk;
  auto pp = pl::plan_profiles(plan, lim);
  EXPECT_EQ(pp.stats.arcs, 0u);
  EXPECT_EQ(pp.stats.arcs_as_chords, 2u);
  // Unequal X/Y steps per mm: a circle is an ellipse on the lattice.
  c.steps_per_mm[1] = 80;
  plan = pl::plan_program(fpgacnc::gcode::parse_string("G2 X10 Y0 I5 J0 F3000\n"), c, {});
  lim = pl::motion_limits(c);
  lim.arc_walk = fake_walk;
  pp = pl::plan_profiles(plan, lim);
  EXPECT_EQ(pp.stats.arcs, 0u);
  EXPECT_EQ(pp.stats.arcs_as_chords, 1u);
  int64_t x = 0;
  for (const auto& p : profiles_of(pp)) x += p.steps[0];
  EXPECT_EQ(x, plan.final_steps[0]);
}

namespace {
// The ARC block of a profile through the arc helper's clock-exact model (arc_walk.h run()).
fpgacnc::models::arc::RunResult run_arc(const pl::Profile& p) {
  namespace ta = fpgacnc::models::arc;
  ta::Frame fr;
  fr.g = {p.arc_fields.i, p.arc_fields.j, p.arc_fields.dx, p.arc_fields.dy, p.arc_fields.code == 3};
  fr.dz = p.arc_fields.dz;
  fr.n_ramp = p.arc_fields.n_ramp;
  fr.c_total = p.arc_fields.c_total;
  fr.v_entry = p.rec.v_entry;
  fr.v_cruise = p.rec.v_cruise;
  fr.v_exit = p.rec.v_exit;
  fr.a = p.rec.a;
  fr.d = p.rec.d;
  return ta::run(fr, p.clocks + 1000);
}
}  // namespace

TEST(Lookahead, ReferenceWalkArcsFromTheCorpus) {
  MachineConfig c;
  c.motion = "profile";
  c.native_arcs = true;
  size_t arcs = 0;
  for (const char* name :
       {"arc-ijk.gcode", "g2-arc.gcode", "circle.gcode", "circle-inch.gcode",
        "full-circle-without-xyz.gcode", "Circle_Diamond_Square_Calibration.gcode"}) {
    const auto plan = pl::plan_gcode_file(std::string(FPGACNC_CORPUS_DIR) + "/" + name, c, {});
    const auto job = v2::pack_job(fpgacnc::plan::plan_motion(plan, c), c, {.heaters = false});
    EXPECT_EQ(job.target, plan.final_steps) << name;
    EXPECT_EQ(job.profile_stats.exit_overshoot, 0u) << name;
    arcs += job.arcs;
    // Every ARC frame's N_RAMP / C_TOTAL: the reference walk lands on the end point with that
    // total (what the device's guard checks).
    auto lim = pl::motion_limits(c);
    lim.arc_walk = pl::reference_arc_walk();
    for (const auto& p : profiles_of(pl::plan_profiles(plan, lim))) {
      if (!p.arc) continue;
      namespace ta = fpgacnc::models::arc;
      const ta::Geometry g{p.arc_fields.i, p.arc_fields.j, p.arc_fields.dx, p.arc_fields.dy,
                           p.arc_fields.code == 3};
      const auto w = ta::walk(g, p.arc_fields.n_ramp);
      EXPECT_TRUE(w.reached) << name << " line " << p.source_line;
      EXPECT_EQ(w.c_total, p.arc_fields.c_total) << name << " line " << p.source_line;
    }
    std::printf("%s: %zu ARC frames, %zu LINE_PROFILE, %llu arcs as chords, %.3f s\n", name,
                job.arcs, job.profiles,
                static_cast<unsigned long long>(job.profile_stats.arcs_as_chords),
                job.total_t / 5e7);
  }
  EXPECT_GT(arcs, 0u);
}

TEST(Lookahead, ReferenceWalkArcsRunClockExact) {
  // Small fast arcs (incl. a full helical circle and a tiny radius) through the arc helper's
  // clock-exact block model: end point and Z exact, no guard, no late move, and the block ends
  // on the clock the host's time model says (the corpus arcs take ~10^9 clocks: too slow here;
  // their end clocks agreed exactly when run once, 2026-11-21).
  MachineConfig c;
  c.laser_requires_m3 = false;
  c.motion = "profile";
  c.native_arcs = true;
  const auto plan = pl::plan_program(
      fpgacnc::gcode::parse_string("G1 X1 F3000\nG3 X2 Y1 I0 J1\nG2 X3 Y2 I1 J0\n"
                                   "G2 X3 Y2 I0.5 J0 Z-0.2\nG3 X3.2 Y2.2 I0.1 J0.1\nG1 X0 Y0\n"),
      c, {});
  auto lim = pl::motion_limits(c);
  lim.arc_walk = pl::reference_arc_walk();
  const auto pp = pl::plan_profiles(plan, lim);
  EXPECT_EQ(pp.stats.arcs, 4u);
  for (const auto& p : profiles_of(pp)) {
    if (!p.arc) continue;
    const auto run = run_arc(p);
    EXPECT_FALSE(run.err) << "line " << p.source_line;
    EXPECT_FALSE(run.late) << "line " << p.source_line;
    EXPECT_EQ(run.x, p.arc_fields.dx) << "line " << p.source_line;
    EXPECT_EQ(run.y, p.arc_fields.dy) << "line " << p.source_line;
    EXPECT_EQ(run.z, p.arc_fields.dz) << "line " << p.source_line;
    EXPECT_EQ(run.end_clock, p.clocks) << "line " << p.source_line;
  }
}

TEST(Packer, ProfileJobTimeCountsReversalPauses) {
  // The job of the simulated-board check (docs/motion.md, "Time model against the RTL"): the
  // board ran these four segments in exactly the clocks below (laser edges) with a 400-clock
  // DIR hold + setup pause at each of the three reversals.
  MachineConfig c;
  c.motion = "profile";
  const auto plan = pl::plan_program(
      fpgacnc::gcode::parse_string("G21 G90\nM3 S1000\nG1 X5 Y2 F3000\nX10 Y0\nX10 Y8\nG0 X0 Y0\n"),
      c, {});
  const auto job = fpgacnc::test::pack_motion(plan, c);
  std::vector<uint64_t> clocks;
  for (const auto& p : profiles_of(pl::plan_profiles(plan, c))) clocks.push_back(p.clocks);
  EXPECT_EQ(clocks, (std::vector<uint64_t>{7'249'937, 7'113'612, 10'222'727, 14'483'012}));
  EXPECT_EQ(job.reversal_gaps, 3u);
  EXPECT_EQ(job.reversal_gap_clocks, 1200u);
  EXPECT_EQ(job.total_t, 39'070'488u);  // board: last STEP 39 925 162 - first run edge 854 674
}
