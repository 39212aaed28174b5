// RTL side of the block-level co-simulation (see cosim_blocks.cpp): the Verilated C++ models of
// tb/ (uart_rx/uart_tx per baud, vdecoder, vprep), clocked by these loops. Reset is held for 8
// edges and released on cycle -20, as in every harness; cycle 1 is the first stimulus edge.
#include <memory>

#include "Vpacket_decoder_v1.h"
#include "Vsegment_prep.h"
#include "Vuart_rx_115200.h"
#include "Vuart_rx_3000000.h"
#include "Vuart_tx_3000000.h"
#include "blocks_job.h"
#include "verilated.h"

namespace fpgacnc::twins {
namespace {

template <class M>
void clock_once(M& m) {
  m.clk = 1;
  m.eval();
  m.clk = 0;
  m.eval();
}
template <class M>
void reset(M& m) {
  m.rst = 1;
  m.clk = 0;
  m.eval();
  for (int i = 0; i < 8; ++i) clock_once(m);
  m.rst = 0;
  for (int i = 0; i < 21; ++i) clock_once(m);
}

template <class M>
BlockRun run_rx(const UartRxJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<M>(ctx.get(), "uart_rx");
  m->rxd = 1;
  m->m_axis_tready = 1;
  reset(*m);
  const SenderTiming st{50'000'000, j.baud};
  BlockRun r;
  const Cycle end = j.frames.empty() ? 0 : j.frames.back().first + 2 * st.frame();
  size_t cur = 0;
  for (Cycle c = 1; c <= end; ++c) {
    while (cur + 1 < j.frames.size() && j.frames[cur + 1].first <= c) ++cur;
    int level = 1;
    if (!j.frames.empty() && j.frames[cur].first <= c)
      level = st.level(j.frames[cur].second, c - j.frames[cur].first);
    m->rxd = static_cast<uint8_t>(level);
    clock_once(*m);
    if (m->m_axis_tvalid) r.events.push_back(BlockEvent{c, {m->m_axis_tdata, 0, 0, 0}});
  }
  m->final();
  return r;
}

}  // namespace

BlockRun rtl_uart_rx(const UartRxJob& j) {
  return j.baud == 115'200 ? run_rx<Vuart_rx_115200>(j) : run_rx<Vuart_rx_3000000>(j);
}

BlockRun rtl_uart_tx(const UartTxJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vuart_tx_3000000>(ctx.get(), "uart_tx");
  m->s_axis_tvalid = 0;
  reset(*m);
  BlockRun r;
  size_t k = 0;
  Cycle offer = j.offers.empty() ? 0 : j.offers[0].second;
  uint8_t prev = 1;
  Cycle quiet = 0;
  for (Cycle c = 1;; ++c) {
    const bool valid = k < j.offers.size() && c >= offer;
    m->s_axis_tvalid = valid ? 1 : 0;
    m->s_axis_tdata = valid ? j.offers[k].first : 0;
    const bool take = valid && m->s_axis_tready;
    clock_once(*m);
    if (take) {
      r.events.push_back(BlockEvent{c, {j.offers[k].first, 0, 0, 0}});
      if (++k < j.offers.size()) offer = c + j.offers[k].second;
    }
    if (m->txd != prev) {
      r.edges.push_back(simboard::Edge{static_cast<uint64_t>(c), simboard::kTx, m->txd});
      prev = m->txd;
    }
    if (k >= j.offers.size() && !m->busy) {
      if (++quiet > 2) break;
    }
  }
  m->final();
  return r;
}

BlockRun rtl_decoder(const DecoderJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vpacket_decoder_v1>(ctx.get(), "packet_decoder_v1");
  m->s_axis_tvalid = 0;
  m->m_axis_tready = 0;
  reset(*m);
  BlockRun r;
  size_t next = 0, k = 0;
  Cycle accept_at = -1;  // accept edge of the pending command (-1: none seen)
  const Cycle end = j.bytes.empty() ? 0 : j.bytes.back().first + 200;
  for (Cycle c = 1; c <= end; ++c) {
    // A byte valid after edge b is on the input for edge b + 1.
    const bool byte = next < j.bytes.size() && j.bytes[next].first + 1 == c;
    m->s_axis_tvalid = byte ? 1 : 0;
    m->s_axis_tdata = byte ? j.bytes[next].second : 0;
    if (byte) ++next;
    m->m_axis_tready = (accept_at == c) ? 1 : 0;
    clock_once(*m);
    if (accept_at == c) accept_at = -1;
    if (m->timeout) ++r.counters[0];
    if (m->overrun) ++r.counters[1];
    if (m->m_axis_tvalid && accept_at < 0) {
      const auto& d = m->m_axis_tdata;  // {code[1:0], a[31:0], b[31:0], feed[15:0]}: 82 bits
      const uint64_t feed = d[0] & 0xffff;
      const uint64_t b = (d[0] >> 16) | (static_cast<uint64_t>(d[1] & 0xffff) << 16);
      const uint64_t a = (d[1] >> 16) | (static_cast<uint64_t>(d[2] & 0xffff) << 16);
      const uint64_t code = (d[2] >> 16) & 3;
      r.events.push_back(BlockEvent{
          c, {code | static_cast<uint64_t>(m->m_axis_tuser) << 8, a, b | feed << 32, 0}});
      accept_at = c + 1 + (k < j.accept_delay.size() ? j.accept_delay[k] : 0);
      ++k;
    }
  }
  m->final();
  return r;
}

BlockRun rtl_prep(const PrepJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vsegment_prep>(ctx.get(), "segment_prep");
  m->s_axis_tvalid = 0;
  m->m_axis_tready = 0;
  m->exec_idle = 1;
  m->min_period = 2 * j.min_half;
  reset(*m);
  BlockRun r;
  size_t k = 0, seg = 0;
  Cycle valid_from = j.commands.empty() ? 0 : j.commands[0].gap;
  Cycle accept_at = -1;
  Cycle quiet = 0;
  Cycle idle_after = -1;  // exec_idle high from the clock after this edge
  uint64_t setup = 0, hold = 0;
  for (int a = 0; a < kAxes; ++a) {
    setup |= static_cast<uint64_t>(j.setup[a]) << (16 * a);
    hold |= static_cast<uint64_t>(j.hold[a]) << (16 * a);
  }
  m->cfg_dir_setup = setup;
  m->cfg_dir_hold = hold;
  for (Cycle c = 1;; ++c) {
    m->exec_idle = c > idle_after ? 1 : 0;
    const bool offering = k < j.commands.size() && c > valid_from;
    if (offering) {
      // { v2, kind[1:0], code[1:0], power[7:0], t[31:0], steps[4 x 32] }: 173 bits
      const PrepCommand& p = j.commands[k];
      for (int a = 0; a < kAxes; ++a) m->s_axis_tdata[a] = p.steps[a];
      m->s_axis_tdata[4] = p.t;
      m->s_axis_tdata[5] = p.power | static_cast<uint32_t>(p.code & 3) << 8 |
                           static_cast<uint32_t>(p.kind & 3) << 10 | (p.v2 ? 1u << 12 : 0u);
    }
    m->s_axis_tvalid = offering ? 1 : 0;
    m->m_axis_tready = (accept_at == c) ? 1 : 0;
    m->eval();  // s_axis_tready depends on the entry's kind and exec_idle
    const bool take = offering && m->s_axis_tready;
    clock_once(*m);
    if (take) {
      r.events.push_back(BlockEvent{c, {k, 0, 0, 0}});
      if (++k < j.commands.size()) valid_from = c + j.commands[k].gap;
    }
    if (m->init_applied)
      r.events.push_back(BlockEvent{c, {1ull << 62 | (m->init_v2 ? 1u : 0u), 0, 0, 0}});
    if (m->clamped) r.events.push_back(BlockEvent{c, {1ull << 63, 0, 0, 0}});
    if (accept_at == c) {
      accept_at = -1;
      idle_after = c + (seg - 1 < j.busy.size() ? j.busy[seg - 1] : 0);
    }
    if (m->m_axis_tvalid && accept_at < 0) {
      r.events.push_back(BlockEvent{
          c,
          {m->m_axis_period | static_cast<uint64_t>(m->m_axis_code) << 32 |
               static_cast<uint64_t>(m->m_axis_dir) << 40 |
               static_cast<uint64_t>(m->m_axis_dir_fast) << 44 |
               static_cast<uint64_t>(m->m_axis_v2) << 45 |
               static_cast<uint64_t>(m->m_axis_power) << 48,
           m->m_axis_total, m->m_axis_steps[0] | static_cast<uint64_t>(m->m_axis_steps[1]) << 32,
           m->m_axis_steps[2] | static_cast<uint64_t>(m->m_axis_steps[3]) << 32,
           m->m_axis_tmn[0] | static_cast<uint64_t>(m->m_axis_tmn[1]) << 32,
           m->m_axis_tmn[6] | static_cast<uint64_t>(m->m_axis_tmn[7]) << 32}});
      accept_at = c + 1 + (seg < j.accept_delay.size() ? j.accept_delay[seg] : 0);
      ++seg;
    }
    if (k >= j.commands.size() && !m->busy && accept_at < 0 && c > idle_after) {
      if (++quiet > 2) break;
    }
  }
  r.counters = {m->numerator_x, m->numerator_y};
  m->final();
  return r;
}

}  // namespace fpgacnc::twins
