// RTL side of the block-level co-simulation (see cosim_blocks.cpp): the Verilated C++ models of
// tb/ (uart_rx/uart_tx per baud, vdecoder, vprep), clocked by these loops. Reset is held for 8
// edges and released on cycle -20, as in every harness; cycle 1 is the first stimulus edge.
#include <memory>

#include "Vframe_decoder.h"
#include "Vresponse_encoder.h"
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
      r.edges.push_back(models::Edge{static_cast<uint64_t>(c), models::kTx, m->txd});
      prev = m->txd;
    }
    if (k >= j.offers.size() && !m->busy) {
      if (++quiet > 2) break;
    }
  }
  m->final();
  return r;
}

BlockRun rtl_frame_decoder(const FrameJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vframe_decoder>(ctx.get(), "frame_decoder");
  m->s_axis_tvalid = 0;
  m->m_axis_tready = 1;
  reset(*m);
  BlockRun r;
  size_t next = 0;
  const Cycle end = j.bytes.empty() ? 0 : j.bytes.back().first + 200;
  std::array<uint64_t, 3> state{0, 0, 0}, counters{0, 0, 0};
  uint64_t pend[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // strobes seen after the previous edge
  for (Cycle c = 1; c <= end; ++c) {
    // A byte valid after edge b is on the input for edge b + 1.
    const bool byte = next < j.bytes.size() && j.bytes[next].first + 1 == c;
    m->s_axis_tvalid = byte ? 1 : 0;
    m->s_axis_tdata = byte ? j.bytes[next].second : 0;
    if (byte) ++next;
    m->m_axis_tready = j.full_at(c - 1) ? 0 : 1;  // room after edge c - 1
    m->eval();
    const bool write = m->m_axis_tvalid && m->m_axis_tready;
    std::array<uint32_t, 6> d{};
    for (int w = 0; w < 6; ++w) d[w] = m->m_axis_tdata[w];
    const Bits entry = write ? bits_of(m->m_axis_tdata, kEntryBits) : Bits(0);
    clock_once(*m);
    if (write) {
      r.events.push_back(
          BlockEvent{c,
                     {kEvWrite | (d[5] & 0x1fffu), d[4], d[0] | static_cast<uint64_t>(d[1]) << 32,
                      d[2] | static_cast<uint64_t>(d[3]) << 32, 0, 0}});
      wide_events(r.events, c, 1, entry.slice(kEntryLow, kEntryBits - kEntryLow));
    }
    // Counters count the strobes of the previous clock (cnc_core's registers).
    counters[0] += pend[0] | pend[1] << 16 | pend[2] << 32 | pend[3] << 48;
    counters[1] += pend[4] | pend[5] << 16 | pend[6] << 32;
    for (auto& x : pend) x = 0;
    const std::array<uint64_t, 3> now{m->next_seq | static_cast<uint64_t>(m->v2_mode) << 8,
                                      counters[0], counters[1]};
    if (now != state) {
      r.events.push_back(BlockEvent{c, {kEvState | now[0], now[1], now[2], 0, 0, 0}});
      state = now;
    }
    auto req = [&](uint64_t kind, uint64_t seq = 0, uint64_t reason = 0) {
      r.events.push_back(BlockEvent{c, {kEvReq | kind | seq << 8 | reason << 16, 0, 0, 0, 0, 0}});
    };
    // Request kinds as the twin numbers them (frame_decoder.h kReq*).
    if (m->hello) req(0);
    if (m->status_req) req(1);
    if (m->nak) req(2, m->nak_seq, m->nak_reason);
    if (m->ack_req) req(3);
    if (m->fault_clear) req(4);
    if (m->cfg_wr)
      r.events.push_back(
          BlockEvent{c,
                     {kEvCfg | m->cfg_axis,
                      (m->cfg_data >> 48) | ((m->cfg_data >> 32) & 0xffff) << 16 |
                          ((m->cfg_data >> 16) & 0xffff) << 32 | (m->cfg_data & 0xffff) << 48,
                      0, 0, 0, 0}});
    if (m->v1_packet) r.events.push_back(BlockEvent{c, {kEvV1, 0, 0, 0, 0, 0}});
    pend[0] = m->frame_ok;
    pend[1] = m->crc_error;
    pend[2] = m->length_error;
    pend[3] = m->unknown_type;
    pend[4] = m->timeout;
    pend[5] = m->v1_overrun;
    pend[6] = m->noise;
  }
  m->final();
  return r;
}

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
template <class W>
unsigned __int128 get_bits(const W& w, int lsb, int width) {
  unsigned __int128 v = 0;
  for (int b = 0; b < width; ++b)
    if ((w[(lsb + b) / 32] >> ((lsb + b) % 32)) & 1u) v |= static_cast<unsigned __int128>(1) << b;
  return v;
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
      // The entry as spec/protocol.toml [entry] lays it out (fpgacnc/spec.h): steps, then fields.
      const PrepCommand& p = j.commands[k];
      for (int w = 0; w < (kEntryBits + 31) / 32; ++w) m->s_axis_tdata[w] = 0;
      for (int a = 0; a < kAxes; ++a) m->s_axis_tdata[a] = p.steps[a];
      const int o = spec::kEntryStepsPerAxis * kAxes;
      auto field = [&](spec::EntryField f, uint64_t v) {
        put_bits(m->s_axis_tdata, o + f.lsb, v, f.width);
      };
      field(spec::kEntryT, p.t);
      field(spec::kEntryPower, p.power);
      field(spec::kEntryCode, p.code & 3u);
      field(spec::kEntryKind, p.kind & 3u);
      field(spec::kEntryV2, p.v2 ? 1 : 0);
      if (p.arc) {  // payload bytes 2..62, byte 2 in the top bits
        field(spec::kEntryArc, 1);
        constexpr int kRaw = static_cast<int>(spec::kArcRawBytes);
        for (int b = 0; b < kRaw; ++b)
          put_bits(m->s_axis_tdata, o + spec::kEntryArcRaw.lsb + 8 * (kRaw - 1 - b),
                   p.arc_raw[static_cast<size_t>(b)], 8);
      }
      if (p.prof) {
        field(spec::kEntryProf, 1);
        field(spec::kEntryVEntry, p.profile.v_entry);
        field(spec::kEntryVCruise, p.profile.v_cruise);
        field(spec::kEntryVExit, p.profile.v_exit);
        field(spec::kEntryDecelAt, p.profile.decel_at);
      }
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
      if (m->m_axis_kind == 1) {
        ProfilePrepared pp{};
        pp.u1 = m->m_axis_prof_u1;
        pp.v1 = m->m_axis_prof_v1;
        pp.op1 = m->m_axis_prof_op1;
        pp.vcma = m->m_axis_prof_vcma;
        pp.vxpa = m->m_axis_prof_vxpa;
        pp.n_dom = m->m_axis_prof_n_dom;
        for (int a = 0; a < kAxes; ++a) {
          pp.v0[a] = get_bits(m->m_axis_prof_v0, 71 * a, 71);
          pp.vc[a] = get_bits(m->m_axis_prof_vc, 71 * a, 71);
          pp.vx[a] = get_bits(m->m_axis_prof_vx, 71 * a, 71);
          pp.acc[a] = static_cast<uint64_t>(get_bits(m->m_axis_prof_acc, 56 * a, 56));
        }
        const ProfileParams pr{0, m->m_axis_prof_vcruise, m->m_axis_prof_vexit,
                               m->m_axis_prof_accel, m->m_axis_prof_decel_at};
        profile_events(r.events, c, pp, pr);
      }
      if (m->m_axis_kind == 2) wide_events(r.events, c, 2, bits_of(m->m_axis_arc, kArcBits).w);
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

BlockRun rtl_encoder(const EncoderJob& j) {
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vresponse_encoder>(ctx.get(), "response_encoder");
  m->m_axis_tready = 0;
  reset(*m);
  BlockRun r;
  size_t next = 0, k = 0;
  Cycle ready_from = 0, quiet = 0;
  const Cycle last = j.strobes.empty() ? 0 : j.strobes.back().edge;
  for (Cycle c = 1;; ++c) {
    // Inputs for edge c: strobes high after edge c - 1, live values after edge c - 1.
    m->ident_req = m->status_req = m->nak_req = m->ack_req = m->done_evt = m->v1_ack = 0;
    while (next < j.strobes.size() && j.strobes[next].edge < c - 1) ++next;
    for (size_t i = next; i < j.strobes.size() && j.strobes[i].edge == c - 1; ++i) {
      const auto& s = j.strobes[i];
      if (s.kind == 0) m->ident_req = 1;
      if (s.kind == 1) m->status_req = 1;
      if (s.kind == 2) {
        m->nak_req = 1;
        m->nak_seq = s.seq;
        m->nak_reason = s.reason;
      }
      if (s.kind == 3) m->ack_req = 1;
      if (s.kind == 5) m->done_evt = 1;
      if (s.kind == 6) m->v1_ack = 1;
    }
    const auto& l = j.live_after(c - 1);
    m->next_seq = l.next_seq;
    m->fifo_level = l.level;
    m->fifo_free = static_cast<uint16_t>(64 - l.level);
    m->segments_done = j.done_after(c - 1);
    m->state = l.state;
    m->faults = (l.state >> 2) & 1;
    for (int a = 0; a < kAxes; ++a) m->position[a] = static_cast<uint32_t>(l.position[a]);
    // counters[143:128] is the first (frames ok): word 4 bits 31:16
    for (int w = 0; w < 5; ++w) m->counters[w] = 0;
    for (int i = 0; i < 9; ++i) {
      const int bit = 16 * (8 - i);
      m->counters[bit / 32] |= static_cast<uint32_t>(l.counters[i]) << (bit % 32);
    }
    m->m_axis_tready = c >= ready_from ? 1 : 0;
    m->eval();
    const bool take = m->m_axis_tvalid && m->m_axis_tready;
    const uint8_t byte = m->m_axis_tdata;
    clock_once(*m);
    if (take) {
      r.events.push_back(BlockEvent{c, {byte, 0, 0, 0, 0, 0}});
      ready_from = c + (k < j.busy.size() ? j.busy[k] : 1);
      ++k;
    }
    if (c > last + 2 && !m->m_axis_tvalid) {
      if (++quiet > 200) break;
    } else {
      quiet = 0;
    }
  }
  m->final();
  return r;
}

}  // namespace fpgacnc::twins
