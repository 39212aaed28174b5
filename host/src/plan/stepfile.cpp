#include "fpgacnc/plan/stepfile.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <ostream>
#include <sstream>
#include <vector>

namespace fpgacnc::plan {
namespace {

struct Field {
  std::string_view text;
  int col = 1;
};

std::vector<Field> split_csv(std::string_view line) {
  std::vector<Field> f;
  size_t start = 0;
  for (size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || line[i] == ',') {
      std::string_view t = line.substr(start, i - start);
      int col = static_cast<int>(start) + 1;
      while (!t.empty() && (t.front() == ' ' || t.front() == '\t')) {
        t.remove_prefix(1);
        ++col;
      }
      while (!t.empty() && (t.back() == ' ' || t.back() == '\t' || t.back() == '\r')) {
        t.remove_suffix(1);
      }
      f.push_back({t, col});
      start = i + 1;
    }
  }
  return f;
}

}  // namespace

Plan read_step_file(std::istream& in, const std::string& name, const config::MachineConfig& cfg) {
  Plan plan;
  plan.source = name;
  plan.numerator = {v1_numerator(cfg.clk_hz, cfg.steps_per_mm[0]),
                    v1_numerator(cfg.clk_hz, cfg.steps_per_mm[1])};
  std::string line;
  int n = 0;
  Steps4 pos{};
  auto integer = [&](const Field& f, const char* what) {
    int64_t v = 0;
    auto r = std::from_chars(f.text.data(), f.text.data() + f.text.size(), v);
    if (f.text.empty() || r.ec != std::errc() || r.ptr != f.text.data() + f.text.size()) {
      throw StepFileError(name, n, f.col,
                          fmt::format("{}: expected an integer, got '{}'", what, f.text));
    }
    return v;
  };
  while (std::getline(in, line)) {
    ++n;
    if (n == 1) continue;  // header
    std::string_view sv = line;
    if (sv.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    const auto f = split_csv(sv);
    if (f.size() < 9) {
      throw StepFileError(name, n, 1,
                          fmt::format("expected at least 9 columns, found {}", f.size()));
    }
    integer(f[0], "segment number");
    const int64_t code = integer(f[2], "motion code");
    if (code < 0 || code > 3) {
      throw StepFileError(name, n, f[2].col, fmt::format("motion code {} not in 0..3", code));
    }
    Segment s;
    s.code = static_cast<uint8_t>(code);
    s.steps[0] = integer(f[5], "steps X");
    s.steps[1] = integer(f[6], "steps Y");
    for (int c : {5, 6}) {
      const int64_t v = s.steps[static_cast<size_t>(c - 5)];
      if (v > std::numeric_limits<int32_t>::max() || v < std::numeric_limits<int32_t>::min()) {
        throw StepFileError(name, n, f[static_cast<size_t>(c)].col,
                            "steps do not fit a v1 packet (int32)");
      }
    }
    double feed = 0.0;
    {
      const Field& ff = f[8];
      auto r = std::from_chars(ff.text.data(), ff.text.data() + ff.text.size(), feed);
      if (ff.text.empty() || r.ec != std::errc() || r.ptr != ff.text.data() + ff.text.size() ||
          !std::isfinite(feed) || feed < 0.0 || feed > 65535.49) {
        throw StepFileError(name, n, ff.col,
                            fmt::format("feed: expected a number in 0..65535, got '{}'", ff.text));
      }
    }
    const long long fr = std::llround(feed);
    if (fr < 1) ++plan.stats.feed_clamped;
    s.feed_v1 = static_cast<uint16_t>(std::max<long long>(fr, 1));
    s.feed_mm_min = feed;
    s.source_line = n;
    const double dx = static_cast<double>(s.steps[0]) / cfg.steps_per_mm[0];
    const double dy = static_cast<double>(s.steps[1]) / cfg.steps_per_mm[1];
    s.length_mm = std::hypot(dx, dy);
    for (size_t a = 0; a < 4; ++a) pos[a] += s.steps[a];
    s.target = pos;
    if (const auto v = check_travel_steps(pos, cfg)) {
      throw TravelError(name, n, *v,
                        fmt::format("segment leaves the travel (soft limits, [travel]): {}",
                                    describe(*v, cfg.fourth_axis)));
    }
    ++plan.stats.segments;
    if (s.code == 0) {
      ++plan.stats.rapid_segments;
    } else {
      ++plan.stats.cutting_segments;
    }
    plan.stats.path_length_mm += s.length_mm;
    // v1 timing: the dominant axis moves at feed_v1 mm/min.
    const double dom = std::max(std::fabs(dx), std::fabs(dy));
    plan.stats.estimated_time_s += dom / s.feed_v1 * 60.0;
    plan.items.emplace_back(s);
  }
  if (n == 0) throw StepFileError(name, 1, 1, "empty step file (no header)");
  if (plan.stats.segments == 0) throw StepFileError(name, n, 1, "empty job (no segments)");
  plan.final_steps = pos;
  for (size_t a = 0; a < 4; ++a) {
    plan.final_mm[a] = static_cast<double>(pos[a]) / cfg.steps_per_mm[a];
  }
  return plan;
}

Plan read_step_file(const std::string& path, const config::MachineConfig& cfg) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw StepFileError(path, 0, 0, "cannot open file");
  return read_step_file(f, path, cfg);
}

void write_step_file(std::ostream& out, const Plan& plan, const config::MachineConfig& cfg) {
  out << "segment,line,motion,x_mm,y_mm,steps_x,steps_y,length_mm,feed,feed_mm_min,steps_z,"
         "steps_e\n";
  size_t i = 0;
  for (const auto& item : plan.items) {
    const auto* s = std::get_if<Segment>(&item);
    if (!s) continue;
    out << fmt::format("{},{},{},{:.6f},{:.6f},{},{},{:.6f},{},{:.3f},{},{}\n", i++, s->source_line,
                       s->code, static_cast<double>(s->target[0]) / cfg.steps_per_mm[0],
                       static_cast<double>(s->target[1]) / cfg.steps_per_mm[1], s->steps[0],
                       s->steps[1], s->length_mm, s->feed_v1, s->feed_mm_min, s->steps[2],
                       s->steps[3]);
  }
}

void write_step_file(const std::string& path, const Plan& plan, const config::MachineConfig& cfg) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw StepFileError(path, 0, 0, "cannot create file");
  write_step_file(f, plan, cfg);
  if (!f) throw StepFileError(path, 0, 0, "write error");
}

bool looks_like_step_file(const std::string& path) {
  if (path.size() >= 4) {
    std::string ext = path.substr(path.size() - 4);
    for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".csv") return true;
  }
  std::ifstream f(path, std::ios::binary);
  std::string first;
  if (!f || !std::getline(f, first)) return false;
  // A step-file header: at least 8 commas and no G-code letter followed by a digit.
  size_t commas = 0;
  for (char c : first) commas += c == ',';
  return commas >= 8 && first.find(';') == std::string::npos &&
         first.find('(') == std::string::npos;
}

}  // namespace fpgacnc::plan
