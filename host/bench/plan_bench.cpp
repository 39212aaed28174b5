// Planning throughput on part.gcode (not a ctest test): prints "plan throughput: N lines/s".
#include <fmt/format.h>

#include <chrono>
#include <string>

#include "fpgacnc/plan/planner.h"

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : std::string(FPGACNC_CORPUS_DIR) + "/part.gcode";
  fpgacnc::config::MachineConfig cfg;
  double best = 0.0;
  uint64_t lines = 0;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto plan = fpgacnc::plan::plan_gcode_file(path, cfg, {});
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lines = plan.input.lines;
    best = std::max(best, static_cast<double>(lines) / s);
  }
  fmt::print("plan throughput: {:.0f} lines/s ({} on {} lines, best of 5)\n", best, path, lines);
  return 0;
}
