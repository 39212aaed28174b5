#include <fmt/format.h>
#include <gtest/gtest.h>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/stream_v2.h"

using fpgacnc::config::MachineConfig;

TEST(Config, DefaultsMatchTheOriginalMachine) {
  MachineConfig c;
  EXPECT_EQ(c.steps_per_mm[0], 160.0);
  EXPECT_EQ(c.steps_per_mm[1], 160.0);
  EXPECT_EQ(c.steps_per_mm[2], 400.0);
  EXPECT_EQ(c.steps_per_mm[3], 100.0);
  EXPECT_EQ(c.clk_hz, 50'000'000u);
  EXPECT_EQ(c.baud, 115200u);
  EXPECT_EQ(c.rapid_feed_mm_min, 3000.0);
  EXPECT_EQ(c.arc_tolerance_mm, 0.01);
  EXPECT_EQ(c.step_timing.step_high, 100u);
  EXPECT_EQ(c.step_timing.dir_setup, 200u);
  EXPECT_EQ(c.ack_timeout_s, 10.0);
  EXPECT_TRUE(c.laser_requires_m3);
}

TEST(Config, ExampleFileLoadsAndEqualsDefaults) {
  const auto c = fpgacnc::config::load_machine_config(FPGACNC_HOST_DIR "/machine.example.toml");
  MachineConfig d;
  EXPECT_EQ(c.steps_per_mm, d.steps_per_mm);
  EXPECT_EQ(c.max_feed_mm_min, d.max_feed_mm_min);
  EXPECT_EQ(c.clk_hz, d.clk_hz);
  EXPECT_EQ(c.baud, d.baud);
  EXPECT_EQ(c.port, d.port);
  EXPECT_EQ(c.rapid_feed_mm_min, d.rapid_feed_mm_min);
  EXPECT_EQ(c.default_feed_mm_min, d.default_feed_mm_min);
  EXPECT_EQ(c.arc_tolerance_mm, d.arc_tolerance_mm);
  EXPECT_EQ(c.ack_timeout_s, d.ack_timeout_s);
  EXPECT_EQ(c.feed_override_pct, d.feed_override_pct);
  EXPECT_EQ(c.dwell_time_pct, d.dwell_time_pct);
  EXPECT_EQ(c.laser_requires_m3, d.laser_requires_m3);
  EXPECT_EQ(c.step_timing.dir_hold, d.step_timing.dir_hold);
  EXPECT_EQ(c.protocol, d.protocol);
  EXPECT_EQ(c.protocol, "auto");
  EXPECT_EQ(c.retransmit_timeout_s, d.retransmit_timeout_s);
  EXPECT_EQ(c.laser_s_max, d.laser_s_max);
}

TEST(Config, ProtocolAndV2Keys) {
  for (const char* p : {"auto", "v1", "v2"}) {
    const auto c =
        fpgacnc::config::parse_machine_config(fmt::format("protocol = \"{}\"\n", p), "m.toml");
    EXPECT_EQ(c.protocol, p);
  }
  const auto c = fpgacnc::config::parse_machine_config(
      "retransmit_timeout_s = 0.05\nlaser_s_max = 255\n", "m.toml");
  EXPECT_EQ(c.retransmit_timeout_s, 0.05);
  EXPECT_EQ(c.laser_s_max, 255.0);
  try {
    fpgacnc::config::parse_machine_config("\nprotocol = \"v3\"\n", "m.toml");
    FAIL();
  } catch (const fpgacnc::config::Error& e) {
    EXPECT_NE(std::string(e.what()).find("m.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"auto\", \"v1\" or \"v2\""), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(fpgacnc::config::parse_machine_config("laser_s_max = 0\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("retransmit_timeout_s = -1\n", "m.toml"),
               fpgacnc::config::Error);
}

TEST(Config, ParsesValues) {
  const auto c = fpgacnc::config::parse_machine_config(
      "baud = 1000000\nport = \"/dev/ttyUSB1\"\nlaser_requires_m3 = false\ndwell_time = 4\n"
      "[steps_per_mm]\nx = 80\n[step_timing]\nstep_high = 1\n",
      "m.toml");
  EXPECT_EQ(c.dwell_time_pct, 4.0);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("dwell_time = 0\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_EQ(c.baud, 1000000u);
  EXPECT_EQ(c.port, "/dev/ttyUSB1");
  EXPECT_FALSE(c.laser_requires_m3);
  EXPECT_EQ(c.steps_per_mm[0], 80.0);
  EXPECT_EQ(c.steps_per_mm[1], 160.0);
  EXPECT_EQ(c.step_timing.step_high, 1u);
}

TEST(Config, FourthAxisIsTheExtruderOrARotaryA) {
  EXPECT_EQ(fpgacnc::config::parse_machine_config("", "m.toml").fourth_axis, 'E');
  const auto c = fpgacnc::config::parse_machine_config(
      "fourth_axis = \"A\"\n[steps_per_mm]\na = 50\n", "m.toml");
  EXPECT_EQ(c.fourth_axis, 'A');
  EXPECT_EQ(c.steps_per_mm[3], 50.0);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("fourth_axis = \"B\"\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("[steps_per_mm]\na = 50\ne = 10\n", "m.toml"),
               fpgacnc::config::Error);
}

TEST(Config, UnknownKeyNamesFileAndKey) {
  try {
    fpgacnc::config::parse_machine_config("baud = 9600\nbogus = 1\n", "m.toml");
    FAIL();
  } catch (const fpgacnc::config::Error& e) {
    EXPECT_EQ(e.file(), "m.toml");
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("'bogus'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fpgacnc::config::parse_machine_config("[steps_per_mm]\nw = 1\n", "m.toml"),
               fpgacnc::config::Error);
}

TEST(Config, WrongTypeNamesKey) {
  try {
    fpgacnc::config::parse_machine_config("[steps_per_mm]\nx = \"many\"\n", "m.toml");
    FAIL();
  } catch (const fpgacnc::config::Error& e) {
    EXPECT_NE(std::string(e.what()).find("m.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("steps_per_mm.x"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fpgacnc::config::parse_machine_config("baud = 1.5\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("laser_requires_m3 = 1\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("protocol = \"v9\"\n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::parse_machine_config("baud = \n", "m.toml"),
               fpgacnc::config::Error);
  EXPECT_THROW(fpgacnc::config::load_machine_config("/nonexistent/m.toml"), fpgacnc::config::Error);
}

// hold_decel_mm_s2 (docs/timing.md "Feed hold and overrides"): the MOTION ramp is
// 2^32 * 256 * a / (v_max * CLK_HZ) per axis (units cancel: a / v in 1/s), the smallest over the
// axes. Defaults: X and Y 1000 mm/s^2 at 200 mm/s (5 /s), Z 100 at 10 (10 /s), E 1000 at 50
// (20 /s): X decides, 2^32 * 256 * 5 / 5e7 = 109 951.16.
TEST(Config, HoldDecelSetsTheMotionRamp) {
  const MachineConfig d;
  EXPECT_EQ(d.hold_decel_mm_s2, 0.0);
  EXPECT_EQ(fpgacnc::link::machine_hold_ramp(d), 109'951u);
  EXPECT_EQ(fpgacnc::link::machine_motion(d).ramp, 109'951u);
  EXPECT_EQ(fpgacnc::link::machine_motion(d).feed, 0x8000);
  EXPECT_FALSE(fpgacnc::link::machine_motion(d).hold);
  // 500 mm/s^2 on every axis: X at 200 mm/s gives 2.5 /s: 54 975.58.
  const auto c = fpgacnc::config::parse_machine_config("hold_decel_mm_s2 = 500\n", "m.toml");
  EXPECT_EQ(c.hold_decel_mm_s2, 500.0);
  EXPECT_EQ(fpgacnc::link::machine_hold_ramp(c), 54'975u);
  // Only the device's axes: with Z alone slower (a 3-axis device), still X; a machine whose X
  // is slow to stop but has 1 axis only is decided by X alone.
  MachineConfig z = d;
  z.max_accel_mm_s2[2] = 10.0;  // Z: 10 / 10 = 1 /s: 21 990.23
  EXPECT_EQ(fpgacnc::link::machine_hold_ramp(z, 3), 21'990u);
  EXPECT_EQ(fpgacnc::link::machine_hold_ramp(z, 2), 109'951u);
  try {
    fpgacnc::config::parse_machine_config("\nhold_decel_mm_s2 = 0\n", "m.toml");
    ADD_FAILURE() << "hold_decel_mm_s2 = 0 accepted";
  } catch (const std::exception& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("m.toml:2"), std::string::npos) << w;
    EXPECT_NE(w.find("hold_decel_mm_s2"), std::string::npos) << w;
  }
}

// [homing]: grbl's $22-$27 and the cycles; bad values name the key.
TEST(Config, HomingKeys) {
  const auto d = fpgacnc::config::parse_machine_config("", "m.toml");
  EXPECT_FALSE(d.homing.enabled);
  EXPECT_EQ(d.homing.cycles, (std::vector<uint32_t>{4, 3}));
  const auto c = fpgacnc::config::parse_machine_config(
      "[homing]\nenabled = true\ndir_invert_mask = 5\nlocate_feed_mm_min = 30\n"
      "seek_feed_mm_min = 800.5\ndebounce_ms = 0\npulloff_mm = 2\ncycles = [\"xy\", \"Z\"]\n"
      "max_travel_mm = { x = 300, z = 80 }\n",
      "m.toml");
  EXPECT_TRUE(c.homing.enabled);
  EXPECT_EQ(c.homing.dir_invert_mask, 5u);
  EXPECT_EQ(c.homing.locate_feed_mm_min, 30.0);
  EXPECT_EQ(c.homing.seek_feed_mm_min, 800.5);
  EXPECT_EQ(c.homing.debounce_ms, 0.0);
  EXPECT_EQ(c.homing.pulloff_mm, 2.0);
  EXPECT_EQ(c.homing.cycles, (std::vector<uint32_t>{3, 4}));
  EXPECT_EQ(c.homing.max_travel_mm, (std::array<double, 3>{300.0, 0.0, 80.0}));
  for (const char* bad : {"[homing]\ndir_invert_mask = 8\n", "[homing]\npulloff_mm = 0\n",
                          "[homing]\ncycles = [\"XQ\"]\n", "[homing]\nbogus = 1\n"}) {
    try {
      fpgacnc::config::parse_machine_config(bad, "m.toml");
      ADD_FAILURE() << bad;
    } catch (const fpgacnc::config::Error& e) {
      EXPECT_EQ(e.line(), 2) << bad;
      EXPECT_NE(std::string(e.what()).find("homing."), std::string::npos) << e.what();
    }
  }
}
