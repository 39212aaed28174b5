#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "fpgacnc/plan/stepfile.h"

namespace pl = fpgacnc::plan;

TEST(StepFile, RoundTripKeepsCodeStepsFeed) {
  fpgacnc::config::MachineConfig cfg;
  cfg.laser_requires_m3 = false;
  for (const char* name : {"jsdc-laser.gcode", "circle.gcode", "g2-arc.gcode"}) {
    SCOPED_TRACE(name);
    const auto p = pl::plan_gcode_file(std::string(FPGACNC_CORPUS_DIR) + "/" + name, cfg, {});
    std::stringstream csv;
    pl::write_step_file(csv, p, cfg);
    const auto q = pl::read_step_file(csv, "rt.csv", cfg);
    std::vector<const pl::Segment*> a, b;
    for (const auto& it : p.items) {
      if (const auto* s = std::get_if<pl::Segment>(&it)) a.push_back(s);
    }
    for (const auto& it : q.items) b.push_back(&std::get<pl::Segment>(it));
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i]->code, b[i]->code) << i;
      EXPECT_EQ(a[i]->steps[0], b[i]->steps[0]) << i;
      EXPECT_EQ(a[i]->steps[1], b[i]->steps[1]) << i;
      EXPECT_EQ(a[i]->feed_v1, b[i]->feed_v1) << i;
    }
    EXPECT_EQ(q.final_steps[0], p.final_steps[0]);
    EXPECT_EQ(q.final_steps[1], p.final_steps[1]);
  }
}

TEST(StepFile, ReadsOriginalColumnsAndRoundsFeed) {
  std::istringstream in(
      "n,x,motion,a,b,sx,sy,c,feed\n"
      "0,,1,0,0,320,-160,0,1199.6\n"
      "1,,0,0,0,-5,7,0,3000\n");
  const auto p = pl::read_step_file(in, "s.csv", {});
  ASSERT_EQ(p.items.size(), 2u);
  const auto& s = std::get<pl::Segment>(p.items[0]);
  EXPECT_EQ(s.code, 1);
  EXPECT_EQ(s.steps[0], 320);
  EXPECT_EQ(s.steps[1], -160);
  EXPECT_EQ(s.feed_v1, 1200);
  EXPECT_EQ(s.source_line, 2);
  EXPECT_EQ(p.final_steps[0], 315);
}

TEST(StepFile, ErrorsNameFileLineColumn) {
  auto expect_err = [](const std::string& text, int line, int col) {
    std::istringstream in(text);
    try {
      pl::read_step_file(in, "s.csv", {});
      ADD_FAILURE() << "no error for " << text;
    } catch (const pl::StepFileError& e) {
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_EQ(e.column(), col) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("s.csv:", 0), 0u) << e.what();
    }
  };
  expect_err("h\n0,,1,0,0,1,2,0,100\n1,,1,0,0,1x,2,0,100\n", 3, 10);
  expect_err("h\n0,,1,0,0,1,2,0\n", 2, 1);
  expect_err("h\n0,,7,0,0,1,2,0,100\n", 2, 4);
  expect_err("h\n0,,1,0,0,1,2,0,fast\n", 2, 16);
  expect_err("h\n", 1, 1);
}

TEST(StepFile, DetectedByExtensionOrContent) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto csv = (dir / "fpgacnc_test_detect.txt").string();
  {
    std::ofstream f(csv);
    f << "segment,line,motion,x_mm,y_mm,steps_x,steps_y,length_mm,feed\n0,1,1,0,0,160,0,1,100\n";
  }
  EXPECT_TRUE(pl::looks_like_step_file(csv));
  const auto p = pl::plan_input_file(csv, {}, {});
  EXPECT_EQ(p.final_steps[0], 160);
  EXPECT_TRUE(pl::looks_like_step_file("job.CSV"));
  EXPECT_FALSE(pl::looks_like_step_file(std::string(FPGACNC_CORPUS_DIR) + "/circle.gcode"));
  std::filesystem::remove(csv);
}
