// A Verilated core bench's v2 requests and answers: the bench (a PinHarness) appends every device
// frame it decodes from its tx pin to `msgs`; these run its clock until the answer comes.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "v2_frames.h"

namespace fpgacnc::tb::v2 {

// Runs the bench until `msgs` grows, at most `limit` clocks; whether it did.
template <typename Bench>
bool wait_msg(Bench& bench, const std::vector<DeviceMsg>& msgs, uint64_t limit) {
  const size_t n = msgs.size();
  for (uint64_t i = 0; i < limit && msgs.size() == n; ++i) bench.tick();
  return msgs.size() > n;
}

// Sends frame `f` and runs the bench until an answer other than DONE arrives (at most `limit`
// clocks); returns it, or an empty message and a test failure naming the frame.
template <typename Bench>
DeviceMsg exchange(Bench& bench, const std::vector<DeviceMsg>& msgs, const std::vector<uint8_t>& f,
                   uint64_t limit) {
  const size_t n0 = msgs.size();
  bench.send(f);
  for (uint64_t i = 0; i < limit; ++i) {
    for (size_t k = n0; k < msgs.size(); ++k)
      if (msgs[k].type != kDone) return msgs[k];
    bench.tick();
  }
  ADD_FAILURE() << "no answer to frame " << hex(f);
  return {};
}

}  // namespace fpgacnc::tb::v2
