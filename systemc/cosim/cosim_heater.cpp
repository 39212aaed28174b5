// Co-simulation of the heater RTL against its twins (CTest label cosim; docs/heater.md).
//
// RTL: the Verilated heater_block (SAMPLE_CLKS 4096, PWM 1024 clocks, internals public), driven
// by a random seeded job: both thermistor tables loaded, then for every simulated second at most
// one of: HEATER_CONFIG (any mode, random gains and limits), HEATER_SETPOINT (also 0 and
// negative), HEATER_SAFETY (periods short enough to trip), HEATER_WATCHDOG, FAULT_CLEAR, an e-stop
// change or a lone valid frame (watchdog feed); thermistor temperatures random-walk with jumps,
// open and shorted sensors, through the LTC2308 pin model. Frames go into the block's frame port
// between samples (clocks 1200..3800 of a 4096-clock second, away from the tick and the eval).
// Twins (fpgacnc/twins/heater.h) in SystemC behind a TLM target socket get the same frames, ticks,
// e-stop changes and, at each eval, the ADC codes the RTL converted. Compared:
//   per eval and channel: temperature (table), controller output u (Q1.28), fault bits, enabled,
//   and the watchdog fault;
//   per channel: the heater pin's edge list against PwmTwin fed with the RTL's duty register and
//   force-off (cycle exact).
// The first disagreement is printed with its cycle, sample and channel; exit 1.
#include <fmt/format.h>

#include <cstdint>
#include <memory>
#include <random>
#include <systemc>
#include <vector>

#include "cosim_args.h"
#include "cosim_heater_job.h"
#include "fpgacnc/models/thermal_plant.h"
#include "fpgacnc/twins/heater.h"
#include "fpgacnc/twins/tlm_common.h"

namespace {

using namespace fpgacnc::cosim::heater;
namespace th = fpgacnc::models::thermal;

// ------------------------------------------------------------------------------------ twins
// The heater twins behind a TLM target: each write carries one Event (in cycle order); an eval
// gets the twins' results written into the payload's Event.
SC_MODULE(HeaterTwins) {
  tlm_utils::simple_target_socket<HeaterTwins> in;
  ht::ChannelTwin ch[2] = {ht::ChannelTwin(ht::SafetySettings{80, 4400, 64, 40, 32, 20}),
                           ht::ChannelTwin(ht::SafetySettings{80, 1920, 64, 40, 32, 60})};
  ht::WatchdogTwin wd;
  bool wd_fault = false, estop = false;
  th::Table table[2] = {};
  bool loaded[2] = {false, false};  // entry 64 written (temp_table's flag)

  SC_CTOR(HeaterTwins) : in("in") {
    in.register_b_transport(this, &HeaterTwins::b_transport);
  }

  bool kill() const {
    return estop || wd_fault;
  }
  void latch_wd() {
    if (wd.expired() && !wd_fault) {
      wd_fault = true;
      for (auto& c : ch) c.kill();
    }
  }

  void b_transport(tlm::tlm_generic_payload & gp, sc_core::sc_time&) {
    Event& e = *reinterpret_cast<Event*>(gp.get_data_ptr());
    auto u16 = [&](size_t i) { return (e.pay[i] << 8) | e.pay[i + 1]; };
    switch (e.kind) {
      case Event::kFrame: {
        wd.frame_ok();
        const int k = e.pay[0] & 1;
        if (e.type == 0x20) {
          ht::PidSettings s;
          s.mode = e.pay[1];
          auto u32 = [&](size_t i) {
            return static_cast<uint32_t>(u16(i)) << 16 | static_cast<uint32_t>(u16(i + 2));
          };
          s.kp = u32(2);
          s.ki = u32(6);
          s.kd = u32(10);
          s.umax = static_cast<uint32_t>(u16(14));
          s.hyst = static_cast<uint32_t>(u16(16));
          s.manual = static_cast<uint32_t>(u16(18));
          ch[k].config(s);
        } else if (e.type == 0x21) {
          ch[k].setpoint(static_cast<int16_t>(u16(1)), kill());
        } else if (e.type == 0x22) {
          const int n = (static_cast<int>(e.pay.size()) - 2) / 2;
          for (int i = 0; i < n; ++i) loaded[k] = loaded[k] || e.pay[1] + i == 64;
          for (int i = 0; i < n; ++i)
            table[k][static_cast<size_t>(e.pay[1] + i)] =
                static_cast<int16_t>(u16(2 + 2 * static_cast<size_t>(i)));
        } else if (e.type == 0x23) {
          ch[k].safety(ht::SafetySettings{static_cast<int16_t>(u16(1)),
                                          static_cast<int16_t>(u16(3)), u16(5), u16(7), u16(9),
                                          u16(11)});
        } else if (e.type == 0x24) {
          wd.period(u16(0));
        }
        break;
      }
      case Event::kFrameOk:
        wd.frame_ok();
        break;
      case Event::kTick:
        wd.tick();
        latch_wd();
        break;
      case Event::kFaultClear:
        for (auto& c : ch) c.fault_clear();
        wd_fault = false;
        latch_wd();
        break;
      case Event::kEstop:
        estop = e.level;
        if (estop)
          for (auto& c : ch) c.kill();
        break;
      case Event::kEval:
        for (int k = 0; k < 2; ++k) {
          e.temp[k] = loaded[k] ? th::table_lookup(table[k], e.code[k]) : -32768;
          const ht::SampleOut o = ch[k].sample(e.temp[k], kill());
          e.u[k] = o.u;
          e.faults[k] = o.faults;
          e.enabled[k] = o.enabled;
        }
        e.wd = wd_fault;
        break;
    }
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
  }
};

SC_MODULE(Bench) {
  tlm_utils::simple_initiator_socket<Bench> out;
  HeaterTwins twins;
  const RtlRun* run = nullptr;
  uint64_t seed = 0;
  bool ok = true;
  std::string verdict;
  uint64_t enabled_samples = 0, active_samples = 0;
  int fault_bits = 0;
  bool wd_seen = false;

  SC_CTOR(Bench) : out("out"), twins("twins") {
    out.bind(twins.in);
    SC_THREAD(go);
  }

  void fail(const std::string& what) {
    if (ok) verdict = what;
    ok = false;
  }

  void go() {
    tlm::tlm_generic_payload gp;
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    uint64_t evals = 0;
    for (const Event& rtl : run->events) {
      Event e = rtl;
      gp.set_command(tlm::TLM_WRITE_COMMAND);
      gp.set_data_ptr(reinterpret_cast<unsigned char*>(&e));
      gp.set_data_length(sizeof(Event));
      out->b_transport(gp, delay);
      if (e.kind != Event::kEval) continue;
      ++evals;
      for (int k = 0; k < 2; ++k) {
        enabled_samples += rtl.enabled[k];
        active_samples += rtl.u[k] != 0;
        fault_bits |= rtl.faults[k];
      }
      wd_seen = wd_seen || rtl.wd;
      for (int k = 0; k < 2 && ok; ++k) {
        auto where = [&] {
          return fmt::format("seed {} cycle {} sample {} channel {}", seed, e.cycle, evals, k);
        };
        if (e.temp[k] != rtl.temp[k])
          fail(fmt::format("{}: temperature twin {} RTL {} (code {})", where(), e.temp[k],
                           rtl.temp[k], e.code[k]));
        else if (e.faults[k] != rtl.faults[k])
          fail(fmt::format("{}: faults twin {:#x} RTL {:#x}", where(), e.faults[k], rtl.faults[k]));
        else if (e.enabled[k] != rtl.enabled[k])
          fail(fmt::format("{}: enabled twin {} RTL {}", where(), e.enabled[k], rtl.enabled[k]));
        else if (e.u[k] != rtl.u[k])
          fail(fmt::format("{}: u twin {} RTL {}", where(), e.u[k], rtl.u[k]));
      }
      if (ok && e.wd != rtl.wd)
        fail(fmt::format("seed {} cycle {}: watchdog fault twin {} RTL {}", seed, e.cycle, e.wd,
                         rtl.wd));
      if (!ok) return;
    }
    const ht::PwmTwin pwm(kPwmBits, 1);
    for (int k = 0; k < 2 && ok; ++k) {
      const auto tw = pwm.run(run->duty[k], run->force[k], run->last);
      const auto& rl = run->pins[k];
      const size_t n = std::min(tw.size(), rl.size());
      for (size_t i = 0; i < n && ok; ++i)
        if (tw[i].cycle != rl[i].cycle || tw[i].level != rl[i].level)
          fail(fmt::format("seed {} channel {} pin edge {}: twin {} at {}, RTL {} at {}", seed, k,
                           i, tw[i].level ? "rise" : "fall", tw[i].cycle,
                           rl[i].level ? "rise" : "fall", rl[i].cycle));
      if (ok && tw.size() != rl.size())
        fail(fmt::format("seed {} channel {}: {} pin edges twin, {} RTL", seed, k, tw.size(),
                         rl.size()));
    }
    fmt::print(
        "cosim_heater seed {}: {} events, {} samples ({} channel-samples enabled, {} with u > 0, "
        "fault bits seen {:#x}, watchdog {}), pin edges {}/{}: {}\n",
        seed, run->events.size(), evals, enabled_samples, active_samples, fault_bits,
        wd_seen ? "tripped" : "not tripped", run->pins[0].size(), run->pins[1].size(),
        ok ? "equal" : verdict);
  }
};

}  // namespace

int sc_main(int argc, char* argv[]) {
  uint64_t seed = 1, seeds = 1, seconds = 600;
  fpgacnc::cosim::Options opt("cosim_heater");
  opt.u64("--seed", &seed).u64("--seeds", &seeds).u64("--seconds", &seconds);
  if (!opt.parse(argc, argv)) return 2;
  if (const char* env = std::getenv("FPGACNC_SEED")) seed = std::strtoull(env, nullptr, 0);
  std::vector<RtlRun> runs;
  for (uint64_t s = 0; s < seeds; ++s) runs.push_back(run_rtl(seed + s, static_cast<int>(seconds)));
  std::vector<std::unique_ptr<Bench>> benches;
  for (uint64_t s = 0; s < seeds; ++s) {
    benches.push_back(std::make_unique<Bench>(fmt::format("bench{}", s).c_str()));
    benches.back()->run = &runs[s];
    benches.back()->seed = seed + s;
  }
  sc_core::sc_start();
  bool ok = true;
  for (auto& b : benches) ok = ok && b->ok;
  fmt::print("cosim_heater: {} seeds from {}, {} s each: {}\n", seeds, seed, seconds,
             ok ? "RTL equals the twins" : "DISAGREEMENT");
  return ok ? 0 : 1;
}
