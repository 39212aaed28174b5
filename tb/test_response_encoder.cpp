// Bench for response_encoder (N_AXES = 4, FIFO_DEPTH 64, 50 MHz, 115200 baud) with a model of
// uart_tx's byte handshake, and for crc16_ccitt: the CRC check value, the docs' ACK and NAK
// vectors byte exact, IDENT and STATUS fields, priority and merging of pending answers, the
// snapshot rule, the device SEQ counter, v1 0xAA bytes only between frames, and the clock that
// decides which rejection a coalesced NAK describes.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "Vcrc16_ccitt.h"
#include "Vresponse_encoder.h"
#include "common/seed.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec_vectors.h"
#include "verilated.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
using V = std::vector<uint8_t>;

TEST(Crc16Ccitt, CheckValueAndResidue) {
  auto ctx = std::make_unique<VerilatedContext>();
  Vcrc16_ccitt m(ctx.get());
  auto clk = [&] {
    m.clk = 0;
    m.eval();
    m.clk = 1;
    m.eval();
  };
  m.rst = 1;
  m.en = 0;
  m.init = 0;
  clk();
  m.rst = 0;
  EXPECT_EQ(m.crc, 0xFFFF);
  const std::string s = "123456789";
  for (size_t i = 0; i < s.size(); ++i) {
    m.en = 1;
    m.init = i == 0;
    m.data = static_cast<uint8_t>(s[i]);
    clk();
  }
  m.en = 0;
  m.init = 0;
  EXPECT_EQ(m.crc, 0x29B1);
  clk();
  EXPECT_EQ(m.crc, 0x29B1) << "CRC changed without en";
  // Residue: the message and its CRC (high byte first) fold to 0.
  for (uint8_t b : {uint8_t{0x29}, uint8_t{0xB1}}) {
    m.en = 1;
    m.data = b;
    clk();
  }
  EXPECT_EQ(m.crc, 0x0000);
  // init with en restarts the message; init alone clears to 0xFFFF.
  std::mt19937_64 rng(fpgacnc::tb::test_seed(20260511, "Crc16Ccitt"));
  for (int t = 0; t < 200; ++t) {
    V msg(1 + rng() % 70);
    for (auto& b : msg) b = static_cast<uint8_t>(rng());
    for (size_t i = 0; i < msg.size(); ++i) {
      m.en = 1;
      m.init = i == 0;
      m.data = msg[i];
      clk();
    }
    m.en = 0;
    m.init = 0;
    ASSERT_EQ(m.crc, v2::crc16(msg)) << "message " << t << ": " << v2::hex(msg);
  }
  m.init = 1;
  clk();
  EXPECT_EQ(m.crc, 0xFFFF);
  m.final();
}

class EncoderBench {
 public:
  explicit EncoderBench(unsigned byte_clocks = 12)
      : ctx_(std::make_unique<VerilatedContext>()), byte_clocks_(byte_clocks) {
    m_ = std::make_unique<Vresponse_encoder>(ctx_.get());
    auto& m = *m_;
    m.ident_req = m.status_req = m.nak_req = m.ack_req = m.done_evt = m.v1_ack = 0;
    m.m_axis_tready = 1;
    m.rst = 1;
    tick();
    tick();
    m.rst = 0;
    tick();
  }
  ~EncoderBench() { m_->final(); }

  void tick() {
    auto& m = *m_;
    m.m_axis_tready = busy_ == 0;
    m.clk = 0;
    m.eval();
    const bool take = m.m_axis_tvalid && m.m_axis_tready;
    const uint8_t byte = m.m_axis_tdata;
    m.clk = 1;
    m.eval();
    ++cycle_;
    if (busy_) --busy_;
    if (take) {
      busy_ = byte_clocks_;
      bytes_.push_back(byte);
      if (auto msg = parser_.push(byte, cycle_)) msgs_.push_back(*msg);
    }
    // Requests are 1-clock strobes.
    m.ident_req = m.status_req = m.nak_req = m.ack_req = m.done_evt = m.v1_ack = 0;
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) tick();
  }
  // Runs until nothing is pending or being sent (no byte for 4 byte times).
  void drain() {
    uint64_t quiet = 0;
    size_t n = bytes_.size();
    while (quiet < 4 * (byte_clocks_ + 4)) {
      tick();
      if (bytes_.size() != n) {
        n = bytes_.size();
        quiet = 0;
      } else {
        ++quiet;
      }
    }
  }

  Vresponse_encoder& dut() { return *m_; }
  const V& bytes() const { return bytes_; }
  const std::vector<v2::DeviceMsg>& msgs() const { return msgs_; }
  void clear() {
    bytes_.clear();
    msgs_.clear();
  }
  uint64_t cycle() const { return cycle_; }
  bool mid_frame() const { return parser_.mid_frame(); }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vresponse_encoder> m_;
  unsigned byte_clocks_;
  unsigned busy_ = 0;
  uint64_t cycle_ = 0;
  V bytes_;
  v2::DeviceParser parser_;
  std::vector<v2::DeviceMsg> msgs_;
};

void set_live(Vresponse_encoder& m, uint8_t next_seq, uint16_t free, uint32_t done) {
  m.next_seq = next_seq;
  m.fifo_free = free;
  m.fifo_level = static_cast<uint16_t>(64 - free);
  m.segments_done = done;
}

// The device-frame vectors of spec/vectors.txt (the docs' worked examples; the host codec test
// reads the same file), in file order from one encoder: ACK (device frame 0), NAK (frame 1).
TEST(ResponseEncoder, WorkedExamplesByteExact) {
  EncoderBench b;
  size_t sent = 0;
  for (const auto& v : fpgacnc::spec::load_vectors()) {
    if (v.type != v2::kAck && v.type != v2::kNak) continue;
    SCOPED_TRACE(v.name + ": " + v.doc);
    ASSERT_EQ(v.seq, sent) << "the encoder numbers its frames from 0";
    set_live(b.dut(), static_cast<uint8_t>(v.field("next_seq")),
             static_cast<uint16_t>(v.field("free")), static_cast<uint32_t>(v.field("done")));
    if (v.type == v2::kAck) {
      b.dut().ack_req = 1;
    } else {
      b.dut().nak_req = 1;
      b.dut().nak_seq = static_cast<uint8_t>(v.field("seq"));
      b.dut().nak_reason = static_cast<uint8_t>(v.field("reason"));
    }
    b.tick();
    b.drain();
    EXPECT_EQ(v2::hex(b.bytes()), v2::hex(v.bytes));
    b.clear();
    ++sent;
  }
  EXPECT_EQ(sent, 2u);
  // Request sampled on edge E: snapshot and 0xA5 offered from E + 1, taken by an idle sink on
  // E + 2.
  EncoderBench c;
  c.dut().ack_req = 1;
  c.tick();
  const uint64_t req = c.cycle();
  c.idle(3);
  ASSERT_EQ(c.bytes().size(), 1u);
  ASSERT_EQ(c.msgs().size(), 0u);
  c.drain();
  ASSERT_EQ(c.msgs().size(), 1u);
  EXPECT_EQ(c.msgs()[0].cycle, req + 2) << "edge that takes the 0xA5";
}

TEST(ResponseEncoder, IdentAndStatusFields) {
  EncoderBench b;
  auto& m = b.dut();
  set_live(m, 0x5A, 40, 0xDEADBEEF);
  m.state = 0x05;
  m.faults = 0x01;
  const int32_t pos[4] = {320, -160, 0x7FFFFFFF, -2147483647 - 1};
  for (int a = 0; a < 4; ++a) m.position[a] = static_cast<uint32_t>(pos[a]);
  uint16_t ctr[9];
  for (int i = 0; i < 9; ++i) ctr[i] = static_cast<uint16_t>(0x1100 * (i + 1) + i);
  // counters[143:128] is the first (frames ok): VlWide words, little-endian.
  for (int w = 0; w < 5; ++w) m.counters[w] = 0;
  for (int i = 0; i < 9; ++i) {
    const int lo = 16 * (8 - i);
    m.counters[lo / 32] |= static_cast<uint32_t>(ctr[i]) << (lo % 32);
  }
  m.limits = 0x13A5C3;  // limit byte 0x13 (axis 3, max), switch states 0xA5C3
  m.ident_req = 1;
  m.status_req = 1;
  b.tick();
  b.drain();
  ASSERT_EQ(b.msgs().size(), 2u);
  const auto& id = b.msgs()[0];
  EXPECT_TRUE(id.crc_ok);
  EXPECT_EQ(id.type, v2::kIdent);
  EXPECT_EQ(id.seq, 0u);
  ASSERT_EQ(id.payload.size(), 18u);
  EXPECT_EQ(id.u8(0), 2u);
  EXPECT_EQ(id.u8(1), 4u);
  EXPECT_EQ(id.u16(2), 64u);
  EXPECT_EQ(id.u32(4), 50'000'000u);
  EXPECT_EQ(id.u32(8), 115'200u);
  EXPECT_EQ(id.u32(12), fpgacnc::spec::kBuildId);
  EXPECT_EQ(id.u8(16), 0x5Au);
  EXPECT_EQ(id.u8(17), 64u);
  const auto& st = b.msgs()[1];
  EXPECT_TRUE(st.crc_ok);
  EXPECT_EQ(st.type, v2::kStatus);
  EXPECT_EQ(st.seq, 1u);
  ASSERT_EQ(st.payload.size(), 46u);  // 30 + 4 * 4 (docs/protocol.md), no heater block
  EXPECT_EQ(st.u8(0), 0x05u);
  EXPECT_EQ(st.u8(1), 0x01u);
  EXPECT_EQ(st.u16(2), 24u);
  EXPECT_EQ(st.u8(4), 0x5Au);
  EXPECT_EQ(st.u32(5), 0xDEADBEEFu);
  for (int a = 0; a < 4; ++a)
    EXPECT_EQ(static_cast<int32_t>(st.u32(9 + 4 * a)), pos[a]) << "axis " << a;
  for (int i = 0; i < 9; ++i) EXPECT_EQ(st.u16(25 + 2 * i), ctr[i]) << "counter " << i;
  EXPECT_EQ(st.u8(43), 0x13u) << "limit byte";
  EXPECT_EQ(st.u16(44), 0xA5C3u) << "switch states";
}

// All requests on one clock: IDENT, STATUS, NAK, ACK in that order; the DONE is merged into the
// ACK; a DONE alone is a DONE frame; requests during a frame merge into one more frame.
TEST(ResponseEncoder, PriorityMergingAndSeq) {
  EncoderBench b;
  set_live(b.dut(), 3, 60, 7);
  auto& m = b.dut();
  m.ident_req = m.status_req = m.nak_req = m.ack_req = m.done_evt = 1;
  m.nak_seq = 4;
  m.nak_reason = v2::kOutOfOrder;
  b.tick();
  b.drain();
  ASSERT_EQ(b.msgs().size(), 4u);
  const uint8_t want[4] = {v2::kIdent, v2::kStatus, v2::kNak, v2::kAck};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(b.msgs()[i].type, want[i]) << "frame " << i;
    EXPECT_EQ(b.msgs()[i].seq, i) << "device SEQ of frame " << i;
    EXPECT_TRUE(b.msgs()[i].crc_ok);
  }
  EXPECT_EQ(b.msgs()[2].u8(0), 4u);
  EXPECT_EQ(b.msgs()[2].u8(1), v2::kOutOfOrder);
  EXPECT_EQ(b.msgs()[2].u8(2), 3u);
  EXPECT_EQ(b.msgs()[2].u16(3), 60u);
  b.clear();
  m.done_evt = 1;
  b.tick();
  b.drain();
  ASSERT_EQ(b.msgs().size(), 1u);
  EXPECT_EQ(b.msgs()[0].type, v2::kDone);
  EXPECT_EQ(b.msgs()[0].seq, 4u);
  EXPECT_EQ(b.msgs()[0].u32(3), 7u);
  // A burst of ACK requests while an ACK goes out: one more ACK, with the latest fields.
  b.clear();
  m.ack_req = 1;
  b.tick();
  // 20 x 6 clocks: shorter than one 13-byte frame at 13 clocks per byte.
  for (int i = 0; i < 20; ++i) {
    set_live(m, static_cast<uint8_t>(10 + i), static_cast<uint16_t>(50 - i), 100u + i);
    m.ack_req = (i % 3) == 0;
    b.tick();
    b.idle(5);
  }
  b.drain();
  ASSERT_EQ(b.msgs().size(), 2u) << "ACK requests during a frame were not merged";
  EXPECT_EQ(b.msgs()[1].u8(0), 29u) << "the second ACK does not carry the latest next_seq";
  EXPECT_EQ(b.msgs()[1].u16(1), 31u);
  EXPECT_EQ(b.msgs()[1].u32(3), 119u);
}

// Fields are snapshotted when the frame starts: changes during the frame do not tear it.
TEST(ResponseEncoder, SnapshotAtFrameStart) {
  EncoderBench b;
  auto& m = b.dut();
  set_live(m, 1, 2, 0x01020304);
  for (int a = 0; a < 4; ++a) m.position[a] = 0x11111111u * (a + 1);
  m.status_req = 1;
  b.tick();
  b.idle(2);  // the frame has started
  for (int i = 0; i < 200; ++i) {
    set_live(m, static_cast<uint8_t>(i), static_cast<uint16_t>(i), 0xFFFF0000u + i);
    for (int a = 0; a < 4; ++a) m.position[a] = static_cast<uint32_t>(i * 7919 + a);
    b.tick();
  }
  b.drain();
  ASSERT_EQ(b.msgs().size(), 1u);
  const auto& st = b.msgs()[0];
  EXPECT_EQ(st.u8(4), 1u);
  EXPECT_EQ(st.u32(5), 0x01020304u);
  for (int a = 0; a < 4; ++a) EXPECT_EQ(st.u32(9 + 4 * a), 0x11111111u * (a + 1)) << "axis " << a;
}

// v1 0xAA bytes: one per v1_ack, never inside a frame; frames still come out whole.
TEST(ResponseEncoder, V1AcksBetweenFrames) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260512, "V1AcksBetweenFrames");
  std::mt19937_64 rng(seed);
  EncoderBench b;
  auto& m = b.dut();
  uint64_t v1 = 0, frames_req = 0;
  for (int i = 0; i < 20'000; ++i) {
    const uint64_t r = rng() % 200;
    if (r == 0) {
      m.v1_ack = 1;
      ++v1;
    } else if (r == 1) {
      m.status_req = 1;
      ++frames_req;
    } else if (r == 2) {
      m.done_evt = 1;
      ++frames_req;
    }
    set_live(m, static_cast<uint8_t>(i), 5, static_cast<uint32_t>(i));
    b.tick();
  }
  b.drain();
  uint64_t aa = 0, frames = 0;
  for (const auto& msg : b.msgs()) {
    if (msg.v1_ack) {
      ++aa;
    } else {
      ++frames;
      EXPECT_TRUE(msg.crc_ok) << "frame " << frames << " seed " << seed;
    }
  }
  EXPECT_EQ(aa, v1) << "seed " << seed;
  EXPECT_GT(frames, 10u);
  EXPECT_LE(frames, frames_req);
  EXPECT_FALSE(b.mid_frame());
}

// The coalescing boundary of docs/protocol.md "Coalesced NAK": with a NAK pending behind an ACK
// on the line, a second NAK request sampled on the edge that hands the ACK's last byte to the
// UART still replaces it (one NAK, the second's SEQ and reason); one edge later the pending NAK
// has been decided and the second gets a NAK of its own.
TEST(ResponseEncoder, CoalescedNakBoundary) {
  // Runs the case (second NAK request before tick `nak2_at`, -1: none); returns the tick whose
  // edge took the ACK's last (13th) byte.
  auto run = [](int nak2_at, std::vector<v2::DeviceMsg>& out) {
    EncoderBench b;
    set_live(b.dut(), 0, 64, 0);
    b.dut().ack_req = 1;
    int t = 0, last_take = -1;
    for (; t < 100'000 && b.bytes().size() < 13; ++t) {
      if (t == 20) {  // the first NAK, long before the ACK's end
        b.dut().nak_req = 1;
        b.dut().nak_seq = 2;
        b.dut().nak_reason = v2::kBadField;
      }
      if (t == nak2_at) {
        b.dut().nak_req = 1;
        b.dut().nak_seq = 12;
        b.dut().nak_reason = v2::kOutOfOrder;
      }
      b.tick();
      if (b.bytes().size() == 13) last_take = t;
    }
    for (int k = 0; k < 4; ++k, ++t) {
      if (t == nak2_at) {
        b.dut().nak_req = 1;
        b.dut().nak_seq = 12;
        b.dut().nak_reason = v2::kOutOfOrder;
      }
      b.tick();
    }
    b.drain();
    out = b.msgs();
    return last_take;
  };
  std::vector<v2::DeviceMsg> ref;
  const int take = run(-1, ref);  // the tick whose edge takes the ACK's last byte
  ASSERT_GT(take, 100);
  ASSERT_EQ(ref.size(), 2u);
  EXPECT_EQ(ref[1].u8(0), 2u);
  std::vector<v2::DeviceMsg> same, later;
  EXPECT_EQ(run(take, same), take);
  ASSERT_EQ(same.size(), 2u) << "a request on the last byte's edge joins the pending NAK";
  EXPECT_EQ(same[0].type, v2::kAck);
  EXPECT_EQ(same[1].type, v2::kNak);
  EXPECT_EQ(same[1].u8(0), 12u) << "the NAK describes the last rejection, not the first";
  EXPECT_EQ(same[1].u8(1), v2::kOutOfOrder);
  EXPECT_EQ(run(take + 1, later), take);
  ASSERT_EQ(later.size(), 3u) << "one edge later: a NAK of its own";
  EXPECT_EQ(later[1].u8(0), 2u);
  EXPECT_EQ(later[1].u8(1), v2::kBadField);
  EXPECT_EQ(later[2].u8(0), 12u);
  EXPECT_EQ(later[2].u8(1), v2::kOutOfOrder);
  EXPECT_EQ(later[2].seq, 2u);
}

}  // namespace
