// Twin of rtl/machine/input_filter.v for the feed hold and cycle-start buttons of cnc_core: the
// clocks in which the filtered level rises (its strobe with q high: feed_rate's hold_req /
// resume_req), from the presses of a button known up front.
//
// The pin level of edge p reaches the first synchronizer flop on p; the sample (second flop) has
// it in the clocks after edge p + 1. q takes a sample that differed from it on F = max(FILTER_CLKS,
// 1) consecutive clocks on the edge after the F-th: a press asserted on edges a .. a + L - 1
// raises q on edge a + 1 + F when L >= F and q was low; q falls again on edge a + L + 1 + F
// unless the next press's sample comes back within F clocks (then q stays high and that press
// raises nothing). The strobe is high in the clock after the edge q rises; feed_rate takes the
// request on the edge after it, so the hold register has it from clock a + 2 + F on.
#pragma once

#include <algorithm>
#include <vector>

#include "fpgacnc/twins/host_schedule.h"

namespace fpgacnc::twins {

// For button b: the first clock of each request its presses make (a + 2 + F), in order.
inline std::vector<Cycle> button_requests(const std::vector<ButtonPress>& presses, int b,
                                          uint32_t filter_clks) {
  const Cycle f = std::max<Cycle>(filter_clks, 1);
  std::vector<Cycle> out;
  bool q = false;
  Cycle end = 0;  // the last edge of the previous press that counted
  for (const ButtonPress& p : presses) {
    if (p.button != b || p.clocks <= 0) continue;
    if (q && p.from - end - 1 >= f) q = false;  // released long enough: q fell before
    if (q) {
      end = std::max(end, p.from + p.clocks - 1);
      continue;
    }
    if (p.clocks >= f) {
      out.push_back(p.from + 2 + f);
      q = true;
      end = p.from + p.clocks - 1;
    }
  }
  return out;
}

}  // namespace fpgacnc::twins
