// Protocol v2 frames as bytes (docs/protocol.md "Frame", "Host to device"): the stimulus side
// of the twins' tests and of the co-simulation, and the host's parser of device frames. Written
// from the protocol tables (the host library has its own codec).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

#include "fpgacnc/models/arc_walk.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins::v2 {

inline void put16(std::vector<uint8_t>& b, uint32_t v) {
  b.push_back(static_cast<uint8_t>(v >> 8));
  b.push_back(static_cast<uint8_t>(v));
}
inline void put32(std::vector<uint8_t>& b, uint32_t v) {
  put16(b, v >> 16);
  put16(b, v & 0xffff);
}

// SYNC, LEN, SEQ, TYPE, payload, CRC (over LEN..payload, high byte first).
inline std::vector<uint8_t> frame(uint8_t seq, uint8_t type, std::span<const uint8_t> payload) {
  if (payload.size() > static_cast<size_t>(kMaxPayload))
    throw std::invalid_argument("v2 frame: payload longer than MAX_PAYLOAD");
  std::vector<uint8_t> b;
  b.reserve(6 + payload.size());
  for (uint8_t x : {kSync, static_cast<uint8_t>(payload.size()), seq, type}) b.push_back(x);
  for (uint8_t x : payload) b.push_back(x);
  put16(b, crc16_ccitt(b.data() + 1, b.size() - 1));
  return b;
}
inline std::vector<uint8_t> frame(uint8_t seq, uint8_t type, std::vector<uint8_t> payload = {}) {
  return frame(seq, type, std::span<const uint8_t>(payload));
}

// LINE payload: flags (code, SHORT), power, T, k axes of steps (int16 when `short_steps`).
inline std::vector<uint8_t> line_payload(uint8_t code, uint8_t power, uint32_t t,
                                         std::span<const int32_t> steps, bool short_steps) {
  std::vector<uint8_t> p{static_cast<uint8_t>((code & 3) | (short_steps ? 0x80 : 0)), power};
  put32(p, t);
  for (int32_t s : steps) {
    if (short_steps)
      put16(p, static_cast<uint16_t>(static_cast<int16_t>(s)));
    else
      put32(p, static_cast<uint32_t>(s));
  }
  return p;
}
// LINE_PROFILE (docs/protocol.md): flags, power, V_entry, V_cruise, V_exit (u48), A, D (u32),
// steps per axis (int16 with SHORT, else int32).
inline std::vector<uint8_t> line_profile_payload(uint8_t code, uint8_t power,
                                                 const ProfileParams& pr,
                                                 std::span<const int32_t> steps, bool short_steps) {
  std::vector<uint8_t> p{static_cast<uint8_t>((code & 3) | (short_steps ? 0x80 : 0)), power};
  for (uint64_t v : {pr.v_entry, pr.v_cruise, pr.v_exit}) {
    put16(p, static_cast<uint32_t>(v >> 32));
    put32(p, static_cast<uint32_t>(v));
  }
  put32(p, pr.accel);
  put32(p, pr.decel_at);
  for (int32_t s : steps) {
    if (short_steps)
      put16(p, static_cast<uint16_t>(static_cast<int16_t>(s)));
    else
      put32(p, static_cast<uint32_t>(s));
  }
  return p;
}
// ARC (docs/protocol.md, 63 bytes): flags (as given: code 2 / 3 in bits 1:0, bits 7:2 reserved),
// power, I, J, DX, DY int24, DZ int32, N_RAMP u24, C_TOTAL u48, V_entry, V_cruise, V_exit u64,
// A u48, D u48 (big-endian; fields wider than their slot are cut to it).
inline std::vector<uint8_t> arc_payload(uint8_t flags, uint8_t power, const models::arc::Frame& f) {
  std::vector<uint8_t> p{flags, power};
  auto put = [&p](uint64_t v, int bytes) {
    for (int b = bytes - 1; b >= 0; --b) p.push_back(static_cast<uint8_t>(v >> (8 * b)));
  };
  put(static_cast<uint32_t>(f.g.i), 3);
  put(static_cast<uint32_t>(f.g.j), 3);
  put(static_cast<uint32_t>(f.g.dx), 3);
  put(static_cast<uint32_t>(f.g.dy), 3);
  put(static_cast<uint32_t>(f.dz), 4);
  put(f.n_ramp, 3);
  put(f.c_total, 6);
  put(f.v_entry, 8);
  put(f.v_cruise, 8);
  put(f.v_exit, 8);
  put(f.a, 6);
  put(f.d, 6);
  return p;
}
// The entry's arc_raw (payload bytes 2..62) as an arc::Frame (int24 fields sign-extended).
inline models::arc::Frame arc_frame_from_raw(const std::array<uint8_t, spec::kArcRawBytes>& r,
                                             bool ccw) {
  auto get = [&r](int at, int bytes) {
    uint64_t v = 0;
    for (int b = 0; b < bytes; ++b) v = v << 8 | r[static_cast<size_t>(at + b)];
    return v;
  };
  auto s24 = [&](int at) {
    const auto v = static_cast<uint32_t>(get(at, 3));
    return static_cast<int32_t>(v << 8) >> 8;
  };
  models::arc::Frame f;
  f.g.i = s24(0);
  f.g.j = s24(3);
  f.g.dx = s24(6);
  f.g.dy = s24(9);
  f.g.ccw = ccw;
  f.dz = static_cast<int32_t>(static_cast<uint32_t>(get(12, 4)));
  f.n_ramp = static_cast<uint32_t>(get(16, 3));
  f.c_total = get(19, 6);
  f.v_entry = get(25, 8);
  f.v_cruise = get(33, 8);
  f.v_exit = get(41, 8);
  f.a = get(49, 6);
  f.d = get(55, 6);
  return f;
}
inline std::vector<uint8_t> config_axis_payload(uint8_t axis, const AxisTiming& t) {
  std::vector<uint8_t> p{axis};
  for (uint32_t v : {t.high, t.low, t.setup, t.hold}) put16(p, v);
  return p;
}
inline std::vector<uint8_t> numerators_payload(uint32_t x, uint32_t y) {
  std::vector<uint8_t> p;
  put32(p, x);
  put32(p, y);
  return p;
}
inline std::vector<uint8_t> dwell_payload(uint32_t t) {
  std::vector<uint8_t> p;
  put32(p, t);
  return p;
}
// MOTION: flags (bit 0 HOLD, bit 1 RESUME), feed and rapid rates (Q1.15), ramp.
inline std::vector<uint8_t> motion_payload(uint8_t flags, uint16_t feed, uint16_t rapid,
                                           uint32_t ramp) {
  std::vector<uint8_t> p{flags};
  put16(p, feed);
  put16(p, rapid);
  put32(p, ramp);
  return p;
}

struct DeviceFrame {
  uint8_t seq, type;
  std::vector<uint8_t> payload;
  uint8_t u8(size_t i) const { return payload.at(i); }
  uint16_t u16(size_t i) const { return static_cast<uint16_t>(u8(i) << 8 | u8(i + 1)); }
  uint32_t u32(size_t i) const { return static_cast<uint32_t>(u16(i)) << 16 | u16(i + 2); }
};

// Byte stream -> frames with a good CRC; hunts for SYNC after garbage or a bad frame.
class FrameParser {
 public:
  std::optional<DeviceFrame> feed(uint8_t b) {
    if (buf_.empty()) {
      if (b == kSync)
        buf_.push_back(b);
      else
        ++noise;
      return std::nullopt;
    }
    buf_.push_back(b);
    if (buf_.size() == 2 && b > kMaxPayload) {
      ++bad;
      buf_.clear();
      return std::nullopt;
    }
    if (buf_.size() < 6 || buf_.size() < 6u + buf_[1]) return std::nullopt;
    const size_t n = buf_[1];
    const uint16_t crc = crc16_ccitt(buf_.data() + 1, 3 + n);
    std::optional<DeviceFrame> f;
    if (crc == static_cast<uint16_t>(buf_[4 + n] << 8 | buf_[5 + n]))
      f = DeviceFrame{buf_[2], buf_[3], {buf_.begin() + 4, buf_.begin() + 4 + n}};
    else
      ++bad;
    buf_.clear();
    return f;
  }
  uint64_t noise = 0, bad = 0;

 private:
  std::vector<uint8_t> buf_;
};

}  // namespace fpgacnc::twins::v2
