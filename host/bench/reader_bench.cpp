// Reader throughput (not a ctest test): Reader::next over a whole file (default part.gcode),
// prints "reader throughput: N lines/s". Usage: host_reader_bench [FILE] [--ngc]
#include <fmt/format.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "fpgacnc/gcode/reader.h"

int main(int argc, char** argv) {
  std::string path = std::string(FPGACNC_CORPUS_DIR) + "/part.gcode";
  bool ngc = false;
  for (int a = 1; a < argc; ++a) {
    if (std::string_view(argv[a]) == "--ngc") {
      ngc = true;
    } else {
      path = argv[a];
    }
  }
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    fmt::print(stderr, "cannot open {}\n", path);
    return 1;
  }
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  fpgacnc::gcode::Syntax syntax;
  syntax.ngc = ngc;
  double best = 0.0;
  uint64_t blocks = 0;
  uint64_t words = 0;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    fpgacnc::gcode::Params params;
    fpgacnc::gcode::Reader reader(path, text, syntax, params);
    fpgacnc::gcode::Block b;
    blocks = 0;
    words = 0;
    while (reader.next(b)) {
      ++blocks;
      words += static_cast<uint64_t>(b.count);
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::max(best, static_cast<double>(blocks) / s);
  }
  fmt::print("reader throughput: {:.0f} lines/s ({}{} on {} lines, {} words, best of 5)\n", best,
             path, ngc ? " as rs274ngc" : "", blocks, words);
  return 0;
}
