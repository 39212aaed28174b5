// Protocol v1 packets for benches, written from docs/protocol.md ("v1") independently of the host's
// packer so that each checks the other.
#pragma once

#include <cstdint>
#include <vector>

#include "fpgacnc/spec.h"

namespace fpgacnc::tb {

inline void put32(std::vector<uint8_t>& v, uint32_t x) {
  for (int s = 24; s >= 0; s -= 8) v.push_back(static_cast<uint8_t>(x >> s));
}

inline std::vector<uint8_t> init_packet(uint32_t nx, uint32_t ny) {
  std::vector<uint8_t> v{spec::kV1InitByte};
  put32(v, nx);
  put32(v, ny);
  return v;
}

inline std::vector<uint8_t> motion_packet(uint8_t code, int32_t sx, int32_t sy, uint16_t feed) {
  std::vector<uint8_t> v{code};
  put32(v, static_cast<uint32_t>(sx));
  put32(v, static_cast<uint32_t>(sy));
  v.push_back(static_cast<uint8_t>(feed >> 8));
  v.push_back(static_cast<uint8_t>(feed));
  return v;
}

}  // namespace fpgacnc::tb
