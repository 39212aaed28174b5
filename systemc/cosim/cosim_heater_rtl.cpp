// The RTL side of cosim_heater: the Verilated heater_block (public internals) on a random job
// (see cosim_heater.cpp). Kept apart from SystemC (Verilator's C++ model and SystemC headers do
// not mix in one translation unit).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include <fmt/format.h>

#include "Vheater_block_pub.h"
#include "Vheater_block_pub___024root.h"
#include "cosim_heater_job.h"
#include "fpgacnc/models/ltc2308_model.h"
#include "fpgacnc/models/pid_ref.h"
#include "fpgacnc/models/thermal_plant.h"
#include "verilated.h"

namespace fpgacnc::cosim::heater {

namespace th = fpgacnc::models::thermal;

namespace {
std::vector<uint8_t> be(std::initializer_list<int> bytes16) {  // 16-bit big-endian fields
  std::vector<uint8_t> v;
  for (int x : bytes16) {
    v.push_back(static_cast<uint8_t>((x >> 8) & 0xFF));
    v.push_back(static_cast<uint8_t>(x & 0xFF));
  }
  return v;
}

}  // namespace

RtlRun run_rtl(uint64_t seed, int seconds) {
  std::mt19937_64 g(seed);
  auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(g); };
  auto real = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(g);
  };

  // Schedule: input events keyed by the edge they act on.
  struct In {
    Cycle cycle;
    Event ev;
  };
  std::vector<In> sched;
  const th::Table table = th::thermistor_table();
  Cycle c0 = 50;
  for (int ch = 0; ch < 2; ++ch)
    for (int first = 0; first < th::kTableEntries; first += 8) {
      Event e;
      e.kind = Event::kFrame;
      e.type = 0x22;
      e.pay = {static_cast<uint8_t>(ch), static_cast<uint8_t>(first)};
      for (int i = first; i < std::min(first + 8, th::kTableEntries); ++i) {
        const auto b = be({table[static_cast<size_t>(i)]});
        e.pay.insert(e.pay.end(), b.begin(), b.end());
      }
      sched.push_back({c0, e});
      c0 += 13;
    }
  bool estop = false;
  for (int s = 1; s < seconds; ++s) {
    const Cycle at = static_cast<Cycle>(s) * kSample + uni(1200, 3800);
    const int r = uni(0, 99);
    Event e;
    e.kind = Event::kFrame;
    const uint8_t ch = static_cast<uint8_t>(uni(0, 1));
    if (r < 12) {  // HEATER_CONFIG
      e.type = 0x20;
      e.pay = {ch, static_cast<uint8_t>(uni(0, 4))};
      for (double x : {real(0, 0.5), real(0, 0.05), real(0, 3.0)}) {
        const uint32_t q = th::to_q8_24(x);
        for (int k = 3; k >= 0; --k) e.pay.push_back(static_cast<uint8_t>(q >> (8 * k)));
      }
      const auto b = be({uni(0x2000, 0x8000), uni(0, 64), uni(0, 0x8000)});
      e.pay.insert(e.pay.end(), b.begin(), b.end());
    } else if (r < 24) {  // HEATER_SETPOINT
      e.type = 0x21;
      const int set = uni(0, 9) == 0 ? uni(-160, 0) : uni(0, 250 * 16);
      const auto b = be({set});
      e.pay = {ch};
      e.pay.insert(e.pay.end(), b.begin(), b.end());
    } else if (r < 30) {  // HEATER_SAFETY
      e.type = 0x23;
      const int tmin = uni(0, 20 * 16), tmax = uni(150 * 16, 400 * 16);
      const auto b = be({tmin, tmax, uni(16, 128), uni(0, 60), uni(0, 80), uni(0, 30)});
      e.pay = {ch};
      e.pay.insert(e.pay.end(), b.begin(), b.end());
    } else if (r < 32) {  // HEATER_WATCHDOG
      e.type = 0x24;
      e.pay = be({uni(0, 3) == 0 ? 0 : uni(3, 20)});
    } else if (r < 36) {
      e.kind = Event::kFaultClear;
    } else if (r < 38) {
      e.kind = Event::kEstop;
      estop = !estop;
      e.level = estop;
    } else if (r < 80) {
      e.kind = Event::kFrameOk;
    } else {
      continue;
    }
    sched.push_back({at, e});
  }

  RtlRun run;
  auto ctx = std::make_unique<VerilatedContext>();
  auto m = std::make_unique<Vheater_block_pub>(ctx.get());
  auto* r = m->rootp;
  fpgacnc::models::Ltc2308Model adc(50e6);
  th::Thermistor therm;
  double temp[2] = {20.0, 20.0};
  int fault_mode[2] = {0, 0};  // 0 ok, 1 open, 2 short
  double target[2] = {20.0, 20.0};
  adc.source = [&](int ch) {
    const int k = ch & 1;
    return fault_mode[k] == 1 ? 3.3 : fault_mode[k] == 2 ? 0.0 : therm.voltage(temp[k]);
  };
  m->frame_wr = m->frame_ok = m->fault_clear = m->estop = 0;
  m->adc_sdo = 0;
  m->rst = 1;
  for (int i = 0; i < 2; ++i) {
    m->clk = 0;
    m->eval();
    m->clk = 1;
    m->eval();
  }
  m->rst = 0;
  size_t si = 0;
  int sdo = 0;
  int prev_duty[2] = {0, 0};
  bool prev_force[2] = {true, true}, prev_pin[2] = {false, false};
  std::vector<std::pair<Cycle, size_t>> pending;  // eval events whose results are read later
  const Cycle last = static_cast<Cycle>(seconds) * kSample;
  for (Cycle n = 1; n <= last; ++n) {
    // Inputs sampled at edge n.
    m->frame_wr = m->frame_ok = m->fault_clear = 0;
    while (si < sched.size() && sched[si].cycle == n) {
      Event e = sched[si++].ev;
      e.cycle = n;
      if (e.kind == Event::kFrame) {
        if (e.type == 0x21)
          target[e.pay[0] & 1] =
              std::max(20.0, static_cast<int16_t>(e.pay[1] << 8 | e.pay[2]) / 16.0);
        m->frame_wr = 1;
        m->frame_ok = 1;
        m->frame_type = e.type;
        m->frame_len = static_cast<uint8_t>(e.pay.size());
        for (int w = 0; w < 5; ++w) m->frame_data[w] = 0;
        for (size_t i = 0; i < e.pay.size(); ++i)
          m->frame_data[i / 4] |= static_cast<uint32_t>(e.pay[i]) << (8 * (i % 4));
      } else if (e.kind == Event::kFrameOk) {
        m->frame_ok = 1;
      } else if (e.kind == Event::kFaultClear) {
        m->fault_clear = 1;
      } else if (e.kind == Event::kEstop) {
        m->estop = e.level;
      }
      run.events.push_back(e);
    }
    m->adc_sdo = static_cast<uint8_t>(sdo);
    m->clk = 0;
    m->eval();
    {
      // PWM inputs in the clock before edge n (force_off follows the e-stop input at once).
      const int duty[2] = {r->heater_block__DOT__u_ch0__DOT__duty_reg,
                           r->heater_block__DOT__u_ch1__DOT__duty_reg};
      const bool force[2] = {r->heater_block__DOT__u_ch0__DOT__force_off != 0,
                             r->heater_block__DOT__u_ch1__DOT__force_off != 0};
      for (int k = 0; k < 2; ++k) {
        if (duty[k] != prev_duty[k] || n == 1) run.duty[k].push_back({n, prev_duty[k] = duty[k]});
        if (force[k] != prev_force[k] || n == 1)
          run.force[k].push_back({n, prev_force[k] = force[k]});
      }
    }
    m->clk = 1;
    m->eval();
    sdo = adc.tick(m->adc_convst, m->adc_sck, m->adc_sdi);
    // Plant stand-in: random walk, jumps, open/short sensors (changed at the tick).
    if (m->tick) {
      Event e;
      e.kind = Event::kTick;
      e.cycle = n + 1;
      run.events.push_back(e);
      for (int k = 0; k < 2; ++k) {
        // Drifts toward the last setpoint (so that channels reach and hold it), with noise and
        // rare jumps (runaway, min/max).
        temp[k] += 0.05 * (target[k] - temp[k]) + std::normal_distribution<double>(0.0, 0.7)(g);
        temp[k] = std::clamp(temp[k], 0.0, 300.0);
        if (uni(0, 299) == 0) temp[k] = real(0, 300);
        if (fault_mode[k] == 0 && uni(0, 599) == 0)
          fault_mode[k] = uni(1, 2);
        else if (fault_mode[k] != 0 && uni(0, 4) == 0)
          fault_mode[k] = 0;
      }
    }
    if (m->sample_done) {
      Event e;
      e.kind = Event::kEval;
      e.cycle = n + 1;
      const size_t nc = adc.conversions.size();
      e.code[0] = adc.conversions[nc - 2].code;
      e.code[1] = adc.conversions[nc - 1].code;
      run.events.push_back(e);
      pending.push_back({n + 100, run.events.size() - 1});
    }
    while (!pending.empty() && pending.front().first == n) {
      Event& e = run.events[pending.front().second];
      pending.erase(pending.begin());
      e.u[0] = r->heater_block__DOT__u_ch0__DOT__u_pid__DOT__u_reg;
      e.u[1] = r->heater_block__DOT__u_ch1__DOT__u_pid__DOT__u_reg;
      e.faults[0] = r->heater_block__DOT__u_ch0__DOT__u_safe__DOT__faults_reg;
      e.faults[1] = r->heater_block__DOT__u_ch1__DOT__u_safe__DOT__faults_reg;
      e.enabled[0] = r->heater_block__DOT__u_ch0__DOT__enable_reg;
      e.enabled[1] = r->heater_block__DOT__u_ch1__DOT__enable_reg;
      e.temp[0] = static_cast<int16_t>(r->heater_block__DOT__t0_reg);
      e.temp[1] = static_cast<int16_t>(r->heater_block__DOT__t1_reg);
      e.wd = m->wd_fault;
    }
    for (int k = 0; k < 2; ++k) {
      const bool pin = (m->heater >> k) & 1;
      if (pin != prev_pin[k]) run.pins[k].push_back({n, prev_pin[k] = pin});
    }
  }
  if (adc.violations() != 0) fmt::print("cosim_heater: ADC pin model: {}\n", adc.first_violation());
  m->final();
  run.last = last;
  return run;
}

}  // namespace fpgacnc::cosim::heater
