#include "fpgacnc/protocol/v2.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace fpgacnc::protocol::v2 {
namespace {

void put16(std::vector<uint8_t>& v, uint16_t x) {
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
void put32(std::vector<uint8_t>& v, uint32_t x) {
  v.push_back(static_cast<uint8_t>(x >> 24));
  v.push_back(static_cast<uint8_t>(x >> 16));
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
uint16_t get16(const std::vector<uint8_t>& v, size_t i) {
  return static_cast<uint16_t>((v[i] << 8) | v[i + 1]);
}
uint32_t get32(const std::vector<uint8_t>& v, size_t i) {
  return (uint32_t{v[i]} << 24) | (uint32_t{v[i + 1]} << 16) | (uint32_t{v[i + 2]} << 8) |
         uint32_t{v[i + 3]};
}

// Precomputed table for the MSB-first CRC (one lookup per byte).
struct CrcTable {
  std::array<uint16_t, 256> t{};
  constexpr CrcTable() {
    for (unsigned i = 0; i < 256; ++i) {
      uint16_t c = static_cast<uint16_t>(i << 8);
      for (int b = 0; b < 8; ++b) {
        c = (c & 0x8000) ? static_cast<uint16_t>((c << 1) ^ 0x1021) : static_cast<uint16_t>(c << 1);
      }
      t[i] = c;
    }
  }
};
constexpr CrcTable kCrcTable;

void expect(const Frame& f, Type type, size_t len) {
  if (f.type != static_cast<uint8_t>(type)) {
    throw ProtocolError(fmt::format("expected a {} frame, got {}",
                                    type_name(static_cast<uint8_t>(type)), type_name(f.type)));
  }
  if (f.payload.size() != len) {
    throw ProtocolError(fmt::format("{}: payload of {} bytes, expected {}", type_name(f.type),
                                    f.payload.size(), len));
  }
}

Frame make(uint8_t seq, Type type, std::vector<uint8_t> payload = {}) {
  return Frame{seq, static_cast<uint8_t>(type), std::move(payload)};
}

Frame credit_frame(uint8_t dev_seq, Type type, const Credit& c) {
  std::vector<uint8_t> p;
  p.reserve(7);
  p.push_back(c.next_seq);
  put16(p, c.free);
  put32(p, c.done);
  return make(dev_seq, type, std::move(p));
}

Credit credit_from(const Frame& f) {
  return Credit{f.payload[0], get16(f.payload, 1), get32(f.payload, 3)};
}

}  // namespace

namespace {
// The TYPE table of spec/protocol.toml (fpgacnc/spec.h).
const spec::TypeInfo* type_info(uint8_t type) {
  for (const auto& t : spec::kTypes)
    if (t.value == type) return &t;
  return nullptr;
}
}  // namespace

std::string type_name(uint8_t type) {
  if (const auto* t = type_info(type)) return std::string(t->name);
  return fmt::format("type 0x{:02X}", type);
}

std::string nak_reason_name(uint8_t reason) {
  for (const auto& r : spec::kNakReasons)
    if (r.value == reason) return std::string(r.name);
  return fmt::format("reason {}", reason);
}

std::string counter_name(size_t index) {
  return index < kCounters ? std::string(spec::kCounterNames[index])
                           : fmt::format("counter {}", index);
}

bool is_sequenced(uint8_t type) {
  const auto* t = type_info(type);
  return t && t->host && t->sequenced;
}

bool is_fifo(uint8_t type) {
  const auto* t = type_info(type);
  return t && t->host && t->fifo;
}

uint16_t crc16(std::span<const uint8_t> data) {
  uint16_t c = 0xFFFF;
  for (const uint8_t b : data) {
    c = static_cast<uint16_t>((c << 8) ^ kCrcTable.t[((c >> 8) ^ b) & 0xFF]);
  }
  return c;
}

void encode_to(const Frame& f, std::vector<uint8_t>& out) {
  if (f.payload.size() > kMaxPayload) {
    throw std::invalid_argument(fmt::format("{} frame: payload of {} bytes exceeds {}",
                                            type_name(f.type), f.payload.size(), kMaxPayload));
  }
  const size_t start = out.size();
  out.push_back(kSync);
  out.push_back(static_cast<uint8_t>(f.payload.size()));
  out.push_back(f.seq);
  out.push_back(f.type);
  out.insert(out.end(), f.payload.begin(), f.payload.end());
  const uint16_t c =
      crc16(std::span<const uint8_t>(out.data() + start + 1, out.size() - start - 1));
  put16(out, c);
}

std::vector<uint8_t> encode(const Frame& f) {
  std::vector<uint8_t> out;
  out.reserve(kOverhead + f.payload.size());
  encode_to(f, out);
  return out;
}

// ---- FrameParser ----

void FrameParser::feed(std::span<const uint8_t> bytes) {
  compact();
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

void FrameParser::compact() {
  if (pos_ > 4096 || (pos_ > 0 && pos_ == buf_.size())) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(pos_));
    pos_ = 0;
  }
}

std::optional<Frame> FrameParser::next() {
  for (;;) {
    // Hunt for a sync byte.
    while (pos_ < buf_.size() && buf_[pos_] != kSync) {
      ++noise_bytes_;
      ++pos_;
    }
    if (buf_.size() - pos_ < 2) return std::nullopt;
    const size_t len = buf_[pos_ + 1];
    if (len > kMaxPayload) {
      ++bad_length_;
      ++pos_;  // reject this sync byte only
      continue;
    }
    if (buf_.size() - pos_ < kOverhead + len) return std::nullopt;
    const uint8_t* p = buf_.data() + pos_;
    const uint16_t want = crc16(std::span<const uint8_t>(p + 1, 3 + len));
    const uint16_t got = static_cast<uint16_t>((p[4 + len] << 8) | p[5 + len]);
    if (want != got) {
      ++crc_errors_;
      ++pos_;
      continue;
    }
    Frame f;
    f.seq = p[2];
    f.type = p[3];
    f.payload.assign(p + 4, p + 4 + len);
    pos_ += kOverhead + len;
    ++frames_;
    compact();
    return f;
  }
}

bool FrameParser::abandon_partial() {
  // next() leaves the buffer at a sync byte (or empty) whenever it returns nullopt.
  if (pos_ >= buf_.size() || buf_[pos_] != kSync) return false;
  ++abandoned_;
  ++pos_;
  return true;
}

void FrameParser::reset() {
  buf_.clear();
  pos_ = 0;
}

// ---- Device -> host ----

size_t status_payload_size(size_t n_axes) {
  return spec::kLenStatusHeader + spec::kLenStatusPerAxis * n_axes;
}

Credit decode_credit(const Frame& f) {
  if (f.type != static_cast<uint8_t>(Type::Ack) && f.type != static_cast<uint8_t>(Type::Done)) {
    throw ProtocolError(fmt::format("expected an ACK or DONE frame, got {}", type_name(f.type)));
  }
  if (f.payload.size() != spec::kLenAck) {
    throw ProtocolError(fmt::format("{}: payload of {} bytes, expected {}", type_name(f.type),
                                    f.payload.size(), spec::kLenAck));
  }
  return credit_from(f);
}

Nak decode_nak(const Frame& f) {
  expect(f, Type::Nak, spec::kLenNak);
  const uint8_t r = f.payload[1];
  if (r < 1 || r > 7) throw ProtocolError(fmt::format("NAK: unknown reason {}", r));
  return Nak{f.payload[0], static_cast<NakReason>(r), f.payload[2], get16(f.payload, 3)};
}

Ident decode_ident(const Frame& f) {
  expect(f, Type::Ident, spec::kLenIdent);
  const auto& p = f.payload;
  Ident i;
  i.version = p[0];
  i.n_axes = p[1];
  i.fifo_depth = get16(p, 2);
  i.clk_hz = get32(p, 4);
  i.baud = get32(p, 8);
  i.build_id = get32(p, 12);
  i.next_seq = p[16];
  i.max_payload = p[17];
  return i;
}

Status decode_status(const Frame& f, size_t n_axes) {
  if (n_axes > (kMaxPayload - spec::kLenStatusHeader) / spec::kLenStatusPerAxis) {
    throw ProtocolError(fmt::format("STATUS: {} axes cannot fit a frame", n_axes));
  }
  const size_t base = status_payload_size(n_axes);
  const size_t with_heaters = base + kHeaterChannels * kHeaterStatusBytes;
  expect(f, Type::Status, f.payload.size() == with_heaters ? with_heaters : base);
  const auto& p = f.payload;
  Status s;
  s.state = p[0];
  s.faults = p[1];
  s.fifo_level = get16(p, 2);
  s.next_seq = p[4];
  s.done = get32(p, 5);
  size_t i = 9;
  s.position.resize(n_axes);
  for (auto& x : s.position) {
    x = static_cast<int32_t>(get32(p, i));
    i += 4;
  }
  for (auto& c : s.counters) {
    c = get16(p, i);
    i += 2;
  }
  s.limit = p[i];
  s.switches = get16(p, i + 1);
  i += 3;
  // Heater block.
  for (; i + kHeaterStatusBytes <= p.size(); i += kHeaterStatusBytes) {
    HeaterStatus h;
    h.temp_q4 = static_cast<int16_t>(get16(p, i));
    h.setpoint_q4 = static_cast<int16_t>(get16(p, i + 2));
    h.duty_q15 = get16(p, i + 4);
    h.mode = p[i + 6];
    h.faults = p[i + 7];
    s.heaters.push_back(h);
  }
  return s;
}

Frame ack(uint8_t dev_seq, const Credit& c) {
  return credit_frame(dev_seq, Type::Ack, c);
}
Frame done(uint8_t dev_seq, const Credit& c) {
  return credit_frame(dev_seq, Type::Done, c);
}

Frame nak(uint8_t dev_seq, const Nak& n) {
  std::vector<uint8_t> p{n.seq, static_cast<uint8_t>(n.reason), n.next_seq};
  put16(p, n.free);
  return make(dev_seq, Type::Nak, std::move(p));
}

Frame ident(uint8_t dev_seq, const Ident& i) {
  std::vector<uint8_t> p{i.version, i.n_axes};
  put16(p, i.fifo_depth);
  put32(p, i.clk_hz);
  put32(p, i.baud);
  put32(p, i.build_id);
  p.push_back(i.next_seq);
  p.push_back(i.max_payload);
  return make(dev_seq, Type::Ident, std::move(p));
}

Frame status(uint8_t dev_seq, const Status& s) {
  std::vector<uint8_t> p{s.state, s.faults};
  put16(p, s.fifo_level);
  p.push_back(s.next_seq);
  put32(p, s.done);
  for (const int32_t x : s.position) put32(p, static_cast<uint32_t>(x));
  for (const uint16_t c : s.counters) put16(p, c);
  p.push_back(s.limit);
  put16(p, s.switches);
  for (const auto& h : s.heaters) {
    put16(p, static_cast<uint16_t>(h.temp_q4));
    put16(p, static_cast<uint16_t>(h.setpoint_q4));
    put16(p, h.duty_q15);
    p.push_back(h.mode);
    p.push_back(h.faults);
  }
  if (p.size() > kMaxPayload) {
    throw std::invalid_argument(
        fmt::format("STATUS frame: {} axes do not fit a frame", s.position.size()));
  }
  return make(dev_seq, Type::Status, std::move(p));
}

// ---- Host -> device ----

Frame hello(uint8_t seq) {
  return make(seq, Type::Hello);
}
Frame status_query(uint8_t seq) {
  return make(seq, Type::StatusQuery);
}
Frame fault_clear(uint8_t seq) {
  return make(seq, Type::FaultClear);
}
Frame release(uint8_t seq) {
  return make(seq, Type::Release);
}

Frame config_axis(uint8_t seq, uint8_t axis, uint16_t step_high, uint16_t step_low,
                  uint16_t dir_setup, uint16_t dir_hold) {
  std::vector<uint8_t> p{axis};
  put16(p, step_high);
  put16(p, step_low);
  put16(p, dir_setup);
  put16(p, dir_hold);
  return make(seq, Type::ConfigAxis, std::move(p));
}

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
  if (flood || mist || fan) return false;
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
Arc parse_arc(const Frame& f) {
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
}  // namespace

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
// Payload layout: flags, power, V_entry u48, V_cruise u48, V_exit u48, A u32, D u32, steps.
constexpr size_t kProfileHeader = spec::kLenLineProfileHeader;

LineProfile parse_line_profile(const Frame& f) {
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
}  // namespace

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

std::optional<NakReason> check_host_frame(const Frame& f, size_t n_axes) {
  const size_t n = f.payload.size();
  switch (static_cast<Type>(f.type)) {
    case Type::Hello:
    case Type::StatusQuery:
    case Type::FaultClear:
    case Type::Release:
      if (n != 0) return NakReason::BadLength;
      return std::nullopt;
    case Type::ConfigAxis:
      if (n != spec::kLenConfigAxis) return NakReason::BadLength;
      if (n_axes && f.payload[0] >= n_axes) return NakReason::BadField;
      return std::nullopt;
    case Type::Numerators:
      if (n != spec::kLenNumerators) return NakReason::BadLength;
      return std::nullopt;
    case Type::Dwell:
      if (n != spec::kLenDwell) return NakReason::BadLength;
      return std::nullopt;
    case Type::Line: {
      if (n < spec::kLenLineHeader) return NakReason::BadLength;
      const size_t w = (f.payload[0] & kLineShort) ? 2 : 4;
      if ((n - spec::kLenLineHeader) % w != 0) return NakReason::BadLength;
      if (n_axes && (n - spec::kLenLineHeader) / w > n_axes) return NakReason::BadLength;
      if (f.payload[0] & 0x7C) return NakReason::BadField;
      return std::nullopt;
    }
    case Type::Output: {
      if (n != kOutputPayload) return NakReason::BadLength;
      const uint8_t mask = f.payload[0], value = f.payload[1], duty = f.payload[2];
      if (mask == 0 || (mask & 0x80) != 0 || (value & ~mask) != 0 || (value & kOutFan) != 0 ||
          ((mask & kOutFan) == 0 && duty != 0))
        return NakReason::BadField;
      return std::nullopt;
    }
    case Type::Arc:
      if (n != kArcPayload) return NakReason::BadLength;
      if (f.payload[0] & 0xF0) return NakReason::BadField;
      if (!arc_field_error(parse_arc(f), n_axes).empty()) return NakReason::BadField;
      return std::nullopt;
    case Type::LineProfile: {
      if (n < kProfileHeader) return NakReason::BadLength;
      const size_t w = (f.payload[0] & kLineShort) ? 2 : 4;
      if ((n - kProfileHeader) % w != 0) return NakReason::BadLength;
      if (n_axes && (n - kProfileHeader) / w > n_axes) return NakReason::BadLength;
      if (f.payload[0] & 0x7C) return NakReason::BadField;
      if (!line_profile_field_error(parse_line_profile(f)).empty()) return NakReason::BadField;
      return std::nullopt;
    }
    // Heaters.
    case Type::HeaterConfig:
      if (n != spec::kLenHeaterConfig) return NakReason::BadLength;
      if (f.payload[0] > 1 || f.payload[1] > 4 || get16(f.payload, 14) > 0x8000 ||
          get16(f.payload, 18) > 0x8000)
        return NakReason::BadField;
      return std::nullopt;
    case Type::HeaterSetpoint:
      if (n != spec::kLenHeaterSetpoint) return NakReason::BadLength;
      if (f.payload[0] > 1) return NakReason::BadField;
      return std::nullopt;
    case Type::ThermistorTable:
      if (n < spec::kLenThermistorTableMin || n > spec::kLenThermistorTableMax || n % 2)
        return NakReason::BadLength;
      if (f.payload[0] > 1 || f.payload[1] + (n - 2) / 2 > kThermistorEntries)
        return NakReason::BadField;
      return std::nullopt;
    case Type::HeaterSafety:
      if (n != spec::kLenHeaterSafety) return NakReason::BadLength;
      if (f.payload[0] > 1 ||
          static_cast<int16_t>(get16(f.payload, 1)) >= static_cast<int16_t>(get16(f.payload, 3)))
        return NakReason::BadField;
      return std::nullopt;
    case Type::HeaterWatchdog:
      if (n != spec::kLenHeaterWatchdog) return NakReason::BadLength;
      return std::nullopt;
    default:
      return NakReason::UnknownType;
  }
}

namespace {
void check_or_throw(const Frame& f, Type type, size_t n_axes) {
  if (f.type != static_cast<uint8_t>(type)) {
    throw ProtocolError(fmt::format("expected a {} frame, got {}",
                                    type_name(static_cast<uint8_t>(type)), type_name(f.type)));
  }
  if (const auto r = check_host_frame(f, n_axes)) {
    throw ProtocolError(fmt::format("{}: {} (payload of {} bytes)", type_name(f.type),
                                    nak_reason_name(static_cast<uint8_t>(*r)), f.payload.size()));
  }
}
}  // namespace

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

ConfigAxis decode_config_axis(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::ConfigAxis, n_axes);
  const auto& p = f.payload;
  return ConfigAxis{p[0], get16(p, 1), get16(p, 3), get16(p, 5), get16(p, 7)};
}

std::array<uint32_t, 2> decode_numerators(const Frame& f) {
  check_or_throw(f, Type::Numerators, 0);
  return {get32(f.payload, 0), get32(f.payload, 4)};
}

// ---- Heaters ----

std::string limit_switch_name(uint8_t limit) {
  static constexpr std::string_view kNames = "XYZABCUVW";
  const unsigned axis = limit & 0x0F;
  const std::string name =
      axis < kNames.size() ? std::string(1, kNames[axis]) : fmt::format("axis {}", axis);
  return name + ((limit & 0x10) ? " max" : " min");
}

std::string describe_limits(const Status& s, size_t n_axes) {
  std::string out;
  if (s.faults & kFaultLimit) out = "LIMIT alarm: " + limit_switch_name(s.limit) + "; ";
  std::string sw;
  for (size_t a = 0; a < n_axes && a < 8; ++a) {
    for (const bool max : {false, true}) {
      if (!((s.switches >> (a + (max ? 8 : 0))) & 1u)) continue;
      sw +=
          (sw.empty() ? "" : ", ") + limit_switch_name(static_cast<uint8_t>(a | (max ? 0x10 : 0)));
    }
  }
  out += "switches: " + (sw.empty() ? std::string("none") : sw);
  if (s.state & kStatePosUntrusted) out += "; positions not trusted (a hard limit tripped)";
  return out;
}

std::string heater_fault_names(uint8_t faults) {
  static constexpr std::array<const char*, 4> kNames{"MINTEMP", "MAXTEMP", "RUNAWAY", "HEATING"};
  std::string s;
  for (size_t b = 0; b < 8; ++b) {
    if (!(faults & (1u << b))) continue;
    if (!s.empty()) s += '|';
    s += b < kNames.size() ? std::string(kNames[b]) : fmt::format("bit{}", b);
  }
  return s.empty() ? "none" : s;
}

Frame heater_config(uint8_t seq, const HeaterConfigFrame& c) {
  if (c.channel > 1 || c.mode > 4 || c.duty_max > 0x8000 || c.manual > 0x8000) {
    throw std::invalid_argument(fmt::format(
        "HEATER_CONFIG: channel {} (0..1), mode {} (0..4), duty_max 0x{:04X} / manual 0x{:04X} "
        "(<= 0x8000)",
        c.channel, c.mode, c.duty_max, c.manual));
  }
  std::vector<uint8_t> p{c.channel, c.mode};
  put32(p, c.kp);
  put32(p, c.ki);
  put32(p, c.kd);
  put16(p, c.duty_max);
  put16(p, c.hysteresis_q4);
  put16(p, c.manual);
  return make(seq, Type::HeaterConfig, std::move(p));
}

Frame heater_setpoint(uint8_t seq, uint8_t channel, int16_t setpoint_q4) {
  if (channel > 1) throw std::invalid_argument(fmt::format("HEATER_SETPOINT: channel {}", channel));
  std::vector<uint8_t> p{channel};
  put16(p, static_cast<uint16_t>(setpoint_q4));
  return make(seq, Type::HeaterSetpoint, std::move(p));
}

Frame thermistor_table(uint8_t seq, const ThermistorChunk& c) {
  if (c.channel > 1 || c.entries.empty() || c.entries.size() > kThermistorChunk ||
      c.first + c.entries.size() > kThermistorEntries) {
    throw std::invalid_argument(
        fmt::format("THERMISTOR_TABLE: channel {}, entries {}..{} (1..8 entries within 0..64)",
                    c.channel, c.first, c.first + c.entries.size()));
  }
  std::vector<uint8_t> p{c.channel, c.first};
  for (const int16_t e : c.entries) put16(p, static_cast<uint16_t>(e));
  return make(seq, Type::ThermistorTable, std::move(p));
}

Frame heater_safety(uint8_t seq, const HeaterSafetyFrame& c) {
  if (c.channel > 1 || c.tmin_q4 >= c.tmax_q4) {
    throw std::invalid_argument(fmt::format("HEATER_SAFETY: channel {}, Tmin {} >= Tmax {}",
                                            c.channel, c.tmin_q4 / 16.0, c.tmax_q4 / 16.0));
  }
  std::vector<uint8_t> p{c.channel};
  put16(p, static_cast<uint16_t>(c.tmin_q4));
  put16(p, static_cast<uint16_t>(c.tmax_q4));
  put16(p, c.runaway_band_q4);
  put16(p, c.runaway_ticks);
  put16(p, c.watch_rise_q4);
  put16(p, c.watch_ticks);
  return make(seq, Type::HeaterSafety, std::move(p));
}

Frame heater_watchdog(uint8_t seq, uint16_t ticks) {
  std::vector<uint8_t> p;
  put16(p, ticks);
  return make(seq, Type::HeaterWatchdog, std::move(p));
}

HeaterConfigFrame decode_heater_config(const Frame& f) {
  check_or_throw(f, Type::HeaterConfig, 0);
  const auto& p = f.payload;
  return HeaterConfigFrame{p[0],         p[1],         get32(p, 2),  get32(p, 6),
                           get32(p, 10), get16(p, 14), get16(p, 16), get16(p, 18)};
}

std::pair<uint8_t, int16_t> decode_heater_setpoint(const Frame& f) {
  check_or_throw(f, Type::HeaterSetpoint, 0);
  return {f.payload[0], static_cast<int16_t>(get16(f.payload, 1))};
}

ThermistorChunk decode_thermistor_table(const Frame& f) {
  check_or_throw(f, Type::ThermistorTable, 0);
  ThermistorChunk c{f.payload[0], f.payload[1], {}};
  for (size_t i = 2; i + 2 <= f.payload.size(); i += 2)
    c.entries.push_back(static_cast<int16_t>(get16(f.payload, i)));
  return c;
}

HeaterSafetyFrame decode_heater_safety(const Frame& f) {
  check_or_throw(f, Type::HeaterSafety, 0);
  const auto& p = f.payload;
  return HeaterSafetyFrame{p[0],
                           static_cast<int16_t>(get16(p, 1)),
                           static_cast<int16_t>(get16(p, 3)),
                           get16(p, 5),
                           get16(p, 7),
                           get16(p, 9),
                           get16(p, 11)};
}

uint16_t decode_heater_watchdog(const Frame& f) {
  check_or_throw(f, Type::HeaterWatchdog, 0);
  return get16(f.payload, 0);
}

std::string hex(std::span<const uint8_t> bytes) {
  std::string s;
  s.reserve(bytes.size() * 3);
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (i) s += ' ';
    s += fmt::format("{:02X}", bytes[i]);
  }
  return s;
}

}  // namespace fpgacnc::protocol::v2
