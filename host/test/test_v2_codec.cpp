// Protocol v2 codec: every worked example of docs/protocol.md byte-exact (encode and decode), the
// CRC check value, the resyncing parser, and decoders rejecting wrong types and lengths.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

#include "fpgacnc/protocol/v2.h"
#include "stream_plan.h"

namespace v2 = fpgacnc::protocol::v2;
using Bytes = std::vector<uint8_t>;

namespace {

// "A5 0A 07" -> bytes (the docs' notation).
Bytes from_hex(const std::string& s) {
  Bytes b;
  size_t i = 0;
  while (i < s.size()) {
    if (s[i] == ' ') {
      ++i;
      continue;
    }
    b.push_back(static_cast<uint8_t>(std::stoul(s.substr(i, 2), nullptr, 16)));
    i += 2;
  }
  return b;
}

v2::Frame parse_one(const Bytes& b) {
  v2::FrameParser p;
  p.feed(b);
  auto f = p.next();
  EXPECT_TRUE(f.has_value()) << v2::hex(b);
  EXPECT_FALSE(p.next().has_value());
  EXPECT_EQ(p.crc_errors(), 0u);
  EXPECT_EQ(p.noise_bytes(), 0u);
  return f.value_or(v2::Frame{});
}

uint32_t codec_seed() {
  const char* e = std::getenv("FPGACNC_SEED");
  return e ? static_cast<uint32_t>(std::strtoul(e, nullptr, 10)) : 20260005u;
}

}  // namespace

TEST(V2Codec, CrcCheckValue) {
  const std::string s = "123456789";
  const Bytes b(s.begin(), s.end());
  EXPECT_EQ(v2::crc16(b), 0x29B1);
  EXPECT_EQ(v2::crc16({}), 0xFFFF);
}

TEST(V2Codec, CrcMatchesBitwiseReference) {
  const uint32_t seed = codec_seed();
  std::printf("seed %u (FPGACNC_SEED)\n", seed);
  std::mt19937 rng(seed);
  for (int n = 0; n < 200; ++n) {
    Bytes b(rng() % 80);
    for (auto& x : b) x = static_cast<uint8_t>(rng());
    uint16_t c = 0xFFFF;
    for (const uint8_t x : b) {
      c ^= static_cast<uint16_t>(x << 8);
      for (int k = 0; k < 8; ++k) {
        c = (c & 0x8000) ? static_cast<uint16_t>((c << 1) ^ 0x1021) : static_cast<uint16_t>(c << 1);
      }
    }
    ASSERT_EQ(v2::crc16(b), c) << "bytes " << v2::hex(b);
  }
}

TEST(V2Codec, WorkedExamplesEncode) {
  EXPECT_EQ(v2::encode(v2::hello()), from_hex("A5 00 00 01 DC BD"));
  EXPECT_EQ(v2::encode(v2::status_query()), from_hex("A5 00 00 02 EC DE"));
  EXPECT_EQ(v2::encode(v2::config_axis(1, 0, 100, 100, 200, 200)),
            from_hex("A5 09 01 04 00 00 64 00 64 00 C8 00 C8 DC 4C"));
  const std::array<int32_t, 2> xy{320, -160};
  EXPECT_EQ(v2::encode(v2::line(7, 1, 255, 5'000'000, xy)),
            from_hex("A5 0A 07 10 81 FF 00 4C 4B 40 01 40 FF 60 C0 B7"));
  const std::array<int32_t, 4> xyze{320, -160, 0, 0};
  EXPECT_EQ(v2::encode(v2::line(8, 1, 255, 5'000'000, xyze, false)),
            from_hex("A5 16 08 10 01 FF 00 4C 4B 40 00 00 01 40 FF FF FF 60 00 00 00 00 00 00 "
                     "00 00 D6 AB"));
  EXPECT_EQ(v2::encode(v2::dwell(9, 50'000'000)), from_hex("A5 04 09 11 02 FA F0 80 9D 53"));
  EXPECT_EQ(v2::encode(v2::ack(0, {8, 63, 5})), from_hex("A5 07 00 80 08 00 3F 00 00 00 05 AA 5D"));
  EXPECT_EQ(v2::encode(v2::nak(1, {9, v2::NakReason::BadCrc, 8, 63})),
            from_hex("A5 05 01 81 09 01 08 00 3F E0 B4"));
}

TEST(V2Codec, WorkedExamplesDecode) {
  auto f = parse_one(from_hex("A5 00 00 01 DC BD"));
  EXPECT_EQ(f.type, static_cast<uint8_t>(v2::Type::Hello));
  EXPECT_TRUE(f.payload.empty());
  EXPECT_EQ(parse_one(from_hex("A5 00 00 02 EC DE")).type,
            static_cast<uint8_t>(v2::Type::StatusQuery));

  f = parse_one(from_hex("A5 09 01 04 00 00 64 00 64 00 C8 00 C8 DC 4C"));
  EXPECT_EQ(f.seq, 1);
  EXPECT_EQ(v2::decode_config_axis(f), (v2::ConfigAxis{0, 100, 100, 200, 200}));

  f = parse_one(from_hex("A5 0A 07 10 81 FF 00 4C 4B 40 01 40 FF 60 C0 B7"));
  EXPECT_EQ(f.seq, 7);
  auto l = v2::decode_line(f, 4);
  EXPECT_EQ(l, (v2::Line{1, 255, 5'000'000, true, {320, -160}}));

  f = parse_one(from_hex(
      "A5 16 08 10 01 FF 00 4C 4B 40 00 00 01 40 FF FF FF 60 00 00 00 00 00 00 00 00 D6 AB"));
  EXPECT_EQ(f.seq, 8);
  l = v2::decode_line(f, 4);
  EXPECT_EQ(l, (v2::Line{1, 255, 5'000'000, false, {320, -160, 0, 0}}));

  f = parse_one(from_hex("A5 04 09 11 02 FA F0 80 9D 53"));
  EXPECT_EQ(f.seq, 9);
  EXPECT_EQ(v2::decode_dwell(f), 50'000'000u);

  f = parse_one(from_hex("A5 07 00 80 08 00 3F 00 00 00 05 AA 5D"));
  EXPECT_EQ(f.type, static_cast<uint8_t>(v2::Type::Ack));
  EXPECT_EQ(v2::decode_credit(f), (v2::Credit{8, 63, 5}));

  f = parse_one(from_hex("A5 05 01 81 09 01 08 00 3F E0 B4"));
  EXPECT_EQ(f.seq, 1);
  EXPECT_EQ(v2::decode_nak(f), (v2::Nak{9, v2::NakReason::BadCrc, 8, 63}));
}

TEST(V2Codec, DeviceFramesRoundTrip) {
  const v2::Ident id{2, 4, 64, 50'000'000, 115200, 0x20260005, 17, 64};
  EXPECT_EQ(v2::decode_ident(parse_one(v2::encode(v2::ident(3, id)))), id);
  EXPECT_EQ(v2::encode(v2::ident(3, id)).size(), 6u + 18u);
  v2::Status st;
  st.state = v2::kStateBusy | v2::kStateV2;
  st.faults = 1;
  st.fifo_level = 63;
  st.next_seq = 200;
  st.done = 0xDEADBEEF;
  st.position = {-5, 7, 1 << 30, -(1 << 30)};
  for (size_t i = 0; i < v2::kCounters; ++i) st.counters[i] = static_cast<uint16_t>(1000 * i + 1);
  st.limit = 0x11;       // Y max
  st.switches = 0x0201;  // X min, Y max
  const auto sb = v2::encode(v2::status(4, st));
  EXPECT_EQ(sb.size(), 6u + 46u);
  // docs/protocol.md: the limit byte and the switch states (big-endian) follow the counters.
  EXPECT_EQ(sb[4 + 43], 0x11u);
  EXPECT_EQ(sb[4 + 44], 0x02u);
  EXPECT_EQ(sb[4 + 45], 0x01u);
  EXPECT_EQ(v2::decode_status(parse_one(sb), 4), st);
  st.faults = v2::kFaultLimit;
  st.state = v2::kStatePosUntrusted;
  EXPECT_EQ(v2::describe_limits(st, 4),
            "LIMIT alarm: Y max; switches: X min, Y max; positions not trusted (a hard limit "
            "tripped)");
  st.switches = 0;
  st.state = 0;
  st.faults = 0;
  EXPECT_EQ(v2::describe_limits(st, 4), "switches: none");
  const auto d = v2::decode_credit(parse_one(v2::encode(v2::done(9, {1, 2, 3}))));
  EXPECT_EQ(d, (v2::Credit{1, 2, 3}));
  const v2::Frame numf = v2::numerators(5, 18'750'000, 7'500'000);
  EXPECT_EQ(v2::encode(numf).size(), 14u);
  EXPECT_EQ(v2::decode_numerators(parse_one(v2::encode(numf))),
            (std::array<uint32_t, 2>{18'750'000, 7'500'000}));
}

// MOTION (docs/protocol.md "MOTION"): big-endian flags, feed, rapid, ramp; unsequenced, the
// device's field rules; STATUS bits 5 HOLD and 6 STOPPED.
TEST(V2Codec, MotionFrameLayoutAndRules) {
  v2::Motion m;
  m.resume = true;
  m.feed = 0x1234;
  m.rapid = 0x8000;
  m.ramp = 0x01020304;
  const auto b = v2::encode(v2::motion(m));
  ASSERT_EQ(b.size(), 6u + 9u);
  EXPECT_EQ(b[1], 9u);     // LEN
  EXPECT_EQ(b[2], 0u);     // SEQ
  EXPECT_EQ(b[3], 0x08u);  // TYPE MOTION
  const std::vector<uint8_t> payload(b.begin() + 4, b.end() - 2);
  EXPECT_EQ(payload, (std::vector<uint8_t>{0x02, 0x12, 0x34, 0x80, 0x00, 0x01, 0x02, 0x03, 0x04}));
  EXPECT_EQ(v2::decode_motion(parse_one(b)), m);
  EXPECT_FALSE(v2::is_sequenced(0x08));
  EXPECT_FALSE(v2::is_fifo(0x08));
  EXPECT_EQ(v2::type_name(0x08), "MOTION");

  // The device's rules: both flags, a reserved flag, a rate of 0 or above 0x8000, ramp 0.
  auto with = [](std::vector<uint8_t> p) {
    return v2::Frame{0, static_cast<uint8_t>(v2::Type::Motion), std::move(p)};
  };
  const std::vector<uint8_t> good{0x01, 0x80, 0x00, 0x40, 0x00, 0x00, 0x00, 0x00, 0x01};
  EXPECT_FALSE(v2::check_host_frame(with(good), 4).has_value());
  auto bad = [&](size_t i, uint8_t v) {
    auto p = good;
    p[i] = v;
    return v2::check_host_frame(with(p), 4);
  };
  EXPECT_EQ(bad(0, 0x03), v2::NakReason::BadField);  // HOLD and RESUME
  EXPECT_EQ(bad(0, 0x06), v2::NakReason::BadField);  // CANCEL and RESUME
  EXPECT_EQ(bad(0, 0x04), std::nullopt);             // CANCEL
  EXPECT_EQ(bad(0, 0x05), std::nullopt);             // HOLD and CANCEL
  EXPECT_EQ(bad(0, 0x08), v2::NakReason::BadField);  // reserved bit 3
  EXPECT_EQ(bad(0, 0x80), v2::NakReason::BadField);  // reserved bit 7
  {
    auto p = good;
    p[1] = 0x00;
    p[2] = 0x00;  // feed 0
    EXPECT_EQ(v2::check_host_frame(with(p), 4), v2::NakReason::BadField);
    p[1] = 0x80;
    p[2] = 0x01;  // feed 0x8001
    EXPECT_EQ(v2::check_host_frame(with(p), 4), v2::NakReason::BadField);
    p = good;
    p[3] = 0x80;
    p[4] = 0x01;  // rapid 0x8001
    EXPECT_EQ(v2::check_host_frame(with(p), 4), v2::NakReason::BadField);
    p = good;
    p[8] = 0x00;  // ramp 0
    EXPECT_EQ(v2::check_host_frame(with(p), 4), v2::NakReason::BadField);
  }
  EXPECT_EQ(v2::check_host_frame(with({0x01}), 4), v2::NakReason::BadLength);
  EXPECT_THROW(v2::decode_motion(with({0x03, 0x80, 0x00, 0x80, 0x00, 0, 0, 0, 1})),
               v2::ProtocolError);
  v2::Motion both;
  both.hold = both.resume = true;
  EXPECT_THROW(v2::motion(both), std::invalid_argument);
  v2::Motion cancel;
  cancel.cancel = true;
  const auto cb = v2::encode(v2::motion(cancel));
  EXPECT_EQ(cb[4], 0x04u);
  EXPECT_EQ(v2::decode_motion(parse_one(cb)), cancel);
  cancel.resume = true;
  EXPECT_THROW(v2::motion(cancel), std::invalid_argument);
  v2::Motion zero;
  zero.feed = 0;
  EXPECT_THROW(v2::motion(zero), std::invalid_argument);
  zero.feed = 1;
  zero.ramp = 0;
  EXPECT_THROW(v2::motion(zero), std::invalid_argument);
}

TEST(V2Codec, MotionRatesAndHoldRamp) {
  EXPECT_EQ(v2::rate_from_percent(100.0), 0x8000);
  EXPECT_EQ(v2::rate_from_percent(50.0), 0x4000);
  EXPECT_EQ(v2::rate_from_percent(25.0), 0x2000);
  EXPECT_EQ(v2::rate_from_percent(10.0), 3277);  // 3276.8 rounded
  EXPECT_EQ(v2::rate_from_percent(1e-9), 1);     // never 0 (the device refuses it)
  EXPECT_THROW(v2::rate_from_percent(0.0), std::invalid_argument);
  EXPECT_THROW(v2::rate_from_percent(150.0), std::invalid_argument);
  // RATE_RAMP is "100 % to 0 in 0.1 s at 50 MHz": a machine whose fastest axis stops from its
  // top speed in 0.1 s (v / a = 0.1 s) gets the same ramp: 2^32 * 256 / 5e6 = 219 902.3.
  EXPECT_EQ(v2::hold_ramp(10'000.0, 1'000.0, 50e6), 219'902u);
  EXPECT_EQ(v2::hold_ramp(10'000.0, 1'000.0, 50e6), fpgacnc::spec::kDefaultRateRamp);
  // Twice the deceleration: half the time, twice the ramp (rounded down).
  EXPECT_EQ(v2::hold_ramp(20'000.0, 1'000.0, 50e6), 439'804u);
  EXPECT_EQ(v2::hold_ramp(1e30, 1.0, 1.0), 0xFFFF'FFFFu);  // clamped
  EXPECT_EQ(v2::hold_ramp(1e-30, 1e9, 50e6), 1u);          // never 0
  EXPECT_THROW(v2::hold_ramp(0.0, 1.0, 50e6), std::invalid_argument);
  EXPECT_THROW(v2::hold_ramp(1.0, -1.0, 50e6), std::invalid_argument);
}

TEST(V2Codec, StatusHoldAndStoppedBits) {
  // docs/protocol.md STATUS byte 0: bit 5 HOLD, bit 6 STOPPED.
  EXPECT_EQ(v2::kStateHold, 1u << 5);
  EXPECT_EQ(v2::kStateStopped, 1u << 6);
  v2::Status st;
  st.state = 0x60 | v2::kStateV2;
  st.position = {1, 2, 3, 4};
  const auto b = v2::encode(v2::status(0, st));
  EXPECT_EQ(b[4], 0x62u);
  const auto d = v2::decode_status(parse_one(b), 4);
  EXPECT_TRUE(d.state & v2::kStateHold);
  EXPECT_TRUE(d.state & v2::kStateStopped);
  EXPECT_FALSE(d.state & v2::kStateBusy);
}

TEST(V2Codec, LineChoosesShortOnlyWhenEveryCountFits) {
  const std::array<int32_t, 2> fits{32767, -32768};
  auto f = v2::line(0, 2, 10, 1000, fits);
  EXPECT_EQ(f.payload.size(), 10u);
  EXPECT_EQ(f.payload[0], 0x82);
  EXPECT_EQ(v2::decode_line(f).steps, (std::vector<int32_t>{32767, -32768}));
  const std::array<int32_t, 2> big{32768, 0};
  f = v2::line(0, 3, 10, 1000, big);
  EXPECT_EQ(f.payload.size(), 14u);
  EXPECT_EQ(f.payload[0], 0x03);
  EXPECT_EQ(v2::decode_line(f).steps, (std::vector<int32_t>{32768, 0}));
  const std::array<int32_t, 14> many{};
  EXPECT_EQ(v2::line(0, 0, 0, 0, many, false).payload.size(), 62u);
  const std::array<int32_t, 15> too_many{};
  EXPECT_THROW(v2::line(0, 0, 0, 0, too_many, false), std::invalid_argument);
  EXPECT_THROW(v2::line(0, 4, 0, 0, fits), std::invalid_argument);
}

TEST(V2Codec, EncodeRejectsOversizedPayload) {
  v2::Frame f;
  f.type = 0x10;
  f.payload.assign(64, 0);
  EXPECT_EQ(v2::encode(f).size(), 70u);
  f.payload.push_back(0);
  EXPECT_THROW(v2::encode(f), std::invalid_argument);
}

TEST(V2Codec, ParserResyncsAfterGarbage) {
  const Bytes ackb = v2::encode(v2::ack(0, {8, 63, 5}));
  const Bytes nakb = v2::encode(v2::nak(1, {9, v2::NakReason::BadCrc, 8, 63}));
  Bytes stream{0x00, 0x13, 0xFF, 0xAA};  // 4 noise bytes
  stream.insert(stream.end(), ackb.begin(), ackb.end());
  stream.push_back(0x42);  // 1 noise byte
  stream.insert(stream.end(), nakb.begin(), nakb.end());
  v2::FrameParser p;
  // Byte by byte: frames come out exactly when their last byte arrives.
  size_t got = 0;
  for (size_t i = 0; i < stream.size(); ++i) {
    p.feed(stream[i]);
    while (auto f = p.next()) {
      ++got;
      if (got == 1) {
        EXPECT_EQ(i, 4 + ackb.size() - 1);
        EXPECT_EQ(v2::decode_credit(*f), (v2::Credit{8, 63, 5}));
      } else {
        EXPECT_EQ(i, stream.size() - 1);
        EXPECT_EQ(v2::decode_nak(*f).seq, 9);
      }
    }
  }
  EXPECT_EQ(got, 2u);
  EXPECT_EQ(p.noise_bytes(), 5u);
  EXPECT_EQ(p.crc_errors(), 0u);
}

TEST(V2Codec, ParserDropsCorruptedFrameAndFindsTheNextOne) {
  const Bytes ackb = v2::encode(v2::ack(0, {8, 63, 5}));
  const Bytes done_b = v2::encode(v2::done(1, {9, 62, 6}));
  for (size_t pos = 1; pos < ackb.size(); ++pos) {
    for (int bit = 0; bit < 8; ++bit) {
      Bytes bad = ackb;
      bad[pos] ^= static_cast<uint8_t>(1u << bit);
      Bytes stream = bad;
      stream.insert(stream.end(), done_b.begin(), done_b.end());
      // More good frames so a LEN corrupted upwards (up to 64) still completes.
      for (int k = 0; k < 8; ++k) stream.insert(stream.end(), done_b.begin(), done_b.end());
      v2::FrameParser p;
      p.feed(stream);
      auto f = p.next();
      ASSERT_TRUE(f.has_value()) << "pos " << pos << " bit " << bit;
      EXPECT_EQ(f->type, static_cast<uint8_t>(v2::Type::Done)) << "pos " << pos << " bit " << bit;
      EXPECT_EQ(v2::decode_credit(*f), (v2::Credit{9, 62, 6}));
      EXPECT_EQ(p.crc_errors() + p.bad_length(), 1u) << "pos " << pos << " bit " << bit;
      size_t more = 0;
      while (p.next()) ++more;
      EXPECT_EQ(more, 8u) << "pos " << pos << " bit " << bit;
    }
  }
}

TEST(V2Codec, ParserCountsBadLengthAndAbandonsPartial) {
  v2::FrameParser p;
  p.feed(Bytes{0xA5, 0x41});  // LEN 65 > 64
  EXPECT_FALSE(p.next().has_value());
  EXPECT_EQ(p.bad_length(), 1u);
  // A header whose LEN was corrupted upwards waits for bytes; abandon_partial() gives it up.
  const Bytes ackb = v2::encode(v2::ack(0, {8, 63, 5}));
  Bytes bad = ackb;
  bad[1] = 40;
  p.feed(bad);
  p.feed(ackb);
  EXPECT_FALSE(p.next().has_value());
  EXPECT_GT(p.buffered(), 0u);
  EXPECT_TRUE(p.abandon_partial());
  auto f = p.next();
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(v2::decode_credit(*f), (v2::Credit{8, 63, 5}));
  EXPECT_EQ(p.abandoned(), 1u);
  EXPECT_FALSE(p.abandon_partial());
}

TEST(V2Codec, ParserRandomStreamRecoversEveryUntouchedFrame) {
  const uint32_t seed = codec_seed();
  std::printf("seed %u (FPGACNC_SEED)\n", seed);
  std::mt19937 rng(seed);
  // Frames separated by random noise without 0xA5 (so no false sync): all found, in order.
  std::vector<v2::Frame> sent;
  Bytes stream;
  for (int i = 0; i < 2000; ++i) {
    v2::Frame f;
    f.seq = static_cast<uint8_t>(rng());
    f.type = static_cast<uint8_t>(rng());
    f.payload.resize(rng() % 65);
    for (auto& b : f.payload) b = static_cast<uint8_t>(rng());
    sent.push_back(f);
    v2::encode_to(f, stream);
    const size_t noise = rng() % 4;
    for (size_t k = 0; k < noise; ++k) {
      uint8_t b = static_cast<uint8_t>(rng());
      if (b == v2::kSync) b = 0;
      stream.push_back(b);
    }
  }
  v2::FrameParser p;
  std::vector<v2::Frame> got;
  size_t i = 0;
  while (i < stream.size()) {
    const size_t n = std::min<size_t>(1 + rng() % 50, stream.size() - i);
    p.feed(std::span<const uint8_t>(stream.data() + i, n));
    i += n;
    while (auto f = p.next()) got.push_back(*f);
  }
  ASSERT_EQ(got.size(), sent.size());
  for (size_t k = 0; k < sent.size(); ++k) ASSERT_EQ(got[k], sent[k]) << "frame " << k;
  EXPECT_EQ(p.crc_errors(), 0u);
}

TEST(V2Codec, DecodersRejectWrongTypeAndLength) {
  v2::Frame f = v2::ack(0, {1, 2, 3});
  EXPECT_THROW(v2::decode_nak(f), v2::ProtocolError);
  EXPECT_THROW(v2::decode_ident(f), v2::ProtocolError);
  EXPECT_THROW(v2::decode_status(f, 4), v2::ProtocolError);
  f.payload.pop_back();
  try {
    v2::decode_credit(f);
    FAIL() << "6-byte ACK accepted";
  } catch (const v2::ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("ACK"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("6 bytes"), std::string::npos) << e.what();
  }
  v2::Frame n = v2::nak(0, {1, v2::NakReason::FifoFull, 2, 3});
  EXPECT_NO_THROW(v2::decode_nak(n));
  n.payload[1] = 0;
  EXPECT_THROW(v2::decode_nak(n), v2::ProtocolError);
  n.payload[1] = fpgacnc::spec::kNakBusy;  // the last reason
  EXPECT_NO_THROW(v2::decode_nak(n));
  n.payload[1] = fpgacnc::spec::kNakBusy + 1;
  EXPECT_THROW(v2::decode_nak(n), v2::ProtocolError);
  n.payload.push_back(0);
  EXPECT_THROW(v2::decode_nak(n), v2::ProtocolError);
  v2::Frame id = v2::ident(0, v2::Ident{});
  id.payload.resize(17);
  EXPECT_THROW(v2::decode_ident(id), v2::ProtocolError);
  v2::Status st;
  st.position.resize(2);
  const v2::Frame s2 = v2::status(0, st);
  EXPECT_NO_THROW(v2::decode_status(s2, 2));
  EXPECT_THROW(v2::decode_status(s2, 4), v2::ProtocolError);
  EXPECT_THROW(v2::decode_credit(v2::hello()), v2::ProtocolError);
}

// docs/protocol.md, LINE_PROFILE worked example.
const char* const kProfileExample =
    "A5 20 0A 12 81 FF 00 00 00 00 00 00 00 04 31 BD E8 2D 00 00 3B 9A CA 00 00 00 46 5E 00 00 01 "
    "20 01 40 FF 60 51 62";

v2::LineProfile profile_example() {
  v2::LineProfile p;
  p.code = 1;
  p.power = 255;
  p.v_entry = 0;
  p.v_cruise = 18'014'398'509;
  p.v_exit = 1'000'000'000;
  p.accel = 18'014;
  p.decel_at = 288;
  p.steps = {320, -160};
  return p;
}

TEST(V2Codec, LineProfileWorkedExample) {
  EXPECT_EQ(v2::encode(v2::line_profile(10, profile_example())), from_hex(kProfileExample));
  const auto f = parse_one(from_hex(kProfileExample));
  EXPECT_EQ(f.seq, 10);
  EXPECT_EQ(v2::type_name(f.type), "LINE_PROFILE");
  auto want = profile_example();
  want.short_steps = true;
  EXPECT_EQ(v2::decode_line_profile(f, 4), want);
  EXPECT_TRUE(v2::is_fifo(0x12) && v2::is_sequenced(0x12));
  // int32 steps for 4 axes: 28 + 16 bytes, same fields
  auto p4 = profile_example();
  p4.steps = {320, -160, 0, 40'000};
  const auto f4 = v2::line_profile(11, p4);
  EXPECT_EQ(f4.payload.size(), 44u);
  EXPECT_EQ(f4.payload[0], 0x01);
  EXPECT_EQ(v2::decode_line_profile(f4, 4), p4);
  EXPECT_THROW(v2::decode_line_profile(f4, 3), v2::ProtocolError);
}

TEST(V2Codec, LineProfileFieldRules) {
  using R = v2::NakReason;
  const auto ok = profile_example();
  EXPECT_EQ(v2::check_host_frame(v2::line_profile(0, ok), 4), std::nullopt);
  // Each rule broken on the wire (the builder refuses them, so patch the encoded payload).
  auto patched = [&](size_t byte, uint8_t value) {
    auto f = v2::line_profile(0, ok);
    f.payload[byte] = value;
    return f;
  };
  EXPECT_EQ(v2::check_host_frame(patched(0, 0x85), 4), R::BadField);   // reserved flag bit 2
  EXPECT_EQ(v2::check_host_frame(patched(8, 0x80), 4), R::BadField);   // V_cruise >= 2^47
  EXPECT_EQ(v2::check_host_frame(patched(8, 0x7F), 4), std::nullopt);  // V_cruise < 2^47
  EXPECT_EQ(v2::check_host_frame(patched(2, 0x01), 4), R::BadField);   // V_entry > V_cruise
  EXPECT_EQ(v2::check_host_frame(patched(14, 0x01), 4), R::BadField);  // V_exit > V_cruise
  auto f = v2::line_profile(0, ok);
  for (size_t i = 14; i < 20; ++i) f.payload[i] = 0;  // V_exit = 0
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadField);
  f = v2::line_profile(0, ok);
  for (size_t i = 20; i < 24; ++i) f.payload[i] = 0;  // A = 0 with V_entry = 0
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadField);
  f.payload[7] = 1;  // A = 0 with V_entry = 1: runs at constant speed
  EXPECT_EQ(v2::check_host_frame(f, 4), std::nullopt);
  f = v2::line_profile(0, ok);
  for (size_t i = 28; i < f.payload.size(); ++i) f.payload[i] = 0;  // no steps
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadField);
  f.payload.resize(28);  // k = 0
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadField);
  f.payload.resize(27);
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadLength);
  f = v2::line_profile(0, ok);
  f.payload.pop_back();
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadLength);
  auto big = ok;
  big.steps = {(1 << 24) - 1, 3};
  EXPECT_EQ(v2::check_host_frame(v2::line_profile(0, big), 4), std::nullopt);
  big.steps = {3, -(1 << 24)};
  EXPECT_THROW(v2::line_profile(0, big), std::invalid_argument);
  auto bad = ok;
  bad.code = 4;
  EXPECT_THROW(v2::line_profile(0, bad), std::invalid_argument);
  bad = ok;
  bad.v_exit = 0;
  EXPECT_THROW(v2::line_profile(0, bad), std::invalid_argument);
  bad = ok;
  bad.steps.assign(10, 1);  // 28 + 10 * 4 > 64
  bad.steps[0] = 40'000;
  EXPECT_THROW(v2::line_profile(0, bad), std::invalid_argument);
}

TEST(V2Codec, HostFrameChecksFollowTheDeviceRules) {
  using R = v2::NakReason;
  EXPECT_EQ(v2::check_host_frame(v2::hello(), 4), std::nullopt);
  v2::Frame f = v2::hello();
  f.payload.push_back(0);
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadLength);
  EXPECT_EQ(v2::check_host_frame(v2::config_axis(0, 3, 1, 1, 1, 1), 4), std::nullopt);
  EXPECT_EQ(v2::check_host_frame(v2::config_axis(0, 4, 1, 1, 1, 1), 4), R::BadField);
  const std::array<int32_t, 3> xyz{1, 2, 3};
  EXPECT_EQ(v2::check_host_frame(v2::line(0, 1, 1, 1, xyz), 4), std::nullopt);
  EXPECT_EQ(v2::check_host_frame(v2::line(0, 1, 1, 1, xyz), 2), R::BadLength);
  f = v2::line(0, 1, 1, 1, xyz);
  f.payload[0] |= 0x04;
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadField);
  EXPECT_THROW(v2::decode_line(f), v2::ProtocolError);
  f = v2::line(0, 1, 1, 1, xyz);
  f.payload.pop_back();  // 6 + 5 bytes: not a whole number of int16
  EXPECT_EQ(v2::check_host_frame(f, 4), R::BadLength);
  f.type = 0x14;  // undefined
  EXPECT_EQ(v2::check_host_frame(f, 4), R::UnknownType);
  EXPECT_EQ(v2::check_host_frame(v2::dwell(0, 1), 4), std::nullopt);
  EXPECT_TRUE(v2::is_fifo(0x10) && v2::is_fifo(0x11) && v2::is_fifo(0x05));
  EXPECT_FALSE(v2::is_fifo(0x04) || v2::is_fifo(0x06) || v2::is_fifo(0x01));
  EXPECT_TRUE(v2::is_sequenced(0x03) && v2::is_sequenced(0x06) && v2::is_sequenced(0x04));
  EXPECT_FALSE(v2::is_sequenced(0x01) || v2::is_sequenced(0x02));
}

// OUTPUT (docs/protocol.md "OUTPUT"): the worked examples byte for byte (CRCs from the bitwise
// CRC of the spec, not from this encoder), decode round trip, and the device's field rules.
TEST(V2Codec, OutputWorkedExamples) {
  v2::OutputSet m8_fan_dout;  // M8, M106 S128, M62 P1
  m8_fan_dout.flood = true;
  m8_fan_dout.fan = 128;
  m8_fan_dout.dout[1] = true;
  const Bytes a = from_hex("A5 03 0C 15 15 11 80 E5 60");
  EXPECT_EQ(v2::encode(v2::output_frame(12, m8_fan_dout)), a);
  EXPECT_EQ(v2::decode_output(parse_one(a)), m8_fan_dout);
  v2::OutputSet m9_m107;  // M9, M107
  m9_m107.flood = false;
  m9_m107.mist = false;
  m9_m107.fan = 0;
  const Bytes b = from_hex("A5 03 0D 15 07 00 00 C3 F8");
  EXPECT_EQ(v2::encode(v2::output_frame(13, m9_m107)), b);
  EXPECT_EQ(v2::decode_output(parse_one(b)), m9_m107);
  EXPECT_EQ(v2::type_name(0x15), "OUTPUT");
  EXPECT_TRUE(v2::is_fifo(0x15));
  EXPECT_TRUE(v2::is_sequenced(0x15));
}

TEST(V2Codec, OutputRoundTripAndFieldRules) {
  using R = v2::NakReason;
  // Every combination of set / not set / level for the 6 on-off outputs, and a fan duty.
  std::mt19937 rng(codec_seed());
  for (int i = 0; i < 2000; ++i) {
    v2::OutputSet o;
    auto pick = [&]() -> std::optional<bool> {
      const unsigned r = rng() % 3;
      if (r == 0) return std::nullopt;
      return r == 1;
    };
    o.flood = pick();
    o.mist = pick();
    for (auto& d : o.dout) d = pick();
    if (rng() % 2) o.fan = static_cast<uint8_t>(rng());
    if (o.empty()) {
      EXPECT_THROW(v2::output_frame(1, o), std::invalid_argument);
      continue;
    }
    const v2::Frame f = v2::output_frame(static_cast<uint8_t>(i), o);
    ASSERT_EQ(f.payload.size(), 3u);
    EXPECT_EQ(v2::check_host_frame(f, 4), std::nullopt);
    EXPECT_EQ(v2::decode_output(f), o);
    // The mask has exactly the outputs given.
    const uint8_t mask = f.payload[0];
    EXPECT_EQ((mask & v2::kOutFlood) != 0, o.flood.has_value());
    EXPECT_EQ((mask & v2::kOutFan) != 0, o.fan.has_value());
    for (size_t n = 0; n < v2::kDigitalOutputs; ++n)
      EXPECT_EQ((mask >> (3 + n) & 1) != 0, o.dout[n].has_value());
  }
  auto raw = [](std::vector<uint8_t> p) {
    return v2::Frame{0, static_cast<uint8_t>(v2::Type::Output), std::move(p)};
  };
  EXPECT_EQ(v2::check_host_frame(raw({0, 0, 0}), 4), R::BadField) << "empty mask";
  EXPECT_EQ(v2::check_host_frame(raw({0x80, 0x80, 0}), 4), std::nullopt) << "M4 (mask bit 7)";
  EXPECT_EQ(v2::check_host_frame(raw({0x80, 0, 0}), 4), std::nullopt) << "M3 (mask bit 7)";
  EXPECT_EQ(v2::check_host_frame(raw({0x01, 0x80, 0}), 4), R::BadField) << "bit 7 not in mask";
  EXPECT_EQ(v2::check_host_frame(raw({0x01, 0x02, 0}), 4), R::BadField) << "value not in mask";
  EXPECT_EQ(v2::check_host_frame(raw({0x04, 0x04, 9}), 4), R::BadField) << "value bit 2";
  EXPECT_EQ(v2::check_host_frame(raw({0x01, 0x01, 9}), 4), R::BadField) << "duty without fan";
  EXPECT_EQ(v2::check_host_frame(raw({0x01, 0x01}), 4), R::BadLength);
  EXPECT_EQ(v2::check_host_frame(raw({0x01, 0x01, 0, 0}), 4), R::BadLength);
  EXPECT_THROW(v2::decode_output(raw({0x01, 0x02, 0})), v2::ProtocolError);
  EXPECT_THROW(v2::decode_output(v2::dwell(0, 1)), v2::ProtocolError);
}

// ---- Packer: plan -> v2 frames ----

#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/plan/stepfile.h"
#include "fpgacnc/protocol/v2_job.h"

namespace {

fpgacnc::plan::Plan plan_str(const std::string& g, const fpgacnc::config::MachineConfig& cfg) {
  return fpgacnc::plan::plan_program(fpgacnc::gcode::parse_string(g, "p.gcode"), cfg, {});
}

std::vector<v2::Line> lines_of(const v2::Job& job) {
  std::vector<v2::Line> out;
  for (const auto& jf : job.frames) {
    if (jf.frame.type == static_cast<uint8_t>(v2::Type::Line))
      out.push_back(v2::decode_line(jf.frame));
  }
  return out;
}

}  // namespace

TEST(V2Packer, WorkedExampleMoveIsTheDocsLineFrame) {
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  cfg.laser_requires_m3 = false;
  // 2 mm x -1 mm at 600 * sqrt(5) mm/min: 0.1 s = 5 000 000 clocks.
  const auto plan = plan_str("G1 X2 Y-1 F1341.6407865\n", cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  ASSERT_EQ(job.frames.size(), 2u);
  EXPECT_EQ(job.frames[0].frame, v2::numerators(0, 18'750'000, 18'750'000));
  v2::Frame f = job.frames[1].frame;
  f.seq = 7;
  EXPECT_EQ(v2::encode(f), from_hex("A5 0A 07 10 81 FF 00 4C 4B 40 01 40 FF 60 C0 B7"));
  EXPECT_EQ(job.total_t, 5'000'000u);
  EXPECT_EQ(job.lines, 1u);
  EXPECT_EQ(job.short_lines, 1u);
  EXPECT_EQ(job.max_axes, 2u);
  ASSERT_EQ(job.config.size(), 4u);
  v2::Frame c = job.config[0];
  c.seq = 1;
  EXPECT_EQ(v2::encode(c), from_hex("A5 09 01 04 00 00 64 00 64 00 C8 00 C8 DC 4C"));
  EXPECT_EQ(job.wire_bytes, 4 * 15u + 14u + 16u);
}

TEST(V2Packer, AxesPowerAndRapids) {
  fpgacnc::config::MachineConfig cfg;  // laser_requires_m3 = true, laser_s_max = 1000
  cfg.motion = "constant";             // the LINE packer
  const auto plan =
      plan_str("G0 X1\nM3 S500\nG1 X2 F600\nG1 Z1\nG1 E5\nS1\nG1 X300\nM5\nG1 X0\n", cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  const auto l = lines_of(job);
  ASSERT_EQ(l.size(), 6u);
  // G0: code 0, power 0, at the rapid feed: 1 mm at 3000 mm/min = 0.02 s.
  EXPECT_EQ(l[0], (v2::Line{0, 0, 1'000'000, true, {160, 0}}));
  // S500 of 1000 -> round(127.5) = 128; 1 mm at 600 mm/min = 0.1 s.
  EXPECT_EQ(l[1], (v2::Line{1, 128, 5'000'000, true, {160, 0}}));
  // Z: k = 3; 1 mm at 600 mm/min (Z max feed 600).
  EXPECT_EQ(l[2], (v2::Line{1, 128, 5'000'000, true, {0, 0, 400}}));
  // E alone: k = 4, its own length 5 mm at 600 mm/min = 0.5 s.
  EXPECT_EQ(l[3], (v2::Line{1, 128, 25'000'000, true, {0, 0, 0, 500}}));
  // S1 -> 0.255 rounds to 0, raised to 1 (S > 0 is never off); 298 mm = 47680 steps: int32.
  EXPECT_EQ(l[4], (v2::Line{1, 1, 1'490'000'000, false, {47'680, 0}}));
  // After M5: laser off, power 0, still at the programmed feed and a feed move (code 1: the
  // device's feed rate, not its rapid rate, applies).
  EXPECT_EQ(l[5].code, 1);
  EXPECT_EQ(l[5].power, 0);
  EXPECT_EQ(l[5].t, 1'500'000'000u);  // 300 mm at 600 mm/min
  EXPECT_EQ(job.max_axes, 4u);
  EXPECT_EQ(job.target, plan.final_steps);
}

TEST(V2Packer, TooFastIsRaisedToTheStepRate) {
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  cfg.laser_requires_m3 = false;
  cfg.max_feed_mm_min = {1e7, 1e7, 1e7, 1e7};
  // 100 mm at 1e6 mm/min: 300 000 clocks for 16 000 steps: below 16 000 * 200.
  const auto job = fpgacnc::test::pack_motion(plan_str("G1 X100 F1000000\n", cfg), cfg);
  const auto l = lines_of(job);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_EQ(l[0].t, 16'000u * 200u);
  EXPECT_EQ(job.t_raised, 1u);
  cfg.step_timing.step_high = 0;  // counts as 1 clock
  cfg.step_timing.step_low = 3;
  EXPECT_EQ(v2::min_period(cfg.step_timing), 4u);
}

TEST(V2Packer, LongMovesAndDwellsAreSplitExactly) {
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  cfg.laser_requires_m3 = false;
  // 100 mm at 1 mm/min: 6000 s = 3e11 clocks -> 70 LINE frames of at most UINT32_MAX.
  const auto plan = plan_str("G1 X100 Y-33.3 F1\nG4 P100\nG4 P0\nG4 P1.5\n", cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  const auto l = lines_of(job);
  const double len = std::hypot(100.0, 5328.0 / 160.0);  // Y: -5328 steps
  const uint64_t want_t = static_cast<uint64_t>(std::llround(len / 1.0 * 60.0 * 50e6));
  ASSERT_EQ(l.size(), static_cast<size_t>((want_t + 0xFFFFFFFFull - 1) / 0xFFFFFFFFull));
  uint64_t t = 0;
  int64_t x = 0, y = 0;
  for (const auto& s : l) {
    t += s.t;
    x += s.steps[0];
    y += s.steps[1];
    EXPECT_LE(s.t, 0xFFFFFFFFull);
  }
  EXPECT_EQ(t, want_t);
  EXPECT_EQ(x, 16'000);
  EXPECT_EQ(y, -5'328);
  EXPECT_EQ(job.split_moves, 1u);
  // Dwells: 100 s = 5e9 clocks -> 2 frames; 0 s -> none; 1.5 s -> 75e6.
  std::vector<uint32_t> d;
  for (const auto& jf : job.frames) {
    if (jf.frame.type == static_cast<uint8_t>(v2::Type::Dwell))
      d.push_back(v2::decode_dwell(jf.frame));
  }
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(uint64_t{d[0]} + d[1], 5'000'000'000u);
  EXPECT_EQ(d[2], 75'000'000u);
  EXPECT_EQ(job.total_t, want_t + 5'000'000'000u + 75'000'000u);
}

TEST(V2Packer, StepFileSegmentsKeepV1Timing) {
  // The v1 worked example as a step file: feed 1200 -> P = 15 625, T = 5 000 000.
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  fpgacnc::plan::Plan p;
  p.numerator = {18'750'000, 18'750'000};
  fpgacnc::plan::Segment s;
  s.code = 1;
  s.steps = {320, -160, 0, 0};
  s.feed_v1 = 1200;
  p.items.emplace_back(s);
  const auto l = lines_of(fpgacnc::test::pack_motion(p, cfg));
  ASSERT_EQ(l.size(), 1u);
  EXPECT_EQ(l[0], (v2::Line{1, 255, 5'000'000, true, {320, -160}}));
}

TEST(V2Packer, RejectsWhatV2CannotCarry) {
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  fpgacnc::plan::Plan p;
  fpgacnc::plan::Segment s;
  s.code = 4;
  s.steps = {1, 0, 0, 0};
  p.items.emplace_back(s);
  EXPECT_THROW(fpgacnc::test::pack_motion(p, cfg), std::invalid_argument);
  cfg.step_timing.dir_setup = 70'000;
  EXPECT_THROW(fpgacnc::test::pack_motion(fpgacnc::plan::Plan{}, cfg), std::invalid_argument);
}

TEST(V2Packer, SessionFramesCarryConsecutiveSequenceNumbers) {
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";  // the LINE packer
  const auto job = fpgacnc::test::pack_motion(plan_str("G1 X1 F600\nG1 Y1\n", cfg), cfg);
  const auto frames = v2::session_frames(job, 254, 2);
  ASSERT_EQ(frames.size(), 2u + job.frames.size() + 1u);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i][2], static_cast<uint8_t>(254 + i)) << "frame " << i;
  }
  EXPECT_EQ(frames.back()[3], static_cast<uint8_t>(v2::Type::Release));
}

namespace {

// TRIGGER, SET_POSITION, TRIGGER_QUERY and TRIGGER_REPORT: the worked examples of
// docs/protocol.md byte for byte, both ways, and the device's field rules.
TEST(V2Codec, TriggerFramesMatchTheDocs) {
  // seq 5, HOME on X max and Y max (mask 0x0300); seq 6, PROBE to contact.
  EXPECT_EQ(v2::encode(v2::trigger(5, v2::TriggerMode::Home, 0x0300, 2)),
            from_hex("A5 03 05 0A 01 03 00 E9 6F"));
  EXPECT_EQ(v2::encode(v2::trigger(6, v2::TriggerMode::Probe)),
            from_hex("A5 03 06 0A 02 00 00 0B BE"));
  const auto home = v2::decode_trigger(parse_one(from_hex("A5 03 05 0A 01 03 00 E9 6F")), 2);
  EXPECT_EQ(home.first, v2::TriggerMode::Home);
  EXPECT_EQ(home.second, 0x0300);
  // 2 axes: seq 7, X = 0, Y = -10.
  const std::vector<int32_t> pos{0, -10};
  const Bytes sp = from_hex("A5 0A 07 0B 00 03 00 00 00 00 FF FF FF F6 5E 0D");
  EXPECT_EQ(v2::encode(v2::set_position(7, 0x0003, pos)), sp);
  const auto dsp = v2::decode_set_position(parse_one(sp), 2);
  EXPECT_EQ(dsp.first, 0x0003);
  EXPECT_EQ(dsp.second, pos);
  EXPECT_EQ(v2::encode(v2::trigger_query()), from_hex("A5 00 00 0C 0D 10"));
  // Device seq 3: HOME done, X max and Y max fired, X latched 312, Y 132.
  const Bytes rb = from_hex("A5 0C 03 85 01 02 03 00 00 00 01 38 00 00 00 84 02 9F");
  const v2::TriggerReport r = v2::decode_trigger_report(parse_one(rb), 2);
  EXPECT_EQ(r.mode, v2::TriggerMode::Home);
  EXPECT_TRUE(r.done());
  EXPECT_FALSE(r.armed());
  EXPECT_EQ(r.fired, 0x0300);  // bytes 03 00: X max and Y max as the doc's mask
  EXPECT_EQ(r.latched, (std::vector<int32_t>{312, 132}));
  EXPECT_EQ(v2::encode(v2::trigger_report(3, r)), rb);

  // Sequenced, not FIFO; the query unsequenced.
  EXPECT_TRUE(v2::is_sequenced(0x0A));
  EXPECT_TRUE(v2::is_sequenced(0x0B));
  EXPECT_FALSE(v2::is_sequenced(0x0C));
  EXPECT_FALSE(v2::is_fifo(0x0A));
  EXPECT_FALSE(v2::is_fifo(0x0B));
  EXPECT_EQ(v2::nak_reason_name(9), "BUSY");
}

TEST(V2Codec, TriggerFieldRules) {
  // Builders refuse what the device would NAK BAD_FIELD (docs/protocol.md "TRIGGER").
  EXPECT_THROW(v2::trigger(0, v2::TriggerMode::Home, 0), std::invalid_argument);
  EXPECT_THROW(v2::trigger(0, v2::TriggerMode::Home, v2::switch_bit(2, true), 2),
               std::invalid_argument);  // axis 2 on a 2-axis board
  EXPECT_THROW(v2::trigger(0, v2::TriggerMode::Probe, 0x0001), std::invalid_argument);
  EXPECT_THROW(v2::trigger(0, v2::TriggerMode::Disarm, 0x0100), std::invalid_argument);
  EXPECT_THROW(v2::trigger(0, static_cast<v2::TriggerMode>(4)), std::invalid_argument);
  EXPECT_NO_THROW(v2::trigger(0, v2::TriggerMode::Home, v2::switch_bit(3, false), 4));
  const std::vector<int32_t> two{1, 2};
  EXPECT_THROW(v2::set_position(0, 0, two), std::invalid_argument);
  EXPECT_THROW(v2::set_position(0, 0x0004, two), std::invalid_argument);  // axis 2
  EXPECT_THROW(v2::set_position(0, 0x8000, two), std::invalid_argument);  // bit 15
  EXPECT_THROW(v2::set_position(0, 1, std::vector<int32_t>{}), std::invalid_argument);

  // check_host_frame: the device's answers to frames built by hand.
  auto tr = [](std::vector<uint8_t> p) {
    return v2::check_host_frame(v2::Frame{0, 0x0A, std::move(p)}, 2);
  };
  EXPECT_EQ(tr({0x01, 0x03, 0x00}), std::nullopt);
  EXPECT_EQ(tr({0x04, 0x00, 0x00}), v2::NakReason::BadField);  // mode 4
  EXPECT_EQ(tr({0x01, 0x00, 0x00}), v2::NakReason::BadField);  // HOME without switches
  EXPECT_EQ(tr({0x01, 0x04, 0x00}), v2::NakReason::BadField);  // axis 2 max on 2 axes
  EXPECT_EQ(tr({0x02, 0x00, 0x01}), v2::NakReason::BadField);  // PROBE with a mask
  EXPECT_EQ(tr({0x00, 0x01, 0x00}), v2::NakReason::BadField);  // DISARM with a mask
  EXPECT_EQ(tr({0x01, 0x03}), v2::NakReason::BadLength);
  auto sp = [](std::vector<uint8_t> p) {
    return v2::check_host_frame(v2::Frame{0, 0x0B, std::move(p)}, 2);
  };
  const std::vector<uint8_t> good{0x00, 0x03, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(sp(good), std::nullopt);
  auto mask = [&](uint8_t hi, uint8_t lo) {
    auto p = good;
    p[0] = hi;
    p[1] = lo;
    return sp(p);
  };
  EXPECT_EQ(mask(0, 0), v2::NakReason::BadField);
  EXPECT_EQ(mask(0, 4), v2::NakReason::BadField);                     // axis 2
  EXPECT_EQ(mask(0x80, 1), v2::NakReason::BadField);                  // bit 15
  EXPECT_EQ(sp({0x00, 0x01, 0, 0, 0, 0}), v2::NakReason::BadLength);  // 1 axis of 2
  EXPECT_EQ(v2::check_host_frame(v2::Frame{0, 0x0C, {0}}, 2), v2::NakReason::BadLength);

  // TRIGGER_REPORT decoder: length, mode, reserved flag bits.
  const v2::Frame rep =
      v2::trigger_report(0, {v2::TriggerMode::Probe, v2::kTriggerArmed, 0, {5, -6}});
  EXPECT_EQ(v2::decode_trigger_report(rep, 2).latched, (std::vector<int32_t>{5, -6}));
  EXPECT_THROW(v2::decode_trigger_report(rep, 3), v2::ProtocolError);
  auto rp = rep;
  rp.payload[1] = 0x04;
  EXPECT_THROW(v2::decode_trigger_report(rp, 2), v2::ProtocolError);
  rp = rep;
  rp.payload[0] = 4;
  EXPECT_THROW(v2::decode_trigger_report(rp, 2), v2::ProtocolError);
}

}  // namespace
