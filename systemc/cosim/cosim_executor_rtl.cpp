// RTL side of the segment_executor block co-simulation: the Verilated C++ model `vexec`
// clocked by this loop (see cosim_executor.cpp).
#include <cstdint>
#include <memory>

#include "Vsegment_executor.h"
#include "arc_stimulus.h"
#include "executor_job.h"
#include "fpgacnc/models/edges.h"
#include "verilated.h"

namespace fpgacnc::twins {
namespace {

void clock_once(Vsegment_executor& m) {
  m.clk = 1;
  m.eval();
  m.clk = 0;
  m.eval();
}

uint64_t pack16(const std::array<AxisTiming, kAxes>& t, uint32_t AxisTiming::*f) {
  uint64_t v = 0;
  for (int a = 0; a < kAxes; ++a) v |= static_cast<uint64_t>(t[a].*f & 0xffff) << (16 * a);
  return v;
}

// Writes `width` bits of v at bit `lsb` of a Verilated wide port (32-bit words).
template <class W>
void put_bits(W& w, int lsb, unsigned __int128 v, int width) {
  for (int b = 0; b < width; ++b) {
    const int bit = lsb + b;
    const uint32_t mask = 1u << (bit % 32);
    if ((v >> b) & 1u)
      w[bit / 32] |= mask;
    else
      w[bit / 32] &= ~mask;
  }
}

// The PROFILE inputs as segment_prep makes them (prepare_profile, checked against the Verilated
// segment_prep by cosim_blocks).
void put_profile(Vsegment_executor& m, const ExecSegment& s) {
  m.s_axis_kind = s.prof ? 1 : s.arc ? 2 : 0;
  if (s.arc)
    put_arc_load(s.arc_frame,
                 [&m](int lsb, unsigned __int128 v, int w) { put_bits(m.s_axis_arc, lsb, v, w); });
  if (!s.prof) return;
  const ProfilePrepared pp = prepare_profile(s.profile, s.steps);
  m.s_axis_prof_u1 = pp.u1;
  m.s_axis_prof_v1 = pp.v1;
  m.s_axis_prof_op1 = pp.op1;
  m.s_axis_prof_accel = s.profile.accel;
  m.s_axis_prof_vcruise = s.profile.v_cruise;
  m.s_axis_prof_vexit = s.profile.v_exit;
  m.s_axis_prof_vcma = pp.vcma;
  m.s_axis_prof_vxpa = pp.vxpa;
  m.s_axis_prof_decel_at = s.profile.decel_at;
  m.s_axis_prof_n_dom = pp.n_dom;
  for (int a = 0; a < kAxes; ++a) {
    put_bits(m.s_axis_prof_v0, 71 * a, pp.v0[a], 71);
    put_bits(m.s_axis_prof_vc, 71 * a, pp.vc[a], 71);
    put_bits(m.s_axis_prof_vx, 71 * a, pp.vx[a], 71);
    put_bits(m.s_axis_prof_acc, 56 * a, pp.acc[a], 56);
  }
}

}  // namespace

RunResult run_executor_rtl(const ExecJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vsegment_executor>(ctx.get(), "segment_executor");
  m->cfg_step_high = pack16(j.timing, &AxisTiming::high);
  m->cfg_step_low = pack16(j.timing, &AxisTiming::low);
  m->cfg_dir_setup = pack16(j.timing, &AxisTiming::setup);
  m->cfg_dir_hold = pack16(j.timing, &AxisTiming::hold);
  m->s_axis_tvalid = 0;
  m->__SYM__abort = 0;
  m->adv = 1;  // the motion rate at 100 %
  m->rst = 1;
  m->clk = 0;
  m->eval();
  for (int i = 0; i < 8; ++i) clock_once(*m);
  m->rst = 0;
  for (int i = 0; i < 21; ++i) clock_once(*m);  // cycles -20..0, as in the system harness
  RunResult r;
  uint32_t prev = 0;
  Cycle c = 0, valid_from = j.offers.empty() ? -1 : j.offers[0].gap;
  size_t next = 0, prof_set = SIZE_MAX;  // offer whose profile inputs are on the ports
  Cycle quiet = 0;
  size_t next_abort = 0;
  while (true) {
    // Inputs for edge c + 1: the next offer is valid once edge valid_from has passed.
    const bool offering = next < j.offers.size() && c >= valid_from;
    if (offering) {
      const ExecSegment& s = j.offers[next].seg;
      m->s_axis_code = s.code;
      m->s_axis_power = s.power;
      m->s_axis_v2 = s.v2 ? 1 : 0;
      m->s_axis_dir_fast = s.dir_fast ? 1 : 0;
      uint8_t d = 0;
      for (int a = 0; a < kAxes; ++a) {
        d |= static_cast<uint8_t>(s.dir[a] ? 1u << a : 0u);
        m->s_axis_steps[a] = s.steps[a];
        m->s_axis_tmn[2 * a] = static_cast<uint32_t>(s.tmn[a]);
        m->s_axis_tmn[2 * a + 1] = static_cast<uint32_t>(s.tmn[a] >> 32);
      }
      m->s_axis_dir = d;
      m->s_axis_total = s.total;
      if (prof_set != next) {  // (wide ports: written once per offer)
        put_profile(*m, s);
        prof_set = next;
      }
    }
    m->s_axis_tvalid = offering ? 1 : 0;
    while (next_abort < j.aborts.size() && j.aborts[next_abort].last < c + 1) ++next_abort;
    const bool abort = next_abort < j.aborts.size() && j.aborts[next_abort].first <= c + 1;
    if (abort || m->__SYM__abort) {  // (Verilator's name of the port `abort`, a C++ word)
      m->__SYM__abort = abort ? 1 : 0;
      m->eval();  // s_axis_tready and laser depend on it combinationally
    }
    const bool accepted = offering && m->s_axis_tready;
    ++c;
    clock_once(*m);
    if (accepted) {
      ++next;
      if (next < j.offers.size()) valid_from = c + j.offers[next].gap;
    }
    const uint32_t sig = (m->step | (m->dir << 4) | (m->laser ? 1u << 8 : 0u));
    if (sig != prev) {
      for (uint8_t s = 0; s < 9; ++s)
        if ((sig ^ prev) >> s & 1u)
          r.edges.push_back(fpgacnc::models::Edge{static_cast<uint64_t>(c), s,
                                                  static_cast<uint8_t>(sig >> s & 1u)});
      prev = sig;
    }
    if (m->seg_start) r.seg_start.push_back(c);
    if (m->seg_done) r.seg_done.push_back(c);
    if (m->seg_done && m->seg_done_v2) r.seg_done_v2.push_back(c);
    if (m->arc_err) r.arc_err.push_back(c + 1);  // (strobe after edge c, latched on c + 1)
    if (m->violation) ++r.violations;            // STEP timing (or arc DIR setup) violation strobes
    if (next >= j.offers.size() && next_abort >= j.aborts.size() && m->idle && !m->step) {
      if (++quiet > 2) break;
    } else {
      quiet = 0;
    }
  }
  for (int a = 0; a < kAxes; ++a) r.position[a] = static_cast<int32_t>(m->position[a]);
  r.end_cycle = r.edges.empty() ? 0 : static_cast<Cycle>(r.edges.back().cycle);
  m->final();
  return r;
}

}  // namespace fpgacnc::twins
