// Control frames and the device's answers (docs/protocol.md "Frame types"): HELLO,
// STATUS_QUERY, FAULT_CLEAR, RELEASE and CONFIG_AXIS from the host; ACK, DONE, NAK, IDENT and
// STATUS from the device (decoders for the host, builders for fake devices and tests).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fpgacnc/protocol/v2.h"
#include "v2_bytes.h"

namespace fpgacnc::protocol::v2 {
using detail::check_or_throw;
using detail::expect;
using detail::get16;
using detail::get32;
using detail::make;
using detail::put16;
using detail::put32;

namespace {

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
  if (r < 1 || r > spec::kNakReasons.size())
    throw ProtocolError(fmt::format("NAK: unknown reason {}", r));
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

Frame config_travel(uint8_t seq, uint8_t axis, bool enable, int32_t min, int32_t max) {
  std::vector<uint8_t> p{axis, static_cast<uint8_t>(enable ? spec::kTravelEnable : 0)};
  put32(p, static_cast<uint32_t>(min));
  put32(p, static_cast<uint32_t>(max));
  return make(seq, Type::ConfigTravel, std::move(p));
}

std::string motion_field_error(const Motion& m) {
  if (m.hold && m.resume) return "HOLD and RESUME in one frame";
  if (m.cancel && m.resume) return "CANCEL and RESUME in one frame";
  if (m.feed < 1 || m.feed > kRateOne)
    return fmt::format("feed rate 0x{:04X} outside 1..0x8000", m.feed);
  if (m.rapid < 1 || m.rapid > kRateOne)
    return fmt::format("rapid rate 0x{:04X} outside 1..0x8000", m.rapid);
  if (m.ramp < 1) return "ramp 0 (the rate would never move)";
  return {};
}

Frame motion(const Motion& m, uint8_t seq) {
  if (const std::string e = motion_field_error(m); !e.empty())
    throw std::invalid_argument("MOTION frame: " + e);
  std::vector<uint8_t> p{static_cast<uint8_t>((m.hold ? kMotionHold : 0) |
                                              (m.resume ? kMotionResume : 0) |
                                              (m.cancel ? kMotionCancel : 0))};
  put16(p, m.feed);
  put16(p, m.rapid);
  put32(p, m.ramp);
  return make(seq, Type::Motion, std::move(p));
}

Motion decode_motion(const Frame& f) {
  check_or_throw(f, Type::Motion, 0);
  const auto& p = f.payload;
  Motion m;
  m.hold = (p[0] & kMotionHold) != 0;
  m.resume = (p[0] & kMotionResume) != 0;
  m.cancel = (p[0] & kMotionCancel) != 0;
  m.feed = get16(p, 1);
  m.rapid = get16(p, 3);
  m.ramp = get32(p, 5);
  return m;
}

uint16_t rate_from_percent(double pct) {
  if (!(pct > 0.0) || pct > 100.0)
    throw std::invalid_argument(fmt::format("motion rate {} % outside (0, 100]", pct));
  const double q = std::round(pct / 100.0 * kRateOne);
  return static_cast<uint16_t>(std::clamp(q, 1.0, static_cast<double>(kRateOne)));
}

uint32_t hold_ramp(double a_hold_steps_s2, double v_max_steps_s, double clk_hz) {
  for (const double x : {a_hold_steps_s2, v_max_steps_s, clk_hz}) {
    if (!std::isfinite(x) || x <= 0.0)
      throw std::invalid_argument(
          fmt::format("hold ramp: deceleration, top speed and clock must be positive ({}, {}, {})",
                      a_hold_steps_s2, v_max_steps_s, clk_hz));
  }
  const double period = std::ldexp(1.0, static_cast<int>(spec::kDefaultRatePeriodLog2));
  const double r =
      std::floor(std::ldexp(1.0, 32) * period * a_hold_steps_s2 / (v_max_steps_s * clk_hz));
  return static_cast<uint32_t>(std::clamp(r, 1.0, std::ldexp(1.0, 32) - 1.0));
}

ConfigAxis decode_config_axis(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::ConfigAxis, n_axes);
  const auto& p = f.payload;
  return ConfigAxis{p[0], get16(p, 1), get16(p, 3), get16(p, 5), get16(p, 7)};
}

// ---- Homing and probing ----

std::string trigger_field_error(TriggerMode mode, uint16_t switches, size_t n_axes) {
  const auto m = static_cast<uint8_t>(mode);
  if (m > spec::kTriggerProbeRelease) return fmt::format("mode {} (0..3)", m);
  if (mode != TriggerMode::Home) {
    if (switches != 0)
      return fmt::format("switch mask 0x{:04X} with mode {} (only HOME takes switches)", switches,
                         m);
    return {};
  }
  if (switches == 0) return "HOME without switches";
  const size_t axes = n_axes == 0 || n_axes > 8 ? 8 : n_axes;
  const uint16_t axis_bits = static_cast<uint16_t>((1u << axes) - 1u);
  const uint16_t allowed = static_cast<uint16_t>(axis_bits | (axis_bits << 8));
  if (switches & ~allowed)
    return fmt::format("switch mask 0x{:04X} names an axis the device does not have ({} axes)",
                       switches, axes);
  return {};
}

Frame trigger(uint8_t seq, TriggerMode mode, uint16_t switches, size_t n_axes) {
  if (const std::string e = trigger_field_error(mode, switches, n_axes); !e.empty())
    throw std::invalid_argument("TRIGGER frame: " + e);
  std::vector<uint8_t> p{static_cast<uint8_t>(mode)};
  put16(p, switches);
  return make(seq, Type::Trigger, std::move(p));
}

Frame set_position(uint8_t seq, uint16_t mask, std::span<const int32_t> position) {
  const size_t n = position.size();
  if (n == 0 || spec::kLenSetPositionHeader + spec::kLenSetPositionPerAxis * n > kMaxPayload)
    throw std::invalid_argument(fmt::format("SET_POSITION frame: {} axes", n));
  if (mask == 0) throw std::invalid_argument("SET_POSITION frame: axis mask 0");
  if (n < 16 && (mask >> n) != 0)
    throw std::invalid_argument(
        fmt::format("SET_POSITION frame: axis mask 0x{:04X} names an axis beyond {}", mask, n));
  std::vector<uint8_t> p;
  put16(p, mask);
  for (const int32_t x : position) put32(p, static_cast<uint32_t>(x));
  return make(seq, Type::SetPosition, std::move(p));
}

Frame trigger_query(uint8_t seq) {
  return make(seq, Type::TriggerQuery);
}

TriggerReport decode_trigger_report(const Frame& f, size_t n_axes) {
  expect(f, Type::TriggerReport,
         spec::kLenTriggerReportHeader + spec::kLenTriggerReportPerAxis * n_axes);
  const auto& p = f.payload;
  if (p[0] > spec::kTriggerProbeRelease)
    throw ProtocolError(fmt::format("TRIGGER_REPORT: mode {} (0..3)", p[0]));
  if (p[1] & ~(kTriggerArmed | kTriggerDone))
    throw ProtocolError(fmt::format("TRIGGER_REPORT: flags 0x{:02X}: bits 7..2 must be 0", p[1]));
  TriggerReport r;
  r.mode = static_cast<TriggerMode>(p[0]);
  r.flags = p[1];
  r.fired = get16(p, 2);
  r.latched.resize(n_axes);
  for (size_t a = 0; a < n_axes; ++a) r.latched[a] = static_cast<int32_t>(get32(p, 4 + 4 * a));
  return r;
}

Frame trigger_report(uint8_t dev_seq, const TriggerReport& r) {
  std::vector<uint8_t> p{static_cast<uint8_t>(r.mode), r.flags};
  put16(p, r.fired);
  for (const int32_t x : r.latched) put32(p, static_cast<uint32_t>(x));
  if (p.size() > kMaxPayload) {
    throw std::invalid_argument(
        fmt::format("TRIGGER_REPORT frame: {} axes do not fit a frame", r.latched.size()));
  }
  return make(dev_seq, Type::TriggerReport, std::move(p));
}

std::pair<TriggerMode, uint16_t> decode_trigger(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::Trigger, n_axes);
  return {static_cast<TriggerMode>(f.payload[0]), get16(f.payload, 1)};
}

std::pair<uint16_t, std::vector<int32_t>> decode_set_position(const Frame& f, size_t n_axes) {
  check_or_throw(f, Type::SetPosition, n_axes);
  std::vector<int32_t> pos((f.payload.size() - spec::kLenSetPositionHeader) /
                           spec::kLenSetPositionPerAxis);
  for (size_t a = 0; a < pos.size(); ++a)
    pos[a] = static_cast<int32_t>(get32(f.payload, spec::kLenSetPositionHeader + 4 * a));
  return {get16(f.payload, 0), std::move(pos)};
}

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

}  // namespace fpgacnc::protocol::v2
