#include "fpgacnc/twins/compare.h"

#include <fmt/format.h>

namespace fpgacnc::twins {

namespace {

std::string edge_text(const models::Edge& e) {
  return fmt::format("cycle {} {} -> {}", e.cycle, models::signal_name(e.signal), e.value);
}

std::string compare_cycles(const char* what, const std::vector<Cycle>& rtl,
                           const std::vector<Cycle>& twin) {
  const size_t n = std::min(rtl.size(), twin.size());
  for (size_t i = 0; i < n; ++i) {
    if (rtl[i] != twin[i])
      return fmt::format("{} #{}: rtl at cycle {}, twin at cycle {}", what, i, rtl[i], twin[i]);
  }
  if (rtl.size() != twin.size()) {
    const bool more_rtl = rtl.size() > twin.size();
    return fmt::format("{}: rtl has {}, twin {}; first extra in {} at cycle {}", what, rtl.size(),
                       twin.size(), more_rtl ? "rtl" : "twin", more_rtl ? rtl[n] : twin[n]);
  }
  return "";
}

}  // namespace

std::string compare_runs(const RunResult& rtl, const RunResult& twin) {
  if (rtl.error != twin.error)
    return fmt::format("host error: rtl '{}', twin '{}'", rtl.error, twin.error);
  const size_t n = std::min(rtl.edges.size(), twin.edges.size());
  for (size_t i = 0; i < n; ++i) {
    const auto& a = rtl.edges[i];
    const auto& b = twin.edges[i];
    if (a.cycle != b.cycle || a.signal != b.signal || a.value != b.value)
      return fmt::format("edge #{}: rtl {}, twin {}", i, edge_text(a), edge_text(b));
  }
  if (rtl.edges.size() != twin.edges.size()) {
    const bool more_rtl = rtl.edges.size() > twin.edges.size();
    return fmt::format("edges: rtl has {}, twin {}; first extra in {}: {}", rtl.edges.size(),
                       twin.edges.size(), more_rtl ? "rtl" : "twin",
                       edge_text(more_rtl ? rtl.edges[n] : twin.edges[n]));
  }
  for (auto s : {compare_cycles("ACK", rtl.acks, twin.acks),
                 compare_cycles("decoder packet_done", rtl.packet_done, twin.packet_done),
                 compare_cycles("segment_executor seg_start", rtl.seg_start, twin.seg_start),
                 compare_cycles("segment_executor seg_done", rtl.seg_done, twin.seg_done),
                 compare_cycles("segment_executor seg_done_v2", rtl.seg_done_v2, twin.seg_done_v2),
                 compare_cycles("segment_executor arc_err", rtl.arc_err, twin.arc_err)}) {
    if (!s.empty()) return s;
  }
  if (rtl.position != twin.position)
    return fmt::format("position: rtl X {} Y {}, twin X {} Y {}", rtl.position[0], rtl.position[1],
                       twin.position[0], twin.position[1]);
  if (rtl.timeouts != twin.timeouts || rtl.overruns != twin.overruns ||
      rtl.frame_errors != twin.frame_errors || rtl.violations != twin.violations)
    return fmt::format(
        "counters (timeouts, overruns, frame errors, violations): rtl {} {} {} {}, twin {} {} {} "
        "{}",
        rtl.timeouts, rtl.overruns, rtl.frame_errors, rtl.violations, twin.timeouts, twin.overruns,
        twin.frame_errors, twin.violations);
  if (rtl.zero_gap != twin.zero_gap)
    return fmt::format("segments started with zero idle clocks: rtl {}, twin {}", rtl.zero_gap,
                       twin.zero_gap);
  if (rtl.error.empty() && rtl.end_cycle != twin.end_cycle)
    return fmt::format("job duration: rtl {} clocks, twin {}", rtl.end_cycle, twin.end_cycle);
  return "";
}

}  // namespace fpgacnc::twins
