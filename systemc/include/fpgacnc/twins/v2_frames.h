// Protocol v2 frames as bytes (docs/protocol.md "Frame", "Host to device"): the stimulus side
// of the twins' tests and of the co-simulation, and the host's parser of device frames. Written
// from the protocol tables (the host library has its own codec).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <vector>

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
