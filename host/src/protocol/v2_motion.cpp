// Motion frames, the FIFO entries of a job (docs/protocol.md "LINE", "LINE_PROFILE", "ARC",
// "DWELL", "OUTPUT", "NUMERATORS"): builders with their field rules, and decoders (fake devices,
// fuzzers, tests).
#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "fpgacnc/protocol/v2.h"
#include "v2_bytes.h"

namespace fpgacnc::protocol::v2 {
using detail::check_or_throw;
using detail::get16;
using detail::get32;
using detail::kProfileHeader;
using detail::make;
using detail::parse_arc;
using detail::parse_line_profile;
using detail::put16;
using detail::put32;

Frame numerators(uint8_t seq, uint32_t numerator_x, uint32_t numerator_y) {
  std::vector<uint8_t> p;
  put32(p, numerator_x);
  put32(p, numerator_y);
  return make(seq, Type::Numerators, std::move(p));
}

Frame line(uint8_t seq, uint8_t code, uint8_t power, uint32_t t, std::span<const int32_t> steps,
           bool short_if_fits) {
  if (code > 3) throw std::invalid_argument(fmt::format("LINE frame: motion code {} > 3", code));
  bool fits16 = short_if_fits;
  for (const int32_t s : steps) {
    if (s < std::numeric_limits<int16_t>::min() || s > std::numeric_limits<int16_t>::max()) {
      fits16 = false;
    }
  }
  const size_t w = fits16 ? 2 : 4;
  if (6 + w * steps.size() > kMaxPayload) {
    throw std::invalid_argument(
        fmt::format("LINE frame: {} axes of {} bytes exceed {} bytes of payload", steps.size(), w,
                    kMaxPayload));
  }
  std::vector<uint8_t> p;
  p.reserve(6 + w * steps.size());
  p.push_back(static_cast<uint8_t>(code | (fits16 ? kLineShort : 0)));
  p.push_back(power);
  put32(p, t);
  for (const int32_t s : steps) {
    if (fits16) {
      put16(p, static_cast<uint16_t>(static_cast<int16_t>(s)));
    } else {
      put32(p, static_cast<uint32_t>(s));
    }
  }
  return make(seq, Type::Line, std::move(p));
}

Frame dwell(uint8_t seq, uint32_t t) {
  std::vector<uint8_t> p;
  put32(p, t);
  return make(seq, Type::Dwell, std::move(p));
}

// ---- OUTPUT (TYPE 0x15) ----
bool OutputSet::empty() const {
  if (flood || mist || fan || laser_dyn) return false;
  for (const auto& d : dout)
    if (d) return false;
  return true;
}

Frame output_frame(uint8_t seq, const OutputSet& o) {
  if (o.empty()) throw std::invalid_argument("OUTPUT: no output to set (an empty mask)");
  uint8_t mask = 0, value = 0, duty = 0;
  auto put = [&](const std::optional<bool>& v, uint8_t bit) {
    if (!v) return;
    mask |= bit;
    if (*v) value |= bit;
  };
  put(o.flood, kOutFlood);
  put(o.mist, kOutMist);
  for (size_t n = 0; n < kDigitalOutputs; ++n) put(o.dout[n], static_cast<uint8_t>(kOutDout0 << n));
  put(o.laser_dyn, kOutLaserDyn);
  if (o.fan) {
    mask |= kOutFan;
    duty = *o.fan;
  }
  return make(seq, Type::Output, {mask, value, duty});
}

// ---- ARC (TYPE 0x13) ----
namespace {
void arc_put(std::vector<uint8_t>& v, uint64_t x, int bytes) {
  for (int b = bytes - 1; b >= 0; --b) v.push_back(static_cast<uint8_t>(x >> (8 * b)));
}
uint64_t arc_get(const std::vector<uint8_t>& v, size_t i, int bytes) {
  uint64_t x = 0;
  for (int b = 0; b < bytes; ++b) x = (x << 8) | v[i + static_cast<size_t>(b)];
  return x;
}
int32_t arc_get24s(const std::vector<uint8_t>& v, size_t i) {
  const uint32_t x = static_cast<uint32_t>(arc_get(v, i, 3));
  return (x & 0x800000u) ? static_cast<int32_t>(x) - (1 << 24) : static_cast<int32_t>(x);
}
}  // namespace

Arc detail::parse_arc(const Frame& f) {
  const auto& p = f.payload;
  Arc a;
  a.code = p[0] & 0x03;
  a.plane = static_cast<ArcPlane>((p[0] >> 2) & 0x03);
  a.power = p[1];
  a.i = arc_get24s(p, 2);
  a.j = arc_get24s(p, 5);
  a.dx = arc_get24s(p, 8);
  a.dy = arc_get24s(p, 11);
  a.dz = static_cast<int32_t>(static_cast<uint32_t>(arc_get(p, 14, 4)));
  a.n_ramp = static_cast<uint32_t>(arc_get(p, 18, 3));
  a.c_total = arc_get(p, 21, 6);
  a.v_entry = arc_get(p, 27, 8);
  a.v_cruise = arc_get(p, 35, 8);
  a.v_exit = arc_get(p, 43, 8);
  a.accel = arc_get(p, 51, 6);
  a.decel_at = arc_get(p, 57, 6);
  return a;
}

std::string arc_field_error(const Arc& a, size_t n_axes) {
  if (a.code != 2 && a.code != 3) return fmt::format("motion code {} (ARC needs 2 or 3)", a.code);
  const auto plane = static_cast<unsigned>(a.plane);
  if (plane > 2) return fmt::format("plane {} (0 XY, 1 ZX, 2 YZ)", plane);
  if (n_axes != 0 && n_axes < 3 && plane != 0)
    return fmt::format("plane {} on a board with {} axes (needs 3)", plane == 1 ? "ZX" : "YZ",
                       n_axes);
  if (n_axes != 0 && n_axes < 3 && a.dz != 0)
    return fmt::format("a helix (DZ {}) on a board with {} axes", a.dz, n_axes);
  const int64_t x0 = -int64_t{a.i}, y0 = -int64_t{a.j};
  const int64_t x1 = int64_t{a.dx} - a.i, y1 = int64_t{a.dy} - a.j;
  if (x0 == 0 && y0 == 0) return "start at the centre (I = J = 0)";
  if (x1 == 0 && y1 == 0) return "end at the centre";
  for (const int64_t c : {x0, y0, x1, y1}) {
    if (c <= -kArcCoordLimit || c >= kArcCoordLimit) {
      return fmt::format("coordinate {} relative to the centre: |.| >= 2^22", c);
    }
  }
  if (a.dz == std::numeric_limits<int32_t>::min()) return "DZ = -2^31";
  if (a.n_ramp == 0 || a.n_ramp > kArcNRampMax)
    return fmt::format("N_RAMP {} not in 1..2^24-1", a.n_ramp);
  if (a.c_total == 0 || a.c_total >= kArcCTotalLimit) {
    return fmt::format("C_TOTAL {} not in 1..2^46-1", a.c_total);
  }
  if (a.v_cruise >= (uint64_t{1} << 63)) return fmt::format("V_cruise {} >= 2^63", a.v_cruise);
  if (a.v_entry > a.v_cruise) return fmt::format("V_entry {} > V_cruise {}", a.v_entry, a.v_cruise);
  if (a.v_exit > a.v_cruise) return fmt::format("V_exit {} > V_cruise {}", a.v_exit, a.v_cruise);
  if (a.v_exit == 0) return "V_exit = 0";
  if (a.accel > kArcU48Max || a.decel_at > kArcU48Max) return "A or D >= 2^48";
  if (a.accel == 0 && a.v_entry == 0) return "A = 0 and V_entry = 0 (never moves)";
  return {};
}

Frame arc(uint8_t seq, const Arc& a) {
  if (const auto e = arc_field_error(a); !e.empty()) throw std::invalid_argument("ARC frame: " + e);
  std::vector<uint8_t> p;
  p.reserve(kArcPayload);
  p.push_back(static_cast<uint8_t>(a.code | static_cast<unsigned>(a.plane) << 2));
  p.push_back(a.power);
  for (const int32_t c : {a.i, a.j, a.dx, a.dy})
    arc_put(p, static_cast<uint32_t>(c) & 0xFFFFFFu, 3);
  arc_put(p, static_cast<uint32_t>(a.dz), 4);
  arc_put(p, a.n_ramp, 3);
  arc_put(p, a.c_total, 6);
  arc_put(p, a.v_entry, 8);
  arc_put(p, a.v_cruise, 8);
  arc_put(p, a.v_exit, 8);
  arc_put(p, a.accel, 6);
  arc_put(p, a.decel_at, 6);
  return make(seq, Type::Arc, std::move(p));
}

namespace {

void put48(std::vector<uint8_t>& v, uint64_t x) {
  put16(v, static_cast<uint16_t>(x >> 32));
  put32(v, static_cast<uint32_t>(x));
}
uint64_t get48(const std::vector<uint8_t>& v, size_t i) {
  return (uint64_t{get16(v, i)} << 32) | get32(v, i + 2);
}

}  // namespace

LineProfile detail::parse_line_profile(const Frame& f) {
  const auto& p = f.payload;
  LineProfile l;
  l.code = p[0] & 0x03;
  l.short_steps = (p[0] & kLineShort) != 0;
  l.power = p[1];
  l.v_entry = get48(p, 2);
  l.v_cruise = get48(p, 8);
  l.v_exit = get48(p, 14);
  l.accel = get32(p, 20);
  l.decel_at = get32(p, 24);
  const size_t w = l.short_steps ? 2 : 4;
  for (size_t i = kProfileHeader; i + w <= p.size(); i += w) {
    l.steps.push_back(w == 2 ? static_cast<int32_t>(static_cast<int16_t>(get16(p, i)))
                             : static_cast<int32_t>(get32(p, i)));
  }
  return l;
}

std::string line_profile_field_error(const LineProfile& p) {
  uint64_t n_dom = 0;
  for (const int32_t s : p.steps) {
    const uint64_t m = s < 0 ? uint64_t{0} - static_cast<uint64_t>(static_cast<int64_t>(s))
                             : static_cast<uint64_t>(s);
    n_dom = std::max(n_dom, m);
  }
  if (n_dom == 0) return "no axis moves (n_dom = 0)";
  if (n_dom > kProfileNDomMax) return fmt::format("n_dom {} >= 2^24", n_dom);
  if (p.v_cruise >= kProfileVMax) return fmt::format("V_cruise {} >= 2^47", p.v_cruise);
  if (p.v_entry > p.v_cruise) return fmt::format("V_entry {} > V_cruise {}", p.v_entry, p.v_cruise);
  if (p.v_exit > p.v_cruise) return fmt::format("V_exit {} > V_cruise {}", p.v_exit, p.v_cruise);
  if (p.v_exit == 0) return "V_exit = 0";
  if (p.accel == 0 && p.v_entry == 0) return "A = 0 and V_entry = 0 (never moves)";
  return {};
}

Frame line_profile(uint8_t seq, const LineProfile& lp, bool short_if_fits) {
  if (lp.code > 3) {
    throw std::invalid_argument(fmt::format("LINE_PROFILE frame: motion code {} > 3", lp.code));
  }
  if (const auto e = line_profile_field_error(lp); !e.empty()) {
    throw std::invalid_argument("LINE_PROFILE frame: " + e);
  }
  bool fits16 = short_if_fits;
  for (const int32_t s : lp.steps) {
    if (s < std::numeric_limits<int16_t>::min() || s > std::numeric_limits<int16_t>::max()) {
      fits16 = false;
    }
  }
  const size_t w = fits16 ? 2 : 4;
  if (kProfileHeader + w * lp.steps.size() > kMaxPayload) {
    throw std::invalid_argument(
        fmt::format("LINE_PROFILE frame: {} axes of {} bytes exceed {} bytes of payload",
                    lp.steps.size(), w, kMaxPayload));
  }
  std::vector<uint8_t> p;
  p.reserve(kProfileHeader + w * lp.steps.size());
  p.push_back(static_cast<uint8_t>(lp.code | (fits16 ? kLineShort : 0)));
  p.push_back(lp.power);
  put48(p, lp.v_entry);
  put48(p, lp.v_cruise);
  put48(p, lp.v_exit);
  put32(p, lp.accel);
  put32(p, lp.decel_at);
  for (const int32_t s : lp.steps) {
    if (fits16) {
      put16(p, static_cast<uint16_t>(static_cast<int16_t>(s)));
    } else {
      put32(p, static_cast<uint32_t>(s));
    }
  }
  return make(seq, Type::LineProfile, std::move(p));
}

Line decode_line(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::Line, n_axes);
  const auto& p = f.payload;
  Line l;
  l.code = p[0] & 0x03;
  l.short_steps = (p[0] & kLineShort) != 0;
  l.power = p[1];
  l.t = get32(p, 2);
  const size_t w = l.short_steps ? 2 : 4;
  for (size_t i = spec::kLenLineHeader; i + w <= p.size(); i += w) {
    l.steps.push_back(w == 2 ? static_cast<int32_t>(static_cast<int16_t>(get16(p, i)))
                             : static_cast<int32_t>(get32(p, i)));
  }
  return l;
}

uint32_t decode_dwell(const Frame& f) {
  check_or_throw(f, Type::Dwell, 0);
  return get32(f.payload, 0);
}

OutputSet decode_output(const Frame& f) {
  check_or_throw(f, Type::Output, 0);
  const uint8_t mask = f.payload[0], value = f.payload[1];
  OutputSet o;
  auto get = [&](uint8_t bit) -> std::optional<bool> {
    if ((mask & bit) == 0) return std::nullopt;
    return (value & bit) != 0;
  };
  o.flood = get(kOutFlood);
  o.mist = get(kOutMist);
  for (size_t n = 0; n < kDigitalOutputs; ++n)
    o.dout[n] = get(static_cast<uint8_t>(kOutDout0 << n));
  o.laser_dyn = get(kOutLaserDyn);
  if ((mask & kOutFan) != 0) o.fan = f.payload[2];
  return o;
}

Arc decode_arc(const Frame& f) {
  check_or_throw(f, Type::Arc, 0);
  return parse_arc(f);
}

LineProfile decode_line_profile(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::LineProfile, n_axes);
  return parse_line_profile(f);
}

std::array<uint32_t, 2> decode_numerators(const Frame& f) {
  check_or_throw(f, Type::Numerators, 0);
  return {get32(f.payload, 0), get32(f.payload, 4)};
}

}  // namespace fpgacnc::protocol::v2
