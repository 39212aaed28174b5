// Heater frames in the v2 codec (worked examples of docs/protocol.md), the heater job (M104/M109/
// M140/M190 semantics and line:col errors) and the streamer with heaters against the fake device
// (order with motion, M109/M190 waits, faults and timeouts naming the G-code line).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "fake_v2_device.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"
#include "stream_plan.h"

namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
namespace heat = fpgacnc::heat;
using fpgacnc::test::FakeV2Device;
using std::chrono::milliseconds;

namespace {

std::string hex_of(const v2::Frame& f) {
  return v2::hex(v2::encode(f));
}

fpgacnc::plan::Plan plan_of(const std::string& gcode, const fpgacnc::config::MachineConfig& cfg) {
  return fpgacnc::plan::plan_program(fpgacnc::gcode::parse_string(gcode, "job.gcode"), cfg, {});
}

// Writes `gcode` to a file (so errors can name the column) and plans it.
fpgacnc::plan::Plan plan_file(const std::string& gcode, const fpgacnc::config::MachineConfig& cfg,
                              const std::string& name) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << gcode;
  return fpgacnc::plan::plan_gcode_file(path.string(), cfg, {});
}

// Plant time of the fake device: 1 ms of wall time is one plant second.
struct FastPlant {
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  double operator()() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1000.0;
  }
};

lk::StreamV2Options heat_options() {
  lk::StreamV2Options o;
  o.retransmit_timeout = milliseconds(1000);
  o.idle_poll = milliseconds(20);
  o.answer_timeout = milliseconds(5000);
  o.heater_poll = milliseconds(3);
  o.plant_time = FastPlant{};
  return o;
}

FakeV2Device::Options heater_device() {
  FakeV2Device::Options d;
  d.heaters = true;
  d.exec_period = std::chrono::microseconds(2000);
  return d;
}

}  // namespace

TEST(HeaterCodec, WorkedExamplesOfProtocolMd) {
  // HEATER_CONFIG from the default bed configuration (the reference tuning).
  fpgacnc::config::MachineConfig cfg;
  const auto cf = heat::config_frame(cfg.heaters.bed(), heat::kBed);
  EXPECT_EQ(cf.kp, 0x00677777u);
  EXPECT_EQ(cf.ki, 0x00052C60u);
  EXPECT_EQ(cf.kd, 0x02055555u);
  EXPECT_EQ(hex_of(v2::heater_config(2, cf)),
            "A5 14 02 20 01 04 00 67 77 77 00 05 2C 60 02 05 55 55 80 00 00 10 00 00 17 D9");
  EXPECT_EQ(hex_of(v2::heater_setpoint(3, 1, heat::to_q4(60.0))), "A5 03 03 21 01 03 C0 D4 F7");
  // Entries 40..47 of the default 100k/3950 table.
  const auto table = heat::thermistor_table(cfg.heaters.bed());
  ASSERT_EQ(table.size(), 65u);
  v2::ThermistorChunk ch{1, 40, std::vector<int16_t>(table.begin() + 40, table.begin() + 48)};
  EXPECT_EQ(hex_of(v2::thermistor_table(4, ch)),
            "A5 12 04 22 01 28 04 86 04 4F 04 15 03 D7 03 96 03 4E 02 FE 02 A4 36 CC");
  // Open sensor (codes above the 3.3 V divider supply) reads the low clamp, a short the high one.
  EXPECT_EQ(table[64], heat::to_q4(-100.0));
  EXPECT_EQ(table[0], heat::to_q4(500.0));
  auto bed = cfg.heaters.bed();
  bed.max_temp_c = 120.0;
  EXPECT_EQ(hex_of(v2::heater_safety(5, heat::safety_frame(bed, 1))),
            "A5 0D 05 23 01 00 50 07 80 00 40 00 28 00 20 00 3C 27 F4");
  EXPECT_EQ(hex_of(v2::heater_watchdog(6, 10)), "A5 02 06 24 00 0A 89 5A");
  // Decoders invert the builders; the device's field rules.
  EXPECT_EQ(v2::decode_heater_config(v2::heater_config(2, cf)), cf);
  EXPECT_EQ(v2::decode_thermistor_table(v2::thermistor_table(4, ch)), ch);
  EXPECT_EQ(v2::decode_heater_setpoint(v2::heater_setpoint(3, 1, 960)).second, 960);
  v2::Frame bad = v2::heater_setpoint(3, 1, 960);
  bad.payload[0] = 2;
  EXPECT_EQ(v2::check_host_frame(bad, 4), v2::NakReason::BadField);
  bad.payload.pop_back();
  EXPECT_EQ(v2::check_host_frame(bad, 4), v2::NakReason::BadLength);
  v2::Frame chunk = v2::thermistor_table(4, ch);
  chunk.payload[1] = 60;  // 60 + 8 > 65
  EXPECT_EQ(v2::check_host_frame(chunk, 4), v2::NakReason::BadField);
  EXPECT_TRUE(v2::is_sequenced(0x21));
  EXPECT_FALSE(v2::is_fifo(0x21));
}

TEST(HeaterCodec, StatusWithAndWithoutTheHeaterBlock) {
  v2::Status s;
  s.state = v2::kStateV2;
  s.faults = v2::kFaultBed;
  s.position = {1, -2, 3, -4};
  s.counters[0] = 7;
  const auto plain = v2::status(1, s);
  EXPECT_EQ(plain.payload.size(), 43u);
  EXPECT_EQ(v2::decode_status(plain, 4), s);
  s.heaters = {{3200, 3200, 0x1234, 0xC4, 0}, {-906, 960, 0, 0x04, v2::kHeaterMinTemp}};
  const auto full = v2::status(1, s);
  EXPECT_EQ(full.payload.size(), 59u);
  const auto d = v2::decode_status(full, 4);
  EXPECT_EQ(d, s);
  EXPECT_DOUBLE_EQ(d.heaters[0].temp_c(), 200.0);
  EXPECT_TRUE(d.heaters[0].enabled());
  EXPECT_TRUE(d.heaters[0].holding());
  EXPECT_DOUBLE_EQ(d.heaters[1].temp_c(), -56.625);
  EXPECT_EQ(v2::heater_fault_names(d.heaters[1].faults), "MINTEMP");
  auto bad = full;
  bad.payload.pop_back();
  EXPECT_THROW(v2::decode_status(bad, 4), v2::ProtocolError);
}

TEST(HeaterJob, PackerPlacesSetpointsBetweenTheFramesOfTheMoves) {
  fpgacnc::config::MachineConfig cfg;
  const auto plan = plan_of(
      "M140 S60\nM104 S200\nG1 X10 F6000\nG4 P0.1\nM190 S60\nG1 X20\nM104 S0\nG1 X30\nM109 "
      "S210\n",
      cfg);
  const auto job = v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
  const auto& hj = job.heaters;
  ASSERT_EQ(hj.actions.size(), 5u);
  // Setup: per channel CONFIG, SAFETY, 9 table chunks; one WATCHDOG.
  const size_t setup = 2u * 11u + 1u;
  EXPECT_EQ(hj.setup.size(), setup);
  ASSERT_EQ(job.frames.size(), setup + 5u + 5u);
  for (size_t i = 0; i < setup; ++i) {
    EXPECT_FALSE(job.frames[i].fifo) << i;
    EXPECT_EQ(job.frames[i].frame, hj.setup[i]) << i;
  }
  // Then: NUMERATORS, M140, M104, X10, dwell, M190, X20, M104 S0, X30, M109 (-1: a FIFO frame).
  const int want_heater[] = {-1, 0, 1, -1, -1, 2, -1, 3, -1, 4};
  for (size_t i = 0; i < 10; ++i) {
    const auto& jf = job.frames[setup + i];
    EXPECT_EQ(jf.heater, want_heater[i]) << "frame " << i;
    EXPECT_EQ(jf.fifo, want_heater[i] < 0) << "frame " << i;
    if (want_heater[i] < 0) continue;
    const auto& a = hj.actions[static_cast<size_t>(want_heater[i])];
    EXPECT_EQ(jf.frame, v2::heater_setpoint(0, a.channel, a.target_q4)) << "frame " << i;
  }
  EXPECT_EQ(job.frames[setup].frame.type, static_cast<uint8_t>(v2::Type::Numerators));
  EXPECT_EQ(job.frames[setup + 4].frame.type, static_cast<uint8_t>(v2::Type::Dwell));
  EXPECT_EQ(job.fifo_frames, 5u);
  EXPECT_EQ(job.heater_frames, setup + 5u);
  const int want_m[] = {140, 104, 190, 104, 109};
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(hj.actions[i].mcode, want_m[i]) << "action " << i;
  EXPECT_EQ(hj.actions[0].channel, heat::kBed);
  EXPECT_EQ(hj.actions[1].channel, heat::kHotend);
  EXPECT_TRUE(hj.actions[2].wait);
  EXPECT_FALSE(hj.actions[3].wait);
  EXPECT_EQ(hj.actions[3].target_q4, 0);
  EXPECT_EQ(hj.actions[4].target_q4, 210 * 16);
  // Not packed: counted, nothing checked.
  const auto motion = v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg, {.heaters = false});
  EXPECT_EQ(motion.frames.size(), 5u);
  EXPECT_EQ(motion.skipped_heater, 5u);
  EXPECT_EQ(motion.heater_frames, 0u);
}

TEST(HeaterJob, SetpointGoesBeforeTheOutputsPackedForTheNextSegment) {
  // The rule of pack_job (v2_job.h): a setpoint goes before the first frame of the segment that
  // follows it, so before an OUTPUT frame already packed for that segment; M106 and M107 around
  // it stay one OUTPUT frame (consecutive outputs merge).
  fpgacnc::config::MachineConfig cfg;
  cfg.motion = "constant";
  const auto plan = plan_of("G1 X1 F600\nM106 S255\nM104 S200\nM107\nG1 X2\n", cfg);
  const auto job = v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
  const size_t setup = job.heaters.setup.size();
  ASSERT_EQ(job.frames.size(), setup + 5u);
  const v2::Type want[] = {v2::Type::Numerators, v2::Type::Line, v2::Type::HeaterSetpoint,
                           v2::Type::Output, v2::Type::Line};
  for (size_t i = 0; i < 5; ++i)
    EXPECT_EQ(job.frames[setup + i].frame.type, static_cast<uint8_t>(want[i])) << "frame " << i;
  EXPECT_EQ(job.outputs, 1u);
  const auto fan = v2::decode_output(job.frames[setup + 3].frame).fan;
  ASSERT_TRUE(fan.has_value());
  EXPECT_EQ(*fan, 0);
}

TEST(HeaterJob, BadHeaterWordsAreLineColErrors) {
  fpgacnc::config::MachineConfig cfg;
  struct Case {
    std::string gcode;
    std::string where;
    std::string what;
  };
  const std::vector<Case> cases = {
      {"G1 X1\nM104\n", ":2:1:", "M104 needs an S word"},
      {"G1 X1\nG1 X2\n  M140 S150\n", ":3:8:", "outside the bed heater's range 5..130"},
      {"M109 S2 ; too cold\n", ":1:6:", "outside the hotend heater's range"},
      {"M190 S300\n", ":1:6:", "max_temp_c"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const auto plan = plan_file(c.gcode, cfg, fmt::format("fpgacnc_heat_bad_{}.gcode", k++));
    try {
      v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
      ADD_FAILURE() << "no error for " << c.gcode;
    } catch (const fpgacnc::gcode::Error& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find(c.where), std::string::npos) << "expected " << c.where << ", got " << w;
      EXPECT_NE(w.find(c.what), std::string::npos) << "expected " << c.what << ", got " << w;
    }
  }
  cfg.heaters.hotend().enabled = false;
  const auto plan = plan_file("G1 X1\nM104 S200\n", cfg, "fpgacnc_heat_bad_off.gcode");
  try {
    v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
    ADD_FAILURE() << "no error for a disabled hot end";
  } catch (const fpgacnc::gcode::Error& e) {
    EXPECT_NE(std::string(e.what()).find(":2:1: error: M104: the hotend heater is disabled"),
              std::string::npos)
        << e.what();
  }
  // Nothing is sent: the packer validates before the first byte.
  FakeV2Device dev(heater_device());
  EXPECT_THROW(fpgacnc::test::stream_plan(dev, plan, cfg, heat_options()), fpgacnc::gcode::Error);
  EXPECT_TRUE(dev.written().empty()) << dev.written().size() << " bytes written";
}

TEST(HeaterStream, SetpointsInOrderWithMotionAndWaitsWait) {
  fpgacnc::config::MachineConfig cfg;
  std::string g = "M140 S60\nM104 S200\n";
  for (int i = 1; i <= 20; ++i) g += fmt::format("G1 X{} F6000\n", i);
  g += "M190 S60\nM109 S200\n";
  for (int i = 21; i <= 40; ++i) g += fmt::format("G1 X{}\n", i);
  g += "M104 S0\nG1 X0\nM140 S0\n";
  const auto plan = plan_of(g, cfg);
  FakeV2Device dev(heater_device());
  size_t statuses = 0;
  auto opt = heat_options();
  opt.on_status = [&](const v2::Status& s) {
    if (!s.heaters.empty()) ++statuses;
  };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, opt);
  fmt::print("{}", lk::format_report(r));
  EXPECT_TRUE(r.position_ok);
  EXPECT_GT(statuses, 0u);
  // Heater frames as the device accepted them: setup (23) then the 6 setpoints.
  const auto& ev = dev.heater_events();
  ASSERT_EQ(ev.size(), 23u + 6u);
  EXPECT_EQ(r.heater_frames, 29u);
  for (size_t i = 0; i < 23; ++i) EXPECT_EQ(ev[i].fifo_accepted, 0u) << "setup frame " << i;
  std::vector<std::pair<int, size_t>> sp;  // (channel, FIFO frames accepted before)
  for (size_t i = 23; i < ev.size(); ++i) {
    ASSERT_EQ(ev[i].frame.type, 0x21);
    sp.emplace_back(ev[i].frame.payload[0], ev[i].fifo_accepted);
  }
  // NUMERATORS + 20 lines before the M190; + 20 before M104 S0; + 1 before M140 S0.
  const std::vector<std::pair<int, size_t>> want = {{1, 1},  {0, 1},  {1, 21},
                                                    {0, 21}, {0, 41}, {1, 42}};
  EXPECT_EQ(sp, want);
  // The waits: the 21st line (first after M109) was accepted with the FIFO drained and both
  // heaters within tolerance.
  const auto& fe = dev.fifo_events();
  ASSERT_GT(fe.size(), 21u);
  EXPECT_EQ(fe[21].fifo_level, 1u) << "the FIFO had not drained before the M190/M109 wait ended";
  EXPECT_NEAR(fe[21].temp[1], 60.0, cfg.heaters.bed().wait_tolerance_c);
  EXPECT_NEAR(fe[21].temp[0], 200.0, cfg.heaters.hotend().wait_tolerance_c);
  ASSERT_EQ(r.heater_waits.size(), 2u);
  EXPECT_EQ(r.heater_waits[0].mcode, 190);
  EXPECT_FALSE(r.heater_waits[0].skipped);
  EXPECT_GE(r.heater_waits[0].plant_s, cfg.heaters.bed().wait_settle_s);
  EXPECT_EQ(r.heater_waits[1].mcode, 109);
}

TEST(HeaterStream, WaitSkippedWhenAboveTheTarget) {
  fpgacnc::config::MachineConfig cfg;
  const auto plan = plan_of("M140 S80\nM190 S80\nM140 S60\nM190 S60\nG1 X1 F600\n", cfg);
  FakeV2Device dev(heater_device());
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, heat_options());
  ASSERT_EQ(r.heater_waits.size(), 2u);
  EXPECT_FALSE(r.heater_waits[0].skipped);
  EXPECT_TRUE(r.heater_waits[1].skipped) << "M190 S60 at 80 degC should not wait (S: heating only)";
}

TEST(HeaterStream, HeaterFaultStopsTheJobNamingTheLine) {
  fpgacnc::config::MachineConfig cfg;
  std::string g = "M140 S60\n";
  for (int i = 1; i <= 400; ++i) g += fmt::format("G1 X{} F6000\n", i % 7);
  const auto plan = plan_of(g, cfg);
  auto d = heater_device();
  d.inject_fault = v2::kHeaterMinTemp;
  d.inject_channel = 1;
  d.inject_after = std::chrono::microseconds(100'000);
  FakeV2Device dev(d);
  try {
    fpgacnc::test::stream_plan(dev, plan, cfg, heat_options());
    FAIL() << "a MINTEMP fault did not stop the job";
  } catch (const lk::Error& e) {
    const std::string w = e.what();
    fmt::print("error: {}\n", w);
    EXPECT_NE(w.find("job stopped at G-code line job.gcode:"), std::string::npos) << w;
    EXPECT_NE(w.find("bed heater fault MINTEMP"), std::string::npos) << w;
    EXPECT_NE(w.find("sensor open"), std::string::npos) << w;
  }
  EXPECT_LT(dev.done(), 401u) << "the job ran to its end despite the fault";
}

TEST(HeaterStream, WaitTimeoutNamesTheLine) {
  fpgacnc::config::MachineConfig cfg;
  cfg.heaters.hotend().wait_timeout_s = 300.0;  // plant s = 0.3 s of wall time here
  const auto plan = plan_of("G1 X1 F600\nM109 S250\nG1 X2\n", cfg);
  auto d = heater_device();
  d.heater_tau = std::chrono::microseconds(100'000'000);  // barely heats
  FakeV2Device dev(d);
  try {
    fpgacnc::test::stream_plan(dev, plan, cfg, heat_options());
    FAIL() << "no timeout";
  } catch (const lk::Error& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("M109 S250 at line job.gcode:2"), std::string::npos) << w;
    EXPECT_NE(w.find("wait_timeout_s = 300"), std::string::npos) << w;
  }
  EXPECT_EQ(dev.fifo_events().size(), 2u) << "the move after the M109 was sent";
}
