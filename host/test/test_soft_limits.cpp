// Soft limits on the host ([travel] in the machine configuration, docs/machine.md "Soft limits"):
// the planner refuses a program whose move leaves the travel, naming FILE:LINE, the axis, the
// limit and by how much, before anything reaches the device. Expected figures are worked out
// from the G-code geometry by hand (comments), not taken from the planner's output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fake_v2_device.h"
#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/grbl/settings.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/plan/stepfile.h"
#include "fpgacnc/protocol/v2.h"
#include "fpgacnc/protocol/v2_job.h"
#include "stream_plan.h"

namespace pl = fpgacnc::plan;
using fpgacnc::config::MachineConfig;
using fpgacnc::test::FakeV2Device;

namespace {

// X in [0, 100], Y in [0, 50] mm; Z and E without soft limits.
MachineConfig box() {
  MachineConfig c;
  c.travel[fpgacnc::config::kX] = {true, 0.0, 100.0};
  c.travel[fpgacnc::config::kY] = {true, 0.0, 50.0};
  return c;
}

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

// The TravelError planning `text` from a file throws (its what() checked by the caller).
std::string refusal(const std::string& name, const std::string& text, const MachineConfig& cfg,
                    pl::TravelViolation* v = nullptr) {
  const std::string path = write_file(name, text);
  try {
    pl::plan_input_file(path, cfg, {});
  } catch (const pl::TravelError& e) {
    if (v) *v = e.violation();
    std::filesystem::remove(path);
    return e.what();
  }
  std::filesystem::remove(path);
  ADD_FAILURE() << "no TravelError for " << text;
  return "";
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

}  // namespace

TEST(SoftLimits, OffByDefault) {
  const MachineConfig c;
  for (const auto& t : c.travel) EXPECT_FALSE(t.enabled);
  // Far outside any plausible travel, still planned.
  const auto p = pl::plan_program(fpgacnc::gcode::parse_string("G0 X-5000 Y9000\n"), c, {});
  EXPECT_EQ(p.final_steps[0], -5000 * 160);
}

TEST(SoftLimits, ConfigReadsTravelAndRefusesBadValues) {
  const auto c = fpgacnc::config::parse_machine_config(
      "[travel]\nx = { min = -1.5, max = 300 }\nz = { min = -80, max = 0 }\n", "m.toml");
  EXPECT_TRUE(c.travel[0].enabled);
  EXPECT_EQ(c.travel[0].min_mm, -1.5);
  EXPECT_EQ(c.travel[0].max_mm, 300.0);
  EXPECT_FALSE(c.travel[1].enabled);
  EXPECT_TRUE(c.travel[2].enabled);
  EXPECT_EQ(c.travel[2].min_mm, -80.0);
  EXPECT_FALSE(c.travel[3].enabled);
  const std::pair<const char*, const char*> bad[] = {
      {"[travel]\nx = { min = 10, max = 10 }\n",
       "m.toml:2:5: error: key 'travel.x': min must be below max"},
      {"[travel]\nx = { min = 0 }\n", "key 'travel.x': give both min and max"},
      {"[travel]\nq = { min = 0, max = 1 }\n", "key 'travel.q': unknown key"},
      {"[travel]\nx = { min = 0, max = 1, mid = 0 }\n", "key 'travel.x.mid': unknown key"},
      {"[travel]\nx = 5\n", "key 'travel.x': expected { min = MM, max = MM }"},
  };
  for (const auto& [text, want] : bad) {
    try {
      fpgacnc::config::parse_machine_config(text, "m.toml");
      ADD_FAILURE() << "accepted " << text;
    } catch (const fpgacnc::config::Error& e) {
      EXPECT_TRUE(has(e.what(), want)) << e.what();
    }
  }
}

TEST(SoftLimits, ProgramInsideTheTravelPasses) {
  // Touches every limit exactly (0 and 100 on X, 0 and 50 on Y) and a circle of radius 20
  // about (50, 25) whose extent is X 30..70, Y 5..45.
  const auto p = pl::plan_program(fpgacnc::gcode::parse_string("G0 X100 Y50\nG1 X0 Y0 F1000\n"
                                                               "G0 X70 Y25\nG2 X70 Y25 I-20 J0\n"
                                                               "G0 X0 Y0\n"),
                                  box(), {});
  EXPECT_EQ(p.final_steps[0], 0);
  EXPECT_GT(p.stats.arc_chords, 3u);
}

TEST(SoftLimits, LineLeavingTheTravelNamesFileLineAxisLimitAndDistance) {
  pl::TravelViolation v;
  // Line 3 ends at X 112.5: 12.5 mm beyond X's max of 100.
  const std::string w = refusal("fpgacnc_soft_line.gcode",
                                "G0 X10 Y10\nG1 X50 F500\nG1 X112.5\n"
                                "G1 X-300\n",
                                box(), &v);
  EXPECT_TRUE(has(w, "fpgacnc_soft_line.gcode:3: error: move leaves the travel")) << w;
  EXPECT_TRUE(has(w, "X reaches 112.500 mm, 12.500 mm beyond its max 100.000 mm")) << w;
  EXPECT_EQ(v.axis, 0);
  EXPECT_TRUE(v.above_max);
  // Below a min, on Y.
  const std::string w2 =
      refusal("fpgacnc_soft_line2.gcode", "G0 X10 Y10\nG91\nG1 Y-10.25 F500\n", box(), &v);
  EXPECT_TRUE(has(w2, "fpgacnc_soft_line2.gcode:3: error:")) << w2;
  EXPECT_TRUE(has(w2, "Y reaches -0.250 mm, 0.250 mm below its min 0.000 mm")) << w2;
  EXPECT_FALSE(v.above_max);
}

TEST(SoftLimits, ArcWhoseEndsAreInsideButWhoseExtentIsNotIsRefused) {
  // Half circles from (80, 25) to (80, 45) about (80, 35), radius 10: from -90 deg to 90 deg.
  // Counter-clockwise (G3) passes 0 deg at X 90; clockwise (G2) passes 180 deg at X 70. Both
  // ends are inside; with X's max at 85 the G3 reaches 5 mm beyond it, the G2 stays inside.
  MachineConfig c = box();
  c.travel[0].max_mm = 85.0;
  pl::TravelViolation v;
  const std::string w =
      refusal("fpgacnc_soft_arc.gcode", "G0 X80 Y25\nG3 X80 Y45 I0 J10 F500\n", c, &v);
  EXPECT_TRUE(has(w, "fpgacnc_soft_arc.gcode:2: error: arc leaves the travel")) << w;
  EXPECT_TRUE(has(w, "X reaches 90.000 mm inside the arc, 5.000 mm beyond its max 85.000 mm")) << w;
  EXPECT_TRUE(v.in_arc);
  const auto ok =
      pl::plan_program(fpgacnc::gcode::parse_string("G0 X80 Y25\nG2 X80 Y45 I0 J10 F500\n"), c, {});
  EXPECT_EQ(ok.final_steps[1], 45 * 160);
  // A full circle from (50, 29) about (50, 14), radius 15: its bottom (-90 deg) is Y -1.
  const std::string w2 = refusal("fpgacnc_soft_circle.gcode", "G0 X50 Y29\nG2 J-15 F500\n", c, &v);
  EXPECT_TRUE(has(w2, ":2: error: arc leaves the travel")) << w2;
  EXPECT_TRUE(has(w2, "Y reaches -1.000 mm inside the arc, 1.000 mm below its min 0.000 mm")) << w2;
}

TEST(SoftLimits, RefusedJobSendsNothing) {
  const std::string path =
      write_file("fpgacnc_soft_nothing.gcode", "G0 X10 Y10\nG1 X20 F500\nG1 X200\n");
  FakeV2Device dev(FakeV2Device::Options{});
  const MachineConfig c = box();
  // The pipeline `fpgacnc stream` runs: plan the file, then pack and stream it.
  EXPECT_THROW(
      {
        const auto p = pl::plan_input_file(path, c, {});
        fpgacnc::test::stream_plan(dev, p, c, fpgacnc::link::stream_v2_options(c));
      },
      pl::TravelError);
  EXPECT_TRUE(dev.written().empty()) << dev.written().size() << " bytes written";
  std::filesystem::remove(path);
}

TEST(SoftLimits, StepFileSegmentLeavingTheTravelIsRefused) {
  // Two segments of +9000 X steps at 160 steps/mm: 56.25 mm, then 112.5 mm (12.5 beyond 100).
  std::stringstream csv(
      "segment,line,motion,x_mm,y_mm,steps_x,steps_y,length_mm,feed\n"
      "0,1,1,0,0,9000,0,56.25,100\n"
      "1,2,1,56.25,0,9000,0,56.25,100\n");
  try {
    pl::read_step_file(csv, "job.csv", box());
    ADD_FAILURE() << "no TravelError";
  } catch (const pl::TravelError& e) {
    const std::string w = e.what();
    EXPECT_TRUE(has(w, "job.csv:3: error: segment leaves the travel")) << w;
    EXPECT_TRUE(has(w, "X reaches 112.500 mm, 12.500 mm beyond its max 100.000 mm")) << w;
  }
}

TEST(SoftLimits, GrblSettingsMapOntoTheTravel) {
  namespace grbl = fpgacnc::grbl;
  MachineConfig c;
  c.travel[0] = {true, 10.0, 310.0};
  grbl::Settings s = grbl::settings_from_config(c);
  EXPECT_EQ(s.values.at(20), 1.0);
  EXPECT_EQ(s.values.at(130), 300.0);
  EXPECT_EQ(s.values.at(131), 200.0);  // grbl's default: Y has no travel
  // $130 moves X's max from its min; Y stays without soft limit (the configuration gives X).
  EXPECT_EQ(grbl::set_value(s, 130, 100.0), 0);
  MachineConfig a = grbl::apply_settings(c, s);
  EXPECT_TRUE(a.travel[0].enabled);
  EXPECT_EQ(a.travel[0].min_mm, 10.0);
  EXPECT_EQ(a.travel[0].max_mm, 110.0);
  EXPECT_FALSE(a.travel[1].enabled);
  // $20=0: off.
  EXPECT_EQ(grbl::set_value(s, 20, 0.0), 0);
  EXPECT_FALSE(grbl::apply_settings(c, s).travel[0].enabled);
  // No travel configured: $20 lists 0; $20=5 is stored as 1 and gives grbl's [-$13x, 0].
  const MachineConfig none;
  grbl::Settings n = grbl::settings_from_config(none);
  EXPECT_EQ(n.values.at(20), 0.0);
  EXPECT_EQ(grbl::set_value(n, 20, 5.0), 0);
  EXPECT_EQ(n.values.at(20), 1.0);
  EXPECT_EQ(grbl::set_value(n, 132, 80.0), 0);
  const MachineConfig g = grbl::apply_settings(none, n);
  EXPECT_EQ(g.travel[2].min_mm, -80.0);
  EXPECT_EQ(g.travel[2].max_mm, 0.0);
  EXPECT_EQ(g.travel[0].min_mm, -200.0);
  EXPECT_FALSE(g.travel[3].enabled);
}

TEST(SoftLimits, ConfigTravelFramesAndNakTravel) {
  namespace v2 = fpgacnc::protocol::v2;
  // X in [0, 100] mm at 160 steps/mm is [0, 16000] steps; Y [0, 50] mm: [0, 8000]. Sent for the
  // configured axes only, big-endian int32 after the axis and the enable flag.
  const auto plan = pl::plan_program(fpgacnc::gcode::parse_string("G0 X1\n"), box(), {});
  const auto job = v2::pack_job(pl::plan_motion(plan, box()), box(), {.heaters = false});
  ASSERT_EQ(job.travel.size(), 2u);
  EXPECT_EQ(job.travel[0].type, fpgacnc::spec::kTypeConfigTravel);
  EXPECT_EQ(job.travel[0].payload,
            (std::vector<uint8_t>{0, 1, 0, 0, 0, 0, 0x00, 0x00, 0x3E, 0x80}));
  EXPECT_EQ(job.travel[1].payload,
            (std::vector<uint8_t>{1, 1, 0, 0, 0, 0, 0x00, 0x00, 0x1F, 0x40}));
  const MachineConfig none;
  const auto plain = pl::plan_program(fpgacnc::gcode::parse_string("G0 X1\n"), none, {});
  EXPECT_TRUE(v2::pack_job(pl::plan_motion(plain, none), none, {.heaters = false}).travel.empty());
  // The device's field rules as the host models them.
  EXPECT_FALSE(v2::check_host_frame(v2::config_travel(0, 3, true, -5, 5), 4));
  EXPECT_EQ(v2::check_host_frame(v2::config_travel(0, 4, true, -5, 5), 4), v2::NakReason::BadField);
  EXPECT_EQ(v2::check_host_frame(v2::config_travel(0, 0, true, 5, -5), 4), v2::NakReason::BadField);
  EXPECT_FALSE(v2::check_host_frame(v2::config_travel(0, 0, false, 5, -5), 4));
  // NAK TRAVEL decodes and has its name.
  const v2::Frame nak{1, fpgacnc::spec::kTypeNak, {7, fpgacnc::spec::kNakTravel, 7, 0, 60}};
  EXPECT_EQ(v2::decode_nak(nak).reason, v2::NakReason::Travel);
  EXPECT_EQ(v2::nak_reason_name(fpgacnc::spec::kNakTravel), "TRAVEL");
}
