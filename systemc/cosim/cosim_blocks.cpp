// Block-level co-simulation of uart_rx (115 200 and 3 000 000 baud), uart_tx (3 Mbaud),
// packet_decoder_v1 and segment_prep against their twins (CTest label cosim). Each block is
// driven alone with random seeded stimulus (random gaps, back-to-back frames and offers, random
// downstream stalls, watchdog pauses, random numerators, steps, feeds and minimum periods, an
// executor busy for a while after each segment so that init commands wait); the
// RTL side is the Verilated C++ block models of tb/ (cosim_blocks_rtl.cpp), the twins run here
// in SystemC with the bench as their neighbours. Every output event (edge and values) and the
// tx edges must be identical; the first difference is reported with its cycle. One GoogleTest per
// block: the twins of the blocks whose tests run are simulated once (SystemC elaborates once a
// process), then each test runs its block's RTL jobs and compares. Options after GoogleTest's:
// --seed, --seeds.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <systemc>

#include "arc_stimulus.h"
#include "cosim_args.h"

#include "blocks_job.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/twins/frame_decoder.h"
#include "fpgacnc/twins/response_encoder.h"
#include "fpgacnc/twins/segment_prep.h"
#include "fpgacnc/twins/uart_rx.h"
#include "fpgacnc/twins/uart_tx.h"
#include "fpgacnc/twins/v2_frames.h"

using namespace fpgacnc::twins;
namespace arc = fpgacnc::models::arc;
namespace spec = fpgacnc::spec;

namespace {

uint32_t pick(std::mt19937_64& g, uint32_t lo, uint32_t hi) {
  return std::uniform_int_distribution<uint32_t>(lo, hi)(g);
}

// The whole FIFO entry as frame_decoder.v lays it out (blocks_job.h kEntryBits).
Bits entry_bits(const FifoEntry& e) {
  Bits b(kEntryBits);
  for (int a = 0; a < kAxes; ++a) b.put(32 * a, e.steps[static_cast<size_t>(a)], 32);
  const int o = spec::kEntryStepsPerAxis * kAxes;
  auto field = [&](spec::EntryField f, uint64_t v) { b.put(o + f.lsb, v, f.width); };
  field(spec::kEntryT, e.t);
  field(spec::kEntryPower, e.power);
  field(spec::kEntryCode, e.code);
  field(spec::kEntryKind, e.kind);
  field(spec::kEntryV2, e.v2);
  field(spec::kEntryProf, e.prof);
  field(spec::kEntryVEntry, e.v_entry);
  field(spec::kEntryVCruise, e.v_cruise);
  field(spec::kEntryVExit, e.v_exit);
  field(spec::kEntryDecelAt, e.decel_at);
  field(spec::kEntryArc, e.arc);
  // arc_raw: payload byte 2 in the top byte
  constexpr int kRaw = static_cast<int>(spec::kArcRawBytes);
  for (int k = 0; k < kRaw; ++k)
    b.put(o + spec::kEntryArcRaw.lsb + 8 * (kRaw - 1 - k), e.arc_raw[static_cast<size_t>(k)], 8);
  return b;
}

// segment_prep's m_axis_arc for an ARC segment, from the twin's frame (arc_stimulus.h).
Bits arc_bits(const arc::Frame& f) {
  Bits b(kArcBits);
  put_arc_load(f, [&b](int lsb, unsigned __int128 v, int w) { b.put(lsb, v, w); });
  return b;
}

// Random ARC fields within the frame rules (docs/protocol.md "ARC"); `bad` in 1..17 breaks one
// rule (BAD_FIELD), 0 keeps them all. Geometry is not walked: the decoder and prep only check and
// derive. Returns the flags byte.
uint8_t random_arc(std::mt19937_64& g, arc::Frame& f, uint32_t bad) {
  const int32_t lim = (1 << 22) - 1;
  auto coord = [&]() -> int32_t {
    const uint32_t k = pick(g, 0, 9);
    const int32_t m = k == 0  ? lim
                      : k < 3 ? static_cast<int32_t>(pick(g, 0, lim))
                              : static_cast<int32_t>(pick(g, 0, 5000));
    return pick(g, 0, 1) ? -m : m;
  };
  do {
    f.g.i = coord();
    f.g.j = coord();
  } while (f.g.i == 0 && f.g.j == 0);
  int32_t x1, y1;
  do {
    x1 = coord();
    y1 = coord();
  } while (x1 == 0 && y1 == 0);
  f.g.dx = x1 + f.g.i;
  f.g.dy = y1 + f.g.j;
  auto u64 = [&](uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(0, hi)(g) >> pick(g, 0, 50);
  };
  f.dz = pick(g, 0, 2) == 0 ? 0 : static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)) >> pick(g, 0, 31);
  if (f.dz == INT32_MIN) f.dz = INT32_MIN + 1;
  f.n_ramp = pick(g, 1, (1u << 24) - 1) >> pick(g, 0, 23);
  if (f.n_ramp == 0) f.n_ramp = 1;
  f.c_total = std::max<uint64_t>(1, u64((1ull << 46) - 1));
  f.v_cruise = pick(g, 0, 9) == 0 ? (1ull << 63) - 1 : u64((1ull << 63) - 1);
  f.v_entry = pick(g, 0, 3) == 0 ? f.v_cruise : u64(f.v_cruise);
  f.v_exit = std::max<uint64_t>(1, pick(g, 0, 3) == 0 ? f.v_cruise : u64(f.v_cruise));
  f.v_cruise = std::max(f.v_cruise, f.v_exit);
  f.a = u64((1ull << 48) - 1);
  if (f.a == 0 && f.v_entry == 0) f.a = 1;
  f.d = u64((1ull << 48) - 1);
  uint8_t flags = static_cast<uint8_t>(pick(g, 2, 3));
  switch (bad) {
    case 1:
      flags = static_cast<uint8_t>(pick(g, 0, 1));
      break;
    case 2:
      flags = static_cast<uint8_t>(flags | 4u << pick(g, 0, 5));
      break;
    case 3:
      f.g.i = f.g.j = 0;
      break;
    case 4:
      f.g.dx = f.g.i;
      f.g.dy = f.g.j;
      break;
    case 5:
      f.g.i = pick(g, 0, 1) ? 1 << 22 : -(1 << 22);
      break;
    case 6:
      f.g.j = pick(g, 0, 1) ? 1 << 22 : -(1 << 22);
      break;
    case 7:
      f.g.dx = f.g.i + (pick(g, 0, 1) ? 1 << 22 : -(1 << 22));
      break;
    case 8:
      f.g.dy = f.g.j + (pick(g, 0, 1) ? 1 << 22 : -(1 << 22));
      break;
    case 9:
      f.dz = INT32_MIN;
      break;
    case 10:
      f.n_ramp = 0;
      break;
    case 11:
      f.c_total = 0;
      break;
    case 12:
      f.c_total = (1ull << 46) | u64((1ull << 48) - 1);
      break;
    case 13:
      f.v_cruise |= 1ull << 63;
      break;
    case 14:
      f.v_entry = f.v_cruise + 1 + u64(~0ull - f.v_cruise - 1);
      break;
    case 15:
      f.v_exit = f.v_cruise + 1 + u64(~0ull - f.v_cruise - 1);
      break;
    case 16:
      f.v_exit = 0;
      break;
    case 17:
      f.a = 0;
      f.v_entry = 0;
      break;
    default:
      break;
  }
  f.g.ccw = (flags & 1) != 0;
  return flags;
}

CoreParams params(uint64_t baud) {
  CoreParams p;
  p.baud = baud;
  return p;
}

SC_MODULE(BlockBench) {
  CycleClock clk{50'000'000};
  CoreParams p115 = params(115'200), p3m = params(3'000'000), pprep;
  PinRecorder pins;
  UartRxTwin rx115, rx3m;
  UartTxTwin tx;
  FrameDecoderTwin dec;
  ResponseEncoderTwin enc;
  tlm_utils::simple_initiator_socket<BlockBench> to_enc_req, to_enc_done, to_enc_applied;
  tlm_utils::simple_target_socket<BlockBench> enc_tx, enc_state;
  const EncoderJob* enc_job = nullptr;
  Cycle enc_ready = 0;
  size_t enc_k = 0;
  SegmentPrepTwin prep;
  tlm_utils::simple_initiator_socket<BlockBench> to_rx115, to_rx3m, to_tx, to_dec, to_prep;
  tlm_utils::simple_target_socket<BlockBench> from_rx115, from_rx3m, from_tx, from_prep,
      prep_status, prep_applied, dec_fifo, dec_resp, dec_cfg;
  const FrameJob* frame_job = nullptr;
  tlm::tlm_generic_payload gp;
  BlockRun* out = nullptr;
  const std::vector<int64_t>* delays = nullptr;
  const std::vector<int64_t>* busy = nullptr;
  size_t delay_index = 0;
  Cycle exec_idle_after = -1;
  uint64_t arc_fifo_writes = 0;  // ARC entries the decoder twin wrote
  std::function<void()> body;

  SC_CTOR(BlockBench)
      : rx115("uart_rx_115200", clk, p115),
        rx3m("uart_rx_3000000", clk, p3m),
        tx("uart_tx", clk, p3m, pins),
        dec("frame_decoder", clk, p115),
        enc("response_encoder", clk, EncoderParams{}),
        prep("segment_prep", clk, pprep) {
    prep.report_applied = true;
    pins.record_tx = true;
    to_rx115.bind(rx115.pin);
    to_rx3m.bind(rx3m.pin);
    to_tx.bind(tx.bytes);
    to_dec.bind(dec.bytes);
    to_prep.bind(prep.commands);
    rx115.bytes.bind(from_rx115);
    rx3m.bytes.bind(from_rx3m);
    tx.line.bind(from_tx);
    dec.fifo.bind(dec_fifo);
    to_enc_req.bind(enc.req);
    to_enc_done.bind(enc.done);
    to_enc_applied.bind(enc.applied);
    enc.tx.bind(enc_tx);
    enc.state.bind(enc_state);
    enc_tx.register_b_transport(this, &BlockBench::on_enc_tx);
    enc_state.register_b_transport(this, &BlockBench::on_enc_state);
    dec.resp.bind(dec_resp);
    dec.cfg.bind(dec_cfg);
    prep.segments.bind(from_prep);
    prep.exec_status.bind(prep_status);
    prep.applied.bind(prep_applied);
    prep_applied.register_b_transport(this, &BlockBench::on_applied);
    from_rx115.register_b_transport(this, &BlockBench::on_byte);
    from_rx3m.register_b_transport(this, &BlockBench::on_byte);
    from_tx.register_b_transport(this, &BlockBench::on_ok);
    dec_fifo.register_b_transport(this, &BlockBench::on_fifo);
    dec_resp.register_b_transport(this, &BlockBench::on_resp);
    dec_cfg.register_b_transport(this, &BlockBench::on_cfg);
    from_prep.register_b_transport(this, &BlockBench::on_segment);
    prep_status.register_b_transport(this, &BlockBench::on_status);
    SC_THREAD(run);
  }

  void start_job() {
    wait(sc_core::sc_time(1, sc_core::SC_US));
    const uint64_t per = clk.period_ps(), now = sc_core::sc_time_stamp().value();
    clk.set_base(sc_core::sc_time::from_value((now + per - 1) / per * per));
    pins.clear();
    delay_index = 0;
    exec_idle_after = -1;
  }
  int64_t next_delay() {
    return delays && delay_index < delays->size() ? (*delays)[delay_index++] : 0;
  }
  void on_ok(tlm::tlm_generic_payload & g, sc_core::sc_time&) {
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_byte(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    out->events.push_back(BlockEvent{clk.at(d), {payload<RxByte>(g).byte, 0, 0, 0}});
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_fifo(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const Cycle c = clk.at(d);
    if (g.is_read()) {
      payload<FifoLevel>(g).level = frame_job->full_at(c) ? v2::kFifoDepth : 0;
    } else {
      const FifoEntry& e = payload<FifoEntry>(g);
      arc_fifo_writes += e.arc;
      out->events.push_back(
          BlockEvent{c,
                     {kEvWrite | (e.v2 ? 1u << 12 : 0u) | static_cast<uint64_t>(e.kind) << 10 |
                          static_cast<uint64_t>(e.code) << 8 | e.power,
                      e.t, e.steps[0] | static_cast<uint64_t>(e.steps[1]) << 32,
                      e.steps[2] | static_cast<uint64_t>(e.steps[3]) << 32, 0, 0}});
      wide_events(out->events, c, 1, entry_bits(e).slice(kEntryLow, kEntryBits - kEntryLow));
    }
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  // The transmitter of an EncoderJob: takes a byte when ready, busy `busy[k]` edges after.
  void on_enc_tx(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const Cycle a = std::max(clk.at(d), enc_ready);
    out->events.push_back(BlockEvent{a, {payload<TxByte>(g).byte, 0, 0, 0, 0, 0}});
    enc_ready = a + (enc_k < enc_job->busy.size() ? enc_job->busy[enc_k] : 1);
    ++enc_k;
    d = clk.delay_to(a);
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  // The live inputs as they are after edge d - 1 (the encoder snapshots on d).
  void on_enc_state(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const auto& l = enc_job->live_after(clk.at(d) - 1);
    StatusSnapshot s{};
    s.dec.next_seq = l.next_seq;
    s.dec.v2_mode = (l.state >> 1) & 1;
    s.busy = l.state & 1;
    s.fault = (l.state >> 2) & 1;
    s.fifo_level = l.level;
    s.position = l.position;
    const auto& k = l.counters;
    s.dec.frames_ok = k[0];
    s.dec.crc_errors = k[1];
    s.dec.length_errors = k[2];
    s.dec.unknown_types = k[3];
    s.dec.timeouts = k[4];
    s.frame_errors = k[5];
    s.dec.overruns = k[6];
    s.dec.noise = k[7];
    s.clamped = k[8];
    payload<StatusSnapshot>(g) = s;
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_resp(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const RespReq& r = payload<RespReq>(g);
    out->events.push_back(BlockEvent{clk.at(d),
                                     {kEvReq | r.kind | static_cast<uint64_t>(r.seq) << 8 |
                                          static_cast<uint64_t>(r.reason) << 16,
                                      0, 0, 0, 0, 0}});
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_cfg(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const CfgAxis& a = payload<CfgAxis>(g);
    out->events.push_back(BlockEvent{clk.at(d),
                                     {kEvCfg | a.axis,
                                      a.timing.high | static_cast<uint64_t>(a.timing.low) << 16 |
                                          static_cast<uint64_t>(a.timing.setup) << 32 |
                                          static_cast<uint64_t>(a.timing.hold) << 48,
                                      0, 0, 0, 0}});
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_segment(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const Segment& s = payload<Segment>(g);
    const Cycle v = clk.at(d);
    uint64_t dir = 0;
    for (int a = 0; a < kAxes; ++a) dir |= s.dir[a] ? 1u << a : 0u;
    out->events.push_back(
        BlockEvent{v,
                   {s.period | static_cast<uint64_t>(s.code) << 32 | dir << 40 |
                        static_cast<uint64_t>(s.dir_fast) << 44 |
                        static_cast<uint64_t>(s.v2) << 45 | static_cast<uint64_t>(s.power) << 48,
                    s.total, s.steps[0] | static_cast<uint64_t>(s.steps[1]) << 32,
                    s.steps[2] | static_cast<uint64_t>(s.steps[3]) << 32, s.tmn[0], s.tmn[3]}});
    if (s.prof) {  // the RTL's products and first master update, as the executor twin derives them
      ProfileParams pr = s.profile;
      pr.v_entry = 0;  // (not an m_axis port: it is U(1))
      profile_events(out->events, v, prepare_profile(s.profile, s.steps), pr);
    }
    if (s.arc) wide_events(out->events, v, 2, arc_bits(s.arc_frame).w);
    // The executor takes it `accept_delay` edges late and is busy `busy` edges after that.
    const size_t j = delay_index;
    const Cycle accept = v + 1 + next_delay();
    exec_idle_after = accept + (busy && j < busy->size() ? (*busy)[j] : 0);
    d = clk.delay_to(accept);
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_applied(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    out->events.push_back(
        BlockEvent{clk.at(d), {1ull << 62 | (payload<Applied>(g).v2 ? 1u : 0u), 0, 0, 0}});
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_status(tlm::tlm_generic_payload & g, sc_core::sc_time&) {
    payload<ExecIdle>(g).edge = exec_idle_after;
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void run() {
    body();
  }
};

// Events of a twin run come in call order; accepts and outputs of the prep interleave in time,
// so both sides' lists are compared sorted by (cycle, values).
void sort_events(BlockRun& r) {
  std::stable_sort(r.events.begin(), r.events.end(), [](const BlockEvent& a, const BlockEvent& b) {
    return a.cycle != b.cycle ? a.cycle < b.cycle : a.v < b.v;
  });
}

std::string compare(BlockRun a, BlockRun b) {
  sort_events(a);
  sort_events(b);
  const size_t n = std::min(a.events.size(), b.events.size());
  for (size_t i = 0; i < n; ++i)
    if (!(a.events[i] == b.events[i]))
      return fmt::format(
          "event #{}: rtl cycle {} ({:x} {:x} {:x} {:x}), twin cycle {} ({:x} {:x} "
          "{:x} {:x})",
          i, a.events[i].cycle, a.events[i].v[0], a.events[i].v[1], a.events[i].v[2],
          a.events[i].v[3], b.events[i].cycle, b.events[i].v[0], b.events[i].v[1], b.events[i].v[2],
          b.events[i].v[3]);
  if (a.events.size() != b.events.size())
    return fmt::format("events: rtl {}, twin {}; first extra at cycle {}", a.events.size(),
                       b.events.size(),
                       a.events.size() > n ? a.events[n].cycle : b.events[n].cycle);
  const size_t m = std::min(a.edges.size(), b.edges.size());
  for (size_t i = 0; i < m; ++i)
    if (a.edges[i].cycle != b.edges[i].cycle || a.edges[i].value != b.edges[i].value)
      return fmt::format("tx edge #{}: rtl cycle {} -> {}, twin cycle {} -> {}", i,
                         a.edges[i].cycle, a.edges[i].value, b.edges[i].cycle, b.edges[i].value);
  if (a.edges.size() != b.edges.size())
    return fmt::format("tx edges: rtl {}, twin {}", a.edges.size(), b.edges.size());
  if (a.counters != b.counters)
    return fmt::format("counters: rtl {} {}, twin {} {}", a.counters[0], a.counters[1],
                       b.counters[0], b.counters[1]);
  return "";
}

UartRxJob rx_job(std::mt19937_64& g, uint64_t baud, size_t n) {
  UartRxJob j{baud, {}};
  const SenderTiming st{50'000'000, baud};
  Cycle t = 1 + pick(g, 0, 50);
  for (size_t i = 0; i < n; ++i) {
    j.frames.push_back({t, static_cast<uint8_t>(pick(g, 0, 255))});
    t += st.frame() + (pick(g, 0, 1) ? 0 : pick(g, 0, 3 * static_cast<uint32_t>(st.frame())));
  }
  return j;
}

UartTxJob tx_job(std::mt19937_64& g, size_t n) {
  UartTxJob j;
  for (size_t i = 0; i < n; ++i)
    j.offers.push_back(
        {static_cast<uint8_t>(pick(g, 0, 255)), pick(g, 0, 2) ? pick(g, 1, 200) : pick(g, 1, 400)});
  return j;
}

// A byte stream for frame_decoder: v1 packets (motion codes 0..3, inits), v2 frames of every
// type (good ones, SEQ in order, duplicated and ahead; reserved types, wrong lengths, reserved
// flag bits, axis >= N_AXES, a corrupted CRC, LEN > 64), noise, packets and frames cut short
// followed by a pause at the watchdog limit (5 000 000 +- 10 clocks), bytes back to back or with
// random gaps; the FIFO full in random intervals (v1 overruns, NAK FIFO_FULL).
FrameJob frame_job(std::mt19937_64& g, size_t packets) {
  using namespace fpgacnc::twins::v2;
  FrameJob j;
  Cycle t = pick(g, 1, 20);
  uint8_t seq = 0;
  auto put = [&](const std::vector<uint8_t>& b, bool cut) {
    size_t len = b.size();
    if (cut) len = pick(g, 1, static_cast<uint32_t>(len) - 1);
    for (size_t k = 0; k < len; ++k) {
      j.bytes.push_back({t, b[k]});
      const uint32_t kind = pick(g, 0, 999);
      t += kind < 900   ? pick(g, 1, 40)
           : kind < 999 ? pick(g, 40, 2000)
                        : pick(g, 4'999'990, 5'000'010);
    }
    if (cut) t += 5'000'001;
  };
  for (size_t i = 0; i < packets; ++i) {
    const uint32_t what = pick(g, 0, 39);
    const bool cut = pick(g, 0, 60) == 0;
    std::vector<uint8_t> b;
    if (what < 4) {  // v1 (noise in v2 mode)
      const auto init =
          fpgacnc::protocol::v1::pack_init(pick(g, 0, 0xFFFF'FFFFu), pick(g, 0, 0xFFFF'FFFFu));
      const auto mot = fpgacnc::protocol::v1::pack_motion(
          static_cast<uint8_t>(pick(g, 0, 3)), static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)),
          static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)), static_cast<uint16_t>(pick(g, 0, 65535)));
      b = what == 0 ? std::vector<uint8_t>(init.begin(), init.end())
                    : std::vector<uint8_t>(mot.begin(), mot.end());
    } else if (what == 4) {  // noise
      for (uint32_t k = pick(g, 1, 4); k > 0; --k)
        b.push_back(static_cast<uint8_t>(pick(g, 0, 255)));
    } else {
      const uint32_t sk = pick(g, 0, 19);
      const uint8_t s = sk < 15   ? seq
                        : sk < 18 ? static_cast<uint8_t>(seq - pick(g, 1, 130))
                                  : static_cast<uint8_t>(seq + pick(g, 1, 126));
      const uint32_t ty = pick(g, 0, 35);
      std::vector<uint8_t> p;
      uint8_t type;
      if (ty < 12) {
        type = kLine;
        const int k = static_cast<int>(pick(g, 0, 4));
        std::vector<int32_t> st(static_cast<size_t>(k));
        for (auto& x : st) x = static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)) >> pick(g, 0, 31);
        bool fits = true;
        for (int32_t x : st) fits = fits && x >= -32768 && x <= 32767;
        p = line_payload(static_cast<uint8_t>(pick(g, 0, 3)), static_cast<uint8_t>(pick(g, 0, 255)),
                         pick(g, 0, 0xFFFF'FFFFu), st, fits && pick(g, 0, 1));
        if (pick(g, 0, 15) == 0) p[0] |= static_cast<uint8_t>(4u << pick(g, 0, 4));  // reserved bit
      } else if (ty < 15) {
        type = kDwell;
        p = dwell_payload(pick(g, 0, 0xFFFF'FFFFu));
      } else if (ty < 17) {
        type = kNumerators;
        p = numerators_payload(pick(g, 0, 0xFFFF'FFFFu), pick(g, 0, 0xFFFF'FFFFu));
      } else if (ty < 19) {
        type = kConfigAxis;
        p = config_axis_payload(
            static_cast<uint8_t>(pick(g, 0, 5)),
            AxisTiming{pick(g, 0, 65535), pick(g, 0, 65535), pick(g, 0, 65535), pick(g, 0, 65535)});
      } else if (ty < 21) {  // CONFIG_TRAVEL: soft limits the LINE / ARC frames then meet
        type = kConfigTravel;
        const auto lim = [&] {
          return static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)) >> pick(g, 0, 31);
        };
        int32_t lo = lim(), hi = lim();
        if (lo > hi && pick(g, 0, 7) != 0) std::swap(lo, hi);  // MIN > MAX: BAD_FIELD if on
        const uint32_t fk = pick(g, 0, 15);
        const uint8_t flags = fk < 11 ? 1 : fk < 15 ? 0 : static_cast<uint8_t>(pick(g, 2, 255));
        p = {static_cast<uint8_t>(pick(g, 0, 5)), flags};
        put32(p, static_cast<uint32_t>(lo));
        put32(p, static_cast<uint32_t>(hi));
      } else if (ty == 29) {  // OUTPUT: good, or random bytes (BAD_FIELD mostly)
        type = kOutput;
        if (pick(g, 0, 3) == 0) {
          p = {static_cast<uint8_t>(pick(g, 0, 255)), static_cast<uint8_t>(pick(g, 0, 255)),
               static_cast<uint8_t>(pick(g, 0, 255))};
        } else {
          const auto mask = static_cast<uint8_t>(pick(g, 1, 0x7F));
          p = {mask, static_cast<uint8_t>(pick(g, 0, 0x7F) & mask & ~0x04u),
               static_cast<uint8_t>((mask & 0x04) ? pick(g, 0, 255) : 0)};
        }
      } else if (ty >= 30) {  // ARC: good, or one field rule broken (BAD_FIELD)
        type = kArc;
        arc::Frame f;
        const uint8_t flags = random_arc(g, f, pick(g, 0, 1) ? 0 : pick(g, 1, 17));
        p = arc_payload(flags, static_cast<uint8_t>(pick(g, 0, 255)), f);
      } else {
        // 0x14 is an unknown type (0x13 is ARC, above)
        const uint8_t types[] = {kHello, kStatusQuery, kFaultClear, kRelease, 0x12,
                                 0x14,   0x25,         0x2F,        0x08,     0x83};
        type = types[pick(g, 0, 9)];
      }
      if (pick(g, 0, 19) == 0) p.resize(pick(g, 0, 20));  // wrong length for the type
      b = frame(s, type, p);
      if (pick(g, 0, 24) == 0)
        b[pick(g, 2, static_cast<uint32_t>(b.size()) - 1)] ^=
            static_cast<uint8_t>(1u << pick(g, 0, 7));
      if (pick(g, 0, 40) == 0) b = {kSync, static_cast<uint8_t>(pick(g, 65, 255))};  // LEN > 64
      if (sk < 15) ++seq;  // (the decoder's next_seq may lag: rejected frames)
    }
    put(b, cut && b.size() > 1);
  }
  for (int k = 0; k < 6; ++k) {
    const Cycle a = pick(g, 0, static_cast<uint32_t>(std::min<Cycle>(t, 0xFFFF'FFFF)));
    j.full.push_back({a, a + pick(g, 0, 3000)});
  }
  return j;
}

// Soft limits (docs/machine.md): CONFIG_TRAVEL frames (random travels, on or off, changed now and
// then) and LINE frames (int16 or int32 steps on 0..4 axes) whose ends fall inside and outside
// them, every frame with the SEQ the decoder expects (the job follows which frames a device
// accepts: a refused LINE, NAK TRAVEL, leaves next_seq); bytes back to back or with random gaps;
// the FIFO never full (NAK FIFO_FULL would leave next_seq too).
FrameJob travel_job(std::mt19937_64& g, size_t lines) {
  using namespace fpgacnc::twins::v2;
  FrameJob j;
  Cycle t = pick(g, 1, 20);
  uint8_t seq = 0;
  struct Tr {
    bool on = false;
    int32_t lo = 0, hi = 0;
  };
  std::array<Tr, kAxes> tr{};
  std::array<int32_t, kAxes> queued{};
  auto put = [&](const std::vector<uint8_t>& b) {
    for (uint8_t x : b) {
      j.bytes.push_back({t, x});
      t += pick(g, 0, 3) ? pick(g, 1, 3) : pick(g, 4, 200);
    }
  };
  auto config = [&](int a) {
    const auto v = [&] {
      return static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)) >> pick(g, 14, 30);
    };
    Tr x{pick(g, 0, 4) != 0, v(), v()};
    if (x.lo > x.hi) std::swap(x.lo, x.hi);
    std::vector<uint8_t> p{static_cast<uint8_t>(a), static_cast<uint8_t>(x.on ? 1 : 0)};
    put32(p, static_cast<uint32_t>(x.lo));
    put32(p, static_cast<uint32_t>(x.hi));
    put(frame(seq++, kConfigTravel, p));
    tr[static_cast<size_t>(a)] = x;
  };
  for (int a = 0; a < kAxes; ++a) config(a);
  for (size_t i = 0; i < lines; ++i) {
    if (pick(g, 0, 15) == 0) config(static_cast<int>(pick(g, 0, kAxes - 1)));
    const int k = static_cast<int>(pick(g, 0, kAxes));
    std::vector<int32_t> st(static_cast<size_t>(k));
    bool fits = true, inside = true;
    for (size_t a = 0; a < st.size(); ++a) {
      st[a] = static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu)) >> pick(g, 14, 31);
      fits = fits && st[a] >= -32768 && st[a] <= 32767;
    }
    for (size_t a = 0; a < kAxes; ++a) {
      const int64_t end = int64_t{queued[a]} + (a < st.size() ? st[a] : 0);
      if (tr[a].on && (end < tr[a].lo || end > tr[a].hi)) inside = false;
    }
    put(frame(seq, kLine,
              line_payload(static_cast<uint8_t>(pick(g, 0, 3)), 0, pick(g, 0, 100'000), st,
                           fits && pick(g, 0, 1))));
    if (!inside) continue;  // NAK TRAVEL: next_seq stays
    ++seq;
    for (size_t a = 0; a < st.size(); ++a)
      queued[a] =
          static_cast<int32_t>(static_cast<uint32_t>(queued[a]) + static_cast<uint32_t>(st[a]));
  }
  return j;
}

// Request strobes in bursts (several kinds on one edge, on consecutive edges, while a frame is
// going out) and alone; NAKs replacing pending NAKs; v1 0xAA among frames; live inputs changing
// between and during frames; a transmitter ready again 1..40 edges after a byte.
EncoderJob encoder_job(std::mt19937_64& g, size_t n) {
  EncoderJob j;
  auto live = [&](Cycle e) {
    EncoderJob::Live l{};
    l.edge = e;
    l.next_seq = static_cast<uint8_t>(pick(g, 0, 255));
    l.state = static_cast<uint8_t>(pick(g, 0, 7));
    l.level = static_cast<uint16_t>(pick(g, 0, 64));
    for (auto& p : l.position) p = static_cast<int32_t>(pick(g, 0, 0xFFFF'FFFFu));
    for (auto& k : l.counters) k = static_cast<uint16_t>(pick(g, 0, 65535));
    return l;
  };
  j.live.push_back(live(0));
  Cycle t = pick(g, 1, 50);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t burst = pick(g, 0, 3) == 0 ? pick(g, 2, 6) : 1;
    for (uint32_t b = 0; b < burst; ++b) {
      const uint32_t w = pick(g, 0, 19);
      const uint8_t kind = w < 2 ? 0 : w < 4 ? 1 : w < 8 ? 2 : w < 12 ? 3 : w < 17 ? 5 : 6;
      bool dup = false;
      for (const auto& s : j.strobes) dup = dup || (s.edge == t && s.kind == kind);
      if (!dup)
        j.strobes.push_back(EncoderJob::Strobe{t, kind, static_cast<uint8_t>(pick(g, 0, 255)),
                                               static_cast<uint8_t>(pick(g, 1, 7))});
      if (pick(g, 0, 1)) ++t;
    }
    if (pick(g, 0, 2) == 0) j.live.push_back(live(t + pick(g, 0, 100)));
    t += pick(g, 0, 3) == 0 ? pick(g, 1, 5) : pick(g, 1, 3000);
    std::sort(j.live.begin(), j.live.end(),
              [](const auto& a, const auto& b) { return a.edge < b.edge; });
  }
  for (size_t i = 0; i < 40 * n; ++i) j.busy.push_back(pick(g, 1, 40));
  return j;
}

// Every kind of FIFO entry: v1 motion (steps up to 2^32 - 1, feed 0), v2 LINE (four signed axes,
// T from 0 to long, clamped or not), numerators (v1 and v2), dwells (T = 0 too), kind 3; random
// DIR setup/hold so that dir_fast goes both ways.
PrepJob prep_job(std::mt19937_64& g, size_t n) {
  PrepJob j;
  j.min_half = pick(g, 0, 3) == 0 ? pick(g, 1, 5000) : pick(g, 1, 100);
  for (int a = 0; a < kAxes; ++a) {
    j.setup[a] = static_cast<uint16_t>(pick(g, 0, 3) == 0 ? 0 : pick(g, 0, 3000));
    j.hold[a] = static_cast<uint16_t>(pick(g, 0, 3) == 0 ? 0 : pick(g, 0, 3000));
  }
  auto steps = [&]() -> uint32_t {
    const uint32_t k = pick(g, 0, 9);
    return k == 0 ? 0 : k < 8 ? pick(g, 0, 100'000) : pick(g, 0, 0xFFFF'FFFFu);
  };
  for (size_t i = 0; i < n; ++i) {
    PrepCommand c{};
    const uint32_t what = pick(g, 0, 15);
    c.v2 = pick(g, 0, 1) == 1;
    c.code = static_cast<uint8_t>(pick(g, 0, 3));
    c.power = static_cast<uint8_t>(pick(g, 0, 255));
    c.kind = what == 0 ? kEntryNumerators : what == 1 ? kEntryDwell : what == 2 ? 3 : kEntryMotion;
    if (c.kind == kEntryNumerators) {
      c.steps = {pick(g, 0, 0xFFFF'FFFFu), pick(g, 0, 0xFFFF'FFFFu), 0, 0};
    } else if (c.kind == kEntryMotion && !c.v2) {
      c.power = 0xFF;
      c.steps = {steps(), steps(), 0, 0};
      c.t = static_cast<uint16_t>(pick(g, 0, 9) == 0 ? 0 : pick(g, 1, 65535));
    } else {
      if (c.kind != kEntryMotion) c.v2 = true;
      for (auto& s : c.steps) {
        const uint32_t m = pick(g, 0, 2) == 0 ? 0 : pick(g, 0, 9) == 0 ? steps() : pick(g, 0, 5000);
        s = pick(g, 0, 1) ? 0u - (m & 0x7FFF'FFFFu) : (m & 0x7FFF'FFFFu);
      }
      const uint32_t tk = pick(g, 0, 7);
      c.t = tk == 0 ? 0 : tk < 3 ? pick(g, 0, 10'000) : pick(g, 0, 0xFFFF'FFFFu);
    }
    if (c.kind == kEntryMotion && pick(g, 0, 2) == 0) {  // LINE_PROFILE within the frame rules
      c.v2 = c.prof = true;
      bool moves = false;
      for (auto& s : c.steps) {
        const uint32_t m = pick(g, 0, 2) == 0   ? 0
                           : pick(g, 0, 4) == 0 ? pick(g, 1, (1u << 24) - 1)
                                                : pick(g, 1, 5000);
        moves = moves || m != 0;
        s = pick(g, 0, 1) ? 0u - m : m;
      }
      if (!moves) c.steps[pick(g, 0, kAxes - 1)] = pick(g, 0, 1) ? 1u : 0u - 1u;
      auto v48 = [&](uint64_t hi) {
        return std::uniform_int_distribution<uint64_t>(0, hi)(g) >> pick(g, 0, 40);
      };
      ProfileParams& pr = c.profile;
      pr.v_cruise = pick(g, 0, 9) == 0 ? (1ull << 47) - 1 : v48((1ull << 47) - 1);
      pr.v_entry = pick(g, 0, 3) == 0 ? pr.v_cruise : v48(pr.v_cruise);
      pr.v_exit = std::max<uint64_t>(1, pick(g, 0, 3) == 0 ? pr.v_cruise : v48(pr.v_cruise));
      pr.v_cruise = std::max(pr.v_cruise, pr.v_exit);
      c.t = pick(g, 0, 3) == 0 ? pick(g, 0, 0xFFFF'FFFFu) : pick(g, 0, 5000);
      if (c.t == 0 && pr.v_entry == 0) c.t = 1;
      pr.accel = c.t;
      pr.decel_at = pick(g, 0, 3) == 0 ? 0 : pick(g, 0, 0xFFFF'FFFFu) >> pick(g, 0, 31);
    }
    if (c.kind == kEntryMotion && !c.prof && pick(g, 0, 4) == 0) {  // ARC within the frame rules
      c.v2 = c.arc = true;
      c.t = 0;
      c.steps = {};
      arc::Frame f;
      c.code = random_arc(g, f, 0);
      const auto raw = v2::arc_payload(c.code, c.power, f);
      std::copy(raw.begin() + 2, raw.end(), c.arc_raw.begin());
    }
    c.gap = pick(g, 0, 1) ? 0 : pick(g, 0, 200);
    j.commands.push_back(c);
  }
  for (size_t i = 0; i < n; ++i) j.accept_delay.push_back(pick(g, 0, 1) ? 0 : pick(g, 0, 300));
  for (size_t i = 0; i < n; ++i) j.busy.push_back(pick(g, 0, 1) ? 0 : pick(g, 0, 3000));
  return j;
}

// The options (sc_main) and the kinds of block job, in the order of their tests.
uint64_t g_seed = 11, g_seeds = 10;
enum Kind : int { kUartRx = 0, kUartTx = 1, kFrameDecoder = 2, kSegmentPrep = 3, kEncoder = 4 };
const std::map<std::string, int> kTestKind = {{"UartRx", kUartRx},
                                              {"UartTx", kUartTx},
                                              {"FrameDecoder", kFrameDecoder},
                                              {"SegmentPrep", kSegmentPrep},
                                              {"ResponseEncoder", kEncoder}};

struct Case {
  std::string name;
  UartRxJob rx;
  UartTxJob tx;
  FrameJob dec;
  PrepJob prep;
  int kind;
  BlockRun twin;
  EncoderJob enc{};
};

// The kinds whose tests run in this process (GoogleTest's filter).
std::set<int> selected_kinds() {
  std::set<int> kinds;
  const testing::UnitTest* u = testing::UnitTest::GetInstance();
  for (int i = 0; i < u->total_test_suite_count(); ++i) {
    const testing::TestSuite* suite = u->GetTestSuite(i);
    for (int j = 0; j < suite->total_test_count(); ++j) {
      const testing::TestInfo* t = suite->GetTestInfo(j);
      const auto k = kTestKind.find(t->name());
      if (t->should_run() && k != kTestKind.end()) kinds.insert(k->second);
    }
  }
  return kinds;
}

// Every seed's jobs of every kind are drawn (so a seed gives the same jobs whichever tests run);
// the twins run the jobs of the selected kinds.
struct TwinRuns {
  std::vector<Case> cases;
  uint64_t arc_fifo_writes = 0;
};

TwinRuns run_twins() {
  const uint64_t seed = g_seed, seeds = g_seeds;
  const std::set<int> kinds = selected_kinds();
  std::vector<Case> cases;
  for (uint64_t s = 0; s < seeds; ++s) {
    std::mt19937_64 g(seed + s);
    cases.push_back(Case{fmt::format("uart_rx 115200 seed {}", seed + s),
                         rx_job(g, 115'200, 60),
                         {},
                         {},
                         {},
                         0,
                         {}});
    cases.push_back(Case{fmt::format("uart_rx 3000000 seed {}", seed + s),
                         rx_job(g, 3'000'000, 300),
                         {},
                         {},
                         {},
                         0,
                         {}});
    cases.push_back(
        Case{fmt::format("uart_tx 3000000 seed {}", seed + s), {}, tx_job(g, 300), {}, {}, 1, {}});
    cases.push_back(
        Case{fmt::format("frame_decoder seed {}", seed + s), {}, {}, frame_job(g, 150), {}, 2, {}});
    cases.push_back(Case{fmt::format("frame_decoder travel seed {}", seed + s),
                         {},
                         {},
                         travel_job(g, 60),
                         {},
                         2,
                         {}});
    cases.push_back(
        Case{fmt::format("segment_prep seed {}", seed + s), {}, {}, {}, prep_job(g, 150), 3, {}});
    Case e{fmt::format("response_encoder seed {}", seed + s), {}, {}, {}, {}, 4, {}};
    e.enc = encoder_job(g, 300);
    cases.push_back(std::move(e));
  }
  std::erase_if(cases, [&](const Case& c) { return !kinds.count(c.kind); });
  BlockBench b("bench");
  b.body = [&] {
    for (Case& c : cases) {
      b.start_job();
      b.out = &c.twin;
      switch (c.kind) {
        case 0: {
          UartRxTwin& rx = c.rx.baud == 115'200 ? b.rx115 : b.rx3m;
          auto& sock = c.rx.baud == 115'200 ? b.to_rx115 : b.to_rx3m;
          rx.reset();
          for (const auto& [t, byte] : c.rx.frames) {
            RxFrame f{byte};
            transport(sock, b.gp, b.clk, f, t);
          }
          break;
        }
        case 1: {
          b.tx.reset();
          Cycle accept = 0;
          for (const auto& [byte, gap] : c.tx.offers) {
            TxByte t{byte};
            accept = transport(b.to_tx, b.gp, b.clk, t, accept + gap);
            c.twin.events.push_back(BlockEvent{accept, {byte, 0, 0, 0}});
          }
          c.twin.edges = b.pins.take_sorted();
          break;
        }
        case 4: {
          b.enc.reset();
          b.enc_job = &c.enc;
          b.enc_ready = 0;
          b.enc_k = 0;
          for (const auto& st : c.enc.strobes) {
            if (st.kind >= 5) {
              SegDone d{st.kind == 5};
              transport(b.to_enc_done, b.gp, b.clk, d, st.edge);
            } else {
              RespReq r{st.kind, st.seq, st.reason};
              transport(b.to_enc_req, b.gp, b.clk, r, st.edge);
            }
          }
          while (b.enc.step(std::numeric_limits<Cycle>::max())) {
          }
          break;
        }
        case 2: {
          b.dec.reset();
          b.frame_job = &c.dec;
          std::vector<std::pair<Cycle, DecoderState>> log;
          b.dec.log = &log;
          for (const auto& [t, byte] : c.dec.bytes) {
            RxByte x{byte};
            transport(b.to_dec, b.gp, b.clk, x, t);
          }
          b.dec.log = nullptr;
          // v1 packets queued, and the state whenever it changes (last value per edge).
          for (Cycle p : b.dec.v1_packet_cycles)
            c.twin.events.push_back(BlockEvent{p, {kEvV1, 0, 0, 0, 0, 0}});
          uint64_t prev[3] = {0, 0, 0};
          for (size_t k = 0; k < log.size(); ++k) {
            if (k + 1 < log.size() && log[k + 1].first == log[k].first) continue;
            const DecoderState& st = log[k].second;
            const uint64_t v[3] = {st.next_seq | static_cast<uint64_t>(st.v2_mode) << 8,
                                   st.frames_ok | static_cast<uint64_t>(st.crc_errors) << 16 |
                                       static_cast<uint64_t>(st.length_errors) << 32 |
                                       static_cast<uint64_t>(st.unknown_types) << 48,
                                   st.timeouts | static_cast<uint64_t>(st.overruns) << 16 |
                                       static_cast<uint64_t>(st.noise) << 32};
            if (v[0] == prev[0] && v[1] == prev[1] && v[2] == prev[2]) continue;
            c.twin.events.push_back(
                BlockEvent{log[k].first, {kEvState | v[0], v[1], v[2], 0, 0, 0}});
            for (int x = 0; x < 3; ++x) prev[x] = v[x];
          }
          break;
        }
        default: {
          b.pprep.timing[0].high = b.pprep.timing[0].low = c.prep.min_half;
          for (int a = 1; a < kAxes; ++a) b.pprep.timing[a] = AxisTiming{1, 1, 0, 0};
          for (int a = 0; a < kAxes; ++a) {
            b.pprep.timing[a].setup = c.prep.setup[a];
            b.pprep.timing[a].hold = c.prep.hold[a];
          }
          b.prep.reset();
          b.delays = &c.prep.accept_delay;
          b.busy = &c.prep.busy;
          Cycle accept = 0;
          for (size_t k = 0; k < c.prep.commands.size(); ++k) {
            const PrepCommand& p = c.prep.commands[k];
            FifoEntry cmd{p.v2, p.kind, p.code, p.power, p.t, p.steps};
            cmd.prof = p.prof;
            cmd.v_entry = p.profile.v_entry;
            cmd.v_cruise = p.profile.v_cruise;
            cmd.v_exit = p.profile.v_exit;
            cmd.decel_at = p.profile.decel_at;
            cmd.arc = p.arc;
            cmd.arc_raw = p.arc_raw;
            accept = transport(b.to_prep, b.gp, b.clk, cmd, accept + p.gap);
            c.twin.events.push_back(BlockEvent{accept, {k, 0, 0, 0}});
          }
          c.twin.counters = {b.prep.num_x, b.prep.num_y};
          for (Cycle e : b.prep.clamp_cycles)
            c.twin.events.push_back(BlockEvent{e, {1ull << 63, 0, 0, 0}});
          break;
        }
      }
      b.delays = nullptr;
      b.busy = nullptr;
      // Past this job's last event before the next starts.
      Cycle last = 0;
      for (const auto& e : c.twin.events) last = std::max(last, e.cycle);
      for (const auto& e : c.twin.edges) last = std::max<Cycle>(last, static_cast<Cycle>(e.cycle));
      wait(b.clk.delay_to(last + 100));
    }
  };
  sc_core::sc_start();
  return TwinRuns{std::move(cases), b.arc_fifo_writes};
}

TwinRuns& twin_runs() {
  static TwinRuns runs = run_twins();
  return runs;
}

// The RTL block model runs each job of `kind`; every event and edge must equal the twin's.
void compare_kind(int kind) {
  TwinRuns& runs = twin_runs();
  size_t jobs = 0, events = 0, prof_segments = 0, arc_segments = 0;
  bool differ = false;
  for (Case& c : runs.cases) {
    if (c.kind != kind) continue;
    ++jobs;
    BlockRun r = c.kind == kUartRx         ? rtl_uart_rx(c.rx)
                 : c.kind == kUartTx       ? rtl_uart_tx(c.tx)
                 : c.kind == kFrameDecoder ? rtl_frame_decoder(c.dec)
                 : c.kind == kEncoder      ? rtl_encoder(c.enc)
                                           : rtl_prep(c.prep);
    events += r.events.size() + r.edges.size();
    for (const auto& e : r.events)
      prof_segments +=
          c.kind == kSegmentPrep && (e.v[0] >> 60) == (kEvProf >> 60) && (e.v[0] >> 40 & 0xff) == 0;
    for (const auto& e : r.events)
      arc_segments += c.kind == kSegmentPrep && e.v[0] == (kEvWide | 2ull << 8);
    const std::string d = compare(r, c.twin);
    if (!d.empty() && std::getenv("COSIM_DEBUG")) {
      sort_events(r);
      sort_events(c.twin);
      size_t first = 0;
      while (first < r.events.size() && first < c.twin.events.size() &&
             r.events[first] == c.twin.events[first])
        ++first;
      for (size_t i = first > 10 ? first - 10 : 0;
           i < std::max(r.events.size(), c.twin.events.size()) && i < first + 4; ++i) {
        auto pr = [](const std::vector<BlockEvent>& v, size_t i) {
          return i < v.size() ? fmt::format("{} {:x} {:x}", v[i].cycle, v[i].v[0], v[i].v[1])
                              : std::string("-");
        };
        fmt::print("  {:40} | {}\n", pr(r.events, i), pr(c.twin.events, i));
      }
    }
    if (!d.empty()) {
      differ = true;
      ADD_FAILURE() << c.name << ": first difference: " << d;
    }
  }
  EXPECT_EQ(jobs, (kind == kUartRx || kind == kFrameDecoder ? 2 : 1) * g_seeds) << "block jobs run";
  EXPECT_GT(events, 0u) << "events compared";
  fmt::print("cosim_blocks: {} block jobs, {} events", jobs, events);
  if (kind == kFrameDecoder) fmt::print(" ({} ARC FIFO writes)", runs.arc_fifo_writes);
  if (kind == kSegmentPrep)
    fmt::print(" ({} prepared PROFILE segments, {} prepared ARC segments)", prof_segments,
               arc_segments);
  fmt::print(": {}\n", differ ? "DIFFER" : "all identical");
}

TEST(CosimBlocks, UartRx) {
  compare_kind(kUartRx);
}
TEST(CosimBlocks, UartTx) {
  compare_kind(kUartTx);
}
TEST(CosimBlocks, FrameDecoder) {
  compare_kind(kFrameDecoder);
}
TEST(CosimBlocks, SegmentPrep) {
  compare_kind(kSegmentPrep);
}
TEST(CosimBlocks, ResponseEncoder) {
  compare_kind(kEncoder);
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  testing::InitGoogleTest(&argc, argv);
  fpgacnc::cosim::Options opts("cosim_blocks");
  opts.u64("--seed", &g_seed).u64("--seeds", &g_seeds);
  if (!opts.parse(argc, argv)) return 2;
  if (!testing::GTEST_FLAG(list_tests)) g_seed = opts.seed(g_seed, g_seeds);
  return RUN_ALL_TESTS();
}
