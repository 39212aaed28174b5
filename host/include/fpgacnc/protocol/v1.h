// Protocol v1 packer (byte-exact with docs/protocol.md, "v1"): big-endian fields.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "fpgacnc/plan/planner.h"
#include "fpgacnc/spec.h"

namespace fpgacnc::protocol::v1 {

inline constexpr uint8_t kInitByte = spec::kV1InitByte;
inline constexpr uint8_t kAck = spec::kV1Ack;
inline constexpr size_t kInitSize = spec::kV1InitSize;
inline constexpr size_t kMotionSize = spec::kV1MotionSize;

std::array<uint8_t, kInitSize> pack_init(uint32_t numerator_x, uint32_t numerator_y);
std::array<uint8_t, kMotionSize> pack_motion(uint8_t code, int32_t steps_x, int32_t steps_y,
                                             uint16_t feed);

// One v1 transaction of a job: a motion packet, or a host-side dwell between packets.
struct Step {
  bool is_dwell = false;
  std::array<uint8_t, kMotionSize> packet{};
  double dwell_s = 0.0;
  size_t segment_index = 0;  // index of the segment among the plan's segments
  int source_line = 0;
};

struct Job {
  std::array<uint8_t, kInitSize> init{};
  std::vector<Step> steps;
  size_t motions = 0;
  size_t skipped_heater = 0;  // heater commands v1 cannot carry
  size_t ze_only = 0;         // Z/E-only segments sent as 0,0 steps
};

// Packs (and validates) the whole plan. Throws std::invalid_argument on a segment v1 cannot
// carry (code > 3, |steps| > INT32_MAX: the planner splits those, a hand-made plan may not).
Job pack_job(const plan::Plan& plan);
// The job as the byte stream a v1 host writes: init then every motion packet.
std::vector<uint8_t> job_bytes(const plan::Plan& plan);

}  // namespace fpgacnc::protocol::v1
