// The laser / spindle power in the v2 packer (docs/machine.md "Laser and spindle PWM",
// docs/grbl.md): S scaled to the power byte by laser_s_min / laser_s_max ($31 / $30), M4 as an
// OUTPUT with mask bit 7 set to 1 (dynamic power) and M3 back to 0, in their place between the
// motion frames: at the first M3 / M4 (whatever the device holds from an earlier job) and where
// the mode changes.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"

namespace v2 = fpgacnc::protocol::v2;

namespace {

v2::Job pack(const std::string& gcode, const fpgacnc::config::MachineConfig& cfg) {
  const auto plan =
      fpgacnc::plan::plan_program(fpgacnc::gcode::parse_string(gcode, "job.gcode"), cfg, {});
  return v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
}

// The job's motion and OUTPUT frames in order: "L<power>" for a LINE / LINE_PROFILE (code != 0),
// "R" for a rapid, "O<mask>:<value>" for an OUTPUT.
std::vector<std::string> trace(const v2::Job& job) {
  std::vector<std::string> t;
  for (const auto& jf : job.frames) {
    const auto& f = jf.frame;
    const auto type = static_cast<v2::Type>(f.type);
    if (type == v2::Type::Output) {
      t.push_back("O" + std::to_string(f.payload[0]) + ":" + std::to_string(f.payload[1]));
    } else if (type == v2::Type::Line || type == v2::Type::LineProfile) {
      const bool rapid = (f.payload[0] & 3) == 0;
      const std::string s = rapid ? "R" : "L" + std::to_string(f.payload[1]);
      if (t.empty() || t.back() != s) t.push_back(s);  // a move split into several frames
    }
  }
  return t;
}

TEST(LaserPower, M4SetsTheDynamicFlagInPlaceAndM3ClearsIt) {
  fpgacnc::config::MachineConfig cfg;
  const auto t = trace(pack("M4 S500\nG1 X10 F1200\nG1 X20 S1000\nM3\nG1 X30\nM5\nG0 X0\n", cfg));
  const std::vector<std::string> want{"O128:128", "L128", "L255", "O128:0", "L255", "R"};
  EXPECT_EQ(t, want);
  const auto o = v2::decode_output(pack("M4 S1\nG1 X1\n", cfg).frames.at(1).frame);
  ASSERT_TRUE(o.laser_dyn.has_value());
  EXPECT_TRUE(*o.laser_dyn);
}

TEST(LaserPower, FirstModeIsSentThenOnlyChanges) {
  fpgacnc::config::MachineConfig cfg;
  EXPECT_EQ(trace(pack("M3 S1000\nG1 X10 F1200\nM5\nM3\nG1 X20\n", cfg)),
            (std::vector<std::string>{"O128:0", "L255"}));
  EXPECT_EQ(trace(pack("G1 X10 F1200\n", cfg)), (std::vector<std::string>{"L0"}))
      << "no M3 / M4: no mode sent (and the laser off)";
  EXPECT_EQ(trace(pack("M4 S250\nG1 X10 F1200\nM4\nG1 X20\nM5\nM4\nG1 X30\n", cfg)),
            (std::vector<std::string>{"O128:128", "L64"}));
}

TEST(LaserPower, SpindleMapFromMinToMax) {
  fpgacnc::config::MachineConfig cfg;
  cfg.laser_s_min = 200.0;  // grbl $31: a spindle's lowest speed
  cfg.laser_s_max = 1000.0;
  // S 100 and 200: the lowest power; 600: (600 - 200) / 800 * 255 = 127.5 -> 128; 1000: 255;
  // above the maximum: 255
  EXPECT_EQ(trace(pack("M3 S100\nG1 X1 F600\nS200\nG1 X2\nS600\nG1 X3\nS1000\nG1 X4\nS2000\nG1 "
                       "X5\n",
                       cfg)),
            (std::vector<std::string>{"O128:0", "L1", "L128", "L255"}));
}

}  // namespace
