// RTL against twin for the circular DDA (CTest label cosim): the SystemC ArcDdaTwin
// (fpgacnc/twins/arc_dda.h) and the Verilated rtl/motion/arc_dda.v run the same random arcs, single
// and in zero-gap chains (each next arc loaded on the edge of the previous one's last move); every
// step edge (axis, direction, edge number) must agree, and the twin's end edge must be the RTL's
// last-move edge. Usage: arc_twin_rtl [--seed N] [--arcs N]. Exit status 1 on any disagreement,
// naming the arc and the first differing edge.
// The Verilated model first: verilated.h must not see SystemC (varc is a plain C++ model).
#include "common/arc_rtl.h"
// clang-format off
#include <fmt/format.h>
// clang-format on

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <systemc>
#include <vector>

#include "../cosim/arc_stimulus.h"
#include "fpgacnc/twins/arc_dda.h"

namespace {

using namespace fpgacnc::twins;
namespace arc = fpgacnc::models::arc;

struct Rec {
  Cycle edge;
  int axis;
  bool dir;
};

SC_MODULE(ArcBench) {
  CycleClock clk{50'000'000};
  ArcDdaTwin twin;
  tlm_utils::simple_initiator_socket<ArcBench> ld;
  tlm_utils::simple_target_socket<ArcBench> xs, ys, zs;
  std::vector<Rec> recs;
  tlm::tlm_generic_payload gp;

  SC_CTOR(ArcBench) : twin("arc_dda", clk), ld("ld"), xs("xs"), ys("ys"), zs("zs") {
    ld.bind(twin.load);
    twin.x_step.bind(xs);
    twin.y_step.bind(ys);
    twin.z_step.bind(zs);
    xs.register_b_transport(this, &ArcBench::on_x);
    ys.register_b_transport(this, &ArcBench::on_y);
    zs.register_b_transport(this, &ArcBench::on_z);
  }
  void on(int axis, tlm::tlm_generic_payload& g, sc_core::sc_time& d) {
    recs.push_back({clk.at(d), axis, payload<PulseCmd>(g).dir});
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_x(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    on(0, g, d);
  }
  void on_y(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    on(1, g, d);
  }
  void on_z(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    on(2, g, d);
  }
};

// The random arcs (arc_stimulus.h, shared with cosim and cosim_executor): radius log-uniform in
// 1..2000 steps, full circles and any sweep, both directions, helices, cruise at 8..100 clocks per
// step (the executor's STEP timing plays no part here), all consistent (no C_TOTAL + 1).
arc::Frame random_frame(std::mt19937_64& rng) {
  ArcStimulus o;
  o.r_log_max = 2000;
  o.cps_lo = 8;
  o.cps_hi = 100;
  o.bad_in = 0;
  return random_arc_frame(rng, o);
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t seed = 64;
  int n_arcs = 300;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seed")) seed = std::strtoull(argv[i + 1], nullptr, 0);
    if (!std::strcmp(argv[i], "--arcs")) n_arcs = std::atoi(argv[i + 1]);
  }
  fmt::print("[seed] arc_twin_rtl: {} (--seed to reproduce)\n", seed);
  ArcBench bench("arc_bench");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int failures = 0, arcs = 0, chains = 0;
  uint64_t edges = 0;
  struct Runner : sc_core::sc_module {
    SC_HAS_PROCESS(Runner);
    std::function<void()> f;
    Runner(sc_core::sc_module_name n, std::function<void()> fn) : sc_module(n), f(std::move(fn)) {
      SC_THREAD(run);
    }
    void run() { f(); }
  };
  fpgacnc::tb::ArcRtl rtl;
  Runner runner("runner", [&] {
    Cycle edge_l = 10;
    while (arcs < n_arcs && failures == 0) {
      std::vector<arc::Frame> fs;
      const int len = 1 + static_cast<int>(u01(rng) * 4);
      for (int q = 0; q < len; ++q) fs.push_back(random_frame(rng));
      const std::vector<arc::RunResult> got = rtl.run_chain(fs, 1ull << 30);
      for (size_t q = 0; q < fs.size() && failures == 0; ++q) {
        bench.recs.clear();
        ArcLoad l{fs[q]};
        transport(bench.ld, bench.gp, bench.clk, l, edge_l);
        // the twin's requests as events of the arc's clocks (clock = edge - L - 1)
        std::vector<arc::Event> tw;
        for (const Rec& r : bench.recs) {
          const uint64_t c = static_cast<uint64_t>(r.edge - edge_l - 1);
          if (tw.empty() || tw.back().clock != c) tw.push_back(arc::Event{c, 0, 0, 0, false});
          const int8_t d = r.dir ? 1 : -1;
          (r.axis == 0 ? tw.back().dx : r.axis == 1 ? tw.back().dy : tw.back().dz) = d;
        }
        const std::vector<arc::Event>& rv = got[q].events;
        const std::string what = fmt::format(
            "arc {} (chain {}, position {}): I={} J={} DX={} DY={} {} DZ={}", arcs, chains, q,
            fs[q].g.i, fs[q].g.j, fs[q].g.dx, fs[q].g.dy, fs[q].g.ccw ? "CCW" : "CW", fs[q].dz);
        for (size_t k = 0; k < std::max(tw.size(), rv.size()); ++k) {
          const bool ok = k < tw.size() && k < rv.size() && tw[k].clock == rv[k].clock &&
                          tw[k].dx == rv[k].dx && tw[k].dy == rv[k].dy && tw[k].dz == rv[k].dz;
          if (!ok) {
            fmt::print(
                "FAIL {}: edge {}: twin {}, RTL {}\n", what, k,
                k < tw.size()
                    ? fmt::format("clock {} ({},{},{})", tw[k].clock, tw[k].dx, tw[k].dy, tw[k].dz)
                    : std::string("none"),
                k < rv.size()
                    ? fmt::format("clock {} ({},{},{})", rv[k].clock, rv[k].dx, rv[k].dy, rv[k].dz)
                    : std::string("none"));
            ++failures;
            break;
          }
        }
        if (failures == 0 && (l.end_edge != edge_l + static_cast<Cycle>(got[q].end_clock) + 1 ||
                              l.err || got[q].err)) {
          fmt::print("FAIL {}: twin end edge {} err {}, RTL last move clock {} err {}\n", what,
                     l.end_edge - edge_l, l.err, got[q].end_clock, got[q].err);
          ++failures;
        }
        edges += tw.size();
        ++arcs;
        edge_l = l.end_edge;  // the next arc of the chain: loaded on the last move's edge
      }
      edge_l += 1 + static_cast<Cycle>(u01(rng) * 5);  // idle between chains (RTL: any gap)
      ++chains;
    }
  });
  sc_core::sc_start();
  fmt::print("[arc] twin == RTL for {} arcs in {} chains ({} step clocks){}\n", arcs, chains, edges,
             failures ? ", FAILED" : "");
  return failures ? 1 : 0;
}
