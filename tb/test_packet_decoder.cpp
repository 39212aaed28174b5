// Bench for packet_decoder_v1, driven byte by byte on s_axis (no UART): the worked examples of
// protocol-v1.md, the 100 ms watchdog at its exact boundary, a million random bytes against a C++
// reference model, and the overrun drop.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "Vpacket_decoder_v1.h"
#include "common/seed.h"
#include "common/v1_packets.h"
#include "verilated.h"

namespace {

using fpgacnc::tb::init_packet;
using fpgacnc::tb::motion_packet;
using fpgacnc::tb::put32;

constexpr uint64_t kWatchdog = 5'000'000;  // WATCHDOG_CLKS default (100 ms at 50 MHz)

struct Command {
  bool init = false;
  uint32_t code = 0;
  uint32_t a = 0, b = 0;  // init: NUMERATOR_X/Y; motion: steps_x/steps_y (two's complement)
  uint32_t feed = 0;
  bool operator==(const Command& o) const {
    return init == o.init && code == o.code && a == o.a && b == o.b && feed == o.feed;
  }
};

std::ostream& operator<<(std::ostream& os, const Command& c) {
  return os << (c.init ? "init" : "motion") << "{code " << c.code << ", a "
            << static_cast<int32_t>(c.a) << ", b " << static_cast<int32_t>(c.b) << ", feed "
            << c.feed << "}";
}

// Reference model of the byte framing (protocol-v1.md), without the watchdog.
class RefDecoder {
 public:
  std::optional<Command> push(uint8_t byte) {
    buf_.push_back(byte);
    const size_t len = buf_[0] == 0xFF ? 9 : 11;
    if (buf_.size() < len) return std::nullopt;
    Command c;
    auto be32 = [&](size_t i) {
      return (uint32_t{buf_[i]} << 24) | (uint32_t{buf_[i + 1]} << 16) |
             (uint32_t{buf_[i + 2]} << 8) | uint32_t{buf_[i + 3]};
    };
    c.init = buf_[0] == 0xFF;
    c.a = be32(1);
    c.b = be32(5);
    if (c.init) {
      c.code = 3;
      c.feed = 0;
    } else {
      c.code = buf_[0] & 3u;
      c.feed = (uint32_t{buf_[9]} << 8) | buf_[10];
    }
    buf_.clear();
    return c;
  }
  bool partial() const { return !buf_.empty(); }
  void drop() { buf_.clear(); }

 private:
  std::vector<uint8_t> buf_;
};

class DecoderBench {
 public:
  DecoderBench() : ctx_(std::make_unique<VerilatedContext>()) {
    m_ = std::make_unique<Vpacket_decoder_v1>(ctx_.get());
    m_->s_axis_tvalid = 0;
    m_->m_axis_tready = 1;
    m_->rst = 1;
    tick();
    tick();
    m_->rst = 0;
    tick();
  }
  ~DecoderBench() { m_->final(); }

  void tick() {
    // A transfer is a clock edge with valid and ready both high: record it before the edge.
    if (m_->m_axis_tvalid && m_->m_axis_tready) out_.push_back(read_out());
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    if (!m_->s_axis_tready) ++not_ready_;
    if (m_->timeout) timeouts_.push_back(cycle_);
    if (m_->overrun) overruns_.push_back(cycle_);
    if (m_->packet_done) {
      ++done_;
      if (!m_->m_axis_tvalid)
        ADD_FAILURE() << "packet_done at cycle " << cycle_ << " without m_axis_tvalid";
    }
  }

  // Presents one byte for one clock (s_axis_tready is required to be high).
  void byte(uint8_t b, uint64_t gap = 0) {
    m_->s_axis_tdata = b;
    m_->s_axis_tvalid = 1;
    if (!m_->s_axis_tready) ADD_FAILURE() << "s_axis_tready low at cycle " << cycle_;
    tick();
    m_->s_axis_tvalid = 0;
    idle(gap);
  }
  void bytes(const std::vector<uint8_t>& v, size_t from = 0, size_t to = SIZE_MAX) {
    for (size_t i = from; i < v.size() && i < to; ++i) byte(v[i]);
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) tick();
  }

  Command read_out() const {
    const auto& w = m_->m_axis_tdata;  // 82 bits: {code, a, b, feed}
    auto bits = [&](int lo, int width) {
      uint64_t v = 0;
      for (int i = 0; i < width; ++i) {
        const int bit = lo + i;
        v |= static_cast<uint64_t>((w[bit / 32] >> (bit % 32)) & 1u) << i;
      }
      return static_cast<uint32_t>(v);
    };
    Command c;
    c.init = m_->m_axis_tuser != 0;
    c.code = bits(80, 2);
    c.a = bits(48, 32);
    c.b = bits(16, 32);
    c.feed = bits(0, 16);
    return c;
  }

  // Commands transferred so far (taken off the list).
  std::vector<Command> take() {
    std::vector<Command> r;
    r.swap(out_);
    return r;
  }

  Vpacket_decoder_v1& dut() { return *m_; }
  uint64_t cycle() const { return cycle_; }
  uint64_t not_ready() const { return not_ready_; }
  uint64_t done() const { return done_; }
  const std::vector<uint64_t>& timeouts() const { return timeouts_; }
  const std::vector<uint64_t>& overruns() const { return overruns_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vpacket_decoder_v1> m_;
  uint64_t cycle_ = 0, not_ready_ = 0, done_ = 0;
  std::vector<Command> out_;
  std::vector<uint64_t> timeouts_, overruns_;
};

Command init_cmd(uint32_t nx, uint32_t ny) {
  return Command{true, 3, nx, ny, 0};
}
Command motion_cmd(uint32_t code, int32_t sx, int32_t sy, uint32_t feed) {
  return Command{false, code & 3u, static_cast<uint32_t>(sx), static_cast<uint32_t>(sy), feed};
}

TEST(PacketDecoder, WorkedExamples) {
  DecoderBench b;
  const std::vector<uint8_t> init = {0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30};
  const std::vector<uint8_t> motion = {0x01, 0x00, 0x00, 0x01, 0x40, 0xFF,
                                       0xFF, 0xFF, 0x60, 0x04, 0xB0};
  EXPECT_EQ(init, init_packet(18'750'000, 18'750'000));
  EXPECT_EQ(motion, motion_packet(1, 320, -160, 1200));

  b.bytes(init);
  const uint64_t last_init = b.cycle();
  b.tick();
  // Latency: valid on the clock after the last byte is accepted.
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u) << "init packet: expected one command by cycle " << last_init + 1;
  EXPECT_EQ(got[0], init_cmd(18'750'000, 18'750'000));
  EXPECT_TRUE(got[0].init);

  b.bytes(motion);
  b.idle(3);
  got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], motion_cmd(1, 320, -160, 1200)) << "got " << got[0];
  EXPECT_FALSE(got[0].init);
  EXPECT_EQ(static_cast<int32_t>(got[0].a), 320);
  EXPECT_EQ(static_cast<int32_t>(got[0].b), -160);
  EXPECT_EQ(got[0].feed, 1200u);
  EXPECT_EQ(b.done(), 2u);
  EXPECT_TRUE(b.timeouts().empty());
  EXPECT_TRUE(b.overruns().empty());
  EXPECT_EQ(b.not_ready(), 0u);
}

// A packet cut off after k bytes plus exactly WATCHDOG_CLKS clocks of silence is dropped; the
// next full packet decodes. Init and motion packets alternate as the cut one.
TEST(PacketDecoder, WatchdogDropsCutPacket) {
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
    EXPECT_TRUE(b.take().empty()) << "k=" << k << ": cut packet produced a command";
    const Command want = motion_cmd(3, 1000 + int32_t(k), -int32_t(k), 4321);
    b.bytes(motion_packet(3, 1000 + int32_t(k), -int32_t(k), 4321));
    b.idle(2);
    auto got = b.take();
    ASSERT_EQ(got.size(), 1u) << "k=" << k << ": packet after the drop not decoded";
    EXPECT_EQ(got[0], want) << "k=" << k << ": got " << got[0];
  }
  EXPECT_EQ(b.timeouts().size(), 10u);
}

// Boundary: a gap of WATCHDOG_CLKS - 1 clocks inside a packet does not drop it.
TEST(PacketDecoder, WatchdogBoundaryKeepsPacket) {
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
    EXPECT_EQ(got[0], motion_cmd(1, 320 + int32_t(k), -160, 1200)) << "k=" << k;
    EXPECT_TRUE(b.timeouts().empty()) << "k=" << k << ": timeout at cycle " << b.timeouts()[0];
  }
  // Same for an init packet cut after byte 4.
  const auto pkt = init_packet(123456789u, 987654321u);
  b.bytes(pkt, 0, 4);
  b.idle(kWatchdog - 1);
  b.bytes(pkt, 4);
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], init_cmd(123456789u, 987654321u));
  EXPECT_TRUE(b.timeouts().empty());
}

// One million random bytes: tready stays high, every command matches the reference model, and
// after 100 ms of silence a valid packet decodes to its fields.
TEST(PacketDecoder, RandomBytesNeverHang) {
  const uint64_t seed = fpgacnc::tb::test_seed(20260501, "RandomBytesNeverHang");
  std::mt19937_64 rng(seed);
  DecoderBench b;
  RefDecoder ref;
  std::vector<Command> want;
  uint64_t compared = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    // Mostly random bytes; sometimes 0xFF to start init packets more often.
    const uint8_t v = (rng() % 16 == 0) ? 0xFF : static_cast<uint8_t>(rng());
    const uint64_t gap = (rng() % 8 == 0) ? rng() % 50 : 0;
    b.byte(v, gap);
    if (auto c = ref.push(v)) want.push_back(*c);
    if (i % 4096 == 0 || i == 999'999) {
      b.idle(2);
      auto got = b.take();
      ASSERT_EQ(got.size(), want.size())
          << "byte " << i << " cycle " << b.cycle() << " seed " << seed;
      for (size_t j = 0; j < got.size(); ++j)
        ASSERT_EQ(got[j], want[j]) << "command " << compared + j << " seed " << seed;
      compared += got.size();
      want.clear();
    }
  }
  EXPECT_EQ(b.not_ready(), 0u) << "s_axis_tready fell";
  EXPECT_TRUE(b.overruns().empty());
  EXPECT_TRUE(b.timeouts().empty());
  EXPECT_GT(compared, 50'000u);
  const bool partial = ref.partial();
  b.idle(kWatchdog);
  EXPECT_EQ(b.timeouts().size(), partial ? 1u : 0u) << "partial packet at the end: " << partial;
  b.bytes(motion_packet(2, -123456, 654321, 65535));
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], motion_cmd(2, -123456, 654321, 65535)) << "got " << got[0];
  std::printf("random bytes: %llu commands compared, %llu clocks\n",
              static_cast<unsigned long long>(compared),
              static_cast<unsigned long long>(b.cycle()));
}

// A second complete packet while m_axis_tready is low is dropped with the overrun strobe; the
// held command is kept.
TEST(PacketDecoder, OverrunDropsSecondPacket) {
  DecoderBench b;
  b.dut().m_axis_tready = 0;
  b.bytes(motion_packet(1, 5, 6, 7));
  b.idle(3);
  ASSERT_TRUE(b.dut().m_axis_tvalid);
  EXPECT_EQ(b.read_out(), motion_cmd(1, 5, 6, 7));
  b.bytes(init_packet(1, 2));
  const uint64_t last = b.cycle();
  b.idle(3);
  ASSERT_EQ(b.overruns().size(), 1u) << "no overrun strobe after the packet ending at " << last;
  EXPECT_EQ(b.overruns()[0], last) << "overrun strobe cycle";
  EXPECT_EQ(b.done(), 1u) << "the dropped packet must not strobe packet_done";
  EXPECT_TRUE(b.dut().m_axis_tvalid);
  EXPECT_EQ(b.read_out(), motion_cmd(1, 5, 6, 7)) << "held command changed by the dropped packet";
  b.dut().m_axis_tready = 1;
  b.idle(2);
  auto got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], motion_cmd(1, 5, 6, 7));
  EXPECT_FALSE(b.dut().m_axis_tvalid);
  b.bytes(motion_packet(0, -1, 1, 100));
  b.idle(2);
  got = b.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], motion_cmd(0, -1, 1, 100));
  EXPECT_EQ(b.overruns().size(), 1u);
}

}  // namespace
