// Closed-form ramps for the event-driven twins (run_profile in timing.h, arc::Dda in arc_walk.h):
// a register Q that adds R per clock while R itself changes by a constant step per clock, and the
// search for the last clock before Q reaches a threshold. Header-only, no SystemC.
#pragma once

#include <algorithm>
#include <cstdint>

namespace fpgacnc::twins::ramp {

using u128 = unsigned __int128;

// Saturating unsigned 128-bit arithmetic: a result at or above kSat = 2^126 is returned as kSat.
// Every threshold compared with these values is far below kSat, so a comparison is exact and a
// value below kSat is the exact result.
inline constexpr u128 kSat = static_cast<u128>(1) << 126;
inline constexpr u128 sat_mul(u128 a, u128 b) {
  if (a == 0 || b == 0) return 0;
  if (a >= kSat || b >= kSat || a > kSat / b) return kSat;
  return std::min(a * b, kSat);
}
inline constexpr u128 sat_add(u128 a, u128 b) {
  return std::min(std::min(a, kSat) + std::min(b, kSat), kSat);
}
// i (i - 1) / 2 and i (i + 1) / 2, saturating.
inline constexpr u128 tri_below(uint64_t i) {
  return i == 0 ? 0 : (i % 2 == 0 ? sat_mul(i / 2, i - 1) : sat_mul(i, (i - 1) / 2));
}
inline constexpr u128 tri_upto(uint64_t i) {
  return i % 2 == 0 ? sat_mul(i / 2, i + 1) : sat_mul(i, (i + 1) / 2);
}

// Q after i clocks of Q(c+1) = Q(c) + R(c), R(c+1) = R(c) +- step, from Q = q, R = r (saturating):
// rising q + i r + step i (i - 1) / 2; falling q + i (r - i step) + step i (i + 1) / 2, every term
// non-negative as long as r - i step >= 0 (the caller's bound on i).
inline constexpr u128 sum(u128 q, u128 r, u128 step, bool falling, uint64_t i) {
  if (!falling) return sat_add(q, sat_add(sat_mul(i, r), sat_mul(step, tri_below(i))));
  return sat_add(q, sat_add(sat_mul(i, r - step * i), sat_mul(step, tri_upto(i))));
}

// The largest i in [0, hi] (hi < 2^62) with ok(i), for ok true up to some i and false after, ok(0)
// true: probes 1, 3, 7, ... then bisects the last gap. O(log i) calls of ok.
template <class Pred>
inline uint64_t last_true(uint64_t hi, Pred ok) {
  uint64_t i = 0, step = 1;
  while (step <= hi - i && ok(i + step)) {
    i += step;
    if (step > hi - i) break;
    step <<= 1;
  }
  while (step > 1) {
    step >>= 1;
    if (step <= hi - i && ok(i + step)) i += step;
  }
  return i;
}

}  // namespace fpgacnc::twins::ramp
