// Relay autotune through a v2 link (`fpgacnc autotune`): the channel is put in ON_OFF mode with
// duty_max = u_high / supply_v and the relay hysteresis, given its thermistor table and safety
// limits and the setpoint; then STATUS is polled and (plant time, temperature, duty * supply_v)
// recorded until analyse_relay() has skip_cycles + cycles complete cycles, or max_plant_s passes.
// At the end the channel's setpoint is set to 0 and its configured mode restored. A heater fault
// stops the test with an Error. The device must speak protocol v2 with heater frames.
#pragma once

#include <chrono>
#include <functional>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/heat/autotune.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::heat {

struct AutotuneLinkOptions {
  uint8_t channel = 1;  // kBed
  RelayOptions relay;   // u_high in volts of the channel's supply; u_low must be 0 (ON_OFF mode)
  double max_plant_s = 3600.0;
  // Link time (link.h: wall time on a port, board time on a simulated board).
  std::chrono::milliseconds poll{50};  // STATUS_QUERY period
  std::chrono::milliseconds answer_timeout{5000};
  std::function<double()> plant_time;  // unset: link time in seconds
  std::function<void(const RelaySample&, const protocol::v2::HeaterStatus&)> on_sample;
};

struct AutotuneLinkResult {
  RelayResult result;
  std::vector<RelaySample> samples;  // duty as volts (duty * supply_v)
  std::vector<double> setpoints;     // per sample
  double plant_s = 0.0;
  double wall_s = 0.0;
};

AutotuneLinkResult run_relay_test(link::Link& link, const config::MachineConfig& cfg,
                                  const AutotuneLinkOptions& o);

}  // namespace fpgacnc::heat
