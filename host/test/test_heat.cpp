// Heater host side: configuration keys, thermistor curve, relay autotune analysis on a pure C++
// first-order-plus-dead-time model of the reference bed (docs/heater.md; this file's own model,
// independent of models/include/fpgacnc/models/thermal_plant.h).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <deque>
#include <random>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/heat/autotune.h"
#include "fpgacnc/heat/heater_config.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/models/thermal_plant.h"

namespace heat = fpgacnc::heat;
using fpgacnc::config::parse_machine_config;

namespace {

// Reference bed (docs/heater.md): K 4.8 degC/V, dead time 10 s, time constant 370 s; sensor
// about 1 s old (first-order lag 1 s), 0.0625 degC resolution, read once a second.
struct Fopdt {
  double k = 4.8, dead_s = 10.0, tau_s = 370.0, lag_s = 1.0, ambient = 20.0, q = 0.0625;
  double dt = 0.05;
  double temp = 20.0, sensed = 20.0;
  std::deque<double> pipe;  // inputs waiting out the dead time
  void step(double u) {
    const size_t n = static_cast<size_t>(std::lround(dead_s / dt));
    pipe.push_back(u);
    const double ud = pipe.size() > n ? pipe.front() : 0.0;
    if (pipe.size() > n) pipe.pop_front();
    temp += dt / tau_s * (ambient + k * ud - temp);
    sensed += dt / lag_s * (temp - sensed);
  }
  double reading() const { return std::floor(sensed / q) * q; }
};

// Relay test on the model: sampled every 1 s, relay output held between samples.
std::vector<heat::RelaySample> relay_run(const heat::RelayOptions& o, double seconds,
                                         Fopdt plant = {}) {
  heat::RelayController relay(o);
  std::vector<heat::RelaySample> s;
  double u = 0.0;
  const int steps_per_sample = static_cast<int>(std::lround(1.0 / plant.dt));
  for (int k = 0; k < static_cast<int>(seconds); ++k) {
    const double y = plant.reading();
    u = relay.update(y);
    s.push_back({static_cast<double>(k), y, u});
    for (int i = 0; i < steps_per_sample; ++i) plant.step(u);
  }
  return s;
}

}  // namespace

TEST(HeatConfig, DefaultsAreTheReferenceBedAndTheHotEnd) {
  fpgacnc::config::MachineConfig c;
  const auto& bed = c.heaters.bed();
  EXPECT_EQ(bed.kp_v_per_c, 9.7);
  EXPECT_EQ(bed.ti_s, 20.0);
  EXPECT_EQ(bed.td_s, 5.0);
  EXPECT_EQ(bed.supply_v, 24.0);
  EXPECT_EQ(bed.mode, heat::Mode::kPid);
  EXPECT_EQ(bed.runaway_band_c, 4.0);
  EXPECT_EQ(bed.runaway_period_s, 40.0);
  EXPECT_EQ(bed.watch_period_s, 60.0);
  const auto& he = c.heaters.hotend();
  EXPECT_EQ(he.watch_period_s, 20.0);
  EXPECT_GT(he.max_temp_c, 250.0);
  EXPECT_EQ(heat::check_heater(bed, "heater.bed"), "");
  EXPECT_EQ(heat::check_heater(he, "heater.hotend"), "");
}

TEST(HeatConfig, ExampleFileHeatersEqualTheDefaults) {
  const auto c = fpgacnc::config::load_machine_config(FPGACNC_HOST_DIR "/machine.example.toml");
  fpgacnc::config::MachineConfig d;
  EXPECT_EQ(c.heaters.watchdog_s, d.heaters.watchdog_s);
  for (size_t ch = 0; ch < heat::kChannels; ++ch) {
    const auto& a = c.heaters.ch[ch];
    const auto& b = d.heaters.ch[ch];
    EXPECT_EQ(heat::config_frame(a, 0), heat::config_frame(b, 0)) << ch;
    EXPECT_EQ(heat::safety_frame(a, 0), heat::safety_frame(b, 0)) << ch;
    EXPECT_EQ(heat::thermistor_table(a), heat::thermistor_table(b)) << ch;
    EXPECT_EQ(a.wait_tolerance_c, b.wait_tolerance_c) << ch;
    EXPECT_EQ(a.wait_settle_s, b.wait_settle_s) << ch;
    EXPECT_EQ(a.wait_timeout_s, b.wait_timeout_s) << ch;
  }
}

TEST(HeatConfig, KeysAreRead) {
  const auto c = parse_machine_config(R"(
[heater]
watchdog_s = 5
[heater.bed]
kp = 10.2
ti_s = 26.5
td_s = 6.4
mode = "onoff"
hysteresis_c = 0.5
max_temp_c = 120
wait_tolerance_c = 0.5
wait_settle_s = 30
[heater.bed.thermistor]
beta = 4267
pullup_ohm = 10000
[heater.hotend]
enabled = false
)",
                                      "m.toml");
  EXPECT_EQ(c.heaters.watchdog_s, 5.0);
  EXPECT_EQ(c.heaters.bed().kp_v_per_c, 10.2);
  EXPECT_EQ(c.heaters.bed().ti_s, 26.5);
  EXPECT_EQ(c.heaters.bed().td_s, 6.4);
  EXPECT_EQ(c.heaters.bed().mode, heat::Mode::kOnOff);
  EXPECT_EQ(c.heaters.bed().hysteresis_c, 0.5);
  EXPECT_EQ(c.heaters.bed().max_temp_c, 120.0);
  EXPECT_EQ(c.heaters.bed().wait_settle_s, 30.0);
  EXPECT_EQ(c.heaters.bed().thermistor.beta, 4267.0);
  EXPECT_EQ(c.heaters.bed().thermistor.pullup_ohm, 10000.0);
  EXPECT_FALSE(c.heaters.hotend().enabled);
}

TEST(HeatConfig, BadKeysNameFileLineAndKey) {
  struct Case {
    const char* text;
    const char* line;
    const char* what;
  };
  const Case cases[] = {
      {"[heater.bed]\nkp = \"x\"\n", "m.toml:2", "heater.bed.kp': expected a number"},
      {"[heater.bed]\nkd = 1\n", "m.toml:2", "heater.bed.kd': unknown key"},
      {"[heater.chamber]\nkp = 1\n", "m.toml:", "unknown key (expected hotend, bed"},
      {"[heater.bed]\nmode = \"bangbang\"\n", "m.toml:2", "expected \"pid\""},
      {"[heater.bed]\nti_s = -1\n", "m.toml:", "heater.bed.ti_s must be >= 0"},
      {"[heater.bed]\nu_max_v = 30\n", "m.toml:", "u_max_v must be in (0, supply_v]"},
      {"[heater.bed.thermistor]\nsource = \"spline\"\n", "m.toml:2", "expected \"beta\" or"},
  };
  for (const auto& cs : cases) {
    try {
      parse_machine_config(cs.text, "m.toml");
      ADD_FAILURE() << "no error for: " << cs.text;
    } catch (const fpgacnc::config::Error& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find(cs.line), std::string::npos) << "expected " << cs.line << ", got " << w;
      EXPECT_NE(w.find(cs.what), std::string::npos) << "expected " << cs.what << ", got " << w;
    }
  }
}

TEST(HeatConfig, ThermistorCurveRoundTrips) {
  heat::ThermistorConfig t;
  const auto c = heat::make_curve(t);
  EXPECT_NEAR(c.resistance(25.0), 100'000.0, 1e-6);
  for (double tc : {0.0, 25.0, 60.0, 110.0, 200.0, 260.0}) {
    EXPECT_NEAR(c.temperature(c.resistance(tc)), tc, 1e-9) << tc;
    const double code = heat::adc_code_of(t, c, tc);
    EXPECT_GT(code, 0.0);
    EXPECT_LT(code, 4095.0);
    EXPECT_NEAR(heat::temp_of_code(t, c, code), tc, 1e-6) << tc;
  }
  // NTC: the code falls as the temperature rises.
  EXPECT_GT(heat::adc_code_of(t, c, 50.0), heat::adc_code_of(t, c, 60.0));
}

TEST(Autotune, GainRulesMatchTheReferenceBed) {
  // Reference relay test: a = 0.45 degC with a 0/12 V relay -> Ku 17.0; Pu 53 s; tuning
  // Kp 10.2, Ti 26.5, Td 6.4.
  const double ku = 4.0 * 6.0 / (M_PI * 0.45);
  EXPECT_NEAR(ku, 17.0, 0.05);
  const auto g = heat::propose_gains(ku, 53.0);
  ASSERT_GE(g.size(), 2u);
  EXPECT_EQ(g[1].rule, "reference bed relay rule");
  EXPECT_NEAR(g[1].kp, 10.2, 0.05);
  EXPECT_NEAR(g[1].ti_s, 26.5, 1e-9);
  EXPECT_NEAR(g[1].td_s, 6.4, 0.05);
  EXPECT_NEAR(g[0].td_s, 53.0 / 8.0, 1e-9);
}

TEST(Autotune, SyntheticSquareWaveIsMeasuredExactly) {
  // A triangle-ish temperature and its relay: period 50 s, amplitude 1.5 degC.
  heat::RelayOptions o;
  o.setpoint_c = 60.0;
  std::vector<heat::RelaySample> s;
  for (int t = 0; t < 400; ++t) {
    const double ph = std::fmod(t, 50.0) / 50.0;
    const double temp = 60.0 + 1.5 * std::sin(2 * M_PI * ph);
    const double u = ph < 0.5 ? 0.0 : 12.0;  // on in the second half (below the setpoint)
    s.push_back({static_cast<double>(t), temp, u});
  }
  const auto r = heat::analyse_relay(s, o);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.period_s, 50.0, 1e-9);
  EXPECT_NEAR(r.amplitude_c, 1.5, 0.01);
  EXPECT_NEAR(r.ku, 24.0 / (M_PI * r.amplitude_c), 1e-9);
  // Too short a series: not ok, says why.
  s.resize(120);
  const auto r2 = heat::analyse_relay(s, o);
  EXPECT_FALSE(r2.ok);
  EXPECT_NE(r2.message.find("complete relay cycles"), std::string::npos) << r2.message;
}

TEST(Autotune, RelayOnTheReferenceBedModel) {
  // The reference relay test: 0/12 V. Setpoint 60 degC from room temperature.
  heat::RelayOptions o;
  o.setpoint_c = 60.0;
  o.u_high = 12.0;
  o.u_low = 0.0;
  const auto s = relay_run(o, 3000.0);
  const auto r = heat::analyse_relay(s, o);
  fmt::print("{}", heat::format_autotune(r, o));
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.period_s, 53.0, 53.0 * 0.15) << "critical period, expected 53 s +-15 %";
  EXPECT_GT(r.ku, 0.0);
  EXPECT_LT(r.period_max_s - r.period_min_s, 3.0) << "limit cycle not settled";
  EXPECT_NEAR(r.mean_c, 60.0, 1.0);
}

// The same relay test on heat-rtl's bed plant (models/include/fpgacnc/models/thermal_plant.h) as
// the device sees it: 1 s ticks, the reading one tick old, through the thermistor, the 12-bit ADC
// and the host's 65-entry table with the RTL's interpolation (Q11.4), relay 0/12 V = duty 0.5 of
// the 24 V supply.
TEST(Autotune, RelayOnTheThermalPlantBedThroughAdcAndTable) {
  namespace th = fpgacnc::models::thermal;
  fpgacnc::config::MachineConfig cfg;
  const auto host_table = heat::thermistor_table(cfg.heaters.bed());
  th::Table table{};
  for (size_t i = 0; i < table.size(); ++i) table[i] = host_table[i];
  EXPECT_EQ(table, th::thermistor_table()) << "host table differs from the bench's";
  th::BedPlant plant;
  th::DelayedSensor sensor(1);
  th::Thermistor ntc;
  heat::RelayOptions o;
  o.setpoint_c = 60.0;
  o.u_high = 12.0;
  heat::RelayController relay(o);
  std::vector<heat::RelaySample> s;
  double temp = plant.temperature();
  for (int k = 0; k < 3000; ++k) {
    const double reading = sensor.sample(temp);
    const int code = th::adc_code(ntc.voltage(reading));
    const double t_c = th::from_q4(th::table_lookup(table, code));
    const double u = relay.update(t_c);
    s.push_back({static_cast<double>(k), t_c, u});
    temp = plant.step(1.0, u / th::kBedSupplyV);
  }
  const auto r = heat::analyse_relay(s, o);
  fmt::print("{}", heat::format_autotune(r, o));
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.period_s, 53.0, 53.0 * 0.15) << "critical period, expected 53 s +-15 %";
  // Polled every 3 s (as through a slow link): the period from interpolated switch instants
  // stays within 1 s of the dense series, the amplitude within 0.1 degC.
  std::vector<heat::RelaySample> sparse;
  for (size_t i = 0; i < s.size(); i += 3) sparse.push_back(s[i]);
  const auto r3 = heat::analyse_relay(sparse, o);
  ASSERT_TRUE(r3.ok) << r3.message;
  EXPECT_NEAR(r3.period_s, r.period_s, 1.0);
  EXPECT_NEAR(r3.amplitude_c, r.amplitude_c, 0.1);
}
