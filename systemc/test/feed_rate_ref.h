// A clock-by-clock reference of the motion rate (docs/timing.md "Feed hold and overrides (the
// motion rate)", the register table read literally), for the tests of the twins that use the
// closed form (feed_rate.h): no pieces, no closed form, one iteration per clock.
#pragma once

#include <cstdint>
#include <vector>

#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins::test {

// One request: the first clock (cycles) with its new value.
struct Req {
  Cycle t;
  int kind;  // 0 MOTION frame, 1 hold input, 2 start input, 3 segment code
  bool hold = false, resume = false;
  uint16_t feed = 0x8000, rapid = 0x8000;
  uint32_t ramp = 1;
  uint8_t code = 0;
  bool cancel = false;  // MOTION CANCEL (kind 0)
};

// The registers clock by clock, as the table defines them: values in clock u (counted from the
// reset release), requests taking effect in the clock they name. CANCEL (rtl/motion/feed_rate.v):
// sets hold and cancel; `flush` is high in a clock with cancel and r = 0 and clears both from the
// next clock (a hold or CANCEL request there sets them again); a resume does not clear the hold
// while cancel was set in the clock before it.
struct Reference {
  std::vector<uint8_t> adv;
  std::vector<uint64_t> r;
  std::vector<uint8_t> hold;
  std::vector<Cycle> flushes;  // clocks (cycles) with flush high
  Reference(const std::vector<Req>& reqs, Cycle phase, uint32_t log2k, uint32_t ramp0, Cycle n) {
    const Cycle k = Cycle{1} << log2k;
    uint64_t rate = uint64_t{1} << 32, acc = 0, cand = uint64_t{1} << 32;
    bool h = false, code0 = true, a = true, c = false, flush = false;
    uint16_t feed = 0x8000, rapid = 0x8000;
    uint32_t ramp = ramp0;
    for (Cycle u = 0; u < n + phase; ++u) {
      bool set = false, clr = false, cset = false;
      for (const Req& q : reqs) {
        if (q.t + phase != u) continue;
        if (q.kind == 0) {
          feed = q.feed;
          rapid = q.rapid;
          ramp = q.ramp;
        }
        if (q.kind == 3) code0 = q.code == 0;
        cset = cset || (q.kind == 0 && q.cancel);
        set = set || (q.kind == 0 && (q.hold || q.cancel)) || q.kind == 1;
        clr = clr || (((q.kind == 0 && q.resume) || q.kind == 2) && !c);
      }
      h = set || (h && !(clr || flush));
      c = cset || (c && !flush);
      flush = c && rate == 0;
      if (u >= phase) {
        adv.push_back(a);
        r.push_back(rate);
        hold.push_back(h);
        if (flush) flushes.push_back(u - phase);
      }
      const uint64_t sum = acc + rate;
      a = sum >= (uint64_t{1} << 32);
      acc = sum & 0xffffffffu;
      const uint64_t tgt = h ? 0 : uint64_t{code0 ? rapid : feed} << 17;
      const uint64_t next_cand = tgt > rate ? (tgt - rate <= ramp ? tgt : rate + ramp)
                                            : (rate - tgt <= ramp ? tgt : rate - ramp);
      if (u % k == k - 1) rate = cand;
      cand = next_cand;
    }
  }
};

}  // namespace fpgacnc::twins::test
