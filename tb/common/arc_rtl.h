// Harness of the Verilated arc_dda (tb/test_arc_dda.cpp, systemc/test/arc_twin_rtl.cpp): loads one
// ARC (fields + the products prep derives, from arc_walk.h) and records the pins as events in the
// reference's clock numbering (the pins show the event of clock c after the (c+1)-th edge that
// follows the load edge). err is also set when busy does not fall with the last move or the block
// does not finish within max_clocks.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "Varc_dda.h"
#include "fpgacnc/models/arc_walk.h"
#include "verilated.h"

namespace fpgacnc::tb {

namespace arc = fpgacnc::models::arc;

class ArcRtl {
 public:
  ArcRtl()
      : ctx_(std::make_unique<VerilatedContext>()), m_(std::make_unique<Varc_dda>(ctx_.get())) {
    m_->rst = 1;
    m_->load = 0;
    m_->run = 1;
    m_->stop = 0;
    tick();
    tick();
    m_->rst = 0;
    tick();
  }

  static void set96(VlWide<3>& w, arc::u128 v) {
    w[0] = static_cast<uint32_t>(v);
    w[1] = static_cast<uint32_t>(v >> 32);
    w[2] = static_cast<uint32_t>(v >> 64);
  }

  // Loads the frame, runs until the block is idle; events in the reference's clock numbering.
  arc::RunResult run(const arc::Frame& f, uint64_t max_clocks) {
    return run_chain({f}, max_clocks).front();
  }

  // Loads the frame and raises `stop` (e-stop) in clocks stop_clock .. stop_clock + stop_len - 1
  // (the reference's numbering); runs max_clocks clocks. Events as run()'s; busy_after: busy on
  // the last clock.
  struct Stopped {
    std::vector<arc::Event> events;
    bool busy_after = true;
  };
  Stopped run_stopped(const arc::Frame& f, uint64_t stop_clock, uint64_t stop_len,
                      uint64_t max_clocks) {
    Stopped out;
    apply(f);
    m_->load = 1;
    tick();
    m_->load = 0;
    for (uint64_t c = 0; c < max_clocks; ++c) {
      m_->stop = c >= stop_clock && c < stop_clock + stop_len;
      tick();
      arc::Event ev;
      ev.clock = c;
      if (m_->x_step) ev.dx = m_->x_dir ? 1 : -1;
      if (m_->y_step) ev.dy = m_->y_dir ? 1 : -1;
      if (m_->z_step) ev.dz = m_->z_dir ? 1 : -1;
      ev.last = m_->last;
      if (ev.dx || ev.dy || ev.dz || ev.last) out.events.push_back(ev);
    }
    m_->stop = 0;
    out.busy_after = m_->busy;
    return out;
  }

  // Arcs back to back: each next arc is loaded on the edge of the previous one's last move (the
  // block's `ending` output), so its clock 0 follows that edge (zero gap). Events of each arc in
  // its own clock numbering.
  std::vector<arc::RunResult> run_chain(const std::vector<arc::Frame>& fs, uint64_t max_clocks) {
    std::vector<arc::RunResult> out(fs.size());
    size_t cur = 0;
    apply(fs[0]);
    m_->load = 1;
    tick();  // the load edge of arc 0: its clock 0 follows
    m_->load = 0;
    uint64_t base = 0;  // edges since the current arc's load edge, before this one
    bool finished = false;
    for (uint64_t guard = 0; guard < max_clocks + 2; ++guard) {
      const bool chain = m_->ending && cur + 1 < fs.size();
      if (chain && m_->end_err) out[cur].err = true;  // the chained load clears the sticky err
      if (chain) {
        apply(fs[cur + 1]);
        m_->load = 1;
      }
      tick();
      m_->load = 0;
      base += 1;  // edge `base` after the load edge: pins show the event of clock base - 1
      arc::RunResult& r = out[cur];
      arc::Event ev;
      ev.clock = base - 1;
      if (m_->x_step) ev.dx = m_->x_dir ? 1 : -1;
      if (m_->y_step) ev.dy = m_->y_dir ? 1 : -1;
      if (m_->z_step) ev.dz = m_->z_dir ? 1 : -1;
      ev.last = m_->last;
      if (ev.dx || ev.dy || ev.dz) r.events.push_back(ev);
      if (ev.dx || ev.dy) r.moves += 1;
      r.x += ev.dx;
      r.y += ev.dy;
      r.z += ev.dz;
      if (ev.last) {
        r.end_clock = ev.clock;
        if (chain) {
          if (!m_->busy) r.err = true;  // the next arc must be running
          r.late = false;               // the sticky flags now belong to the next arc
          cur += 1;
          base = 0;
        } else {
          r.err = r.err || m_->err || m_->busy;  // busy falls on the edge of the last move
          r.late = m_->late;
          finished = true;
          break;
        }
      }
    }
    if (!finished) out[cur].err = true;
    return out;
  }

 private:
  void apply(const arc::Frame& f) {
    const arc::Derived d = arc::derive(f);
    const auto s24 = [](int64_t v) { return static_cast<uint32_t>(v) & 0xFFFFFFu; };
    m_->ccw = f.g.ccw;
    m_->i_in = s24(f.g.i);
    m_->j_in = s24(f.g.j);
    m_->dx_in = s24(f.g.dx);
    m_->dy_in = s24(f.g.dy);
    m_->dz_in = static_cast<uint32_t>(f.dz);
    m_->n_ramp = f.n_ramp;
    m_->dt_q = static_cast<uint64_t>(d.dt_q) & ((uint64_t{1} << 48) - 1);
    m_->dt_r = static_cast<uint32_t>(d.dt_r);
    m_->c_total = f.c_total;
    m_->v_entry = f.v_entry;
    m_->v_cruise = f.v_cruise;
    m_->v_exit = f.v_exit;
    m_->acc_a = f.a;
    m_->dec_d = f.d;
    set96(m_->vz_entry, d.vz_entry);
    set96(m_->vz_cruise, d.vz_cruise);
    set96(m_->vz_exit, d.vz_exit);
    set96(m_->az, d.az);
  }

  void tick() {
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
  }
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Varc_dda> m_;
};

}  // namespace fpgacnc::tb
