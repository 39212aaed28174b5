#include <gtest/gtest.h>

#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/protocol/v1.h"

namespace v1 = fpgacnc::protocol::v1;

TEST(PackerV1, InitWorkedExample) {
  const auto b = v1::pack_init(18'750'000, 18'750'000);
  const std::array<uint8_t, 9> want{0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30};
  EXPECT_EQ(b, want);
}

TEST(PackerV1, MotionWorkedExample) {
  const auto b = v1::pack_motion(1, 320, -160, 1200);
  const std::array<uint8_t, 11> want{0x01, 0x00, 0x00, 0x01, 0x40, 0xFF,
                                     0xFF, 0xFF, 0x60, 0x04, 0xB0};
  EXPECT_EQ(b, want);
}

TEST(PackerV1, JobBytesAreInitThenMotions) {
  fpgacnc::config::MachineConfig cfg;
  cfg.laser_requires_m3 = false;
  const auto prog = fpgacnc::gcode::parse_string("G1 X2 Y-1 F1341.64\nG4 P0\nM104 S200\n");
  const auto plan = fpgacnc::plan::plan_program(prog, cfg, {});
  const auto bytes = v1::job_bytes(plan);
  ASSERT_EQ(bytes.size(), 9u + 11u);
  const auto init = v1::pack_init(18'750'000, 18'750'000);
  EXPECT_TRUE(std::equal(init.begin(), init.end(), bytes.begin()));
  // 2 mm = 320 steps, -1 mm = -160 steps; X dominant: 1341.64 * 2 / sqrt(5) = 1200.0
  const auto m = v1::pack_motion(1, 320, -160, 1200);
  EXPECT_TRUE(std::equal(m.begin(), m.end(), bytes.begin() + 9));
  const auto job = v1::pack_job(plan);
  EXPECT_EQ(job.skipped_heater, 1u);
  EXPECT_EQ(job.motions, 1u);
}

TEST(PackerV1, RejectsSegmentsV1CannotCarry) {
  fpgacnc::plan::Plan p;
  fpgacnc::plan::Segment s;
  s.code = 1;
  s.steps = {int64_t{1} << 33, 0, 0, 0};
  p.items.emplace_back(s);
  EXPECT_THROW(v1::pack_job(p), std::invalid_argument);
}
