// Heater commands of a job (M104/M109/M140/M190) and the heater frames of a v2 session.
//
// G-code semantics (docs/heater.md, "Host"):
//   M104 S<t>  hot-end setpoint t degC, no wait (S0: off);
//   M109 S<t>  hot-end setpoint t, then wait: the streamer stops sending, lets the FIFO drain,
//              and polls STATUS until |T - t| <= wait_tolerance_c has held for wait_settle_s
//              (plant seconds); error after wait_timeout_s. As in Marlin, S waits only when
//              heating: if T is already above t + tolerance the job goes on at once;
//   M140/M190  the same for the bed.
// A heater frame is sequenced and not queued (docs/protocol.md): a setpoint acts when the device
// receives it, i.e. ahead of the motion still in its FIFO (as Marlin applies M104 ahead of the
// moves in its planner); M109/M190 are the synchronising forms.
// Errors before anything is sent (FILE:LINE:COL naming the S word, or the M word): a heater
// M code without S, S above the channel's max_temp_c (or, for S > 0, below min_temp_c), a
// channel that is disabled in the machine configuration.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/heat/heater_config.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::protocol::v2 {
struct Job;
}

namespace fpgacnc::heat {

struct HeaterAction {
  uint8_t channel = 0;
  double target_c = 0.0;
  int16_t target_q4 = 0;
  bool wait = false;
  int mcode = 0;
  int source_line = 0;
};

struct HeaterJob {
  std::vector<HeaterAction> actions;  // in program order
  std::array<bool, kChannels> used{};
  // Sent after CONFIG_AXIS, before any FIFO frame: per used channel HEATER_CONFIG, HEATER_SAFETY,
  // THERMISTOR_TABLE x 9; then HEATER_WATCHDOG when any channel is used.
  std::vector<protocol::v2::Frame> setup;
  HeaterSet config;
  std::string source;  // G-code file (error messages)
  bool any() const { return used[0] || used[1]; }
};

// Device fixed-point values of a channel's configuration (docs/heater.md "Number formats").
protocol::v2::HeaterConfigFrame config_frame(const HeaterConfig& h, uint8_t channel);
protocol::v2::HeaterSafetyFrame safety_frame(const HeaterConfig& h, uint8_t channel);
// The 65-entry table: entry i = temperature at ADC code 64 i, Q11.4 rounded, clamped to
// -100 .. 500 degC (an open sensor reads the low clamp, a short the high one).
std::vector<int16_t> thermistor_table(const HeaterConfig& h);
int16_t to_q4(double temp_c);
uint16_t ticks(double seconds, double sample_s);  // rounded, saturated at 65535

// Validates the plan's heater commands in program order (throws gcode::Error
// "FILE:LINE:COL: error: ..."; the column of the bad word is read from plan.source, 0 when it
// cannot be read) and makes the setup frames of the channels they use. The v2 packer
// (protocol/v2_job.h) calls it and places the setpoints between the job's frames.
HeaterJob make_heater_job(const plan::Plan& plan, const config::MachineConfig& cfg);

// "bed 59.9/60.0 C 41%  hotend 24.1/off" from a STATUS heater block ("" when none).
std::string format_heaters(const protocol::v2::Status& s);

// The faults in `bad` (device fault bits: heater channels, watchdog, e-stop, hard limit) with the
// channel details of `s` and a hint at the likely cause, for error messages.
std::string describe_faults(const protocol::v2::Status& s, uint8_t bad);

}  // namespace fpgacnc::heat
