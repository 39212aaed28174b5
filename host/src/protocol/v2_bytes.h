// Private to the v2 codec's files (host/src/protocol/v2_*.cpp): big-endian field access, the
// frame constructor and the checks the decoders share.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::protocol::v2::detail {

inline void put16(std::vector<uint8_t>& v, uint16_t x) {
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
inline void put32(std::vector<uint8_t>& v, uint32_t x) {
  v.push_back(static_cast<uint8_t>(x >> 24));
  v.push_back(static_cast<uint8_t>(x >> 16));
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
inline uint16_t get16(const std::vector<uint8_t>& v, size_t i) {
  return static_cast<uint16_t>((v[i] << 8) | v[i + 1]);
}
inline uint32_t get32(const std::vector<uint8_t>& v, size_t i) {
  return (uint32_t{v[i]} << 24) | (uint32_t{v[i + 1]} << 16) | (uint32_t{v[i + 2]} << 8) |
         uint32_t{v[i + 3]};
}

inline Frame make(uint8_t seq, Type type, std::vector<uint8_t> payload = {}) {
  return Frame{seq, static_cast<uint8_t>(type), std::move(payload)};
}

// ProtocolError unless `f` is of `type` with a payload of `len` bytes.
void expect(const Frame& f, Type type, size_t len);
// ProtocolError unless `f` is of `type` and check_host_frame accepts it (v2_check.cpp).
void check_or_throw(const Frame& f, Type type, size_t n_axes);

// The fields of an ARC / LINE_PROFILE payload whose length is already checked (v2_motion.cpp).
Arc parse_arc(const Frame& f);
LineProfile parse_line_profile(const Frame& f);
// LINE_PROFILE payload: flags, power, V_entry u48, V_cruise u48, V_exit u48, A u32, D u32, steps.
constexpr size_t kProfileHeader = spec::kLenLineProfileHeader;

}  // namespace fpgacnc::protocol::v2::detail
