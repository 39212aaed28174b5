// The stop-and-wait v1 host as a schedule of UART frames on the rx pin, shared by every
// harness (virtual board, RTL runner, co-simulation) so that both models see the same byte
// stream at the same cycles: packet i's first frame starts `gap` clocks after the host became
// ready (the end of the previous packet's ACK byte on tx, or the end of the previous packet's
// last frame when it expects no ACK, e.g. the init packet); frames of a packet follow back to
// back (SenderTiming::frame() clocks each).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <vector>

#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

struct HostPacket {
  std::vector<uint8_t> bytes;
  bool ack = true;  // the host waits for an ACK after it
  int64_t gap = 1;  // clocks from "ready" to the first start edge
};

struct HostFrame {
  Cycle start;  // first edge that sees the start bit
  uint8_t byte;
};

class StopAndWaitHost {
 public:
  StopAndWaitHost(std::vector<HostPacket> packets, const SenderTiming& sender, int64_t ack_frame)
      : packets_(std::move(packets)), sender_(sender), ack_frame_(ack_frame) {}

  bool done() const { return next_ >= packets_.size() && !waiting_; }
  bool waiting() const { return waiting_; }
  size_t packets_sent() const { return next_; }
  Cycle ready() const { return ready_; }
  // Frames of the next packet (empty when waiting for an ACK or done).
  std::vector<HostFrame> next_packet() {
    std::vector<HostFrame> f;
    if (waiting_ || next_ >= packets_.size()) return f;
    const HostPacket& p = packets_[next_++];
    Cycle t = ready_ + p.gap;
    for (uint8_t b : p.bytes) {
      f.push_back(HostFrame{t, b});
      t += sender_.frame();
    }
    waiting_ = p.ack;
    ready_ = t;
    return f;
  }
  // The start edge of a byte on tx (an ACK when 0xAA and one is awaited).
  void on_tx_byte(Cycle start, uint8_t byte) {
    if (waiting_ && byte == 0xAA) {
      waiting_ = false;
      ready_ = start + ack_frame_;
      acks.push_back(start);
    } else {
      ++unexpected;
    }
  }
  std::vector<Cycle> acks;
  uint64_t unexpected = 0;

 private:
  std::vector<HostPacket> packets_;
  SenderTiming sender_;
  int64_t ack_frame_;
  size_t next_ = 0;
  bool waiting_ = false;
  Cycle ready_ = 0;
};

// A packed job as host packets: init (no ACK), then each motion packet (ACK); a dwell adds its
// time (in clocks) to the gap before the next packet.
inline std::vector<HostPacket> job_packets(const protocol::v1::Job& job, uint64_t clk_hz,
                                           size_t max_moves = SIZE_MAX) {
  std::vector<HostPacket> out;
  out.push_back(HostPacket{{job.init.begin(), job.init.end()}, false, 1});
  int64_t extra = 0;
  size_t moves = 0;
  for (const auto& s : job.steps) {
    if (s.is_dwell) {
      extra += static_cast<int64_t>(s.dwell_s * static_cast<double>(clk_hz) + 0.5);
      continue;
    }
    if (moves++ >= max_moves) break;
    out.push_back(HostPacket{{s.packet.begin(), s.packet.end()}, true, 1 + extra});
    extra = 0;
  }
  return out;
}

}  // namespace fpgacnc::twins
