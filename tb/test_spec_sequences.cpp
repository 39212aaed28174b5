// The worked sequences of spec/vectors.txt (generated from spec/protocol.toml; the host codec
// test and the twin board test read the same file) through cnc_core's pins, the default board
// (N_AXES 4, 50 MHz, 115 200 baud): each from reset, the host frames bit-banged onto rx back to
// back (UartDriver, no idle time between bytes), every byte on tx collected until the line has
// been quiet for 20 byte times. The device frames are the stated ones, byte exact and in order:
// where rejections coalesce, the NAK describes the last frame rejected before it was decided.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <vector>

#include "Vcnc_core.h"
#include "common/core_pins.h"
#include "common/v2_frames.h"
#include "fpgacnc/spec_vectors.h"

namespace {

namespace v2 = fpgacnc::tb::v2;

constexpr uint64_t kByteClocks = 4341;  // 10 bits at 115 200 baud, rounded up

class SeqBench : public fpgacnc::tb::PinHarness<Vcnc_core> {
 public:
  SeqBench() : PinHarness(fpgacnc::tb::kCoreAxes, fpgacnc::tb::kCorePins) {
    fpgacnc::tb::reset_core(*this);
  }
  // Cycles on which cnc_core's `naks` counter (NAKs requested by the decoder) went up.
  const std::vector<uint64_t>& nak_requests() const { return nak_requests_; }

 protected:
  void observe() override {
    if (dut().naks != naks_) {
      naks_ = dut().naks;
      nak_requests_.push_back(cycle());
    }
  }

 private:
  uint16_t naks_ = 0;
  std::vector<uint64_t> nak_requests_;
};

TEST(SpecSequences, CncCorePins) {
  const auto seqs = fpgacnc::spec::load_sequences();
  ASSERT_GE(seqs.size(), 2u);
  size_t coalesced = 0;
  for (const auto& s : seqs) {
    SCOPED_TRACE(s.name + ": " + s.doc);
    SeqBench b;
    const uint64_t t0 = b.cycle();
    b.send(s.host_bytes());
    uint64_t quiet = 0;
    size_t n = b.tx_bytes().size();
    while (quiet < 20 * kByteClocks) {
      b.tick();
      if (b.tx_bytes().size() != n) {
        n = b.tx_bytes().size();
        quiet = 0;
      } else {
        ++quiet;
      }
    }
    std::vector<uint8_t> got;
    v2::DeviceParser parser;
    std::vector<v2::DeviceMsg> msgs;
    for (const auto& x : b.tx_bytes()) {
      EXPECT_TRUE(x.framing_ok) << "tx byte at cycle " << x.start_cycle;
      got.push_back(x.value);
      if (auto m = parser.push(x.value, x.start_cycle)) msgs.push_back(*m);
    }
    EXPECT_EQ(v2::hex(got), v2::hex(s.device_bytes())) << "the device frames, byte exact";
    // The same, frame by frame: a failure names the NAK that differs.
    ASSERT_EQ(msgs.size(), s.replies.size());
    size_t naks = 0;
    for (size_t i = 0; i < msgs.size(); ++i) {
      const auto& r = s.replies[i];
      EXPECT_TRUE(msgs[i].crc_ok);
      EXPECT_EQ(msgs[i].type, r.type) << "reply " << i;
      EXPECT_EQ(msgs[i].seq, i) << "device SEQ of reply " << i;
      if (r.type == v2::kNak && msgs[i].type == v2::kNak) {
        EXPECT_EQ(msgs[i].u8(0), r.field("seq")) << "NAK " << i << ": SEQ of the rejected frame";
        EXPECT_EQ(msgs[i].u8(1), r.field("reason")) << "NAK " << i << ": reason";
        EXPECT_EQ(msgs[i].u8(2), r.field("next_seq")) << "NAK " << i << ": next_seq";
        ++naks;
      }
    }
    coalesced += b.nak_requests().size() > naks;
    // The timing behind it (docs/protocol.md "Coalesced NAK"): each NAK request and each device
    // frame's first byte, in byte times after the first host byte.
    std::printf("%s: NAK requests at byte", s.name.c_str());
    for (uint64_t c : b.nak_requests()) std::printf(" %.3f", static_cast<double>(c - t0) / 4340.28);
    std::printf("; device frames start at byte");
    for (const auto& m : msgs) std::printf(" %.3f", static_cast<double>(m.cycle - t0) / 4340.28);
    std::printf("\n");
  }
  EXPECT_GE(coalesced, 1u) << "a sequence where one NAK stands for several rejections";
}

}  // namespace
