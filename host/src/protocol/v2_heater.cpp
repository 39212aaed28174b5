// Heater frames (docs/protocol.md "Heater frames", number formats in docs/heater.md):
// HEATER_CONFIG, HEATER_SETPOINT, THERMISTOR_TABLE, HEATER_SAFETY, HEATER_WATCHDOG builders and
// decoders, and the names of a channel's fault bits.
#include <fmt/format.h>

#include <array>

#include "fpgacnc/protocol/v2.h"
#include "v2_bytes.h"

namespace fpgacnc::protocol::v2 {
using detail::check_or_throw;
using detail::get16;
using detail::get32;
using detail::make;
using detail::put16;
using detail::put32;

// ---- Heaters ----

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

}  // namespace fpgacnc::protocol::v2
