// Regression test (CTest prep_abort_dir): segment_prep's DIR
// tracking after an abort.
// Verilated segment_prep + segment_executor chained as in cnc_core (tb/test_profile.cpp's bench),
// DIR setup 3, DIR hold 2, STEP 1/1 (min period 2) on every axis.
// Entries: DWELL T=1000; A: X +10 over T=10000 (prepared while the dwell runs, waits in S_OUT);
// abort (one clock) during the dwell: A dropped after prep tracked X as +, the X pin stays low;
// B: Y +5 over T=100 (from idle, HOLD/SETUP); C: X +10 over T=20 (P = 2) queued on B's last tick.
// The bug it caught: a DIR setup violation at X only with the abort (prep kept tracking X as +
// after the abort dropped A, so C got dir_fast 1 although X reverses at the pins with P = 2 <
// hold + setup). Fixed: an abort marks every axis's DIR unknown in segment_prep (unk_reg), so C
// takes the executor's HOLD/SETUP path. Exits 1 on any DIR setup violation at X.
#include <cstdio>
#include <memory>
#include <vector>

#include "Vsegment_executor.h"
#include "Vsegment_prep.h"
#include "common/fifo_entry.h"
#include "verilated.h"

using fpgacnc::tb::Entry;

int run(bool with_abort) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto p = std::make_unique<Vsegment_prep>(ctx.get());
  auto e = std::make_unique<Vsegment_executor>(ctx.get());
  p->min_period = 2;
  e->cfg_step_high = e->cfg_step_low = e->cfg_dir_setup = e->cfg_dir_hold = 0;
  for (int a = 0; a < 4; ++a) {
    e->cfg_step_high |= uint64_t{1} << (16 * a);
    e->cfg_step_low |= uint64_t{1} << (16 * a);
    e->cfg_dir_setup |= uint64_t{3} << (16 * a);
    e->cfg_dir_hold |= uint64_t{2} << (16 * a);
  }
  p->cfg_dir_setup = e->cfg_dir_setup;
  p->cfg_dir_hold = e->cfg_dir_hold;
  Entry dwell;
  dwell.v2 = true;
  dwell.kind = fpgacnc::tb::kDwell;
  dwell.t = 1000;
  std::vector<Entry> en{dwell, fpgacnc::tb::v2_line(0, 0, 10000, {10, 0, 0, 0}),
                        fpgacnc::tb::v2_line(0, 0, 100, {0, 5, 0, 0}),
                        fpgacnc::tb::v2_line(0, 0, 20, {10, 0, 0, 0})};
  auto connect = [&] {
    e->s_axis_code = p->m_axis_code;
    e->s_axis_power = p->m_axis_power;
    e->s_axis_v2 = p->m_axis_v2;
    e->s_axis_dir_fast = p->m_axis_dir_fast;
    e->s_axis_dir = p->m_axis_dir;
    for (int w = 0; w < 4; ++w) e->s_axis_steps[w] = p->m_axis_steps[w];
    for (int w = 0; w < 8; ++w) e->s_axis_tmn[w] = p->m_axis_tmn[w];
    e->s_axis_total = p->m_axis_total;
    e->s_axis_kind = p->m_axis_kind;
    e->s_axis_tvalid = p->m_axis_tvalid;
    p->m_axis_tready = e->s_axis_tready;
    p->exec_idle = e->idle;
  };
  uint64_t cyc = 0;
  auto clock = [&] {
    connect();
    p->clk = e->clk = 0;
    p->eval();
    e->eval();
    p->clk = e->clk = 1;
    p->eval();
    e->eval();
    ++cyc;
  };
  e->adv = 1;  // the motion rate at 100 %
  p->rst = e->rst = 1;
  clock();
  clock();
  p->rst = e->rst = 0;
  clock();
  size_t next = 0;
  int prev_dir = e->dir & 1, prev_step = e->step & 1;
  uint64_t last_dir_edge = 0;
  int bad = 0;
  for (int i = 0; i < 3000; ++i) {
    p->__SYM__abort = e->__SYM__abort = (with_abort && cyc == 600) ? 1 : 0;
    const bool offering = next < en.size();
    if (offering) en[next].pack(p->s_axis_tdata);
    p->s_axis_tvalid = offering;
    connect();
    p->eval();
    e->eval();
    const bool take = offering && p->s_axis_tready;
    const int fast = p->m_axis_dir_fast, valid = p->m_axis_tvalid, ready = e->s_axis_tready;
    clock();
    if (take) ++next;
    if (valid && ready)
      std::printf("  cycle %llu: executor accepts a segment, dir_fast %d\n",
                  (unsigned long long)cyc, fast);
    const int d = e->dir & 1, s = e->step & 1;
    if (d != prev_dir) {
      last_dir_edge = cyc;
      std::printf("  cycle %llu: DIR X -> %d\n", (unsigned long long)cyc, d);
    }
    if (s && !prev_step && cyc - last_dir_edge < 3) {
      std::printf("  cycle %llu: STEP X rises %llu clocks after the DIR X edge (DIR setup 3)\n",
                  (unsigned long long)cyc, (unsigned long long)(cyc - last_dir_edge));
      ++bad;
    }
    prev_dir = d;
    prev_step = s;
  }
  p->final();
  e->final();
  return bad;
}

int main() {
  std::printf("without abort:\n");
  const int a = run(false);
  std::printf("with an abort on cycle 600:\n");
  const int b = run(true);
  std::printf("DIR setup violations at X: %d without abort, %d with\n", a, b);
  return (a == 0 && b == 0) ? 0 : 1;
}
