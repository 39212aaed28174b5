// Bench for frame_decoder (N_AXES = 4), driven byte by byte on s_axis (no UART), with a model of
// the FIFO's write side (tready set by the test). Protocol v1 (ported from the packet decoder's
// bench: worked examples, the 100 ms watchdog at its exact boundary, a million random bytes
// against a reference framer, the overrun drop) and protocol v2 (docs/protocol.md: worked
// examples, every NAK reason, duplicates, out-of-order, FIFO_FULL, modes, ten million random
// bytes in v2 mode, the worked frames and sequences of spec/vectors.txt).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "Vframe_decoder.h"
#include "common/seed.h"
#include "common/v1_packets.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec_vectors.h"
#include "verilated.h"

namespace {

using fpgacnc::tb::init_packet;
using fpgacnc::tb::motion_packet;
namespace v2 = fpgacnc::tb::v2;

constexpr int kAxes = 4;
constexpr uint64_t kWatchdog = 5'000'000;  // WATCHDOG_CLKS default (100 ms at 50 MHz)

// One FIFO entry: {v2, kind, code, power, t, steps[4]}.
struct Entry {
  bool v2 = false;
  uint32_t kind = 0, code = 0, power = 0, t = 0;
  int32_t steps[kAxes] = {0, 0, 0, 0};
  // LINE_PROFILE and ARC fields (not compared by ==; the spec vector test checks them)
  uint64_t prof = 0, v_entry = 0, v_cruise = 0, v_exit = 0, decel_at = 0, arc = 0;
  std::vector<uint8_t> arc_raw;  // ARC payload bytes 2.., byte 2 first
  bool operator==(const Entry& o) const {
    for (int a = 0; a < kAxes; ++a)
      if (steps[a] != o.steps[a]) return false;
    return v2 == o.v2 && kind == o.kind && code == o.code && power == o.power && t == o.t;
  }
};

std::ostream& operator<<(std::ostream& os, const Entry& e) {
  os << "{v2 " << e.v2 << ", kind " << e.kind << ", code " << e.code << ", power " << e.power
     << ", t " << e.t << ", steps";
  for (int a = 0; a < kAxes; ++a) os << ' ' << e.steps[a];
  return os << '}';
}

Entry v1_motion(uint32_t code, int32_t sx, int32_t sy, uint32_t feed) {
  Entry e;
  e.code = code & 3u;
  e.power = 0xFF;
  e.t = feed;
  e.steps[0] = sx;
  e.steps[1] = sy;
  return e;
}
Entry v1_init(uint32_t nx, uint32_t ny) {
  Entry e;
  e.kind = 1;
  e.steps[0] = static_cast<int32_t>(nx);
  e.steps[1] = static_cast<int32_t>(ny);
  return e;
}
Entry v2_line(uint32_t code, uint32_t power, uint32_t t, std::vector<int32_t> steps) {
  Entry e;
  e.v2 = true;
  e.code = code;
  e.power = power;
  e.t = t;
  for (size_t a = 0; a < steps.size(); ++a) e.steps[a] = steps[a];
  return e;
}
Entry v2_dwell(uint32_t t) {
  Entry e;
  e.v2 = true;
  e.kind = 2;
  e.t = t;
  return e;
}
Entry v2_num(uint32_t nx, uint32_t ny) {
  Entry e = v1_init(nx, ny);
  e.v2 = true;
  return e;
}

struct Nak {
  uint64_t cycle;
  uint8_t seq, reason;
};

// Reference model of the v1 framing in auto mode (protocol.md "Telling v1 from v2"), without
// the watchdog: 0x00..0x03 motion, 0xFF init, 0xA5 a v2 frame (skipped by its LEN; a good CRC
// switches to v2 mode), anything else noise.
class RefFramer {
 public:
  std::optional<Entry> push(uint8_t b) {
    if (buf_.empty()) {
      if (b == 0xA5) {
        buf_.push_back(b);
        return std::nullopt;
      }
      if (v2_mode_ || !(b == 0xFF || b <= 3)) {
        ++noise_;
        return std::nullopt;
      }
    }
    buf_.push_back(b);
    if (buf_[0] == 0xA5) {
      if (buf_.size() == 2 && b > v2::kMaxPayload) buf_.clear();
      if (buf_.size() >= 2 && buf_.size() == size_t{buf_[1]} + 6) {
        const uint16_t crc = static_cast<uint16_t>((buf_[buf_.size() - 2] << 8) | buf_.back());
        if (v2::crc16(buf_.data() + 1, buf_.size() - 3) == crc) {
          v2_mode_ = true;
          ++good_frames_;
        }
        ++frames_;
        buf_.clear();
      }
      return std::nullopt;
    }
    const size_t len = buf_[0] == 0xFF ? 9 : 11;
    if (buf_.size() < len) return std::nullopt;
    auto be32 = [&](size_t i) {
      return (uint32_t{buf_[i]} << 24) | (uint32_t{buf_[i + 1]} << 16) |
             (uint32_t{buf_[i + 2]} << 8) | uint32_t{buf_[i + 3]};
    };
    Entry e = buf_[0] == 0xFF
                  ? v1_init(be32(1), be32(5))
                  : v1_motion(buf_[0], static_cast<int32_t>(be32(1)), static_cast<int32_t>(be32(5)),
                              (uint32_t{buf_[9]} << 8) | buf_[10]);
    buf_.clear();
    return e;
  }
  bool partial() const { return !buf_.empty(); }
  uint64_t noise() const { return noise_; }
  uint64_t frames() const { return frames_; }
  uint64_t good_frames() const { return good_frames_; }

 private:
  std::vector<uint8_t> buf_;
  bool v2_mode_ = false;
  uint64_t noise_ = 0, frames_ = 0, good_frames_ = 0;
};

class DecoderBench {
 public:
  DecoderBench() : ctx_(std::make_unique<VerilatedContext>()) {
    m_ = std::make_unique<Vframe_decoder>(ctx_.get());
    m_->s_axis_tvalid = 0;
    m_->m_axis_tready = 1;
    m_->rst = 1;
    tick();
    tick();
    m_->rst = 0;
    tick();
    clear_records();
  }
  ~DecoderBench() { m_->final(); }

  void tick() {
    // The FIFO write is a strobe in the clock before the edge: record it before the edge.
    m_->clk = 0;
    m_->eval();
    if (m_->m_axis_tvalid) {
      if (!m_->m_axis_tready)
        ADD_FAILURE() << "m_axis_tvalid without m_axis_tready at cycle " << cycle_ + 1;
      out_.push_back(read_out());
      write_cycles_.push_back(cycle_ + 1);
    }
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    if (!m_->s_axis_tready) ++not_ready_;
    if (m_->timeout) timeouts_.push_back(cycle_);
    if (m_->v1_overrun) overruns_.push_back(cycle_);
    if (m_->v1_packet) ++v1_packets_;
    if (m_->nak) naks_.push_back(Nak{cycle_, m_->nak_seq, m_->nak_reason});
    if (m_->ack_req) acks_.push_back(cycle_);
    if (m_->hello) ++hellos_;
    if (m_->status_req) ++status_reqs_;
    if (m_->cfg_wr) ++cfg_writes_;
    if (m_->fault_clear) ++fault_clears_;
    if (m_->release_req) ++releases_;
    if (m_->frame_ok) ++frames_ok_;
    if (m_->crc_error) ++crc_errors_;
    if (m_->length_error) ++length_errors_;
    if (m_->unknown_type) ++unknown_types_;
    if (m_->noise) ++noise_;
  }

  // Presents one byte for one clock (s_axis_tready is required to be high), then `gap` clocks.
  void byte(uint8_t b, uint64_t gap = 0) {
    m_->s_axis_tdata = b;
    m_->s_axis_tvalid = 1;
    if (!m_->s_axis_tready) ADD_FAILURE() << "s_axis_tready low at cycle " << cycle_;
    tick();
    m_->s_axis_tvalid = 0;
    idle(gap);
  }
  void bytes(const std::vector<uint8_t>& v, size_t from = 0, size_t to = SIZE_MAX,
             uint64_t gap = 0) {
    for (size_t i = from; i < v.size() && i < to; ++i) byte(v[i], gap);
  }
  // A frame with a few idle clocks between bytes (as from a UART), then the CHECK clocks.
  void frame(const std::vector<uint8_t>& v) {
    bytes(v, 0, SIZE_MAX, 3);
    idle(3);
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) tick();
  }

  Entry read_out() const {
    const auto& w = m_->m_axis_tdata;  // the whole entry (spec::entry_width(kAxes) bits)
    auto bits64 = [&](int lo, int width) {
      uint64_t v = 0;
      for (int i = 0; i < width; ++i) {
        const int bit = lo + i;
        v |= static_cast<uint64_t>((w[bit / 32] >> (bit % 32)) & 1u) << i;
      }
      return v;
    };
    auto bits = [&](int lo, int width) { return static_cast<uint32_t>(bits64(lo, width)); };
    Entry e;
    for (int a = 0; a < kAxes; ++a) e.steps[a] = static_cast<int32_t>(bits(32 * a, 32));
    auto field = [&](fpgacnc::spec::EntryField f) { return bits(32 * kAxes + f.lsb, f.width); };
    e.t = field(fpgacnc::spec::kEntryT);
    e.power = field(fpgacnc::spec::kEntryPower);
    e.code = field(fpgacnc::spec::kEntryCode);
    e.kind = field(fpgacnc::spec::kEntryKind);
    e.v2 = field(fpgacnc::spec::kEntryV2) != 0;
    namespace spec = fpgacnc::spec;
    auto field64 = [&](spec::EntryField f) { return bits64(32 * kAxes + f.lsb, f.width); };
    e.prof = field64(spec::kEntryProf);
    e.v_entry = field64(spec::kEntryVEntry);
    e.v_cruise = field64(spec::kEntryVCruise);
    e.v_exit = field64(spec::kEntryVExit);
    e.decel_at = field64(spec::kEntryDecelAt);
    e.arc = field64(spec::kEntryArc);
    const int raw_top = 32 * kAxes + spec::kEntryArcRaw.lsb + spec::kEntryArcRaw.width;
    for (int k = 0; k < spec::kEntryArcRaw.width / 8; ++k)
      e.arc_raw.push_back(static_cast<uint8_t>(bits64(raw_top - 8 * (k + 1), 8)));
    return e;
  }

  // Entries written so far (taken off the list).
  std::vector<Entry> take() {
    std::vector<Entry> r;
    r.swap(out_);
    return r;
  }
  void clear_records() {
    out_.clear();
    write_cycles_.clear();
    timeouts_.clear();
    overruns_.clear();
    naks_.clear();
    acks_.clear();
    v1_packets_ = hellos_ = status_reqs_ = cfg_writes_ = fault_clears_ = releases_ = frames_ok_ =
        crc_errors_ = length_errors_ = unknown_types_ = noise_ = 0;
  }

  Vframe_decoder& dut() { return *m_; }
  uint64_t cycle() const { return cycle_; }
  uint64_t not_ready() const { return not_ready_; }
  const std::vector<uint64_t>& write_cycles() const { return write_cycles_; }
  const std::vector<uint64_t>& timeouts() const { return timeouts_; }
  const std::vector<uint64_t>& overruns() const { return overruns_; }
  const std::vector<Nak>& naks() const { return naks_; }
  const std::vector<uint64_t>& acks() const { return acks_; }
  uint64_t v1_packets() const { return v1_packets_; }
  uint64_t hellos() const { return hellos_; }
  uint64_t status_reqs() const { return status_reqs_; }
  uint64_t cfg_writes() const { return cfg_writes_; }
  uint64_t fault_clears() const { return fault_clears_; }
  uint64_t releases() const { return releases_; }
  uint64_t frames_ok() const { return frames_ok_; }
  uint64_t crc_errors() const { return crc_errors_; }
  uint64_t length_errors() const { return length_errors_; }
  uint64_t unknown_types() const { return unknown_types_; }
  uint64_t noise() const { return noise_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vframe_decoder> m_;
  uint64_t cycle_ = 0, not_ready_ = 0;
  std::vector<Entry> out_;
  std::vector<uint64_t> write_cycles_, timeouts_, overruns_, acks_;
  std::vector<Nak> naks_;
  uint64_t v1_packets_ = 0, hellos_ = 0, status_reqs_ = 0, cfg_writes_ = 0, fault_clears_ = 0,
           releases_ = 0, frames_ok_ = 0, crc_errors_ = 0, length_errors_ = 0, unknown_types_ = 0,
           noise_ = 0;
};

// ================================================================ v1

TEST(FrameDecoderV1, WorkedExamples) {
  DecoderBench b;
  const std::vector<uint8_t> init = {0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30};
  const std::vector<uint8_t> motion = {0x01, 0x00, 0x00, 0x01, 0x40, 0xFF,
                                       0xFF, 0xFF, 0x60, 0x04, 0xB0};
  EXPECT_EQ(init, init_packet(18'750'000, 18'750'000));
  EXPECT_EQ(motion, motion_packet(1, 320, -160, 1200));

  b.bytes(init);
  const uint64_t last_init = b.cycle();
  b.tick();
  // Latency: written on the edge after the last byte's edge.
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u) << "init packet: expected one entry by cycle " << last_init + 1;
  EXPECT_EQ(b.write_cycles()[0], last_init + 1) << "write edge of the init entry";
  EXPECT_EQ(got[0], v1_init(18'750'000, 18'750'000)) << "got " << got[0];

  b.bytes(motion);
  b.idle(3);
  got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_motion(1, 320, -160, 1200)) << "got " << got[0];
  EXPECT_EQ(b.v1_packets(), 2u);
  EXPECT_TRUE(b.timeouts().empty());
  EXPECT_TRUE(b.overruns().empty());
  EXPECT_TRUE(b.naks().empty());
  EXPECT_TRUE(b.acks().empty());
  EXPECT_EQ(b.not_ready(), 0u);
  EXPECT_EQ(b.dut().v2_mode, 0);
}

// A packet cut off after k bytes plus exactly WATCHDOG_CLKS clocks of silence is dropped; the
// next full packet decodes. Init and motion packets alternate as the cut one.
TEST(FrameDecoderV1, WatchdogDropsCutPacket) {
  DecoderBench b;
  for (size_t k = 1; k <= 10; ++k) {
    const auto cut = (k % 2 == 1 && k < 9) ? init_packet(0x11223344u + k, 0x55667788u)
                                           : motion_packet(2, -7 * int32_t(k), 9, 600);
    b.bytes(cut, 0, k);
    const uint64_t last = b.cycle();
    const size_t t0 = b.timeouts().size();
    b.idle(kWatchdog);
    ASSERT_EQ(b.timeouts().size(), t0 + 1)
        << "k=" << k << ": expected one timeout strobe within " << kWatchdog
        << " clocks of silence after the byte at cycle " << last;
    EXPECT_EQ(b.timeouts().back(), last + kWatchdog) << "k=" << k << ": timeout strobe cycle";
    b.idle(100);
    EXPECT_EQ(b.timeouts().size(), t0 + 1) << "k=" << k << ": timeout strobed more than once";
    EXPECT_TRUE(b.take().empty()) << "k=" << k << ": cut packet produced an entry";
    const Entry want = v1_motion(3, 1000 + int32_t(k), -int32_t(k), 4321);
    b.bytes(motion_packet(3, 1000 + int32_t(k), -int32_t(k), 4321));
    b.idle(2);
    auto got = b.take();
    ASSERT_EQ(got.size(), 1u) << "k=" << k << ": packet after the drop not decoded";
    EXPECT_EQ(got[0], want) << "k=" << k << ": got " << got[0];
  }
  EXPECT_EQ(b.timeouts().size(), 10u);
  EXPECT_TRUE(b.naks().empty()) << "a v1 timeout must not NAK";
}

// Boundary: a gap of WATCHDOG_CLKS - 1 clocks inside a packet does not drop it.
TEST(FrameDecoderV1, WatchdogBoundaryKeepsPacket) {
  DecoderBench b;
  for (size_t k : {size_t{1}, size_t{5}, size_t{8}, size_t{10}}) {
    const auto pkt = motion_packet(1, 320 + int32_t(k), -160, 1200);
    b.bytes(pkt, 0, k);
    b.idle(kWatchdog - 1);
    b.bytes(pkt, k);
    b.idle(2);
    auto got = b.take();
    ASSERT_EQ(got.size(), 1u) << "k=" << k << ": packet with a " << kWatchdog - 1
                              << "-clock gap was dropped";
    EXPECT_EQ(got[0], v1_motion(1, 320 + int32_t(k), -160, 1200)) << "k=" << k;
    EXPECT_TRUE(b.timeouts().empty()) << "k=" << k << ": timeout at cycle " << b.timeouts()[0];
  }
  const auto pkt = init_packet(123456789u, 987654321u);
  b.bytes(pkt, 0, 4);
  b.idle(kWatchdog - 1);
  b.bytes(pkt, 4);
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_init(123456789u, 987654321u));
  EXPECT_TRUE(b.timeouts().empty());
}

// One million random bytes in auto mode: tready stays high, every entry matches the reference
// framer (noise first bytes discarded, 0xA5 frames skipped), and after 100 ms of silence a valid
// packet decodes to its fields.
TEST(FrameDecoderV1, RandomBytesMatchReference) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260501, "RandomBytesMatchReference");
  std::mt19937_64 rng(seed);
  DecoderBench b;
  RefFramer ref;
  std::vector<Entry> want;
  uint64_t compared = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    // Random bytes; often a v1 first byte (0x00..0x03 or 0xFF) so that many packets start.
    uint8_t v = static_cast<uint8_t>(rng());
    const uint64_t r = rng() % 16;
    if (r == 0) v = 0xFF;
    if (r == 1 || r == 2) v = static_cast<uint8_t>(rng() % 4);
    const uint64_t gap = (rng() % 8 == 0) ? rng() % 50 : 0;
    b.byte(v, gap);
    if (auto c = ref.push(v)) want.push_back(*c);
    if (i % 4096 == 0 || i == 999'999) {
      b.idle(2);
      auto got = b.take();
      ASSERT_EQ(got.size(), want.size())
          << "byte " << i << " cycle " << b.cycle() << " seed " << seed;
      for (size_t j = 0; j < got.size(); ++j)
        ASSERT_EQ(got[j], want[j]) << "entry " << compared + j << " seed " << seed;
      compared += got.size();
      want.clear();
      ASSERT_EQ(b.noise(), ref.noise()) << "noise bytes, byte " << i << " seed " << seed;
    }
  }
  EXPECT_EQ(b.not_ready(), 0u) << "s_axis_tready fell";
  EXPECT_TRUE(b.overruns().empty());
  EXPECT_TRUE(b.timeouts().empty());
  EXPECT_EQ(b.cfg_writes(), 0u);
  EXPECT_GT(compared, 30'000u);
  EXPECT_GT(ref.frames(), 100u) << "too few 0xA5 frames exercised";
  EXPECT_EQ(ref.good_frames(), 0u) << "seed " << seed
                                   << ": a random frame had a good CRC (the reference does not "
                                      "model the answers); pick another seed";
  const bool partial = ref.partial();
  b.idle(kWatchdog);
  EXPECT_EQ(b.timeouts().size(), partial ? 1u : 0u) << "partial packet at the end: " << partial;
  b.bytes(motion_packet(2, -123456, 654321, 65535));
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_motion(2, -123456, 654321, 65535)) << "got " << got[0];
  std::printf(
      "random bytes: %llu entries compared, %llu v2 frames skipped, %llu noise, %llu clocks\n",
      static_cast<unsigned long long>(compared), static_cast<unsigned long long>(ref.frames()),
      static_cast<unsigned long long>(ref.noise()), static_cast<unsigned long long>(b.cycle()));
}

// A v1 packet completing while the FIFO is full is dropped with the overrun strobe.
TEST(FrameDecoderV1, OverrunWhenFifoFull) {
  DecoderBench b;
  b.dut().m_axis_tready = 0;
  b.bytes(motion_packet(1, 5, 6, 7));
  const uint64_t last = b.cycle();
  b.idle(3);
  ASSERT_EQ(b.overruns().size(), 1u) << "no overrun strobe after the packet ending at " << last;
  EXPECT_EQ(b.overruns()[0], last + 1) << "overrun strobe cycle (the CHECK edge)";
  EXPECT_TRUE(b.take().empty());
  EXPECT_EQ(b.v1_packets(), 0u);
  b.dut().m_axis_tready = 1;
  b.bytes(motion_packet(0, -1, 1, 100));
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_motion(0, -1, 1, 100));
  EXPECT_EQ(b.overruns().size(), 1u);
}

// First bytes other than 0x00..0x03, 0xFF and 0xA5 are discarded and counted, one strobe each.
TEST(FrameDecoderV1, NoiseFirstBytesDiscarded) {
  DecoderBench b;
  uint64_t n = 0;
  for (int v = 0x04; v < 0xFF; ++v) {
    if (v == 0xA5) continue;
    b.byte(static_cast<uint8_t>(v), 1);
    ++n;
  }
  EXPECT_EQ(b.noise(), n);
  b.idle(kWatchdog + 10);
  EXPECT_TRUE(b.timeouts().empty()) << "a noise byte started a packet";
  b.bytes(motion_packet(3, 7, -7, 77));
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_motion(3, 7, -7, 77));
}

// ================================================================ v2

TEST(FrameDecoderV2, CrcCheckValue) {
  const std::vector<uint8_t> s = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(v2::crc16(s), 0x29B1);
}

// The docs' host-frame vectors, byte exact from the builder, then decoded.
TEST(FrameDecoderV2, WorkedExamples) {
  using V = std::vector<uint8_t>;
  const V hello = {0xA5, 0x00, 0x00, 0x01, 0xDC, 0xBD};
  const V status = {0xA5, 0x00, 0x00, 0x02, 0xEC, 0xDE};
  const V cfg = {0xA5, 0x09, 0x01, 0x04, 0x00, 0x00, 0x64, 0x00,
                 0x64, 0x00, 0xC8, 0x00, 0xC8, 0xDC, 0x4C};
  const V line_s = {0xA5, 0x0A, 0x07, 0x10, 0x81, 0xFF, 0x00, 0x4C,
                    0x4B, 0x40, 0x01, 0x40, 0xFF, 0x60, 0xC0, 0xB7};
  const V line_l = {0xA5, 0x16, 0x08, 0x10, 0x01, 0xFF, 0x00, 0x4C, 0x4B, 0x40,
                    0x00, 0x00, 0x01, 0x40, 0xFF, 0xFF, 0xFF, 0x60, 0x00, 0x00,
                    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xD6, 0xAB};
  const V dwell = {0xA5, 0x04, 0x09, 0x11, 0x02, 0xFA, 0xF0, 0x80, 0x9D, 0x53};
  EXPECT_EQ(v2::hex(v2::hello()), v2::hex(hello));
  EXPECT_EQ(v2::hex(v2::status_query()), v2::hex(status));
  EXPECT_EQ(v2::hex(v2::config_axis(1, 0, 100, 100, 200, 200)), v2::hex(cfg));
  EXPECT_EQ(v2::hex(v2::line(7, 1, 255, 5'000'000, {320, -160}, true)), v2::hex(line_s));
  EXPECT_EQ(v2::hex(v2::line(8, 1, 255, 5'000'000, {320, -160, 0, 0}, false)), v2::hex(line_l));
  EXPECT_EQ(v2::hex(v2::dwell(9, 50'000'000)), v2::hex(dwell));

  DecoderBench b;
  b.frame(hello);
  EXPECT_EQ(b.hellos(), 1u);
  EXPECT_EQ(b.dut().v2_mode, 1) << "a good HELLO switches to v2 mode";
  b.frame(status);
  EXPECT_EQ(b.status_reqs(), 1u);
  EXPECT_TRUE(b.acks().empty()) << "HELLO/STATUS_QUERY are not ACKed";
  // next_seq 0: seq 0 FAULT_CLEAR, then the CONFIG_AXIS example (seq 1).
  b.frame(v2::fault_clear(0));
  EXPECT_EQ(b.fault_clears(), 1u);
  b.frame(cfg);
  ASSERT_EQ(b.cfg_writes(), 1u);
  EXPECT_EQ(b.dut().cfg_axis, 0u);
  EXPECT_EQ(b.dut().cfg_data, 0x0064'0064'00C8'00C8ull);
  for (uint8_t s = 2; s < 7; ++s) b.frame(v2::fault_clear(s));
  EXPECT_EQ(b.dut().next_seq, 7u);
  b.frame(line_s);
  b.frame(line_l);
  b.frame(dwell);
  EXPECT_EQ(b.dut().next_seq, 10u);
  auto got = b.take();
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0], v2_line(1, 255, 5'000'000, {320, -160})) << got[0];
  EXPECT_EQ(got[1], v2_line(1, 255, 5'000'000, {320, -160, 0, 0})) << got[1];
  EXPECT_EQ(got[2], v2_dwell(50'000'000)) << got[2];
  EXPECT_EQ(b.acks().size(), 10u);
  EXPECT_TRUE(b.naks().empty());
  EXPECT_EQ(b.frames_ok(), 12u);
  // NUMERATORS, 4-axis SHORT and int32 steps with negative values on every axis.
  b.frame(v2::numerators(10, 9'375'000, 4'000'000));
  b.frame(v2::line(11, 3, 7, 12345, {-1, 2, -32768, 32767}, true));
  b.frame(v2::line(12, 2, 0, 1, {-100000, 7, 8, -2147483647 - 1}, false));
  b.frame(v2::line(13, 0, 1, 0, {}, true));
  got = b.take();
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0], v2_num(9'375'000, 4'000'000)) << got[0];
  EXPECT_EQ(got[1], v2_line(3, 7, 12345, {-1, 2, -32768, 32767})) << got[1];
  EXPECT_EQ(got[2], v2_line(2, 0, 1, {-100000, 7, 8, -2147483647 - 1})) << got[2];
  EXPECT_EQ(got[3], v2_line(0, 1, 0, {})) << got[3];
  // Fewer axes than N_AXES: the others are 0 (stale payload bytes of earlier frames ignored).
  b.frame(v2::line(14, 1, 9, 100, {5}, false));
  b.frame(v2::line(15, 1, 9, 100, {5, -6, 7}, true));
  got = b.take();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], v2_line(1, 9, 100, {5})) << got[0];
  EXPECT_EQ(got[1], v2_line(1, 9, 100, {5, -6, 7})) << got[1];
  EXPECT_TRUE(b.naks().empty());
}

// Each NAK reason, its SEQ and cycle; nothing reaches the FIFO or the configuration.
TEST(FrameDecoderV2, NakReasons) {
  DecoderBench b;
  b.frame(v2::hello());
  b.clear_records();
  auto expect_nak = [&](const std::vector<uint8_t>& f, uint8_t seq, uint8_t reason,
                        const char* what) {
    const size_t n0 = b.naks().size();
    b.frame(f);
    ASSERT_EQ(b.naks().size(), n0 + 1) << what << ": " << v2::hex(f);
    EXPECT_EQ(b.naks().back().reason, reason) << what;
    EXPECT_EQ(b.naks().back().seq, seq) << what;
  };
  // BAD_CRC: each byte of a frame flipped in turn (a flip of SYNC is noise, not a frame).
  const auto good = v2::line(0, 1, 255, 1000, {10, 20}, true);
  for (size_t i = 1; i < good.size(); ++i) {
    auto bad = good;
    bad[i] ^= static_cast<uint8_t>(1u << (i % 8));
    const size_t n0 = b.naks().size();
    b.frame(bad);
    if (i == 1) b.idle(kWatchdog);  // a changed LEN may leave a cut frame: let it time out
    ASSERT_GE(b.naks().size(), n0 + 1) << "flip of byte " << i;
    if (i == 1) continue;  // LEN changed: a length/timeout error, not necessarily BAD_CRC
    EXPECT_EQ(b.naks()[n0].reason, v2::kBadCrc) << "flip of byte " << i;
    EXPECT_EQ(b.naks()[n0].seq, bad[2]) << "flip of byte " << i;
  }
  EXPECT_GE(b.crc_errors(), good.size() - 2);
  // BAD_LENGTH at once: LEN 65; the NAK strobe is high from the LEN byte's edge.
  b.byte(0xA5, 2);
  b.byte(65);
  const uint64_t len_edge = b.cycle();
  b.tick();
  ASSERT_FALSE(b.naks().empty());
  EXPECT_EQ(b.naks().back().cycle, len_edge) << "NAK strobe not on the LEN byte's edge";
  EXPECT_EQ(b.naks().back().reason, v2::kBadLength);
  EXPECT_EQ(b.naks().back().seq, 0u);
  // ... and the next byte is hunted from at once: a whole frame right behind decodes.
  b.frame(v2::fault_clear(0));
  EXPECT_EQ(b.fault_clears(), 1u) << "frame right after a LEN > 64 not decoded";
  // BAD_LENGTH for the type.
  expect_nak(v2::frame(v2::kDwell, 1, {1, 2, 3}), 1, v2::kBadLength, "DWELL with 3 bytes");
  expect_nak(v2::frame(v2::kHello, 9, {1}), 9, v2::kBadLength, "HELLO with a payload");
  expect_nak(v2::frame(v2::kNumerators, 1, std::vector<uint8_t>(9, 0)), 1, v2::kBadLength,
             "NUMERATORS with 9 bytes");
  expect_nak(v2::frame(v2::kConfigAxis, 1, std::vector<uint8_t>(8, 0)), 1, v2::kBadLength,
             "CONFIG_AXIS with 8 bytes");
  expect_nak(v2::frame(v2::kLine, 1, {0x81, 1, 0, 0, 0, 10, 0}), 1, v2::kBadLength,
             "LINE SHORT with an odd step byte");
  expect_nak(v2::frame(v2::kLine, 1, {0x01, 1, 0, 0, 0, 10, 0, 0}), 1, v2::kBadLength,
             "LINE int32 with 2 step bytes");
  expect_nak(v2::line(1, 1, 1, 100, {1, 2, 3, 4, 5}, true), 1, v2::kBadLength, "LINE, 5 axes");
  expect_nak(v2::line(1, 1, 1, 100, {1, 2, 3, 4, 5}, false), 1, v2::kBadLength,
             "LINE int32, 5 axes");
  expect_nak(v2::frame(v2::kLine, 1, {0x01, 1, 0, 0, 0}), 1, v2::kBadLength, "LINE of 5 bytes");
  // UNKNOWN_TYPE (reserved and undefined types), checked before the length.
  for (uint8_t t : {0x00, 0x09, 0x14, 0x25, 0x2F, 0x80, 0x84, 0xFF}) {
    expect_nak(v2::frame(t, 1, {1, 2, 3}), 1, v2::kUnknownType, "unknown type");
  }
  // BAD_FIELD.
  for (uint8_t f : {0x04, 0x08, 0x10, 0x20, 0x40}) {
    auto p = v2::line_payload(1, 1, 100, {1, 1}, true);
    p[0] |= f;
    expect_nak(v2::frame(v2::kLine, 1, p), 1, v2::kBadField, "LINE reserved flag bit");
  }
  expect_nak(v2::config_axis(1, 4, 1, 1, 1, 1), 1, v2::kBadField, "CONFIG_AXIS axis 4");
  expect_nak(v2::config_axis(1, 255, 1, 1, 1, 1), 1, v2::kBadField, "CONFIG_AXIS axis 255");
  // OUT_OF_ORDER: next_seq is 1; seq 2 .. 128 are ahead.
  for (uint8_t s : {2, 3, 100, 128}) {
    expect_nak(v2::line(s, 1, 1, 100, {1}, true), s, v2::kOutOfOrder, "ahead");
  }
  // TIMEOUT: cut after k bytes; SEQ as received, 0 before the SEQ byte.
  const auto f = v2::line(1, 1, 1, 100, {1, 2}, true);
  for (size_t k : {size_t{1}, size_t{2}, size_t{3}, size_t{4}, size_t{9}, f.size() - 1}) {
    const size_t n0 = b.naks().size(), t0 = b.timeouts().size();
    b.bytes(f, 0, k, 3);
    const uint64_t last = b.cycle() - 3;
    b.idle(kWatchdog);
    ASSERT_EQ(b.timeouts().size(), t0 + 1) << "k=" << k;
    EXPECT_EQ(b.timeouts().back(), last + kWatchdog) << "k=" << k;
    ASSERT_EQ(b.naks().size(), n0 + 1) << "k=" << k;
    EXPECT_EQ(b.naks().back().reason, v2::kTimeout) << "k=" << k;
    EXPECT_EQ(b.naks().back().seq, k >= 3 ? 1u : 0u) << "k=" << k;
    EXPECT_EQ(b.naks().back().cycle, last + kWatchdog) << "k=" << k;
  }
  EXPECT_TRUE(b.take().empty()) << "a rejected frame reached the FIFO";
  EXPECT_EQ(b.cfg_writes(), 0u);
  EXPECT_EQ(b.dut().next_seq, 1u);
  EXPECT_EQ(b.acks().size(), 1u) << "only the FAULT_CLEAR was ACKed";
  // FIFO_FULL: not accepted, next_seq unchanged, then accepted once there is room.
  b.dut().m_axis_tready = 0;
  expect_nak(v2::line(1, 1, 1, 100, {1}, true), 1, v2::kFifoFull, "FIFO full");
  expect_nak(v2::dwell(1, 5), 1, v2::kFifoFull, "FIFO full, DWELL");
  expect_nak(v2::numerators(1, 5, 6), 1, v2::kFifoFull, "FIFO full, NUMERATORS");
  b.frame(v2::config_axis(1, 3, 1, 2, 3, 4));  // not a FIFO frame: accepted
  EXPECT_EQ(b.cfg_writes(), 1u);
  EXPECT_EQ(b.dut().cfg_axis, 3u);
  EXPECT_EQ(b.dut().cfg_data, 0x0001'0002'0003'0004ull);
  EXPECT_EQ(b.dut().next_seq, 2u);
  b.dut().m_axis_tready = 1;
  b.frame(v2::line(2, 1, 1, 100, {1}, true));
  EXPECT_EQ(b.take().size(), 1u);
  EXPECT_EQ(b.dut().next_seq, 3u);
  EXPECT_EQ(b.dut().v2_mode, 1);
}

// Duplicates (next_seq - 1 .. next_seq - 128) are ACKed and not executed; next_seq wraps.
TEST(FrameDecoderV2, DuplicatesAndWrap) {
  DecoderBench b;
  b.frame(v2::hello());
  // 300 accepted frames: next_seq wraps to 300 mod 256 = 44.
  for (int i = 0; i < 300; ++i) b.frame(v2::line(static_cast<uint8_t>(i), 1, 1, 10, {i}, true));
  EXPECT_EQ(b.dut().next_seq, 44u);
  ASSERT_EQ(b.take().size(), 300u);
  b.clear_records();
  // Duplicates: every seq in next_seq-128 .. next_seq-1.
  for (int d = 1; d <= 128; ++d) {
    const uint8_t s = static_cast<uint8_t>(44 - d);
    b.frame(v2::line(s, 1, 1, 10, {99}, true));
    ASSERT_EQ(b.acks().size(), static_cast<size_t>(d)) << "duplicate seq " << int(s);
  }
  // The same for non-FIFO frames: a duplicate CONFIG_AXIS/FAULT_CLEAR does nothing.
  b.frame(v2::config_axis(43, 0, 1, 1, 1, 1));
  b.frame(v2::fault_clear(200));
  EXPECT_EQ(b.cfg_writes(), 0u);
  EXPECT_EQ(b.fault_clears(), 0u);
  EXPECT_TRUE(b.take().empty()) << "a duplicate was enqueued";
  EXPECT_TRUE(b.naks().empty());
  EXPECT_EQ(b.dut().next_seq, 44u);
  // next_seq - 129 = next_seq + 127 is ahead.
  b.frame(v2::line(static_cast<uint8_t>(44 - 129), 1, 1, 10, {1}, true));
  ASSERT_EQ(b.naks().size(), 1u);
  EXPECT_EQ(b.naks()[0].reason, v2::kOutOfOrder);
  // Out of order then go-back-N: 45 (ahead) NAKed, 44 then 45 accepted.
  b.frame(v2::line(45, 1, 1, 10, {45}, true));
  b.frame(v2::line(44, 1, 1, 10, {44}, true));
  b.frame(v2::line(45, 1, 1, 10, {45}, true));
  auto got = b.take();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].steps[0], 44);
  EXPECT_EQ(got[1].steps[0], 45);
  EXPECT_EQ(b.naks().size(), 2u);
  EXPECT_EQ(b.dut().next_seq, 46u);
}

// Modes: a good v2 frame -> v2 mode (v1 bytes are noise); RELEASE -> auto (v1 works again).
// A frame with a bad CRC does not switch the mode.
TEST(FrameDecoderV2, ModesAndRelease) {
  DecoderBench b;
  auto bad = v2::hello();
  bad[4] ^= 1;
  b.frame(bad);
  EXPECT_EQ(b.dut().v2_mode, 0);
  b.bytes(motion_packet(1, 1, 2, 3));
  b.idle(2);
  EXPECT_EQ(b.take().size(), 1u);
  b.frame(v2::status_query());
  EXPECT_EQ(b.dut().v2_mode, 1);
  b.bytes(motion_packet(1, 1, 2, 3));
  b.bytes(init_packet(1, 2));
  b.idle(kWatchdog + 10);
  EXPECT_TRUE(b.take().empty()) << "v1 packet decoded in v2 mode";
  EXPECT_TRUE(b.timeouts().empty()) << "v1 bytes started a packet in v2 mode";
  EXPECT_EQ(b.noise(), 20u);
  b.frame(v2::release(0));
  EXPECT_EQ(b.releases(), 1u);
  EXPECT_EQ(b.dut().v2_mode, 0);
  EXPECT_EQ(b.dut().next_seq, 1u);
  b.bytes(motion_packet(2, -5, 5, 50));
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], v1_motion(2, -5, 5, 50));
  // A duplicate RELEASE (its ACK was lost) also leaves auto mode in place.
  b.frame(v2::release(0));
  EXPECT_EQ(b.dut().v2_mode, 0);
  EXPECT_EQ(b.releases(), 1u);
  EXPECT_EQ(b.acks().size(), 2u);
}

// Ten million random bytes after a HELLO (v2 mode): no FIFO or configuration write, tready
// always high, no hang; then a valid LINE frame is enqueued.
TEST(FrameDecoderV2, RandomBytesInV2Mode) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260505, "RandomBytesInV2Mode");
  std::mt19937_64 rng(seed);
  DecoderBench b;
  b.frame(v2::hello());
  b.clear_records();
  uint64_t a5 = 0;
  for (int i = 0; i < 10'000'000; ++i) {
    const uint64_t r = rng();
    // Some 0xA5 bytes more than chance, so that many frames start.
    const uint8_t v = (r & 0xF00) == 0 ? 0xA5 : static_cast<uint8_t>(r);
    if (v == 0xA5) ++a5;
    b.byte(v, (r >> 16) & 1);
  }
  EXPECT_EQ(b.write_cycles().size(), 0u) << "seed " << seed << ": random bytes reached the FIFO";
  EXPECT_EQ(b.cfg_writes(), 0u) << "seed " << seed;
  EXPECT_EQ(b.fault_clears(), 0u) << "seed " << seed;
  EXPECT_EQ(b.not_ready(), 0u);
  EXPECT_EQ(b.dut().v2_mode, 1);
  EXPECT_GT(b.naks().size(), 10'000u) << "few frames were rejected: too few were tried";
  EXPECT_GT(b.noise(), 1'000'000u);
  b.idle(kWatchdog + 2);
  const uint8_t seq = b.dut().next_seq;
  EXPECT_EQ(seq, 0u) << "seed " << seed << ": a random frame was accepted";
  b.frame(v2::line(seq, 1, 200, 777, {-3, 4}, true));
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u) << "seed " << seed << ": the LINE after the noise was not enqueued";
  EXPECT_EQ(got[0], v2_line(1, 200, 777, {-3, 4}));
  std::printf("v2 noise: %llu 0xA5, %zu NAKs, %llu CRC errors, %llu length errors, %llu clocks\n",
              static_cast<unsigned long long>(a5), b.naks().size(),
              static_cast<unsigned long long>(b.crc_errors()),
              static_cast<unsigned long long>(b.length_errors()),
              static_cast<unsigned long long>(b.cycle()));
}

}  // namespace

// The worked frames of spec/vectors.txt (generated from spec/protocol.toml; the host codec test
// and the twin codec test read the same file): each into a fresh decoder in v2 mode whose
// next_seq is the frame's SEQ (reached with FAULT_CLEAR frames); the answer strobes and the FIFO
// entry are the stated ones.
TEST(FrameDecoderV2, SpecVectors) {
  namespace spec = fpgacnc::spec;
  const auto vectors = spec::load_vectors();
  size_t checked = 0, entries = 0;
  for (const auto& v : vectors) {
    if (!v.has_answer) continue;  // device frames
    SCOPED_TRACE(v.name + ": " + v.doc);
    DecoderBench b;
    b.frame(v2::hello());
    for (int s = 0; s < v.seq; ++s)
      b.frame(v2::frame(v2::kFaultClear, static_cast<uint8_t>(s), {}));
    ASSERT_EQ(b.naks().size(), 0u);
    ASSERT_EQ(b.acks().size(), size_t{v.seq});
    b.clear_records();
    b.frame(v.bytes);
    b.idle(4);
    const auto got = b.take();
    if (v.answer == "NAK") {
      ASSERT_EQ(b.naks().size(), 1u);
      EXPECT_EQ(b.naks()[0].reason, v.answer_value) << "NAK " << v.nak_name;
      EXPECT_EQ(b.naks()[0].seq, v.seq) << "the NAK names the SEQ as received";
      EXPECT_TRUE(b.acks().empty());
      EXPECT_TRUE(got.empty());
    } else {
      EXPECT_TRUE(b.naks().empty());
      EXPECT_EQ(b.frames_ok(), 1u);
      EXPECT_EQ(b.hellos(), v.answer == "IDENT" ? 1u : 0u);
      EXPECT_EQ(b.status_reqs(), v.answer == "STATUS" ? 1u : 0u);
      EXPECT_EQ(b.acks().size(), v.answer == "ACK" ? 1u : 0u);
      EXPECT_EQ(b.dut().v2_mode, 1);
      ASSERT_EQ(got.size(), v.has_entry() ? 1u : 0u);
      if (v.has_entry()) {
        const Entry& e = got[0];
        EXPECT_EQ(e.kind, v.entry_field("kind"));
        EXPECT_EQ(e.v2, v.entry_field("v2") != 0);
        EXPECT_EQ(e.code, v.entry_field("code"));
        EXPECT_EQ(e.power, v.entry_field("power"));
        EXPECT_EQ(e.t, v.entry_field("t"));
        const auto steps = v.entry_steps();
        for (int a = 0; a < kAxes; ++a)
          EXPECT_EQ(e.steps[a], a < static_cast<int>(steps.size()) ? steps[a] : 0) << "axis " << a;
        EXPECT_EQ(e.prof, static_cast<uint64_t>(v.entry_field("prof")));
        EXPECT_EQ(e.v_entry, static_cast<uint64_t>(v.entry_field("v_entry")));
        EXPECT_EQ(e.v_cruise, static_cast<uint64_t>(v.entry_field("v_cruise")));
        EXPECT_EQ(e.v_exit, static_cast<uint64_t>(v.entry_field("v_exit")));
        EXPECT_EQ(e.decel_at, static_cast<uint64_t>(v.entry_field("decel_at")));
        EXPECT_EQ(e.arc, static_cast<uint64_t>(v.entry_field("arc")));
        // ARC: the payload's bytes 2.. as received; else 0
        std::vector<uint8_t> raw(e.arc_raw.size(), 0);
        if (v.entry_field("arc") != 0)
          for (size_t k = 0; k < raw.size() && 6 + k < v.bytes.size() - 2; ++k)
            raw[k] = v.bytes[6 + k];
        EXPECT_EQ(e.arc_raw, raw);
        ++entries;
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 15u);
  EXPECT_GE(entries, 7u);
}

// The worked sequences of spec/vectors.txt into a fresh decoder, back to back: one answer request
// per frame (IDENT, ACK or NAK with the SEQ as received and the reason); the NAK frames the
// sequence states are among the NAK requests, in order (a coalesced NAK is the last request of
// its group: the response encoder's part, checked through cnc_core's pins by
// test_spec_sequences), and the last request is always the last NAK sent.
TEST(FrameDecoderV2, SpecSequencesRequests) {
  namespace spec = fpgacnc::spec;
  const auto seqs = spec::load_sequences();
  ASSERT_GE(seqs.size(), 2u);
  for (const auto& s : seqs) {
    SCOPED_TRACE(s.name + ": " + s.doc);
    DecoderBench b;
    b.bytes(s.host_bytes(), 0, SIZE_MAX, 3);
    b.idle(4);
    EXPECT_EQ(b.hellos() + b.status_reqs() + b.acks().size() + b.naks().size(), s.sends.size())
        << "one answer request per frame";
    size_t k = 0, stated = 0;  // the stated NAKs, in order, among the requests
    for (const auto& r : s.replies) {
      if (r.type != v2::kNak) continue;
      ++stated;
      while (k < b.naks().size() &&
             !(b.naks()[k].seq == r.field("seq") && b.naks()[k].reason == r.field("reason")))
        ++k;
      EXPECT_LT(k, b.naks().size()) << "NAK of seq " << r.field("seq") << " requested";
      ++k;
    }
    if (stated > 0) {
      EXPECT_EQ(k, b.naks().size()) << "the last request is the last NAK";
    }
  }
}
