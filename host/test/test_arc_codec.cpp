// ARC frame (TYPE 0x13) codec: the worked frame of docs/protocol.md, round trips, and the
// BAD_LENGTH / BAD_FIELD rules the device applies.
#include <gtest/gtest.h>

#include <random>

#include "fpgacnc/protocol/v2.h"

namespace v2 = fpgacnc::protocol::v2;

namespace {

v2::Arc worked() {
  v2::Arc a;
  a.code = 3;
  a.power = 255;
  a.i = -100;
  a.j = 0;
  a.dx = -100;
  a.dy = 100;
  a.dz = 0;
  a.n_ramp = 127;
  a.c_total = 15703;
  a.v_cruise = 1125544154615ull;
  a.v_entry = a.v_exit = 281386038653ull;
  a.accel = 1125544;
  a.decel_at = 13828;
  return a;
}

TEST(ArcCodec, WorkedFrame) {
  const v2::Frame f = v2::arc(11, worked());
  EXPECT_EQ(v2::hex(v2::encode(f)),
            "A5 3F 0B 13 03 FF FF FF 9C 00 00 00 FF FF 9C 00 00 64 00 00 00 00 00 00 7F 00 00 00 "
            "00 3D 57 00 00 00 41 83 EA 35 7D 00 00 01 06 0F A8 D5 F7 00 00 00 41 83 EA 35 7D 00 "
            "00 00 11 2C A8 00 00 00 00 36 04 47 F8");
  EXPECT_EQ(v2::decode_arc(f), worked());
  EXPECT_TRUE(v2::is_sequenced(0x13));
  EXPECT_TRUE(v2::is_fifo(0x13));
  EXPECT_EQ(v2::type_name(0x13), "ARC");
}

TEST(ArcCodec, RoundTripRandom) {
  std::mt19937_64 rng(65);
  for (int n = 0; n < 2000; ++n) {
    v2::Arc a;
    a.code = 2 + (rng() & 1);
    a.power = static_cast<uint8_t>(rng());
    const auto c = [&] { return static_cast<int32_t>(rng() % 4000001) - 2000000; };
    a.i = c();
    a.j = c();
    a.dx = c();
    a.dy = c();
    if (a.i == 0 && a.j == 0) a.i = 1;
    if (a.dx == a.i && a.dy == a.j) a.dx += 1;
    a.dz = static_cast<int32_t>(rng());
    if (a.dz == INT32_MIN) a.dz = 0;
    a.n_ramp = 1 + static_cast<uint32_t>(rng() % v2::kArcNRampMax);
    a.c_total = 1 + rng() % (v2::kArcCTotalLimit - 1);
    a.v_cruise = 1 + (rng() >> 2);
    a.v_entry = rng() % (a.v_cruise + 1);
    a.v_exit = 1 + rng() % a.v_cruise;
    a.accel = rng() & v2::kArcU48Max;
    a.decel_at = rng() & v2::kArcU48Max;
    if (a.accel == 0 && a.v_entry == 0) a.accel = 1;
    const v2::Frame f = v2::arc(static_cast<uint8_t>(n), a);
    ASSERT_EQ(f.payload.size(), v2::kArcPayload);
    ASSERT_EQ(v2::decode_arc(f), a) << "arc " << n;
    ASSERT_FALSE(v2::check_host_frame(f, 4).has_value());
  }
}

TEST(ArcCodec, DeviceRules) {
  const v2::Frame good = v2::arc(1, worked());
  auto with = [&](auto mutate) {
    v2::Frame f = good;
    mutate(f.payload);
    return v2::check_host_frame(f, 4);
  };
  EXPECT_EQ(with([](auto& p) { p.pop_back(); }), v2::NakReason::BadLength);
  EXPECT_EQ(with([](auto& p) { p.push_back(0); }), v2::NakReason::BadLength);
  EXPECT_EQ(with([](auto& p) { p[0] = 0x13; }), v2::NakReason::BadField);  // reserved bit 4
  EXPECT_EQ(with([](auto& p) { p[0] = 0x0F; }), v2::NakReason::BadField);  // plane 3
  EXPECT_EQ(with([](auto& p) { p[0] = 0x01; }), v2::NakReason::BadField);  // code 1
  EXPECT_EQ(with([](auto& p) { p[2] = p[3] = p[4] = 0; }),
            v2::NakReason::BadField);                                    // I = 0, J = 0
  EXPECT_EQ(with([](auto& p) { p[20] = 0; }), v2::NakReason::BadField);  // N_RAMP = 0
  EXPECT_EQ(with([](auto& p) {
              p[26] = 0;
              p[25] = 0;
            }),
            v2::NakReason::BadField);  // C_TOTAL 0
  EXPECT_EQ(with([](auto& p) {
              p[50] = 0;
              p[49] = 0;
              p[48] = 0;
              p[47] = 0;
              p[46] = 0;
              p[45] = 0;
              p[44] = 0;
              p[43] = 0;
            }),
            v2::NakReason::BadField);  // V_exit = 0
  v2::Arc a = worked();
  a.v_entry = a.v_cruise + 1;
  EXPECT_THROW(v2::arc(1, a), std::invalid_argument);
  a = worked();
  a.i = -(1 << 22);
  EXPECT_THROW(v2::arc(1, a), std::invalid_argument);
  a = worked();
  a.dx = a.i;
  a.dy = a.j;  // end at the centre
  EXPECT_NE(v2::arc_field_error(a), "");
  a = worked();
  a.dx = a.dy = 0;  // full circle: fine
  EXPECT_EQ(v2::arc_field_error(a), "");
}

}  // namespace

// Planes (flags bits 3:2): G17 XY = 0 (flags = the motion code), G18 ZX = 1, G19 YZ = 2; 3 and a
// plane other than XY on a 2-axis board are refused; the plane survives the round trip.
TEST(ArcCodec, Planes) {
  v2::Arc a = worked();
  EXPECT_EQ(a.plane, v2::ArcPlane::XY) << "default";
  const v2::Frame xy = v2::arc(1, a);
  EXPECT_EQ(xy.payload[0], a.code) << "XY: flags as without planes";
  for (const auto plane : {v2::ArcPlane::ZX, v2::ArcPlane::YZ}) {
    a.plane = plane;
    const v2::Frame f = v2::arc(1, a);
    EXPECT_EQ(f.payload[0], a.code | static_cast<unsigned>(plane) << 2);
    EXPECT_EQ(std::vector<uint8_t>(f.payload.begin() + 1, f.payload.end()),
              std::vector<uint8_t>(xy.payload.begin() + 1, xy.payload.end()))
        << "only the flags differ";
    EXPECT_EQ(v2::decode_arc(f), a);
    EXPECT_EQ(v2::check_host_frame(f, 4), std::nullopt);
    EXPECT_EQ(v2::check_host_frame(f, 3), std::nullopt);
    EXPECT_EQ(v2::check_host_frame(f, 2), v2::NakReason::BadField) << "needs 3 axes";
    EXPECT_FALSE(v2::arc_field_error(a, 2).empty());
  }
  a.plane = static_cast<v2::ArcPlane>(3);
  EXPECT_THROW(v2::arc(1, a), std::invalid_argument);
  a.plane = v2::ArcPlane::XY;
  a.dz = 5;
  EXPECT_EQ(v2::check_host_frame(v2::arc(1, a), 2), v2::NakReason::BadField) << "helix, 2 axes";
  a.dz = 0;
  EXPECT_EQ(v2::check_host_frame(v2::arc(1, a), 2), std::nullopt) << "flat XY arc, 2 axes";
}
