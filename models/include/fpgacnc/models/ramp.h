// Closed-form ramps for the event-driven models (run_profile in the twins' timing.h, arc::Dda in
// arc_walk.h): a register Q that adds R per clock while R itself changes by a constant step per
// clock, and the search for the last clock before Q reaches a threshold. Header-only, no SystemC.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace fpgacnc::models::ramp {

using u128 = unsigned __int128;

// Saturating unsigned 128-bit arithmetic: a result at or above kSat = 2^126 is returned as kSat.
// Every threshold compared with these values is far below kSat, so a comparison is exact and a
// value below kSat is the exact result.
inline constexpr u128 kSat = static_cast<u128>(1) << 126;
inline constexpr u128 sat_mul(u128 a, u128 b) {
  u128 r = 0;
  if (__builtin_mul_overflow(a, b, &r) || r > kSat) return kSat;
  return r;
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

// The largest i in [0, hi] (hi < 2^62) with sum(q, r, step, falling, i) < target, for q < target
// (and r - hi step >= 0 when falling): a floating-point root of the quadratic as the first guess,
// corrected exactly (last_true when the guess is off by more than a few).
inline uint64_t last_below(u128 q, u128 r, u128 step, bool falling, u128 target, uint64_t hi) {
  const auto ok = [&](uint64_t i) { return sum(q, r, step, falling, i) < target; };
  const double rem = static_cast<double>(target - q), s = static_cast<double>(step),
               v = static_cast<double>(r);
  double x;  // real i at which the sum reaches target
  if (step == 0) {
    x = v > 0 ? rem / v : static_cast<double>(hi);
  } else if (!falling) {
    const double b = v - s / 2, root = std::sqrt(b * b + 2 * s * rem);
    x = b >= 0 ? 2 * rem / (b + root) : (root - b) / s;
  } else {
    const double b = v + s / 2, disc = b * b - 2 * s * rem;
    x = disc < 0 ? static_cast<double>(hi) : 2 * rem / (b + std::sqrt(disc));
  }
  uint64_t i = !(x > 1) ? 0 : x >= static_cast<double>(hi) ? hi : static_cast<uint64_t>(x);
  for (int tries = 0; tries < 4; ++tries) {
    if (ok(i)) {
      if (i == hi || !ok(i + 1)) return i;
      ++i;
    } else {
      --i;  // ok(0) holds: i > 0 here
    }
  }
  return last_true(hi, ok);
}

}  // namespace fpgacnc::models::ramp
