#include "fpgacnc/protocol/v1.h"

#include <fmt/format.h>

#include <limits>
#include <stdexcept>

namespace fpgacnc::protocol::v1 {
namespace {

void put_be32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}

}  // namespace

std::array<uint8_t, kInitSize> pack_init(uint32_t numerator_x, uint32_t numerator_y) {
  std::array<uint8_t, kInitSize> b{};
  b[0] = kInitByte;
  put_be32(&b[1], numerator_x);
  put_be32(&b[5], numerator_y);
  return b;
}

std::array<uint8_t, kMotionSize> pack_motion(uint8_t code, int32_t steps_x, int32_t steps_y,
                                             uint16_t feed) {
  std::array<uint8_t, kMotionSize> b{};
  b[0] = code;
  put_be32(&b[1], static_cast<uint32_t>(steps_x));
  put_be32(&b[5], static_cast<uint32_t>(steps_y));
  b[9] = static_cast<uint8_t>(feed >> 8);
  b[10] = static_cast<uint8_t>(feed);
  return b;
}

Job pack_job(const plan::Plan& plan) {
  Job job;
  job.init = pack_init(plan.numerator[0], plan.numerator[1]);
  size_t seg_index = 0;
  constexpr int64_t lo = std::numeric_limits<int32_t>::min();
  constexpr int64_t hi = std::numeric_limits<int32_t>::max();
  for (const auto& item : plan.items) {
    if (const auto* s = std::get_if<plan::Segment>(&item)) {
      if (s->code > 3) {
        throw std::invalid_argument(
            fmt::format("segment {} (line {}): motion code {} not valid in v1", seg_index,
                        s->source_line, s->code));
      }
      if (s->steps[0] < lo || s->steps[0] > hi || s->steps[1] < lo || s->steps[1] > hi) {
        throw std::invalid_argument(
            fmt::format("segment {} (line {}): steps ({}, {}) do not fit a v1 packet", seg_index,
                        s->source_line, s->steps[0], s->steps[1]));
      }
      Step st;
      st.packet = pack_motion(s->code, static_cast<int32_t>(s->steps[0]),
                              static_cast<int32_t>(s->steps[1]), s->feed_v1);
      st.segment_index = seg_index++;
      st.source_line = s->source_line;
      if (s->steps[0] == 0 && s->steps[1] == 0) ++job.ze_only;
      job.steps.push_back(st);
      ++job.motions;
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      Step st;
      st.is_dwell = true;
      st.dwell_s = d->seconds;
      st.segment_index = seg_index;
      st.source_line = d->source_line;
      job.steps.push_back(st);
    } else {
      ++job.skipped_heater;
    }
  }
  return job;
}

std::vector<uint8_t> job_bytes(const plan::Plan& plan) {
  const Job job = pack_job(plan);
  std::vector<uint8_t> out(job.init.begin(), job.init.end());
  out.reserve(kInitSize + job.motions * kMotionSize);
  for (const auto& s : job.steps) {
    if (!s.is_dwell) out.insert(out.end(), s.packet.begin(), s.packet.end());
  }
  return out;
}

}  // namespace fpgacnc::protocol::v1
