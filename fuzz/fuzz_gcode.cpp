// libFuzzer target: arbitrary bytes as a G-code file through the host interpreter, the planner
// (default machine) and the v1 packer.
//
// Contract checked: parse_string returns a program or throws gcode::Error whose what() is
// "fuzz.gcode:LINE:COL: error: ..." with LINE an existing line (1-based) and COL within it (or
// one past its end); planning and packing a program the interpreter accepted never throws and
// ends at the interpreter's final position (rounded to steps), the segments' steps summing to
// it. Any other exception (uncaught: libFuzzer reports it as a crash), crash, sanitizer report,
// leak or hang is a bug.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"

namespace {

namespace gc = fpgacnc::gcode;
namespace pl = fpgacnc::plan;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_gcode: contract violated: %s\n", what.c_str());
  std::abort();
}

// Lines as std::getline splits them (the last one may be empty and then does not count).
std::vector<std::string_view> split_lines(std::string_view s) {
  std::vector<std::string_view> v;
  size_t a = 0;
  while (a < s.size()) {
    const size_t nl = s.find('\n', a);
    if (nl == std::string_view::npos) {
      v.push_back(s.substr(a));
      break;
    }
    v.push_back(s.substr(a, nl - a));
    a = nl + 1;
  }
  return v;
}

void check_error(const gc::Error& e, std::string_view text) {
  const auto lines = split_lines(text);
  const std::string msg = e.what();
  if (e.file() != "fuzz.gcode") fail("error names file '" + e.file() + "': " + msg);
  if (e.line() < 1) fail("error without a line number: " + msg);
  const size_t n = std::max<size_t>(lines.size(), 1);
  if (static_cast<size_t>(e.line()) > n) fail("error line past the end of the input: " + msg);
  const size_t len = lines.empty() ? 0 : lines[static_cast<size_t>(e.line()) - 1].size();
  if (e.column() < 1 || static_cast<size_t>(e.column()) > len + 1) {
    fail("error column outside its line (length " + std::to_string(len) + "): " + msg);
  }
  const std::string prefix =
      "fuzz.gcode:" + std::to_string(e.line()) + ":" + std::to_string(e.column()) + ": error: ";
  if (msg.rfind(prefix, 0) != 0 || msg.size() == prefix.size()) {
    fail("error text is not 'FILE:LINE:COL: error: MESSAGE': " + msg);
  }
}

// Upper bound of the chords the planner cuts an arc into (its own formula, with margin), so
// that a few long lines of huge arcs do not turn one input into millions of segments.
double chord_estimate(const gc::Move& m, double tol) {
  const double r = std::max(std::hypot(m.start[0] - m.center[0], m.start[1] - m.center[1]),
                            std::hypot(m.end[0] - m.center[0], m.end[1] - m.center[1]));
  double max_angle = 2.0 * std::numbers::pi / 3.0;
  if (tol > 0.0 && tol < r) max_angle = std::min(max_angle, 2.0 * std::acos(1.0 - tol / r));
  return 2.0 * std::numbers::pi / max_angle + 2.0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gc::Program prog;
  try {
    prog = gc::parse_string(text, "fuzz.gcode");
  } catch (const gc::Error& e) {
    check_error(e, text);
    return 0;
  }

  const fpgacnc::config::MachineConfig cfg;
  double budget = 0.0;  // segments
  for (const auto& c : prog.commands) {
    if (const auto* m = std::get_if<gc::Move>(&c)) {
      const bool arc = m->motion == gc::Motion::kArcCw || m->motion == gc::Motion::kArcCcw;
      budget += (arc ? chord_estimate(*m, cfg.arc_tolerance_mm) : 1.0) * 16.0;
    }
  }
  if (budget > 2e5) return 0;  // valid but too expensive to plan here

  pl::Plan plan = pl::plan_program(prog, cfg, pl::PlanOptions{});
  // The planner ends where the interpreter ended, and the segments sum to it.
  gc::Vec4 end{};
  for (const auto& c : prog.commands) {
    if (const auto* m = std::get_if<gc::Move>(&c)) end = m->end;
  }
  pl::Steps4 sum{};
  for (const auto& it : plan.items) {
    if (const auto* s = std::get_if<pl::Segment>(&it)) {
      for (size_t a = 0; a < 4; ++a) {
        sum[a] += s->steps[a];
        if (s->steps[a] > INT32_MAX || s->steps[a] < -INT32_MAX) fail("segment beyond int32");
      }
      if (s->code > 3 || s->feed_v1 < 1) fail("bad segment code or feed");
    }
  }
  for (size_t a = 0; a < 4; ++a) {
    const int64_t want = std::llround(end[a] * cfg.steps_per_mm[a]);
    if (plan.final_steps[a] != want || sum[a] != want) {
      fail("axis " + std::to_string(a) + ": planned final " + std::to_string(plan.final_steps[a]) +
           ", segment sum " + std::to_string(sum[a]) + ", interpreter end " + std::to_string(want));
    }
  }
  const auto job = fpgacnc::protocol::v1::pack_job(plan);
  if (job.motions != plan.stats.segments) fail("packed motions != planned segments");
  return 0;
}
