// Heater configuration of a machine: the `[heater.hotend]` and `[heater.bed]` tables of the
// machine TOML (host/machine.example.toml, docs/heater.md "Host"). Units are the ones of the
// reference bed in docs/heater.md: gains in volts of heater supply per degC, times in seconds.
// The host turns them into the device's fixed-point formats when it builds the heater frames.
//
// Defaults: the bed is the reference heated bed (24 V supply, step-response tuning Kp 9.7 V/degC,
// Ti 20 s, Td 5 s); the hot end is a 40 W / 24 V cartridge (tuned on the hot-end plant model of
// models/include/fpgacnc/models/thermal_plant.h, see docs/heater.md). Both use a 100k NTC (beta
// 3950) read through the LTC2308 with a 4.7 kOhm pull-up.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace fpgacnc::heat {

// Device channels (STATUS order, frame `channel` byte).
enum Channel : uint8_t { kHotend = 0, kBed = 1 };
inline constexpr size_t kChannels = 2;
inline constexpr std::array<const char*, kChannels> kChannelNames{"hotend", "bed"};

enum class Mode : uint8_t { kOff = 0, kManual = 1, kOnOff = 2, kP = 3, kPid = 4 };
// "off", "manual", "onoff", "p", "pid".
const char* mode_name(Mode m);
bool parse_mode(const std::string& s, Mode& out);

struct ThermistorConfig {
  // "beta": table computed from beta/r25/pull-up/ADC reference; "file": a CSV of
  // "temperature_c,resistance_ohm" rows (header optional) interpolated in log(R).
  std::string source = "beta";
  std::string file;
  double beta = 3950.0;
  double r25_ohm = 100'000.0;   // resistance at 25 degC
  double pullup_ohm = 4'700.0;  // pull-up from the divider supply to the ADC input
  double supply_v = 3.3;        // divider supply
  double adc_vref_v = 4.096;    // LTC2308 unipolar full scale (code 4095)
};

struct HeaterConfig {
  bool enabled = true;
  Mode mode = Mode::kPid;
  double kp_v_per_c = 9.7;    // proportional gain, volts of heater supply per degC
  double ti_s = 20.0;         // integral time (0: no integral term)
  double td_s = 5.0;          // derivative time
  double supply_v = 24.0;     // heater supply: duty = u / supply_v
  double u_max_v = 24.0;      // output clamp (PWM limit), volts
  double hysteresis_c = 1.0;  // on/off mode: on below set - h, off above set + h
  double manual_v = 0.0;      // manual mode output
  double sample_s = 1.0;      // control sample period
  // Safety (hardware, per channel).
  double min_temp_c = 5.0;         // below: sensor open (or a heater in a freezer)
  double max_temp_c = 130.0;       // above: over-temperature / sensor short
  double runaway_band_c = 4.0;     // holding: |T - set| above this for longer than ...
  double runaway_period_s = 40.0;  // ... this is a runaway
  double watch_rise_c = 2.0;       // after a setpoint increase: rise at least this much ...
  double watch_period_s = 60.0;    // ... within this period
  // Host waits (M109/M190).
  double wait_tolerance_c = 1.0;   // |T - target| within this ...
  double wait_settle_s = 10.0;     // ... for this long (plant seconds)
  double wait_timeout_s = 1800.0;  // give up (plant seconds) with an error naming the line
  ThermistorConfig thermistor;
};

struct HeaterSet {
  std::array<HeaterConfig, kChannels> ch;
  // Device watchdog: heaters off when no valid frame arrives for this long (0: off). The streamer
  // keeps it fed with STATUS_QUERY while a job runs.
  double watchdog_s = 10.0;
  HeaterSet();
  HeaterConfig& hotend() { return ch[kHotend]; }
  HeaterConfig& bed() { return ch[kBed]; }
  const HeaterConfig& hotend() const { return ch[kHotend]; }
  const HeaterConfig& bed() const { return ch[kBed]; }
};

// Defaults of each channel (see the file comment).
HeaterConfig default_hotend();
HeaterConfig default_bed();

// Range checks; returns "" or the first problem ("heater.bed.ti_s must be >= 0").
std::string check_heater(const HeaterConfig& h, const std::string& key);

// Temperature of a thermistor reading: resistance (ohm) -> degC and back, from the config's
// beta parameters (source "beta") or its CSV table (source "file"; loaded by load_table()).
struct ThermistorCurve {
  std::vector<std::pair<double, double>> points;  // (degC, ohm), ascending temperature
  double beta = 3950.0, r25 = 100'000.0;
  bool table = false;
  double resistance(double temp_c) const;
  double temperature(double ohm) const;
};
// Throws std::runtime_error naming the file and line for a bad CSV.
ThermistorCurve make_curve(const ThermistorConfig& t);
// ADC code (0..4095, 12-bit LTC2308, 1 mV per code with the 4.096 V reference) of a temperature
// and back (divider: pull-up to supply_v, thermistor to ground; code = 4096 * v / adc_vref_v,
// clamped to 0..4095; not rounded).
double adc_code_of(const ThermistorConfig& t, const ThermistorCurve& c, double temp_c);
double temp_of_code(const ThermistorConfig& t, const ThermistorCurve& c, double code);

}  // namespace fpgacnc::heat
