// Protocol v2 frames for benches, written from docs/protocol.md ("v2") independently of the
// host's packer so that each checks the other: CRC-16/CCITT-FALSE, host frame builders, and a
// parser of the device's byte stream (v2 frames and v1 0xAA bytes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fpgacnc/spec.h"

namespace fpgacnc::tb::v2 {

// The numbers come from spec/protocol.toml (fpgacnc/spec.h, generated); the codec below is
// written here.
inline constexpr uint8_t kSync = spec::kSync;
inline constexpr int kMaxPayload = static_cast<int>(spec::kMaxPayload);

enum Type : uint8_t {
  kHello = spec::kTypeHello,
  kStatusQuery = spec::kTypeStatusQuery,
  kFaultClear = spec::kTypeFaultClear,
  kConfigAxis = spec::kTypeConfigAxis,
  kConfigTravel = spec::kTypeConfigTravel,
  kNumerators = spec::kTypeNumerators,
  kRelease = spec::kTypeRelease,
  kLine = spec::kTypeLine,
  kDwell = spec::kTypeDwell,
  kLineProfile = spec::kTypeLineProfile,
  kArc = spec::kTypeArc,
  kOutput = spec::kTypeOutput,
  kAck = spec::kTypeAck,
  kNak = spec::kTypeNak,
  kDone = spec::kTypeDone,
  kStatus = spec::kTypeStatus,
  kIdent = spec::kTypeIdent,
};

enum Reason : uint8_t {
  kBadCrc = spec::kNakBadCrc,
  kBadLength = spec::kNakBadLength,
  kUnknownType = spec::kNakUnknownType,
  kTimeout = spec::kNakTimeout,
  kOutOfOrder = spec::kNakOutOfOrder,
  kFifoFull = spec::kNakFifoFull,
  kBadField = spec::kNakBadField,
  kTravel = spec::kNakTravel,
};

// CRC-16/CCITT-FALSE, bit by bit: poly 0x1021, init 0xFFFF, no reflection, no final XOR.
inline uint16_t crc16(const uint8_t* p, size_t n, uint16_t crc = 0xFFFF) {
  for (size_t i = 0; i < n; ++i) {
    crc = static_cast<uint16_t>(crc ^ (uint16_t{p[i]} << 8));
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint16_t>((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
  }
  return crc;
}
inline uint16_t crc16(const std::vector<uint8_t>& v) {
  return crc16(v.data(), v.size());
}

inline void be16(std::vector<uint8_t>& v, uint32_t x) {
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
inline void be32(std::vector<uint8_t>& v, uint32_t x) {
  for (int s = 24; s >= 0; s -= 8) v.push_back(static_cast<uint8_t>(x >> s));
}

// A whole frame: A5, LEN, SEQ, TYPE, payload, CRC (high byte first) over LEN..payload.
inline std::vector<uint8_t> frame(uint8_t type, uint8_t seq, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> v;
  v.reserve(payload.size() + 6);
  v.push_back(kSync);
  v.push_back(static_cast<uint8_t>(payload.size()));
  v.push_back(seq);
  v.push_back(type);
  for (uint8_t b : payload) v.push_back(b);
  const uint16_t c = crc16(v.data() + 1, v.size() - 1);
  be16(v, c);
  return v;
}

inline std::vector<uint8_t> hello(uint8_t seq = 0) {
  return frame(kHello, seq, {});
}
inline std::vector<uint8_t> status_query(uint8_t seq = 0) {
  return frame(kStatusQuery, seq, {});
}
inline std::vector<uint8_t> fault_clear(uint8_t seq) {
  return frame(kFaultClear, seq, {});
}
inline std::vector<uint8_t> release(uint8_t seq) {
  return frame(kRelease, seq, {});
}
inline std::vector<uint8_t> config_axis(uint8_t seq, uint8_t axis, uint16_t high, uint16_t low,
                                        uint16_t setup, uint16_t hold) {
  std::vector<uint8_t> p{axis};
  be16(p, high);
  be16(p, low);
  be16(p, setup);
  be16(p, hold);
  return frame(kConfigAxis, seq, p);
}
// CONFIG_TRAVEL: axis, flags (bit 0 enable), MIN, MAX (signed steps).
inline std::vector<uint8_t> config_travel(uint8_t seq, uint8_t axis, bool enable, int32_t min,
                                          int32_t max, uint8_t flags_extra = 0) {
  std::vector<uint8_t> p{axis, static_cast<uint8_t>((enable ? 1 : 0) | flags_extra)};
  be32(p, static_cast<uint32_t>(min));
  be32(p, static_cast<uint32_t>(max));
  return frame(kConfigTravel, seq, p);
}
inline std::vector<uint8_t> numerators(uint8_t seq, uint32_t nx, uint32_t ny) {
  std::vector<uint8_t> p;
  be32(p, nx);
  be32(p, ny);
  return frame(kNumerators, seq, p);
}
inline std::vector<uint8_t> dwell(uint8_t seq, uint32_t t) {
  std::vector<uint8_t> p;
  be32(p, t);
  return frame(kDwell, seq, p);
}
// OUTPUT (docs/protocol.md "OUTPUT"): mask (bit 0 flood, 1 mist, 2 fan, 3..6 digital outputs
// 0..3), value (the same bits; the fan's is 0), fan duty (0 unless mask bit 2).
inline constexpr uint8_t kOutFlood = spec::kOutFlood, kOutMist = spec::kOutMist,
                         kOutFan = spec::kOutFan;
inline constexpr uint8_t out_dout(int n) {
  return static_cast<uint8_t>(spec::kOutDout0 << n);
}
inline std::vector<uint8_t> output(uint8_t seq, uint8_t mask, uint8_t value, uint8_t duty) {
  return frame(kOutput, seq, {mask, value, duty});
}
// LINE payload: flags (code, SHORT), power, T, steps for the given axes (int16 when short_steps).
inline std::vector<uint8_t> line_payload(uint8_t code, uint8_t power, uint32_t t,
                                         const std::vector<int32_t>& steps, bool short_steps) {
  std::vector<uint8_t> p{static_cast<uint8_t>((code & 3u) | (short_steps ? 0x80u : 0u)), power};
  be32(p, t);
  for (int32_t s : steps) {
    if (short_steps)
      be16(p, static_cast<uint16_t>(s));
    else
      be32(p, static_cast<uint32_t>(s));
  }
  return p;
}
inline std::vector<uint8_t> line(uint8_t seq, uint8_t code, uint8_t power, uint32_t t,
                                 const std::vector<int32_t>& steps, bool short_steps) {
  return frame(kLine, seq, line_payload(code, power, t, steps, short_steps));
}
// LINE_PROFILE (docs/protocol.md): flags (code, SHORT), power, V_entry, V_cruise, V_exit u48, A,
// D u32, steps (int16 when short_steps).
inline std::vector<uint8_t> line_profile(uint8_t seq, uint8_t code, uint8_t power, uint64_t v_entry,
                                         uint64_t v_cruise, uint64_t v_exit, uint32_t accel,
                                         uint32_t decel_at, const std::vector<int32_t>& steps,
                                         bool short_steps) {
  std::vector<uint8_t> p{static_cast<uint8_t>((code & 3u) | (short_steps ? 0x80u : 0u)), power};
  for (uint64_t v : {v_entry, v_cruise, v_exit}) {
    be16(p, static_cast<uint32_t>(v >> 32));
    be32(p, static_cast<uint32_t>(v));
  }
  be32(p, accel);
  be32(p, decel_at);
  for (int32_t s : steps) {
    if (short_steps)
      be16(p, static_cast<uint16_t>(s));
    else
      be32(p, static_cast<uint32_t>(s));
  }
  return frame(kLineProfile, seq, p);
}
// Whether every step fits int16 (SHORT form).
inline bool fits_short(const std::vector<int32_t>& steps) {
  for (int32_t s : steps)
    if (s < -32768 || s > 32767) return false;
  return true;
}

// A device frame or a v1 0xAA byte taken from the tx stream.
struct DeviceMsg {
  bool v1_ack = false;
  uint8_t seq = 0, type = 0;
  std::vector<uint8_t> payload;
  bool crc_ok = false;
  uint64_t cycle = 0;  // start cycle of its first byte (when known)

  uint32_t u8(size_t i) const { return payload.at(i); }
  uint32_t u16(size_t i) const { return (u8(i) << 8) | u8(i + 1); }
  uint32_t u32(size_t i) const { return (u16(i) << 16) | u16(i + 2); }
};

// Parses the device's byte stream: 0xAA between frames is a v1 ACK, 0xA5 starts a frame.
class DeviceParser {
 public:
  // Returns a message when a byte completes one; other bytes between frames are kept as junk.
  std::optional<DeviceMsg> push(uint8_t b, uint64_t cycle = 0) {
    if (buf_.empty()) {
      if (b == spec::kV1Ack) {
        DeviceMsg m;
        m.v1_ack = true;
        m.crc_ok = true;
        m.cycle = cycle;
        return m;
      }
      if (b != kSync) {
        ++junk_;
        return std::nullopt;
      }
      start_ = cycle;
    }
    buf_.push_back(b);
    if (buf_.size() >= 2 && buf_.size() == size_t{buf_[1]} + 6) {
      DeviceMsg m;
      m.seq = buf_[2];
      m.type = buf_[3];
      m.payload.assign(buf_.begin() + 4, buf_.end() - 2);
      const uint16_t got = static_cast<uint16_t>((buf_[buf_.size() - 2] << 8) | buf_.back());
      m.crc_ok = crc16(buf_.data() + 1, buf_.size() - 3) == got;
      m.cycle = start_;
      buf_.clear();
      return m;
    }
    return std::nullopt;
  }
  bool mid_frame() const { return !buf_.empty(); }
  uint64_t junk() const { return junk_; }

 private:
  std::vector<uint8_t> buf_;
  uint64_t start_ = 0;
  uint64_t junk_ = 0;
};

inline std::string hex(const std::vector<uint8_t>& v) {
  static const char* d = "0123456789ABCDEF";
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i) s += ' ';
    s += d[v[i] >> 4];
    s += d[v[i] & 15];
  }
  return s;
}

}  // namespace fpgacnc::tb::v2
