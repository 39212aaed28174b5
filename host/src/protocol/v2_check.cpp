// The device's acceptance rules for every host frame (docs/protocol.md "Field rules"): the
// NAK a device gives a frame's length, type or fields (check_host_frame, used by fake devices
// and fuzzers), and the check every decoder of a host frame makes first.
#include <fmt/format.h>

#include "fpgacnc/protocol/v2.h"
#include "v2_bytes.h"

namespace fpgacnc::protocol::v2 {
using detail::get16;
using detail::kProfileHeader;
using detail::parse_arc;
using detail::parse_line_profile;

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
    case Type::ConfigTravel: {
      if (n != spec::kLenConfigTravel) return NakReason::BadLength;
      if (n_axes && f.payload[0] >= n_axes) return NakReason::BadField;
      if (f.payload[1] & ~spec::kTravelEnable) return NakReason::BadField;
      const auto be = [&](size_t i) {
        return static_cast<int32_t>(uint32_t{f.payload[i]} << 24 |
                                    uint32_t{f.payload[i + 1]} << 16 |
                                    uint32_t{f.payload[i + 2]} << 8 | f.payload[i + 3]);
      };
      if ((f.payload[1] & spec::kTravelEnable) && be(2) > be(6)) return NakReason::BadField;
      return std::nullopt;
    }
    case Type::Motion: {
      if (n != spec::kLenMotion) return NakReason::BadLength;
      const uint8_t flags = f.payload[0];
      const uint16_t feed = get16(f.payload, 1), rapid = get16(f.payload, 3);
      const uint32_t ramp = detail::get32(f.payload, 5);
      if ((flags & spec::kMotionReserved) ||
          ((flags & spec::kMotionResume) && (flags & (spec::kMotionHold | spec::kMotionCancel))) ||
          feed < 1 || feed > spec::kRateOne || rapid < 1 || rapid > spec::kRateOne || ramp < 1)
        return NakReason::BadField;
      return std::nullopt;
    }
    case Type::Trigger: {
      if (n != spec::kLenTrigger) return NakReason::BadLength;
      if (f.payload[0] > spec::kTriggerProbeRelease) return NakReason::BadField;
      if (!trigger_field_error(static_cast<TriggerMode>(f.payload[0]), get16(f.payload, 1), n_axes)
               .empty())
        return NakReason::BadField;
      return std::nullopt;
    }
    case Type::SetPosition: {
      const size_t h = spec::kLenSetPositionHeader, w = spec::kLenSetPositionPerAxis;
      if (n_axes ? n != h + w * n_axes : (n < h + w || (n - h) % w != 0))
        return NakReason::BadLength;
      const size_t axes = (n - h) / w;
      const uint16_t mask = get16(f.payload, 0);
      if (mask == 0 || (axes < 16 && (mask >> axes) != 0)) return NakReason::BadField;
      return std::nullopt;
    }
    case Type::TriggerQuery:
      if (n != 0) return NakReason::BadLength;
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
      if (mask == 0 || (value & ~mask) != 0 || (value & kOutFan) != 0 ||
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

void detail::check_or_throw(const Frame& f, Type type, size_t n_axes) {
  if (f.type != static_cast<uint8_t>(type)) {
    throw ProtocolError(fmt::format("expected a {} frame, got {}",
                                    type_name(static_cast<uint8_t>(type)), type_name(f.type)));
  }
  if (const auto r = check_host_frame(f, n_axes)) {
    throw ProtocolError(fmt::format("{}: {} (payload of {} bytes)", type_name(f.type),
                                    nak_reason_name(static_cast<uint8_t>(*r)), f.payload.size()));
  }
}

}  // namespace fpgacnc::protocol::v2
