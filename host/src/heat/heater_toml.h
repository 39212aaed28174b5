// Internal: reads the `[heater]` table of a machine TOML into a HeaterSet (called by
// host/src/config/machine.cpp). Throws config::Error with the file, line and column of the key.
#pragma once

#include <string>
#include <toml.hpp>

#include "fpgacnc/heat/heater_config.h"

namespace fpgacnc::heat {

void read_heater_toml(const toml::value& heater, HeaterSet& out, const std::string& file);

}  // namespace fpgacnc::heat
