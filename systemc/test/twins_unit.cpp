// Unit tests of the twins (CTest label unit): the documented arithmetic (docs/protocol.md worked
// examples and v2 test vectors, docs/timing.md), each v2 block twin driven alone through its
// sockets (frame_decoder: every NAK reason and the SEQ rules; response_encoder: priorities and
// the ACK test vector; segment_executor: queued segments), and small jobs on the virtual board
// whose edge times follow from the documented latencies. One GoogleTest per block; the blocks and
// the board run in one simulation (SystemC elaborates once a process), run by the first test that
// needs it, which keeps each block's checks and failures for the block's test.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <systemc>

#include "feed_rate_ref.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/spec_vectors.h"
#include "fpgacnc/twins/v2_frames.h"
#include "fpgacnc/twins/virtual_board.h"

namespace {

using namespace fpgacnc::twins;

// The checks of one block: how many ran, and the description of each that failed.
struct Record {
  size_t checks = 0;
  std::vector<std::string> failures;
};
Record* current = nullptr;  // the block whose checks run now

void check(bool ok, const std::string& what) {
  if (current == nullptr) {
    ADD_FAILURE() << "a check outside a block: " << what;
    return;
  }
  ++current->checks;
  if (!ok) current->failures.push_back(what);
}
template <class A, class B>
void check_eq(const A& a, const B& b, const std::string& what) {
  check(a == static_cast<A>(b), fmt::format("{}: got {}, expected {}", what, a, b));
}
using Bytes = std::vector<uint8_t>;
void check_bytes(const Bytes& got, const Bytes& want, const std::string& what) {
  check(got == want, fmt::format("{}: got {:02X}, expected {:02X}", what, fmt::join(got, " "),
                                 fmt::join(want, " ")));
}

void arithmetic() {
  // docs/protocol.md worked example: X 320, Y -160, feed 1200, NUMERATOR 18 750 000.
  const PreparedTiming t = prepare_timing(320, 160, 18'750'000, 18'750'000, 1200, 62'500, 200);
  check(t.x_dominant, "X dominant");
  check_eq(t.period, 15'625u, "P");
  check_eq(t.total, 5'000'000u, "T");
  for (uint64_t k = 1; k <= 160; ++k) check_eq(dda_tick(k, 160, t.total), k * 31'250, "Y step");
  check_eq(dda_tick(1, 3, 10), 4, "ceil(10/3)");
  check_eq(dda_tick(3, 3, 10), 10, "last step on tick T");
  // feed 0 and the clamp.
  check_eq(prepare_timing(5, 1, 1000, 1000, 0, 62'500, 200).period, 62'500u, "feed 0");
  check_eq(prepare_timing(5, 1, 1000, 1000, 10, 62'500, 200).period, 200u, "clamp");
  check_eq(prepare_timing(1, 5, 1000, 5000, 10, 62'500, 2).period, 500u, "Y dominant");
  // 128-bit product: k * T beyond 64 bits.
  check_eq(dda_tick(2'000'000'000ull, 2'000'000'000ull, 0xFFFF'FFFF'0000'0000ull),
           0xFFFF'FFFF'0000'0000ull, "128-bit DDA");
  // UART timers at 50 MHz / 115200: 434.03 clocks per bit.
  const BitTimer bt(50'000'000, 115'200);
  check_eq(bt.tx_boundary(1), 435, "tx boundary 1 = ceil(434.03)");
  check_eq(bt.tx_boundary(10), 4341, "tx frame");
  check(bt.rx_tick(1) >= 216 && bt.rx_tick(1) <= 218, "rx start check at mid-bit");
  const SenderTiming st{50'000'000, 115'200};
  check_eq(st.frame(), 4340, "sender frame (round(10 * 434.03))");
  check_eq(st.level(0x01, 0), 0, "start bit");
  check_eq(st.level(0x01, 500), 1, "bit 0 of 0x01");
  check_eq(st.level(0x01, 1000), 0, "bit 1 of 0x01");
  check_eq(st.level(0x01, 4339), 1, "stop bit");
}

// docs/protocol.md "v2": CRC check value, the worked examples (test vectors), SEQ classes, the
// v2 LINE timing and dir_fast.
void v2_arithmetic() {
  const std::string s = "123456789";
  check_eq(crc16_ccitt(reinterpret_cast<const uint8_t*>(s.data()), s.size()), 0x29B1,
           "CRC-16/CCITT-FALSE check value");
  using namespace fpgacnc::twins::v2;
  check_bytes(frame(0, kHello), {0xA5, 0x00, 0x00, 0x01, 0xDC, 0xBD}, "HELLO");
  check_bytes(frame(0, kStatusQuery), {0xA5, 0x00, 0x00, 0x02, 0xEC, 0xDE}, "STATUS_QUERY");
  check_bytes(
      frame(1, kConfigAxis, config_axis_payload(0, AxisTiming{100, 100, 200, 200})),
      {0xA5, 0x09, 0x01, 0x04, 0x00, 0x00, 0x64, 0x00, 0x64, 0x00, 0xC8, 0x00, 0xC8, 0xDC, 0x4C},
      "CONFIG_AXIS");
  const int32_t xy[2] = {320, -160};
  check_bytes(frame(7, kLine, line_payload(1, 255, 5'000'000, xy, true)),
              {0xA5, 0x0A, 0x07, 0x10, 0x81, 0xFF, 0x00, 0x4C, 0x4B, 0x40, 0x01, 0x40, 0xFF, 0x60,
               0xC0, 0xB7},
              "LINE SHORT");
  const int32_t xyze[4] = {320, -160, 0, 0};
  check_bytes(frame(8, kLine, line_payload(1, 255, 5'000'000, xyze, false)),
              {0xA5, 0x16, 0x08, 0x10, 0x01, 0xFF, 0x00, 0x4C, 0x4B, 0x40, 0x00, 0x00, 0x01, 0x40,
               0xFF, 0xFF, 0xFF, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xD6, 0xAB},
              "LINE int32");
  check_bytes(frame(9, kDwell, dwell_payload(50'000'000)),
              {0xA5, 0x04, 0x09, 0x11, 0x02, 0xFA, 0xF0, 0x80, 0x9D, 0x53}, "DWELL");
  check_bytes(frame(0, kAck, {0x08, 0x00, 0x3F, 0x00, 0x00, 0x00, 0x05}),
              {0xA5, 0x07, 0x00, 0x80, 0x08, 0x00, 0x3F, 0x00, 0x00, 0x00, 0x05, 0xAA, 0x5D},
              "ACK");
  check_bytes(frame(1, kNak, {0x09, 0x01, 0x08, 0x00, 0x3F}),
              {0xA5, 0x05, 0x01, 0x81, 0x09, 0x01, 0x08, 0x00, 0x3F, 0xE0, 0xB4}, "NAK");
  // The parser finds the frames after noise and a corrupted frame.
  FrameParser fp;
  Bytes stream{0x00, 0x13, 0xAA};
  auto ack = frame(0, kAck, {0x08, 0x00, 0x3F, 0x00, 0x00, 0x00, 0x05});
  auto bad = ack;
  bad[6] ^= 1;
  stream.insert(stream.end(), bad.begin(), bad.end());
  stream.insert(stream.end(), ack.begin(), ack.end());
  int good = 0;
  for (uint8_t b : stream)
    if (auto f = fp.feed(b)) good += f->type == kAck && f->u32(3) == 5 ? 1 : 0;
  check_eq(good, 1, "parser: one good ACK after noise and a bad frame");
  check_eq(fp.bad, 1u, "parser: one bad frame");

  check(classify_seq(7, 7) == SeqClass::Accept, "SEQ = next_seq");
  check(classify_seq(6, 7) == SeqClass::Duplicate, "SEQ = next_seq - 1");
  check(classify_seq(135, 7) == SeqClass::Duplicate, "SEQ = next_seq - 128 (mod 256)");
  check(classify_seq(134, 7) == SeqClass::Ahead, "SEQ = next_seq - 129 is ahead");
  check(classify_seq(8, 7) == SeqClass::Ahead, "SEQ = next_seq + 1");
  check(classify_seq(255, 0) == SeqClass::Duplicate, "wrap: 255 before 0");

  // The LINE example: T = 5 000 000, X 320, Y -160: P = 15 625, no clamp.
  V2Timing v = prepare_v2({320, 160, 0, 0}, 5'000'000, 200);
  check_eq(v.period, 15'625u, "v2 P");
  check_eq(v.total, 5'000'000u, "v2 T");
  check(!v.clamped, "v2 not clamped");
  v = prepare_v2({320, 0, 0, 7}, 1000, 200);
  check(v.clamped, "T / n < min_period: clamped");
  check_eq(v.total, 64'000u, "clamped T = n_dom * min_period");
  check_eq(v.period, 200u, "clamped P");
  v = prepare_v2({0, 0, 0, 0}, 1234, 200);
  check_eq(v.total, 1234u, "no steps: T ticks");
  check(!v.clamped, "no steps: never clamped");
  std::array<AxisTiming, kAxes> tm{};
  tm[0] = AxisTiming{1, 1, 30, 20};
  tm[1] = AxisTiming{1, 1, 0, 0};
  check(dir_fast({true, false, false, false}, tm, 50), "dir_fast: P = hold + setup");
  check(!dir_fast({true, false, false, false}, tm, 49), "dir_fast: P < hold + setup");
  check(dir_fast({false, true, false, false}, tm, 2), "dir_fast: 0 settings count as 1");
  check(!dir_fast({false, true, false, false}, tm, 1), "dir_fast: 1 < 1 + 1");
  check(dir_fast({false, false, false, false}, tm, 1), "dir_fast: no reversal");
}

// ---- frame_decoder alone -----------------------------------------------------------------------

SC_MODULE(DecoderBench) {
  CoreParams p;
  CycleClock clk{50'000'000};
  FrameDecoderTwin dec;
  tlm_utils::simple_initiator_socket<DecoderBench> to_dec;
  tlm_utils::simple_target_socket<DecoderBench> fifo, resp, cfg;
  std::vector<std::pair<Cycle, FifoEntry>> writes;
  std::vector<std::pair<Cycle, RespReq>> reqs;
  std::vector<CfgAxis> cfgs;
  uint32_t level = 0;  // FIFO level answered to the decoder
  tlm::tlm_generic_payload gp;
  Cycle t = 10;

  SC_CTOR(DecoderBench)
      : dec("frame_decoder", clk, (p.watchdog_clks = 1000, p)),
        to_dec("to_dec"),
        fifo("fifo"),
        resp("resp"),
        cfg("cfg") {
    to_dec.bind(dec.bytes);
    dec.fifo.bind(fifo);
    dec.resp.bind(resp);
    dec.cfg.bind(cfg);
    fifo.register_b_transport(this, &DecoderBench::on_fifo);
    resp.register_b_transport(this, &DecoderBench::on_resp);
    cfg.register_b_transport(this, &DecoderBench::on_cfg);
    dec.reset();
  }
  void on_fifo(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    if (g.is_read())
      payload<FifoLevel>(g).level = level;
    else
      writes.emplace_back(clk.at(d), payload<FifoEntry>(g));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_resp(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    reqs.emplace_back(clk.at(d), payload<RespReq>(g));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_cfg(tlm::tlm_generic_payload & g, sc_core::sc_time&) {
    cfgs.push_back(payload<CfgAxis>(g));
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  // Bytes valid every 10 edges from `t` on.
  void send(const Bytes& b) {
    for (uint8_t x : b) {
      RxByte r{x};
      transport(to_dec, gp, clk, r, t);
      t += 10;
    }
  }
  // Runs `b` and returns the requests and writes it caused.
  std::pair<std::vector<RespReq>, size_t> run(const Bytes& b) {
    const size_t r0 = reqs.size(), w0 = writes.size();
    send(b);
    std::vector<RespReq> out;
    for (size_t i = r0; i < reqs.size(); ++i) out.push_back(reqs[i].second);
    return {out, writes.size() - w0};
  }
};

bool is_nak(const std::vector<RespReq>& r, uint8_t seq, uint8_t reason) {
  return r.size() == 1 && r[0].kind == kReqNak && r[0].seq == seq && r[0].reason == reason;
}
bool is_ack(const std::vector<RespReq>& r) {
  return r.size() == 1 && r[0].kind == kReqAck;
}

// The worked frames of spec/vectors.txt (generated from spec/protocol.toml; the host codec test
// and the Verilated frame_decoder bench read the same file) through the decoder twin, in v2 mode
// with next_seq brought to the frame's SEQ by FAULT_CLEAR frames: the stated answer and entry.
void spec_vector_tests(DecoderBench& b) {
  using namespace fpgacnc::twins::v2;
  const auto vectors = fpgacnc::spec::load_vectors();
  size_t checked = 0, entries = 0;
  for (const auto& v : vectors) {
    const std::string at = "spec vector " + v.name;
    // The twin's framing and CRC rebuild every frame but the one with a bad CRC.
    const Bytes payload(v.bytes.begin() + 4, v.bytes.end() - 2);
    const bool bad_crc = v.has_answer && v.answer == "NAK" && v.answer_value == kBadCrc;
    check((frame(v.seq, v.type, payload) == v.bytes) != bad_crc, at + ": framing and CRC");
    if (!v.has_answer) continue;  // device frames
    b.run(frame(0, kHello));
    for (int n = 0; b.dec.current().next_seq != v.seq && n < 256; ++n)
      b.run(frame(b.dec.current().next_seq, kFaultClear));
    check(b.dec.current().next_seq == v.seq, at + ": next_seq reached");
    const auto [r, w] = b.run(v.bytes);
    if (v.answer == "NAK") {
      check(is_nak(r, v.seq, v.answer_value) && w == 0, at + ": NAK " + v.nak_name);
    } else {
      const uint8_t want = v.answer == "IDENT"    ? kReqIdent
                           : v.answer == "STATUS" ? kReqStatus
                                                  : kReqAck;
      check(r.size() == 1 && r[0].kind == want, at + ": answer " + v.answer);
      check(w == (v.has_entry() ? 1u : 0u), at + ": FIFO writes");
      if (v.has_entry() && w == 1) {
        const FifoEntry& e = b.writes.back().second;
        check_eq(int{e.kind}, v.entry_field("kind"), at + ": kind");
        check_eq(int{e.v2}, v.entry_field("v2"), at + ": v2");
        check_eq(int{e.code}, v.entry_field("code"), at + ": code");
        check_eq(int{e.power}, v.entry_field("power"), at + ": power");
        check_eq(int64_t{e.t}, v.entry_field("t"), at + ": t");
        const auto steps = v.entry_steps();
        for (size_t a = 0; a < e.steps.size(); ++a)
          check_eq(static_cast<int64_t>(static_cast<int32_t>(e.steps[a])),
                   a < steps.size() ? steps[a] : 0, at + fmt::format(": steps[{}]", a));
        check_eq(int{e.prof}, v.entry_field("prof"), at + ": prof");
        check_eq(e.v_entry, static_cast<uint64_t>(v.entry_field("v_entry")), at + ": v_entry");
        check_eq(e.v_cruise, static_cast<uint64_t>(v.entry_field("v_cruise")), at + ": v_cruise");
        check_eq(e.v_exit, static_cast<uint64_t>(v.entry_field("v_exit")), at + ": v_exit");
        check_eq(int64_t{e.decel_at}, v.entry_field("decel_at"), at + ": decel_at");
        check_eq(int{e.arc}, v.entry_field("arc"), at + ": arc");
        for (size_t k = 0; k < e.arc_raw.size(); ++k) {
          const uint8_t want_raw = v.entry_field("arc") != 0 ? v.bytes[6 + k] : 0;
          check_eq(int{e.arc_raw[k]}, int{want_raw}, at + fmt::format(": arc_raw[{}]", k));
        }
        ++entries;
      }
    }
    ++checked;
  }
  check(checked >= 15 && entries >= 7, "spec vectors: all checked");
}

void decoder_tests(DecoderBench& b) {
  using namespace fpgacnc::twins::v2;
  // v1 in auto mode: the worked example packets, byte-exact into the FIFO.
  const auto init = fpgacnc::protocol::v1::pack_init(18'750'000, 18'750'000);
  const auto move = fpgacnc::protocol::v1::pack_motion(1, 320, -160, 1200);
  auto [r, w] = b.run(Bytes(init.begin(), init.end()));
  check(r.empty() && w == 1, "v1 init: one FIFO write, no answer");
  check(b.writes.back().second.kind == kEntryNumerators && !b.writes.back().second.v2 &&
            b.writes.back().second.steps[0] == 18'750'000,
        "v1 init entry");
  const Cycle last = b.t - 10;  // valid edge of the last byte
  check_eq(b.writes.back().first, last + kDecoderTake + kDecoderWrite, "v1 write edge");
  std::tie(r, w) = b.run(Bytes(move.begin(), move.end()));
  const FifoEntry& m = b.writes.back().second;
  check(w == 1 && m.kind == kEntryMotion && !m.v2 && m.code == 1 && m.power == 0xFF &&
            m.t == 1200 && static_cast<int32_t>(m.steps[1]) == -160 && m.steps[0] == 320,
        "v1 motion entry");
  // Noise in auto mode: counted, nothing else.
  std::tie(r, w) = b.run({0x04, 0x13, 0xFE});
  check(r.empty() && w == 0, "auto mode noise ignored");
  check_eq(b.dec.current().noise, 3u, "noise counted");
  // HELLO switches to v2 mode and asks for IDENT; SEQ ignored.
  std::tie(r, w) = b.run(frame(77, kHello));
  check(r.size() == 1 && r[0].kind == kReqIdent, "HELLO -> IDENT");
  check(b.dec.current().v2_mode, "a good frame switches to v2 mode");
  // v1 bytes are noise now.
  std::tie(r, w) = b.run(Bytes(move.begin(), move.end()));
  check(r.empty() && w == 0, "v2 mode: a v1 packet is noise");
  // Sequenced frames.
  const int32_t xy[2] = {320, -160};
  const auto line = [&](uint8_t seq) {
    return frame(seq, kLine, line_payload(1, 200, 5'000'000, xy, true));
  };
  std::tie(r, w) = b.run(line(0));
  check(is_ack(r) && w == 1, "LINE seq 0 accepted");
  const FifoEntry& e = b.writes.back().second;
  check(e.v2 && e.kind == kEntryMotion && e.code == 1 && e.power == 200 && e.t == 5'000'000 &&
            e.steps[0] == 320 && static_cast<int32_t>(e.steps[1]) == -160 && e.steps[2] == 0,
        "LINE entry (SHORT steps sign-extended)");
  check_eq(b.dec.current().next_seq, 1, "next_seq 1");
  std::tie(r, w) = b.run(line(0));
  check(is_ack(r) && w == 0, "duplicate ACKed, not executed");
  std::tie(r, w) = b.run(line(2));
  check(is_nak(r, 2, kOutOfOrder) && w == 0, "ahead: NAK OUT_OF_ORDER");
  auto bad = line(1);
  bad[8] ^= 0x10;
  std::tie(r, w) = b.run(bad);
  check(is_nak(r, 1, kBadCrc) && w == 0, "NAK BAD_CRC");
  std::tie(r, w) = b.run({kSync, 65});
  check(is_nak(r, 0, kBadLength) && w == 0, "LEN > 64: NAK BAD_LENGTH at once");
  std::tie(r, w) = b.run(frame(1, 0x12, {1, 2, 3}));
  check(is_nak(r, 1, kBadLength), "LINE_PROFILE of 3 bytes: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(1, 0x25));
  check(is_nak(r, 1, kUnknownType), "heater type 0x25 reserved: NAK UNKNOWN_TYPE");
  std::tie(r, w) = b.run(frame(1, 0x20));
  check(is_nak(r, 1, kBadLength), "HEATER_CONFIG without payload: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(1, kDwell, {0, 0, 1}));
  check(is_nak(r, 1, kBadLength), "DWELL of 3 bytes: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(1, kLine, {0x81, 0, 0, 0, 0, 1, 0, 1, 0}));
  check(is_nak(r, 1, kBadLength), "LINE with half an axis: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(1, kLine, Bytes(6 + 5 * 4, 0)));
  check(is_nak(r, 1, kBadLength), "LINE with 5 axes: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(1, kLine, line_payload(1, 1, 10, xy, true)));
  check(is_ack(r) && w == 1, "LINE seq 1 accepted");
  auto flags = line_payload(1, 1, 10, xy, true);
  flags[0] |= 0x04;
  std::tie(r, w) = b.run(frame(2, kLine, flags));
  check(is_nak(r, 2, kBadField) && w == 0, "reserved flag bit: NAK BAD_FIELD");
  std::tie(r, w) = b.run(frame(2, kConfigAxis, config_axis_payload(4, AxisTiming{})));
  check(is_nak(r, 2, kBadField), "axis 4: NAK BAD_FIELD");
  // MOTION (docs/protocol.md): unsequenced, answered by STATUS, the request to the motion rate on
  // L + 2 (L the take edge of the last byte); BAD_FIELD: flag bits 7:3, RESUME with HOLD or CANCEL,
  // a rate outside 1..0x8000, ramp 0; LEN other than 9: BAD_LENGTH. Nothing goes to the FIFO and
  // next_seq stays.
  {
    namespace spec = fpgacnc::spec;
    std::vector<MotionReq> got;
    b.dec.on_motion = [&](const MotionReq& m) { got.push_back(m); };
    std::tie(r, w) = b.run(frame(200, spec::kTypeMotion, motion_payload(1, 0x4000, 0x8000, 77)));
    check(r.size() == 1 && r[0].kind == kReqStatus && w == 0, "MOTION HOLD -> STATUS");
    check(got.size() == 1 && got[0].hold && !got[0].resume && got[0].feed == 0x4000 &&
              got[0].rapid == 0x8000 && got[0].ramp == 77,
          "MOTION HOLD: the request's fields");
    if (got.size() == 1)
      check_eq(got[0].from, b.t - 10 + kDecoderTake + kMotionTakes,
               "MOTION: the rate's clock L + 2");
    check_eq(b.dec.current().next_seq, 2, "MOTION: next_seq unchanged");
    std::tie(r, w) = b.run(frame(9, spec::kTypeMotion, motion_payload(2, 1, 1, 1)));
    check(r.size() == 1 && r[0].kind == kReqStatus && got.size() == 2 && got[1].resume &&
              !got[1].hold && got[1].feed == 1 && got[1].rapid == 1,
          "MOTION RESUME at the lowest rates -> STATUS");
    const std::array<std::pair<Bytes, const char*>, 8> bad_motion{{
        {motion_payload(3, 0x8000, 0x8000, 1), "HOLD with RESUME"},
        {motion_payload(6, 0x8000, 0x8000, 1), "CANCEL with RESUME"},
        {motion_payload(8, 0x8000, 0x8000, 1), "flag bit 3"},
        {motion_payload(0x80, 0x8000, 0x8000, 1), "flag bit 7"},
        {motion_payload(0, 0, 0x8000, 1), "feed 0"},
        {motion_payload(0, 0x8001, 0x8000, 1), "feed 0x8001"},
        {motion_payload(0, 0x8000, 0, 1), "rapid 0"},
        {motion_payload(0, 0x8000, 0x8000, 0), "ramp 0"},
    }};
    for (const auto& [pl, what] : bad_motion) {
      std::tie(r, w) = b.run(frame(5, spec::kTypeMotion, pl));
      check(is_nak(r, 5, kBadField) && got.size() == 2,
            fmt::format("MOTION with {}: NAK BAD_FIELD, no request", what));
    }
    std::tie(r, w) = b.run(frame(5, spec::kTypeMotion, {0, 0x80, 0, 0x80, 0, 0, 0, 0}));
    check(is_nak(r, 5, kBadLength) && got.size() == 2, "MOTION of 8 bytes: NAK BAD_LENGTH");
    b.dec.on_motion = nullptr;
  }
  std::tie(r, w) = b.run(frame(2, kConfigAxis, config_axis_payload(3, AxisTiming{5, 6, 7, 8})));
  check(is_ack(r) && b.cfgs.size() == 1 && b.cfgs[0].axis == 3 && b.cfgs[0].timing.low == 6 &&
            b.cfgs[0].timing.hold == 8,
        "CONFIG_AXIS applied");
  b.level = v2::kFifoDepth;
  std::tie(r, w) = b.run(frame(3, kDwell, dwell_payload(100)));
  check(is_nak(r, 3, kFifoFull) && w == 0, "no free slot: NAK FIFO_FULL, not accepted");
  check_eq(b.dec.current().next_seq, 3, "FIFO_FULL leaves next_seq");
  b.level = 0;
  std::tie(r, w) = b.run(frame(3, kDwell, dwell_payload(100)));
  check(is_ack(r) && w == 1 && b.writes.back().second.kind == kEntryDwell &&
            b.writes.back().second.t == 100,
        "DWELL entry");
  std::tie(r, w) = b.run(frame(4, kNumerators, numerators_payload(5, 6)));
  check(is_ack(r) && w == 1 && b.writes.back().second.kind == kEntryNumerators &&
            b.writes.back().second.v2 && b.writes.back().second.steps[1] == 6,
        "NUMERATORS entry");
  std::tie(r, w) = b.run(frame(5, kStatusQuery, {1}));
  check(is_nak(r, 5, kBadLength), "STATUS_QUERY with a payload: NAK BAD_LENGTH");
  std::tie(r, w) = b.run(frame(200, kStatusQuery));
  check(r.size() == 1 && r[0].kind == kReqStatus, "STATUS_QUERY (SEQ ignored)");
  std::tie(r, w) = b.run(frame(5, kFaultClear));
  check(r.size() == 2 && r[0].kind == kReqFaultClear && r[1].kind == kReqAck, "FAULT_CLEAR");
  // A frame cut short: NAK TIMEOUT when the watchdog expires (1000 edges here).
  const auto cut = line(6);
  b.send(Bytes(cut.begin(), cut.begin() + 5));
  const Cycle last_take = b.t - 10 + kDecoderTake;
  const size_t r0 = b.reqs.size();
  b.dec.advance(last_take + 1000);
  check_eq(b.reqs.size(), r0, "no timeout before the watchdog expires");
  b.dec.advance(last_take + 1001);
  check(b.reqs.size() == r0 + 1 && b.reqs.back().second.reason == kTimeout &&
            b.reqs.back().second.seq == 6 && b.reqs.back().first == last_take + 1000,
        "NAK TIMEOUT (SEQ as received) after edge last + WATCHDOG_CLKS");
  check_eq(b.dec.current().timeouts, 1u, "timeouts counted");
  // A duplicate RELEASE also returns to auto mode (after a HELLO switched to v2 again).
  b.run(frame(0, kHello));
  std::tie(r, w) = b.run(frame(5, kRelease));
  check(is_ack(r) && !b.dec.current().v2_mode, "duplicate RELEASE -> auto mode");
  b.run(frame(0, kHello));
  // RELEASE: ACK, back to auto mode: v1 again.
  std::tie(r, w) = b.run(frame(6, kRelease));
  check(is_ack(r) && !b.dec.current().v2_mode, "RELEASE -> auto mode");
  std::tie(r, w) = b.run(Bytes(move.begin(), move.end()));
  check(w == 1, "auto mode again: v1 packet accepted");
  // SEQ wrap: 250 frames later next_seq wraps through 255 -> 0.
  uint8_t seq = 7;
  size_t writes = 0;
  for (int i = 0; i < 250; ++i) {
    std::tie(r, w) = b.run(frame(seq++, kDwell, dwell_payload(1)));
    writes += w;
  }
  check_eq(writes, 250u, "250 frames through the SEQ wrap");
  check_eq(b.dec.current().next_seq, 1, "next_seq wrapped");
  std::tie(r, w) = b.run(frame(255, kDwell, dwell_payload(1)));
  check(is_ack(r) && w == 0, "duplicate across the wrap");
}

// ---- response_encoder alone --------------------------------------------------------------------

SC_MODULE(EncoderBench) {
  CycleClock clk{50'000'000};
  ResponseEncoderTwin enc;
  tlm_utils::simple_initiator_socket<EncoderBench> req, done, applied;
  tlm_utils::simple_target_socket<EncoderBench> tx, state;
  std::vector<std::pair<Cycle, uint8_t>> bytes;  // (accept edge, byte)
  StatusSnapshot snap;
  Cycle busy_until = -1;
  tlm::tlm_generic_payload gp;

  SC_CTOR(EncoderBench)
      : enc("response_encoder", clk, EncoderParams{}),
        req("req"),
        done("done"),
        applied("applied"),
        tx("tx"),
        state("state") {
    req.bind(enc.req);
    applied.bind(enc.applied);
    done.bind(enc.done);
    enc.tx.bind(tx);
    enc.state.bind(state);
    tx.register_b_transport(this, &EncoderBench::on_tx);
    state.register_b_transport(this, &EncoderBench::on_state);
    enc.reset();
  }
  // A transmitter that takes one byte per 10 edges.
  void on_tx(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    const Cycle a = std::max(clk.at(d), busy_until);
    bytes.emplace_back(a, payload<TxByte>(g).byte);
    busy_until = a + 10;
    d = clk.delay_to(a);
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void on_state(tlm::tlm_generic_payload & g, sc_core::sc_time&) {
    payload<StatusSnapshot>(g) = snap;
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void request(Cycle c, uint8_t kind, uint8_t seq = 0, uint8_t reason = 0) {
    RespReq r{kind, seq, reason};
    transport(req, gp, clk, r, c);
  }
  void seg_done(Cycle c, bool v2) {
    SegDone d{v2};
    transport(done, gp, clk, d, c);
  }
  // The frames sent so far, split by the parser.
  std::vector<v2::DeviceFrame> frames() {
    v2::FrameParser p;
    std::vector<v2::DeviceFrame> out;
    for (auto [c, b] : bytes)
      if (auto f = p.feed(b)) out.push_back(*f);
    return out;
  }
};

void encoder_tests(EncoderBench& b) {
  using namespace fpgacnc::twins::v2;
  // The ACK test vector: next_seq 8, 63 free (level 1), 5 segments done.
  b.snap.dec.next_seq = 8;
  b.snap.fifo_level = 1;
  for (int i = 0; i < 5; ++i) b.seg_done(104, true);
  b.request(104, kReqAck);
  while (b.enc.step(1'000'000)) {
  }
  Bytes got;
  for (auto [c, x] : b.bytes) got.push_back(x);
  // DONE and ACK were both pending: one ACK (it stands for the DONE).
  Bytes want;
  for (const auto& v : fpgacnc::spec::load_vectors())
    if (v.name == "ack") want = v.bytes;  // spec/vectors.txt: next_seq 8, 63 free, 5 done
  check(!want.empty(), "spec vector ack present");
  check_bytes(got, want, "ACK frame (spec/vectors.txt), a pending DONE folded into it");
  check_eq(b.bytes.front().first, 104 + kRespStart + 1,
           "first byte taken kRespStart + 1 after the last strobe");
  for (size_t i = 1; i < b.bytes.size(); ++i)
    check_eq(b.bytes[i].first, b.bytes[i - 1].first + 10, "bytes back to back");
  // Priority: IDENT, STATUS, NAK, ACK, DONE when all are pending on the same edge.
  b.bytes.clear();
  const Cycle t = 10'000;
  b.seg_done(t, true);
  b.request(t, kReqAck);
  b.request(t, kReqNak, 9, kBadCrc);
  b.request(t, kReqStatus);
  b.request(t, kReqIdent);
  b.request(t, kReqNak, 10, kOutOfOrder);  // replaces the pending NAK
  while (b.enc.step(1'000'000)) {
  }
  auto f = b.frames();
  check_eq(f.size(), 4u, "four frames (ACK stands for DONE)");
  if (f.size() == 4) {
    check_eq(f[0].type, kIdent, "IDENT first");
    check_eq(f[1].type, kStatus, "then STATUS");
    check_eq(f[2].type, kNak, "then NAK");
    check_eq(f[3].type, kAck, "then ACK");
    check_eq(f[0].seq, 1, "device SEQ counts frames");
    check_eq(f[0].payload.size(), 18u, "IDENT length");
    check_eq(f[0].u8(0), 2, "IDENT version");
    check_eq(f[0].u8(1), kAxes, "IDENT N_AXES");
    check_eq(f[0].u16(2), 64, "IDENT FIFO depth");
    check_eq(f[0].u32(4), 50'000'000u, "IDENT CLK_HZ");
    check_eq(f[0].u32(8), 115'200u, "IDENT BAUD");
    check_eq(f[0].u8(17), 64, "IDENT MAX_PAYLOAD");
    check_eq(f[1].payload.size(), static_cast<size_t>(kStatusPayload), "STATUS length");
    check_eq(f[2].u8(0), 10, "the newer NAK replaced the older");
    check_eq(f[2].u8(1), kOutOfOrder, "NAK reason");
    check_eq(f[3].u32(3), 6u, "segments done 6");
  }
  // v1 moves: one 0xAA each, between frames, offered 2 edges after seg_done.
  b.bytes.clear();
  b.seg_done(50'000, false);
  b.seg_done(50'001, false);
  while (b.enc.step(1'000'000)) {
  }
  check(b.bytes.size() == 2 && b.bytes[0].second == 0xAA && b.bytes[1].second == 0xAA, "two 0xAA");
  if (b.bytes.size() == 2) {
    check_eq(b.bytes[0].first, 50'000 + kRespStart + 1, "0xAA taken on seg_done + 3");
    check_eq(b.bytes[1].first, 50'010 + kRespStart + 1, "second 0xAA back to back");
  }
  // Nothing before the limit: no frame decided.
  b.bytes.clear();
  b.request(60'000, kReqAck);
  check(!b.enc.step(60'000 + kRespStart), "no frame before the limit");
  check(b.enc.step(60'001 + kRespStart), "the frame at the limit - 1");
}

// ---- segment_executor alone: queued segments -----------------------------------------------

SC_MODULE(ExecBench) {
  CoreParams p;
  CycleClock clk{50'000'000};
  PinRecorder pins;
  SegmentExecutorTwin exec;
  std::array<std::unique_ptr<DdaLinearTwin>, kAxes> dda;
  std::array<std::unique_ptr<StepPulseTwin>, kAxes> pulse;
  tlm_utils::simple_initiator_socket<ExecBench> seg, status, abort;
  tlm_utils::simple_target_socket<ExecBench> done;
  std::vector<std::pair<Cycle, bool>> seg_done;
  tlm::tlm_generic_payload gp;

  SC_CTOR(ExecBench)
      : exec("segment_executor", clk, p, pins),
        seg("seg"),
        status("status"),
        abort("abort"),
        done("done") {
    seg.bind(exec.segments);
    status.bind(exec.status);
    abort.bind(exec.abort);
    exec.done.bind(done);
    done.register_b_transport(this, &ExecBench::on_done);
    make_axis_twins(exec, clk, p, pins, dda, pulse);
  }
  void on_done(tlm::tlm_generic_payload & g, sc_core::sc_time & d) {
    seg_done.emplace_back(clk.at(d), payload<SegDone>(g).v2);
    g.set_response_status(tlm::TLM_OK_RESPONSE);
  }
  void reset() {
    exec.reset();
    for (auto& x : pulse) x->reset();
    pins.clear();
    seg_done.clear();
  }
  static Segment make(std::array<int32_t, kAxes> steps, uint64_t t, uint8_t code, uint8_t power,
                      bool fast) {
    Segment s{};
    s.code = code;
    s.power = power;
    s.total = t;
    s.v2 = true;
    s.dir_fast = fast;
    for (int a = 0; a < kAxes; ++a) {
      s.dir[a] = steps[a] >= 0;
      s.steps[a] = static_cast<uint32_t>(steps[a] < 0 ? -steps[a] : steps[a]);
      s.tmn[a] = t - s.steps[a];
    }
    return s;
  }
  Cycle offer(Segment s, Cycle valid) {
    return transport(seg, gp, clk, s, valid);
  }
};

// Abort (e-stop) on edges 537..539 in the run of X +10 over 1000 ticks (R = 37, X steps on edges
// 137, 237, ...): the 5th step (on 537) and later are cut, the laser falls on 537, no seg_done;
// the next segment (offered on 540, no reversal) is accepted after the settle time, 539 + max DIR
// setup (30) + 1 = 570, and runs from there.
void executor_abort_tests(ExecBench& b) {
  b.p.timing[0] = AxisTiming{5, 5, 30, 20};
  for (int a = 1; a < kAxes; ++a) b.p.timing[a] = AxisTiming{5, 5, 10, 20};
  b.reset();
  AbortSpan span{537, 539};
  transport(b.abort, b.gp, b.clk, span, 537);
  b.offer(ExecBench::make({10, 0, 0, 0}, 1000, 1, 255, false), 5);
  const Cycle a2 = b.offer(ExecBench::make({2, 0, 0, 0}, 100, 0, 0, false), 540);
  check_eq(a2, 570, "abort: next accept after max DIR setup");
  check_eq(b.exec.seg_start_cycles.size(), 2u, "abort: two runs");
  if (b.exec.seg_start_cycles.size() == 2)
    check_eq(b.exec.seg_start_cycles[1], 570, "R after abort");
  check_eq(b.seg_done.size(), 1u, "abort: no seg_done for the dropped segment");
  if (!b.seg_done.empty()) check_eq(b.seg_done[0].first, 670, "seg_done of the next segment");
  check_eq(b.pulse[0]->position, 6, "abort: 4 steps before it, 2 after");
  check_eq(b.exec.aborted, 1u, "abort: one segment dropped");
  const auto edges = b.pins.take_sorted();
  std::vector<uint64_t> laser, rises;
  for (const auto& e : edges) {
    if (e.signal == fpgacnc::models::kLaser) laser.push_back(e.cycle);
    if (e.signal == fpgacnc::models::step_signal(0) && e.value == 1) rises.push_back(e.cycle);
  }
  check_eq(laser.size(), 2u, "abort: laser rise and fall");
  if (laser.size() == 2) check_eq(laser[1], 537u, "abort: laser low from the abort edge");
  check_eq(rises.size(), 6u, "abort: X STEP rises");
  if (rises.size() == 6) {
    check_eq(rises[3], 437u, "last rise before the abort");
    check_eq(rises[4], 620u, "first rise after it: 570 + 50");
  }
}

void executor_tests(ExecBench& b) {
  b.p.timing[0] = AxisTiming{5, 5, 30, 20};
  b.p.timing[1] = AxisTiming{5, 5, 30, 20};
  b.reset();
  // Segment 1: X +10, Y +1 over 1000 ticks, laser; valid on edge 5: accepted 6; X and Y
  // reverse (DIR resets low): D = max(7, -20 + 20) = 7, R = 7 + 30 = 37.
  const Cycle a1 = b.offer(ExecBench::make({10, 1, 0, 0}, 1000, 1, 255, true), 5);
  check_eq(a1, 6, "first accept");
  check_eq(b.exec.seg_start_cycles.at(0), 37, "first R after DIR setup");
  const Cycle e1 = 37 + 1000;
  // Segment 2, valid long before e1, same direction: zero gap, R' = e1.
  const Cycle a2 = b.offer(ExecBench::make({5, 3, 0, 0}, 500, 2, 10, false), 100);
  check_eq(a2, e1, "queued: accepted on the last tick");
  check_eq(b.exec.seg_start_cycles.at(1), e1, "zero gap: R' = R + T");
  // Segment 3: X reverses with dir_fast: zero gap; DIR X changes at max(e2 + 1, last X rise +
  // hold) = e2 + 20 (X's last step is on e2).
  const Cycle e2 = e1 + 500;
  b.offer(ExecBench::make({-4, 3, 0, 0}, 400, 0, 0, true), e1 + 1);
  check_eq(b.exec.seg_start_cycles.at(2), e2, "reversal with dir_fast: zero gap");
  // Segment 4: Y reverses without dir_fast: idle, HOLD, SETUP.
  const Cycle e3 = e2 + 400;
  b.offer(ExecBench::make({0, -2, 0, 0}, 300, 0, 0, false), e2 + 5);
  const Cycle d4 = std::max(e3 + 2, e3 + 20);  // accept e3 + 1, Y's last rise on e3
  check_eq(b.exec.seg_start_cycles.at(3), d4 + 30, "reversal without dir_fast: DIR wait");
  // Segment 5 offered after segment 4 ended: not ready in time, accepted on valid + 1.
  const Cycle e4 = d4 + 30 + 300;
  b.offer(ExecBench::make({0, -1, 0, 0}, 100, 0, 0, true), e4 + 50);
  check_eq(b.exec.seg_start_cycles.at(4), e4 + 51, "late segment: R = valid + 1");
  check_eq(b.exec.zero_gap, 2u, "two zero-gap starts");
  const auto edges = b.pins.take_sorted();
  std::vector<fpgacnc::models::Edge> laser, dir_x;
  for (const auto& e : edges) {
    if (e.signal == fpgacnc::models::kLaser) laser.push_back(e);
    if (e.signal == fpgacnc::models::dir_signal(0)) dir_x.push_back(e);
  }
  // Laser: one rise on R1, stays high through segment 2 (code 2, power 10), falls on e2.
  check_eq(laser.size(), 2u, "laser: one pulse over two back-to-back cutting segments");
  if (laser.size() == 2) {
    check_eq(laser[0].cycle, 37u, "laser rises on R1");
    check_eq(laser[1].cycle, static_cast<uint64_t>(e2), "laser falls at the end of segment 2");
  }
  check_eq(dir_x.size(), 2u, "DIR X: two changes");
  if (dir_x.size() == 2)
    check_eq(dir_x[1].cycle, static_cast<uint64_t>(e2 + 20), "fast DIR change after hold");
  // No STEP X rise within hold before / setup after the fast DIR change.
  for (const auto& e : edges)
    if (e.signal == 0 && e.value == 1)
      check(e.cycle + 20 <= static_cast<uint64_t>(e2 + 20) ||
                e.cycle >= static_cast<uint64_t>(e2 + 20 + 30),
            fmt::format("STEP X at {} respects hold/setup around the DIR change", e.cycle));
  check_eq(b.pulse[0]->position, 10 + 5 - 4, "X position");
  check_eq(b.pulse[1]->position, 1 + 3 + 3 - 2 - 1, "Y position");
  // Zero-length and dwell.
  b.reset();
  b.offer(ExecBench::make({0, 0, 0, 0}, 0, 1, 255, true), 10);
  check_eq(b.seg_done.at(0).first, 11, "zero-length: done on its accept edge");
  b.offer(ExecBench::make({0, 0, 0, 0}, 700, 0, 0, true), 12);
  check_eq(b.seg_done.at(1).first, 13 + 700, "dwell: T ticks");
  check(b.pins.size() == 0, "no edges from a zero-length segment and a dwell");
}

// ---- whole boards ------------------------------------------------------------------------------

HostScript worked_example_job() {
  using namespace fpgacnc::protocol::v1;
  const auto init = pack_init(18'750'000, 18'750'000);
  const auto move = pack_motion(1, 320, -160, 1200);
  return HostScript{{HostPacket{{init.begin(), init.end()}, false, 1},
                     HostPacket{{move.begin(), move.end()}, true, 1}},
                    {}};
}

void worked_example(const RunResult& r) {
  check(r.error.empty(), "host error: " + r.error);
  const SenderTiming st{50'000'000, 115'200};
  const BitTimer bt(50'000'000, 115'200);
  // Init frames from cycle 1, the motion packet 1 clock after them, its last byte 10 frames on.
  const Cycle last_start = 1 + 9 * st.frame() + 1 + 10 * st.frame();
  const Cycle valid = last_start + 2 + bt.rx_tick(10);  // uart_rx: synchronizer + stop sample
  const Cycle take = valid + kDecoderTake;
  const Cycle a = take + kDecoderWrite + kFifoWriteToValid;  // FIFO -> prep accept
  const Cycle A = a + kPrepLatency + 1;                      // executor accept
  const Cycle D = A + 1;    // X reverses (DIR 0 -> 1), hold long over
  const Cycle R = D + 200;  // DIR setup
  check_eq(r.packet_done.size(), 2u, "packets");
  check_eq(r.packet_done.back(), take + kDecoderResp, "packet_done");
  check_eq(r.seg_start.at(0), R, "run start R");
  check_eq(r.position[0], 320, "X position");
  check_eq(r.position[1], -160, "Y position");
  check_eq(r.acks.size(), 1u, "one ACK");
  check_eq(r.acks.at(0), R + 5'000'000 + kRespStart + 1, "ACK start edge = R + T + 3");
  // Edges: DIR X at D; laser at R; first X step at R + 15625; last steps at R + T.
  std::vector<fpgacnc::models::Edge> x_steps, y_steps;
  bool dir_ok = false, laser_ok = false;
  for (const auto& e : r.edges) {
    if (e.signal == 4 && e.cycle == static_cast<uint64_t>(D) && e.value == 1) dir_ok = true;
    if (e.signal == 8 && e.cycle == static_cast<uint64_t>(R) && e.value == 1) laser_ok = true;
    if (e.signal == 0 && e.value == 1) x_steps.push_back(e);
    if (e.signal == 1 && e.value == 1) y_steps.push_back(e);
  }
  check(dir_ok, "DIR X rises at D");
  check(laser_ok, "laser rises at R");
  check_eq(x_steps.size(), 320u, "X pulses");
  check_eq(y_steps.size(), 160u, "Y pulses");
  check_eq(x_steps.front().cycle, static_cast<uint64_t>(R + 15'625), "first X step");
  check_eq(y_steps.front().cycle, static_cast<uint64_t>(R + 31'250), "first Y step");
  check_eq(x_steps.back().cycle, static_cast<uint64_t>(R + 5'000'000), "last X step at R + T");
  check_eq(y_steps.back().cycle, static_cast<uint64_t>(R + 5'000'000), "last Y step at R + T");
}

void zero_move_and_watchdog(const RunResult& r) {
  check(r.error.empty(), "host error: " + r.error);
  check_eq(r.timeouts, 1u, "one watchdog timeout");
  check_eq(r.acks.size(), 1u, "ACK of the zero move");
  check(r.edges.empty(), "a zero move makes no edges");
  // The zero move completes on the executor's accept edge: ACK 3 edges later.
  check_eq(r.acks.at(0), r.seg_done.at(0) + kRespStart + 1, "ACK 3 edges after seg_done");
}

// A v2 session: CONFIG_AXIS, NUMERATORS, 40 short LINE frames (a square spiral on X/Y, reversals
// with dir_fast, one clamped), a DWELL: every segment after the first starts on the previous
// one's last tick (zero gap), the STATUS at the end has the positions and counters.
V2Script spiral_script(std::vector<uint64_t>& t_out, std::array<int64_t, 2>& pos) {
  using namespace fpgacnc::twins::v2;
  V2Script s;
  for (uint8_t a = 0; a < kAxes; ++a)
    s.items.push_back(V2Item{kConfigAxis, config_axis_payload(a, AxisTiming{50, 50, 100, 100})});
  s.items.push_back(V2Item{kNumerators, numerators_payload(1000, 2000)});
  pos = {0, 0};
  for (int i = 0; i < 40; ++i) {
    const int32_t n = 5 + i;
    int32_t xy[2] = {0, 0};
    xy[i % 2] = (i / 2) % 2 ? -n : n;
    xy[1 - i % 2] = i == 20 ? 0 : 1;
    // Segments last longer than a frame on the wire (16 bytes, 69 000 clocks at 115 200 baud),
    // so the FIFO fills.
    uint32_t t = static_cast<uint32_t>(n) * 20'000;
    if (i == 20) t = 10;  // clamped to n * 100
    t_out.push_back(i == 20 ? static_cast<uint64_t>(n) * 100 : t);
    pos[0] += xy[0];
    pos[1] += xy[1];
    s.items.push_back(V2Item{kLine, line_payload(1, 128, t, xy, true)});
  }
  s.items.push_back(V2Item{kDwell, dwell_payload(12'345)});
  t_out.push_back(12'345);
  return s;
}

void spiral(const RunResult& r, const std::vector<uint64_t>& t, const std::array<int64_t, 2>& pos,
            const std::vector<std::vector<uint8_t>>& status_payloads) {
  std::vector<fpgacnc::twins::v2::DeviceFrame> statuses;
  for (const auto& p : status_payloads)
    statuses.push_back(fpgacnc::twins::v2::DeviceFrame{0, fpgacnc::twins::v2::kStatus, p});
  check(r.error.empty(), "v2 host error: " + r.error);
  check_eq(r.position[0], pos[0], "v2 X position");
  check_eq(r.position[1], pos[1], "v2 Y position");
  check_eq(r.segments_done, 1u + t.size(), "segments done: NUMERATORS + LINEs + DWELL");
  check_eq(r.clamped, 1u, "one clamped segment");
  check_eq(r.seg_start.size(), t.size(), "seg_start per segment");
  check_eq(r.naks, 0u, "no NAK");
  size_t zero = 0;
  for (size_t i = 1; i < r.seg_start.size() && i < t.size(); ++i)
    zero += r.seg_start[i] == r.seg_start[i - 1] + static_cast<Cycle>(t[i - 1]) ? 1 : 0;
  check_eq(zero, t.size() - 1, "every segment after the first starts on R + T (zero gap)");
  check_eq(r.zero_gap, t.size() - 1, "executor: zero-gap starts");
  check_eq(statuses.size(), 1u, "one STATUS");
  if (!statuses.empty()) {
    const auto& s = statuses[0];
    check_eq(s.u8(0) & 3, 2, "STATUS: idle, v2 mode");
    check_eq(static_cast<int32_t>(s.u32(9)), pos[0], "STATUS position X");
    check_eq(static_cast<int32_t>(s.u32(13)), pos[1], "STATUS position Y");
    check_eq(s.u32(5), 1u + t.size(), "STATUS segments done");
    check_eq(s.u16(25), 4u + 1 + t.size() + 1 + 1, "STATUS frames ok (HELLO..STATUS_QUERY)");
    check_eq(s.u16(25 + 16), 1u, "STATUS clamped");
  }
}

// A v2 session of LINE_PROFILE frames on the virtual board: an accelerating X/Y move, a cruise
// joined with zero gap, a deceleration from the first clock, then one that reverses X
// (HOLD/SETUP: accelerate, cruise, decelerate). Checked
// against an independent real-valued model (per-tick V and U in long double): every STEP rise of
// X and Y is 0 <= rise - (R + t_ideal) < 1 clock after its ideal time, exact counts, J per
// segment, zero gap where no axis reverses.
struct ProfileMove {
  ProfileParams pr;
  std::array<int32_t, 2> xy;
};
std::vector<ProfileMove> profile_moves() {
  const uint64_t v = (1ull << 48) / 120;  // 120 clocks per step (STEP high + low = 100)
  // Each segment lasts longer than the next frame on the wire (38 bytes, about 165 000 clocks at
  // 115 200 baud), so the next one is queued before its end.
  return {
      {{0, v, v, 400'000'000, 10'000}, {3000, -2000}},       // 0 -> cruise
      {{v, v, v, 1, 10'000}, {2500, -2500}},                 // cruise, A = 1
      {{v, v, v / 8, 400'000'000, 0}, {900, -300}},          // decelerates from the first clock
      {{v / 8, v, v / 8, 400'000'000, 1900}, {-2000, 600}},  // X reverses: up, cruise, down
  };
}
V2Script profile_script(std::array<int64_t, 2>& pos) {
  using namespace fpgacnc::twins::v2;
  V2Script s;
  for (uint8_t a = 0; a < kAxes; ++a)
    s.items.push_back(V2Item{kConfigAxis, config_axis_payload(a, AxisTiming{50, 50, 100, 100})});
  pos = {0, 0};
  for (const auto& m : profile_moves()) {
    pos[0] += m.xy[0];
    pos[1] += m.xy[1];
    s.items.push_back(V2Item{kLineProfile, line_profile_payload(1, 200, m.pr, m.xy, true)});
  }
  return s;
}
// The ideal times of the steps of an axis with n of n_dom steps (clocks after R, long double).
std::vector<long double> ideal_steps(const ProfileParams& pr, uint32_t n, uint32_t n_dom) {
  std::vector<long double> t;
  const long double two48 = std::ldexp(1.0L, 48);
  long double u = 0, v = static_cast<long double>(pr.v_entry) / two48;
  uint64_t vi = pr.v_entry;  // the commanded staircase (integer V per clock)
  for (uint64_t c = 0; t.size() < n && c < 100'000'000; ++c) {
    const long double next = u + v;
    while (t.size() < n) {
      const long double target = static_cast<long double>(t.size() + 1) * n_dom / n;
      if (next < target) break;
      t.push_back(c + (target - u) / v);
    }
    u = next;
    profile_update(pr, u >= pr.decel_at, vi);
    v = static_cast<long double>(vi) / two48;
  }
  return t;
}
void profile_job(const RunResult& r, const std::array<int64_t, 2>& pos) {
  const auto moves = profile_moves();
  check(r.error.empty(), "LINE_PROFILE host error: " + r.error);
  check_eq(r.naks, 0u, "LINE_PROFILE: no NAK");
  check_eq(r.position[0], pos[0], "LINE_PROFILE X position");
  check_eq(r.position[1], pos[1], "LINE_PROFILE Y position");
  check_eq(r.segments_done, moves.size(), "LINE_PROFILE segments done");
  check_eq(r.seg_start.size(), moves.size(), "LINE_PROFILE seg_start per segment");
  if (r.seg_start.size() != moves.size()) return;
  long double worst = 0;
  for (size_t i = 0; i < moves.size(); ++i) {
    const auto& m = moves[i];
    const std::array<uint32_t, kAxes> n{static_cast<uint32_t>(std::abs(m.xy[0])),
                                        static_cast<uint32_t>(std::abs(m.xy[1])), 0, 0};
    const uint32_t n_dom = std::max(n[0], n[1]);
    const ProfileRun run = run_profile(m.pr, n);
    const Cycle start = r.seg_start[i], end = start + static_cast<Cycle>(run.ticks_total);
    if (i + 1 < moves.size() && i + 1 != 3)
      check_eq(r.seg_start[i + 1], end, fmt::format("LINE_PROFILE #{}: zero gap", i + 1));
    if (i + 1 == 3) check(r.seg_start[i + 1] > end, "LINE_PROFILE #3 reverses X: HOLD/SETUP gap");
    for (int a = 0; a < 2; ++a) {
      std::vector<Cycle> rises;
      for (const auto& e : r.edges)
        if (e.signal == fpgacnc::models::step_signal(a) && e.value == 1 &&
            static_cast<Cycle>(e.cycle) > start && static_cast<Cycle>(e.cycle) <= end)
          rises.push_back(static_cast<Cycle>(e.cycle));
      const auto ideal = ideal_steps(m.pr, n[a], n_dom);
      check_eq(rises.size(), static_cast<size_t>(n[a]),
               fmt::format("LINE_PROFILE #{} axis {}: exact count", i, a));
      for (size_t k = 0; k < rises.size() && k < ideal.size(); ++k) {
        const long double d = static_cast<long double>(rises[k] - start) - ideal[k];
        worst = std::max(worst, d);
        check(d >= 0 && d < 1,
              fmt::format("LINE_PROFILE #{} axis {} step {}: rise at R + {}, "
                          "ideal R + {:.6f} (expected 0 <= d < 1)",
                          i, a, k + 1, rises[k] - start, static_cast<double>(ideal[k])));
      }
    }
  }
  fmt::print("twins_unit: LINE_PROFILE job on the board: worst rise - ideal = 1 - {:.3g} clock\n",
             static_cast<double>(1.0L - worst));
}

// A feed hold, its resume and a feed override on the board (v2): LINE X -50 in 10^6 ticks (code
// 1, laser power 200), a DWELL of 1 tick, LINE X -40 in 4 * 10^5 ticks (code 1), LINE X -30 in
// 3 * 10^5 ticks (code 0, rapid). Before the DWELL frame: MOTION HOLD (ramp 2^20: 4 096 periods,
// about 10^6 clocks, from 100 % to 0), a STATUS_QUERY at once (answered after the HOLD's STATUS
// has gone out at 115 200 baud: HOLD, not STOPPED yet), one 1.5 * 10^6 clocks later (HOLD and
// STOPPED), MOTION RESUME; before the second LINE: MOTION feed 25 %, rapid 100 %. No axis
// reverses (DIR stays low from reset), so each segment is accepted on its run edge (seg_start).
// The step rises, the segment ends and the laser are checked against the clock-by-clock
// reference of the rate (feed_rate_ref.h) with its requests at the accepted MOTION frames' clocks
// and the segments' codes at their run edges: the k-th step of n over T ticks in tick
// ceil(k * T / n) (docs/timing.md "Steps"), tick j the j-th clock with adv high from R.
struct HoldLine {
  int32_t x;
  uint32_t t;
  uint8_t code;
};
constexpr HoldLine kHoldLines[] = {
    {-50, 1'000'000, 1}, {0, 1, 0}, {-40, 400'000, 1}, {-30, 300'000, 0}};
V2Script hold_script() {
  using namespace fpgacnc::twins::v2;
  namespace spec = fpgacnc::spec;
  V2Script s;
  for (const HoldLine& l : kHoldLines) {
    if (l.x == 0) {
      s.items.push_back(V2Item{kDwell, dwell_payload(l.t)});
      continue;
    }
    const int32_t st[1] = {l.x};
    s.items.push_back(V2Item{kLine, line_payload(l.code, 200, l.t, st, true)});
  }
  const auto hold = static_cast<uint8_t>(spec::kMotionHold);
  const auto resume = static_cast<uint8_t>(spec::kMotionResume);
  auto& dwell = s.items[1].side;
  dwell.push_back(V2Side{spec::kTypeMotion, motion_payload(hold, 0x8000, 0x8000, 1u << 20), 5000});
  dwell.push_back(V2Side{kStatusQuery, {}, 1});
  dwell.push_back(V2Side{kStatusQuery, {}, 1'500'000});
  dwell.push_back(V2Side{spec::kTypeMotion, motion_payload(resume, 0x8000, 0x8000, 1u << 28), 1});
  s.items[2].side.push_back(
      V2Side{spec::kTypeMotion, motion_payload(0, 0x2000, 0x8000, 1u << 30), 1});
  return s;
}
void hold_job(const RunResult& r, const CoreParams& p) {
  namespace spec = fpgacnc::spec;
  check(r.error.empty(), "host error: " + r.error);
  check_eq(r.motion_from.size(), size_t{3}, "three MOTION frames accepted");
  check_eq(r.seg_start.size(), std::size(kHoldLines), "a seg_start per segment");
  check_eq(r.runs, 4, "the board ran the job once more per MOTION frame");
  if (r.motion_from.size() != 3 || r.seg_start.size() != std::size(kHoldLines)) return;
  std::vector<test::Req> reqs;
  test::Req h{r.motion_from[0], 0, true, false, 0x8000, 0x8000, 1u << 20};
  test::Req u{r.motion_from[1], 0, false, true, 0x8000, 0x8000, 1u << 28};
  test::Req f{r.motion_from[2], 0, false, false, 0x2000, 0x8000, 1u << 30};
  reqs = {h, u, f};
  for (size_t i = 0; i < std::size(kHoldLines); ++i) {
    test::Req c{r.seg_start[i], 3};
    c.code = kHoldLines[i].code;
    reqs.push_back(c);
  }
  const Cycle n = r.end_cycle + 10;
  const test::Reference ref(reqs, p.rate_phase, spec::kDefaultRatePeriodLog2,
                            spec::kDefaultRateRamp, n);
  // the edge of tick j from R (the j-th clock >= R with adv high, + 1)
  auto tick_edge = [&](Cycle run, uint64_t j) -> Cycle {
    for (Cycle t = run; t < n; ++t)
      if (ref.adv[static_cast<size_t>(t)] && --j == 0) return t + 1;
    return -1;
  };
  std::vector<Cycle> rises, laser;
  for (const auto& e : r.edges) {
    if (e.signal == fpgacnc::models::step_signal(0) && e.value == 1)
      rises.push_back(static_cast<Cycle>(e.cycle));
    if (e.signal == fpgacnc::models::kLaser) laser.push_back(static_cast<Cycle>(e.cycle));
  }
  std::vector<Cycle> want_rises, want_laser;
  for (size_t i = 0; i < std::size(kHoldLines); ++i) {
    const HoldLine& l = kHoldLines[i];
    const Cycle run = r.seg_start[i];
    const auto steps = static_cast<uint64_t>(l.x < 0 ? -l.x : l.x);
    for (uint64_t k = 1; k <= steps; ++k)
      want_rises.push_back(tick_edge(run, (k * l.t + steps - 1) / steps));
    const Cycle end = tick_edge(run, l.t);
    check_eq(r.seg_done.size() > i ? r.seg_done[i] : -1, end,
             fmt::format("segment {} ends on the edge of its last tick", i));
    if (l.x == 0 || l.code == 0) continue;  // (the laser is off in dwells and rapids)
    // laser high in the segment's clocks with r > 0 (pin edges where the level changes)
    bool on = false;
    for (Cycle t = run; t < end; ++t) {
      const bool want = ref.r[static_cast<size_t>(t)] != 0;
      if (want != on) want_laser.push_back(t);
      on = want;
    }
    if (on) want_laser.push_back(end);
  }
  // back-to-back cutting segments keep the laser high: the recorder drops a fall and a rise on
  // one edge
  for (size_t i = 1; i < want_laser.size();)
    if (want_laser[i] == want_laser[i - 1]) {
      want_laser.erase(want_laser.begin() + static_cast<std::ptrdiff_t>(i) - 1,
                       want_laser.begin() + static_cast<std::ptrdiff_t>(i) + 1);
    } else {
      ++i;
    }
  check(rises == want_rises, fmt::format("STEP X rises at the reference's ticks ({} of {})",
                                         rises.size(), want_rises.size()));
  for (size_t k = 0; k < rises.size() && k < want_rises.size(); ++k)
    if (rises[k] != want_rises[k]) {
      check(false, fmt::format("step {}: board {}, reference {}", k + 1, rises[k], want_rises[k]));
      break;
    }
  check(laser == want_laser, fmt::format("laser edges {} as the reference's r = 0 gate: {}",
                                         fmt::join(laser, " "), fmt::join(want_laser, " ")));
  // the hold stretches the first LINE: it ends later than 10^6 ticks after its run edge
  check(r.seg_done.size() == std::size(kHoldLines) &&
            r.seg_done[0] - r.seg_start[0] > Cycle{2'000'000},
        "the hold stretches the first LINE by more than 10^6 clocks");
  // STATUS: the HOLD answer, STATUS_QUERY during the ramp, while stopped, one for the RESUME and
  // the feed rate (the second request came while the first's STATUS was still going out: one
  // answer), the final STATUS_QUERY
  std::string st;
  for (const auto& x : r.statuses) st += fmt::format(" {:02X}", x[0]);
  check_eq(r.statuses.size(), size_t{5}, "STATUS answers (state bytes" + st + ")");
  if (r.statuses.size() == 5) {
    auto state = [&](size_t i) {
      return r.statuses[i][0] & (spec::kStateHold | spec::kStateStopped);
    };
    check_eq(state(0), int{spec::kStateHold}, "MOTION HOLD's STATUS: HOLD");
    check_eq(state(1), int{spec::kStateHold}, "STATUS during the ramp: HOLD, not STOPPED");
    check_eq(state(2), int{spec::kStateHold | spec::kStateStopped}, "STATUS held: HOLD, STOPPED");
    check_eq(state(3), 0, "MOTION RESUME's STATUS: neither");
    check_eq(state(4), 0, "the last STATUS: neither");
  }
}

// The worked sequences of spec/vectors.txt (the host codec test and the Verilated cnc_core bench
// read the same file) on a virtual board of their own (tx recorded): each job from reset, the
// host frames back to back (one packet, no ACK awaited), the bytes decoded from the tx pin's
// edges (8N1, sampled at the bit centres) are the stated device frames in order; where
// rejections coalesce, the NAK describes the last frame rejected before it was decided.
HostScript sequence_job(const fpgacnc::spec::Sequence& s) {
  return HostScript{{HostPacket{s.host_bytes(), false, 1}}, {}};
}
Bytes tx_bytes(const std::vector<fpgacnc::models::Edge>& edges, const CoreParams& p) {
  std::vector<std::pair<uint64_t, int>> tx;  // the level after each edge
  for (const auto& e : edges)
    if (e.signal == fpgacnc::models::kTx) tx.emplace_back(e.cycle, e.value);
  const double cpb = static_cast<double>(p.clk_hz) / static_cast<double>(p.baud);
  auto level_at = [&](uint64_t c) {
    int lv = 1;
    for (const auto& [cy, v] : tx) {
      if (cy > c) break;
      lv = v;
    }
    return lv;
  };
  Bytes out;
  uint64_t idle_from = 0;  // no start bit before this (the last stop bit's centre)
  for (const auto& [c, v] : tx) {
    if (v != 0 || c < idle_from) continue;
    uint8_t byte = 0;
    for (int b = 1; b <= 8; ++b)
      byte |= static_cast<uint8_t>(level_at(c + static_cast<uint64_t>((b + 0.5) * cpb)) << (b - 1));
    check(level_at(c + static_cast<uint64_t>(9.5 * cpb)) == 1, "tx stop bit");
    out.push_back(byte);
    idle_from = c + static_cast<uint64_t>(9.5 * cpb);
  }
  return out;
}
void sequences(const std::vector<RunResult>& results, const CoreParams& p) {
  const auto seqs = fpgacnc::spec::load_sequences();
  check(seqs.size() >= 2 && results.size() == seqs.size(), "a job per worked sequence");
  for (size_t k = 0; k < seqs.size() && k < results.size(); ++k) {
    const auto& s = seqs[k];
    const RunResult& r = results[k];
    const std::string at = "sequence " + s.name;
    check(r.error.empty(), at + ": host error " + r.error);
    const Bytes got = tx_bytes(r.edges, p);
    check_bytes(got, s.device_bytes(), at + ": device frames");
    // Frame by frame: the NAKs' SEQ and reason.
    fpgacnc::twins::v2::FrameParser fp;
    std::vector<fpgacnc::twins::v2::DeviceFrame> frames;
    for (uint8_t x : got)
      if (auto f = fp.feed(x)) frames.push_back(*f);
    check_eq(frames.size(), s.replies.size(), at + ": device frames");
    for (size_t i = 0; i < frames.size() && i < s.replies.size(); ++i) {
      const auto& r2 = s.replies[i];
      check_eq(int{frames[i].type}, int{r2.type}, at + fmt::format(": reply {} type", i));
      check_eq(int{frames[i].seq}, static_cast<int>(i),
               at + fmt::format(": reply {} device SEQ", i));
      if (r2.type == fpgacnc::twins::v2::kNak && frames[i].type == r2.type) {
        check_eq(int64_t{frames[i].u8(0)}, r2.field("seq"),
                 at + fmt::format(": NAK {} SEQ of the rejected frame", i));
        check_eq(int64_t{frames[i].u8(1)}, r2.field("reason"),
                 at + fmt::format(": NAK {} reason", i));
      }
    }
  }
}

// Runs `body` with its checks kept in `r`.
void in_block(Record& r, const std::function<void()>& body) {
  current = &r;
  body();
  current = nullptr;
}

// A block's test: its checks ran and none failed.
void expect_passed(const Record& r) {
  EXPECT_GT(r.checks, 0u) << "no check of this block ran";
  for (const std::string& f : r.failures) ADD_FAILURE() << f;
}

// The simulation of the block benches and the virtual board's jobs, once; each block's checks by
// name.
std::map<std::string, Record> run_simulation() {
  std::map<std::string, Record> rec;
  DecoderBench dec_bench("decoder_bench");
  EncoderBench enc_bench("encoder_bench");
  ExecBench exec_bench("exec_bench");
  CoreParams p;
  VirtualBoard board("virtual_board", p);
  std::vector<RunResult> results;
  auto keep = [&](RunResult&& r) { results.push_back(std::move(r)); };
  board.add_job(TwinJob{worked_example_job(), p.timing, keep});
  // A truncated packet (3 bytes), a pause past the watchdog, then a move with no steps.
  const auto zero = fpgacnc::protocol::v1::pack_motion(0, 0, 0, 100);
  board.add_job(TwinJob{HostScript{{HostPacket{{0x01, 0x00, 0x00}, false, 1},
                                    HostPacket{{zero.begin(), zero.end()}, true, 6'000'000}},
                                   {}},
                        p.timing, keep});
  std::vector<uint64_t> spiral_t;
  std::array<int64_t, 2> spiral_pos{};
  V2Script sp = spiral_script(spiral_t, spiral_pos);
  board.add_job(TwinJob{HostScript{{}, sp}, p.timing, keep});
  std::array<int64_t, 2> profile_pos{};
  board.add_job(TwinJob{HostScript{{}, profile_script(profile_pos)}, p.timing, keep});
  board.add_job(TwinJob{HostScript{{}, hold_script()}, p.timing, keep});
  VirtualBoard seq_board("virtual_board_tx", p, true);
  std::vector<RunResult> seq_results;
  for (const auto& s : fpgacnc::spec::load_sequences())
    seq_board.add_job(TwinJob{sequence_job(s), p.timing,
                              [&](RunResult&& r) { seq_results.push_back(std::move(r)); }});
  // The block benches run in a thread of their own (sockets need a running simulation).
  struct Blocks : sc_core::sc_module {
    SC_HAS_PROCESS(Blocks);
    DecoderBench& d;
    EncoderBench& e;
    ExecBench& x;
    std::map<std::string, Record>& rec;
    Blocks(sc_core::sc_module_name n, DecoderBench& d, EncoderBench& e, ExecBench& x,
           std::map<std::string, Record>& rec)
        : sc_module(n), d(d), e(e), x(x), rec(rec) {
      SC_THREAD(run);
    }
    void run() {
      in_block(rec["frame_decoder"], [&] { decoder_tests(d); });
      in_block(rec["spec_vectors"], [&] { spec_vector_tests(d); });
      in_block(rec["response_encoder"], [&] { encoder_tests(e); });
      in_block(rec["segment_executor"], [&] { executor_tests(x); });
      in_block(rec["segment_executor_abort"], [&] { executor_abort_tests(x); });
    }
  } blocks("blocks", dec_bench, enc_bench, exec_bench, rec);
  sc_core::sc_start();
  const char* jobs[] = {"board_worked_example", "board_zero_move_and_watchdog", "board_spiral",
                        "board_profile_job", "board_hold"};
  if (results.size() == 5) {
    in_block(rec[jobs[0]], [&] { worked_example(results[0]); });
    in_block(rec[jobs[1]], [&] { zero_move_and_watchdog(results[1]); });
    in_block(rec[jobs[2]], [&] { spiral(results[2], spiral_t, spiral_pos, results[2].statuses); });
    in_block(rec[jobs[3]], [&] { profile_job(results[3], profile_pos); });
    in_block(rec[jobs[4]], [&] { hold_job(results[4], p); });
  } else {
    for (const char* j : jobs) in_block(rec[j], [&] { check(false, "all jobs ran"); });
  }
  in_block(rec["board_spec_sequences"], [&] { sequences(seq_results, p); });
  return rec;
}

const Record& simulated(const std::string& block) {
  static const std::map<std::string, Record> rec = run_simulation();
  return rec.at(block);
}

TEST(TwinsUnit, V1Arithmetic) {
  Record r;
  in_block(r, arithmetic);
  expect_passed(r);
}
TEST(TwinsUnit, V2Arithmetic) {
  Record r;
  in_block(r, v2_arithmetic);
  expect_passed(r);
}
TEST(TwinsUnit, FrameDecoder) {
  expect_passed(simulated("frame_decoder"));
}
TEST(TwinsUnit, FrameDecoderSpecVectors) {
  expect_passed(simulated("spec_vectors"));
}
TEST(TwinsUnit, ResponseEncoder) {
  expect_passed(simulated("response_encoder"));
}
TEST(TwinsUnit, SegmentExecutor) {
  expect_passed(simulated("segment_executor"));
}
TEST(TwinsUnit, SegmentExecutorAbort) {
  expect_passed(simulated("segment_executor_abort"));
}
TEST(TwinsUnit, BoardWorkedExample) {
  expect_passed(simulated("board_worked_example"));
}
TEST(TwinsUnit, BoardZeroMoveAndWatchdog) {
  expect_passed(simulated("board_zero_move_and_watchdog"));
}
TEST(TwinsUnit, BoardSpiral) {
  expect_passed(simulated("board_spiral"));
}
TEST(TwinsUnit, BoardProfileJob) {
  expect_passed(simulated("board_profile_job"));
}
TEST(TwinsUnit, BoardHold) {
  expect_passed(simulated("board_hold"));
}
TEST(TwinsUnit, BoardSpecSequences) {
  expect_passed(simulated("board_spec_sequences"));
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
