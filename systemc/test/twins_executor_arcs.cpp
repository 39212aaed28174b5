// segment_executor's twin with its event-driven ARC run (SegmentExecutorTwin::run_arc on
// arc::Dda::skip_quiet) against the clock-by-clock form (clockwise_executor.h), bit for bit, on
// random jobs (CTest label unit): arcs of radius 1..30 (tiny ones reverse X / Y faster than DIR
// hold + setup: pending in-arc DIR writes, DIR-setup violations), fast arcs whose moves wait for
// the walk, helices, inconsistent C_TOTAL (arc error), lines and dwells between them (STEP
// hold references, DIR levels), offers back to back or late, random STEP/DIR timings and
// aborts (e-stop spans) inside arcs. Compared: every pin edge, the arcs' step request,
// violation and error edges, DIR-write counts, the segment trace, seg_done, positions and pulse
// violations. Fixed seeds; exit status 1 on any difference. Options: --jobs N, --seed S.
#include <fmt/format.h>

#include <cstdlib>
#include <random>
#include <string>
#include <systemc>

#include "../cosim/arc_stimulus.h"
#include "clockwise_executor.h"
#include "fpgacnc/twins/segment_executor.h"

namespace {

using namespace fpgacnc::twins;
namespace arc = fpgacnc::models::arc;
int failures = 0;

void fail(const std::string& what) {
  if (++failures <= 20) fmt::print("FAIL: {}\n", what);
}

uint32_t pick(std::mt19937_64& g, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
}

struct Job {
  std::array<AxisTiming, kAxes> timing{};
  std::vector<std::pair<Segment, Cycle>> offers;  // segment, gap after the previous accept
  std::vector<AbortSpan> aborts;
};

// What a run gives (everything the executor and its pulses expose).
struct Outcome {
  std::vector<Edge> edges;
  std::vector<Cycle> seg_done, seg_start, arc_err, arc_viol, arc_steps, accepts;
  std::vector<std::array<Cycle, 6>> trace;
  uint64_t arcs = 0, arc_errors = 0, arc_dir_writes = 0, aborted = 0;
  std::array<int64_t, kAxes> position{};
  std::array<uint64_t, kAxes> pulse_violations{};
};

template <class Exec>
struct Bench : sc_core::sc_module {
  CoreParams p;
  CycleClock clk{50'000'000};
  PinRecorder pins;
  Exec exec;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse;
  tlm_utils::simple_initiator_socket<Bench> seg, status, abort;
  tlm_utils::simple_target_socket<Bench> done;
  std::vector<Cycle> seg_done;
  tlm::tlm_generic_payload gp;

  explicit Bench(sc_core::sc_module_name n)
      : sc_module(n),
        exec("segment_executor", clk, p, pins),
        seg("seg"),
        status("status"),
        abort("abort"),
        done("done") {
    seg.bind(exec.segments);
    status.bind(exec.status);
    abort.bind(exec.abort);
    exec.done.bind(done);
    done.register_b_transport(this, &Bench::on_done);
    make_axis_twins(exec, clk, p, pins, dda, pulse);
  }
  void on_done(tlm::tlm_generic_payload& g, sc_core::sc_time& d) {
    seg_done.push_back(clk.at(d));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  Outcome run(const Job& j) {
    p.timing = j.timing;
    exec.reset();
    for (auto& x : pulse) x->reset();
    pins.clear();
    seg_done.clear();
    for (const AbortSpan& a : j.aborts) {
      AbortSpan s = a;
      transport(abort, gp, clk, s, a.first);
    }
    Outcome o;
    Cycle accept = 0;
    for (const auto& [s0, gap] : j.offers) {
      Segment s = s0;
      accept = transport(seg, gp, clk, s, accept + gap);
      o.accepts.push_back(accept);
    }
    o.edges = pins.take_sorted();
    o.seg_done = seg_done;
    o.seg_start = exec.seg_start_cycles;
    o.arc_err = exec.arc_err_cycles;
    o.arc_viol = exec.arc_violation_cycles;
    o.arc_steps = exec.arc_step_edges;
    for (const auto& t : exec.trace)
      o.trace.push_back({t.accept, t.dir_edge, t.fast_dir, t.run, t.end, t.cut});
    o.arcs = exec.arcs;
    o.arc_errors = exec.arc_errors;
    o.arc_dir_writes = exec.arc_dir_writes;
    o.aborted = exec.aborted;
    for (int a = 0; a < kAxes; ++a) {
      o.position[a] = pulse[a]->position;
      o.pulse_violations[a] = pulse[a]->violations;
    }
    return o;
  }
};

// A job of arcs with lines and dwells between them (see the file comment).
Job random_job(uint64_t seed) {
  std::mt19937_64 g(seed);
  Job j;
  const uint32_t r = std::array<uint32_t, 4>{3, 20, 150, 600}[pick(g, 0, 3)];
  for (auto& t : j.timing) {
    auto v = [&](uint32_t lo) { return pick(g, 0, 15) == 0 ? 0u : pick(g, lo, r); };
    t = AxisTiming{v(1), v(1), v(0), v(0)};
  }
  CoreParams p;
  p.timing = j.timing;
  const uint32_t minp = p.min_period();
  const uint32_t n = pick(g, 2, 8);
  for (uint32_t i = 0; i < n; ++i) {
    Segment s{};
    s.v2 = true;
    const uint32_t kind = pick(g, 0, 9);
    if (kind < 6) {  // ARC, as segment_prep prepares it
      ArcStimulus o;
      o.r_min = 1;
      o.r_span = pick(g, 0, 1) == 0 ? 4 : 29;
      o.cps_lo = pick(g, 0, 3) == 0 ? pick(g, 1, 20) : std::max<uint32_t>(minp, 20);
      o.cps_hi = o.cps_lo + pick(g, 0, 3 * minp);
      o.bad_in = 6;
      s.arc = true;
      s.arc_frame = random_arc_frame(g, o);
      if (pick(g, 0, 4) == 0) s.arc_frame.dz = static_cast<int32_t>(pick(g, 0, 4000)) - 2000;
      s.code = s.arc_frame.g.ccw ? 3 : 2;
      s.power = static_cast<uint8_t>(pick(g, 0, 255));
      s.steps = {1, 1, 0, 0};
      const std::array<bool, 2> d0 = arc::start_dirs(s.arc_frame.g);
      s.dir = {d0[0], d0[1], s.arc_frame.dz >= 0, false};
      const int32_t dz = s.arc_frame.dz;
      s.steps[2] = dz < 0 ? 0u - static_cast<uint32_t>(dz) : static_cast<uint32_t>(dz);
    } else if (kind < 9) {  // a LINE
      s.code = static_cast<uint8_t>(pick(g, 0, 1));
      uint32_t nd = 0;
      for (int a = 0; a < kAxes; ++a) {
        s.steps[a] = pick(g, 0, 2) == 0 ? 0 : pick(g, 1, 30);
        s.dir[a] = pick(g, 0, 1) == 1;
        nd = std::max(nd, s.steps[a]);
      }
      s.period = minp + pick(g, 0, 2 * minp);
      s.total = static_cast<uint64_t>(s.period) * nd;
      for (int a = 0; a < kAxes; ++a) s.tmn[a] = s.total - s.steps[a];
    } else {  // a dwell
      s.total = pick(g, 1, 500);
      s.dir = {true, true, true, true};
      s.tmn = {s.total, s.total, s.total, s.total};
    }
    const Cycle gap = pick(g, 0, 5) == 0 ? pick(g, 0, 3000) : pick(g, 0, 2);
    j.offers.emplace_back(s, gap);
  }
  return j;
}

bool same(const Outcome& a, const Outcome& b, std::string& what) {
  auto diff = [&](const char* name, bool eq) {
    if (!eq && what.empty()) what = name;
  };
  diff("accept edges", a.accepts == b.accepts);
  if (a.edges.size() != b.edges.size()) {
    diff("edge count", false);
  } else {
    for (size_t k = 0; k < a.edges.size(); ++k)
      if (a.edges[k].cycle != b.edges[k].cycle || a.edges[k].signal != b.edges[k].signal ||
          a.edges[k].value != b.edges[k].value) {
        what = fmt::format("edge {}: {} sig {} = {} / {} sig {} = {}", k, a.edges[k].cycle,
                           a.edges[k].signal, a.edges[k].value, b.edges[k].cycle, b.edges[k].signal,
                           b.edges[k].value);
        break;
      }
  }
  diff("seg_done", a.seg_done == b.seg_done);
  diff("seg_start", a.seg_start == b.seg_start);
  diff("arc_err edges", a.arc_err == b.arc_err);
  diff("arc violation edges", a.arc_viol == b.arc_viol);
  diff("arc step edges", a.arc_steps == b.arc_steps);
  diff("trace", a.trace == b.trace);
  diff("arc counters", a.arcs == b.arcs && a.arc_errors == b.arc_errors &&
                           a.arc_dir_writes == b.arc_dir_writes && a.aborted == b.aborted);
  diff("positions", a.position == b.position);
  diff("pulse violations", a.pulse_violations == b.pulse_violations);
  return what.empty();
}

struct Runner : sc_core::sc_module {
  SC_HAS_PROCESS(Runner);
  Bench<SegmentExecutorTwin> fresh{"event_driven"};
  Bench<ref::ClockwiseExecutorTwin> old{"clock_by_clock"};
  uint64_t jobs, seed;
  uint64_t arcs = 0, dir_writes = 0, violations = 0, errors = 0, aborted = 0, edges = 0;
  Runner(sc_core::sc_module_name n, uint64_t jobs, uint64_t seed)
      : sc_module(n), jobs(jobs), seed(seed) {
    SC_THREAD(run);
  }
  void run() {
    for (uint64_t k = 0; k < jobs; ++k) {
      Job j = random_job(seed + k);
      // Half the jobs with 1..3 aborts somewhere in the run (the arcs' run windows first).
      std::mt19937_64 g((seed + k) * 0x9E3779B97F4A7C15ull + 17);
      if (pick(g, 0, 1) == 0) {
        const Outcome plain = fresh.run(j);
        Cycle after = 0;
        const uint32_t na = pick(g, 1, 3);
        for (uint32_t i = 0; i < na && !plain.trace.empty(); ++i) {
          const auto& t = plain.trace[pick(g, 0, static_cast<uint32_t>(plain.trace.size() - 1))];
          const Cycle lo = std::max(after + 1, t[3]), hi = std::max(lo, t[4] + 5);
          const Cycle first =
              lo + pick(g, 0, static_cast<uint32_t>(std::min<Cycle>(hi - lo, 1 << 30)));
          const Cycle last = first + pick(g, 0, 50);
          if (!j.aborts.empty() && first <= j.aborts.back().last) continue;
          j.aborts.push_back(AbortSpan{first, last});
          after = last + 1;
        }
      }
      const Outcome a = fresh.run(j), b = old.run(j);
      std::string what;
      if (!same(a, b, what)) fail(fmt::format("job {}: {}", seed + k, what));
      arcs += a.arcs;
      dir_writes += a.arc_dir_writes;
      violations += a.arc_viol.size();
      errors += a.arc_errors;
      aborted += a.aborted;
      edges += a.edges.size();
    }
  }
};

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t jobs = 1500, seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--jobs") jobs = std::strtoull(argv[i + 1], nullptr, 10);
    if (k == "--seed") seed = std::strtoull(argv[i + 1], nullptr, 10);
  }
  Runner r("runner", jobs, seed);
  sc_core::sc_start();
  fmt::print(
      "twins_executor_arcs: {} jobs, {} arcs ({} in-arc DIR writes, {} DIR-setup violation "
      "strobes, "
      "{} arc errors), {} segments aborted, {} edges; {} failures\n",
      jobs, r.arcs, r.dir_writes, r.violations, r.errors, r.aborted, r.edges, failures);
  // the stimulus must reach what it is for
  if (r.dir_writes == 0 || r.violations == 0 || r.errors == 0 || r.aborted == 0) {
    fmt::print("FAIL: stimulus misses a case\n");
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
