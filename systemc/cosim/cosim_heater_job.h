// Shared between cosim_heater.cpp (twins, SystemC) and cosim_heater_rtl.cpp (the Verilated
// heater_block, no SystemC): the job's events and the RTL's results.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "fpgacnc/spec.h"
#include "fpgacnc/twins/heater.h"

namespace fpgacnc::cosim::heater {

using fpgacnc::twins::Cycle;
namespace ht = fpgacnc::twins::heater;

constexpr Cycle kSample = spec::kBenchSampleClks;
constexpr int kPwmBits = 10;

struct Event {
  enum Kind { kFrame, kFrameOk, kTick, kEval, kFaultClear, kEstop };
  Kind kind = kFrame;
  Cycle cycle = 0;  // the edge it acts on
  uint8_t type = 0;
  std::vector<uint8_t> pay;
  int code[2] = {0, 0};
  bool level = false;
  // RTL results of an eval (read 100 clocks after it) and the twin's, filled by the twin target.
  int temp[2] = {0, 0};
  int64_t u[2] = {0, 0};
  int faults[2] = {0, 0};
  bool enabled[2] = {false, false};
  bool wd = false;
};

struct RtlRun {
  std::vector<Event> events;
  std::vector<ht::PinEdge> pins[2];
  std::vector<std::pair<Cycle, int>> duty[2];
  std::vector<std::pair<Cycle, bool>> force[2];
  Cycle last = 0;
};

RtlRun run_rtl(uint64_t seed, int seconds);

}  // namespace fpgacnc::cosim::heater
