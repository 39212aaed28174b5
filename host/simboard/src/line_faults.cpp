#include "fpgacnc/simboard/line_faults.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace fpgacnc::simboard {
namespace {

constexpr uint8_t kSync = 0xA5;
constexpr uint32_t kMaxPayload = 64;

// splitmix64 finaliser: derives independent stream seeds from the user's seed.
uint64_t mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

void check_p(double p, const char* what) {
  if (!(p >= 0.0 && p <= 1.0)) {
    throw std::invalid_argument(
        fmt::format("line faults: {} = {} is not a probability in [0, 1]", what, p));
  }
}

}  // namespace

void LineFaults::validate() const {
  check_p(ber_to_board, "BER to board");
  check_p(ber_to_host, "BER to host");
  check_p(drop, "drop");
  check_p(dup, "dup");
  check_p(lose_frames, "lose-frames");
  for (const auto& s : stalls) {
    if (s.clocks == 0) throw std::invalid_argument("line faults: a stall of 0 clocks");
  }
}

std::string LineFaults::describe() const {
  if (!any()) return "none";
  std::string s = fmt::format("seed {}", seed);
  if (ber_to_board > 0) s += fmt::format(", BER to board {:g}", ber_to_board);
  if (ber_to_host > 0) s += fmt::format(", BER to host {:g}", ber_to_host);
  if (drop > 0) s += fmt::format(", drop {:g}", drop);
  if (dup > 0) s += fmt::format(", dup {:g}", dup);
  if (lose_frames > 0) s += fmt::format(", lose device frames {:g}", lose_frames);
  for (const auto& st : stalls) {
    s += fmt::format(", stall {} {} for {} clocks",
                     st.trigger == LineStall::Trigger::kCycle ? "at cycle" : "after byte", st.at,
                     st.clocks);
  }
  return s;
}

std::string describe(const LineFaultStats& s) {
  return fmt::format(
      "dropped {}, duplicated {}, rx frames corrupted {} ({} bits), device frames lost {}/{} "
      "({} bytes), tx bytes corrupted {} ({} bits), stalls {} ({} clocks)",
      s.bytes_dropped, s.bytes_duplicated, s.frames_flipped_to_board, s.bits_flipped_to_board,
      s.device_frames_lost, s.device_frames, s.device_bytes_lost, s.bytes_flipped_to_host,
      s.bits_flipped_to_host, s.stalls, s.stall_clocks);
}

uint64_t LineFaultInjector::Rng::next() {
  s_ += 0x9E3779B97F4A7C15ull;
  return mix(s_);
}

bool LineFaultInjector::Rng::chance(double p) {
  if (p <= 0.0) return false;
  if (p >= 1.0) return true;
  return static_cast<double>(next() >> 11) * 0x1p-53 < p;
}

LineFaultInjector::LineFaultInjector(const LineFaults& faults)
    : f_(faults),
      r_drop_(mix(faults.seed ^ 0x01)),
      r_dup_(mix(faults.seed ^ 0x02)),
      r_ber_board_(mix(faults.seed ^ 0x03)),
      r_ber_host_(mix(faults.seed ^ 0x04)),
      r_lose_(mix(faults.seed ^ 0x05)),
      stall_done_(faults.stalls.size(), false) {
  f_.validate();
}

void LineFaultInjector::to_board(uint8_t byte, std::vector<LineFrame>& out) {
  ++st_.bytes_to_board;
  if (r_drop_.chance(f_.drop)) {
    ++st_.bytes_dropped;
    return;
  }
  const int copies = r_dup_.chance(f_.dup) ? 2 : 1;
  if (copies == 2) ++st_.bytes_duplicated;
  for (int c = 0; c < copies; ++c) {
    LineFrame fr{byte, 0, c == 1};
    if (f_.ber_to_board > 0) {
      for (int b = 0; b < 10; ++b) {
        if (r_ber_board_.chance(f_.ber_to_board)) fr.flip |= static_cast<uint16_t>(1u << b);
      }
      if (fr.flip) {
        ++st_.frames_flipped_to_board;
        st_.bits_flipped_to_board += static_cast<uint64_t>(std::popcount(fr.flip));
      }
    }
    out.push_back(fr);
  }
}

void LineFaultInjector::to_host(uint8_t byte, uint64_t cycle, std::vector<uint8_t>& out) {
  ++st_.bytes_from_board;
  // Device frame boundaries from the bytes as sent.
  bool first = false;
  switch (tx_state_) {
    case TxState::kIdle:
      first = true;
      if (byte == kSync) tx_state_ = TxState::kLen;
      break;
    case TxState::kLen:
      if (byte > kMaxPayload) {
        tx_state_ = TxState::kIdle;
      } else {
        tx_remaining_ = 4 + byte;  // SEQ, TYPE, payload, CRC (2)
        tx_state_ = TxState::kBody;
      }
      break;
    case TxState::kBody:
      if (--tx_remaining_ == 0) tx_state_ = TxState::kIdle;
      break;
  }
  if (first) {
    ++st_.device_frames;
    tx_losing_ = r_lose_.chance(f_.lose_frames);
    if (tx_losing_) ++st_.device_frames_lost;
  }
  TxByteRecord rec{cycle, byte, byte, tx_losing_};
  if (tx_losing_) {
    ++st_.device_bytes_lost;
  } else {
    uint8_t flip = 0;
    if (f_.ber_to_host > 0) {
      for (int b = 0; b < 8; ++b) {
        if (r_ber_host_.chance(f_.ber_to_host)) flip |= static_cast<uint8_t>(1u << b);
      }
      if (flip) {
        ++st_.bytes_flipped_to_host;
        st_.bits_flipped_to_host += static_cast<uint64_t>(std::popcount(flip));
      }
    }
    rec.delivered = static_cast<uint8_t>(byte ^ flip);
    out.push_back(rec.delivered);
  }
  if (f_.log) tx_log_.push_back(rec);
}

uint64_t LineFaultInjector::hold_before_frame(uint64_t cycle, uint64_t frame_index) {
  uint64_t hold = 0;
  for (size_t i = 0; i < f_.stalls.size(); ++i) {
    if (stall_done_[i]) continue;
    const LineStall& s = f_.stalls[i];
    if (s.trigger == LineStall::Trigger::kBytes) {
      if (frame_index >= s.at) {
        stall_done_[i] = true;
        if (frame_index == s.at) hold = std::max(hold, s.clocks);
      }
    } else if (cycle >= s.at) {
      stall_done_[i] = true;
      if (cycle - s.at < s.clocks) hold = std::max(hold, s.at + s.clocks - cycle);
    }
  }
  if (hold) {
    ++st_.stalls;
    st_.stall_clocks += hold;
  }
  return hold;
}

void LineFaultInjector::frame_started(const LineFrame& frame, uint64_t cycle, uint64_t held) {
  ++st_.frames_to_board;
  if (f_.log) rx_log_.push_back(RxFrameRecord{cycle, held, frame});
}

}  // namespace fpgacnc::simboard
