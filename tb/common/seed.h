// Seeds for randomized benches: a fixed default per test, overridden by FPGACNC_SEED, printed so
// that any failure can be reproduced.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace fpgacnc::tb {

inline uint64_t test_seed(uint64_t fallback, const char* what) {
  uint64_t seed = fallback;
  if (const char* env = std::getenv("FPGACNC_SEED")) seed = std::strtoull(env, nullptr, 0);
  std::printf("[seed] %s: %llu (set FPGACNC_SEED to reproduce)\n", what,
              static_cast<unsigned long long>(seed));
  return seed;
}

}  // namespace fpgacnc::tb
