// The command-FIFO entry that segment_prep takes (rtl-back contract, docs/timing.md): the layout of
// spec/protocol.toml [entry] (fpgacnc/spec.h; docs/architecture.md "Command-FIFO entry"),
// steps[32*N-1:0] (axis a in [32*a+:32]) then the fields. The ARC fields stay 0 here.
// LINE_PROFILE: prof = 1, v2 = 1, kind 0, t = A; the profile fields are 0 for every other entry.
#pragma once

#include <cstdint>
#include <initializer_list>

#include "fpgacnc/spec.h"

namespace fpgacnc::tb {

inline constexpr int kEntryAxes = 4;
inline constexpr int kEntryWords = (spec::entry_width(kEntryAxes) + 31) / 32;

enum EntryKind {
  kMotion = spec::kKindMotion,
  kNumerators = spec::kKindNumerators,
  kDwell = spec::kKindDwell,
  kKind3 = spec::kKindOutput
};

struct Entry {
  bool v2 = false;
  int kind = kMotion;
  int code = 0;
  int power = 0xFF;
  uint32_t t = 0;  // v1: feed; v2 LINE / DWELL: T
  int32_t steps[kEntryAxes] = {0, 0, 0, 0};
  bool prof = false;  // LINE_PROFILE (t = A)
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;
  uint32_t decel_at = 0;

  // Writes the entry into a Verilated wide port (`words` 32-bit words, 11 for 4 axes).
  template <class Wide>
  void pack(Wide& w, int words = kEntryWords) const {
    for (int i = 0; i < words; ++i) w[i] = 0;
    auto put = [&](int pos, int width, uint64_t v) {
      for (int b = 0; b < width; ++b)
        if ((v >> b) & 1) w[(pos + b) / 32] |= 1u << ((pos + b) % 32);
    };
    for (int a = 0; a < kEntryAxes; ++a) put(32 * a, 32, static_cast<uint32_t>(steps[a]));
    const int sw = spec::kEntryStepsPerAxis * kEntryAxes;
    auto field = [&](spec::EntryField f, uint64_t v) { put(sw + f.lsb, f.width, v); };
    field(spec::kEntryT, t);
    field(spec::kEntryPower, static_cast<uint64_t>(power));
    field(spec::kEntryCode, static_cast<uint64_t>(code));
    field(spec::kEntryKind, static_cast<uint64_t>(kind));
    field(spec::kEntryV2, v2 ? 1 : 0);
    field(spec::kEntryProf, prof ? 1 : 0);
    field(spec::kEntryVEntry, v_entry);
    field(spec::kEntryVCruise, v_cruise);
    field(spec::kEntryVExit, v_exit);
    field(spec::kEntryDecelAt, decel_at);
  }
};

inline Entry v1_motion(int code, int32_t x, int32_t y, uint16_t feed) {
  Entry e;
  e.code = code;
  e.t = feed;
  e.steps[0] = x;
  e.steps[1] = y;
  return e;
}
inline Entry numerators(uint32_t nx, uint32_t ny, bool v2 = false) {
  Entry e;
  e.v2 = v2;
  e.kind = kNumerators;
  e.steps[0] = static_cast<int32_t>(nx);
  e.steps[1] = static_cast<int32_t>(ny);
  return e;
}
inline Entry v2_line(int code, int power, uint32_t t, std::initializer_list<int32_t> steps) {
  Entry e;
  e.v2 = true;
  e.code = code;
  e.power = power;
  e.t = t;
  int a = 0;
  for (int32_t s : steps) e.steps[a++] = s;
  return e;
}
inline Entry line_profile(int code, int power, uint64_t v_entry, uint64_t v_cruise, uint64_t v_exit,
                          uint32_t accel, uint32_t decel_at, std::initializer_list<int32_t> steps) {
  Entry e;
  e.v2 = true;
  e.prof = true;
  e.code = code;
  e.power = power;
  e.t = accel;
  e.v_entry = v_entry;
  e.v_cruise = v_cruise;
  e.v_exit = v_exit;
  e.decel_at = decel_at;
  int a = 0;
  for (int32_t s : steps) e.steps[a++] = s;
  return e;
}
inline Entry dwell(uint32_t t) {
  Entry e;
  e.v2 = true;
  e.kind = kDwell;
  e.power = 0;
  e.t = t;
  return e;
}

}  // namespace fpgacnc::tb
