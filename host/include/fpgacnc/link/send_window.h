// The go-back-N send window of protocol v2 (docs/protocol.md, "Host streaming"): which sequenced
// frames may go out, the round-trip estimate and retransmission timeout, and the AIMD window.
// Pure bookkeeping over frame indices 0, 1, 2, ... of a session (frame i carries SEQ seq0 + i
// modulo 256) and link time (link.h); it sends and reads nothing (V2Session does).
//
//  - The caller sends frame sent() while may_send(limit) and records it with mark_sent().
//  - acknowledge(next_seq) takes a cumulative ACK/DONE/NAK/STATUS next_seq: frames below it are
//    acknowledged; a next_seq behind the window or ahead of anything ever sent is stale.
//  - go_back() (a NAK) sends again from the oldest unacknowledged frame; NAKs while the device is
//    still at that point (stale_nak()) are about copies sent before it and are ignored.
//  - timer_expired(): the oldest unacknowledged frame waited longer than rto() since the later of
//    the last progress and its (last) sending; on_timeout() goes back, then only that frame is
//    sent (probing) until something is acknowledged, and the timeout doubles (up to 8x).
//  - rto() is at least the configured minimum and above the measured frame -> ACK time (RFC 6298
//    estimator, Karn's rule: only frames sent once are measured).
//  - Window (as TCP congestion control): full on a clean line; halved at each go-back, grown by
//    one frame per acknowledged frame below ssthresh, by 1/cwnd above it.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "fpgacnc/link/link.h"

namespace fpgacnc::link {

class SendWindow {
 public:
  using Time = Link::Time;
  struct Options {
    std::chrono::milliseconds min_rto{300};  // retransmission timeout floor
    size_t max_unacked = 127;                // largest window
  };
  SendWindow(Options options, uint8_t seq0, Time now);

  uint8_t seq_of(size_t index) const { return static_cast<uint8_t>(seq0_ + index); }
  size_t acked() const { return acked_; }  // frames [0, acked) acknowledged
  size_t sent() const { return sent_; }    // next frame to send
  size_t high() const { return high_; }    // frames [0, high) sent at least once
  bool probing() const { return probing_; }
  size_t window() const { return static_cast<size_t>(cwnd_); }

  // Whether frame sent() may go out now, with frames [0, limit) available.
  bool may_send(size_t limit) const;
  // Records the sending of frame sent() at `now`; returns true when it is a retransmission.
  bool mark_sent(Time now);
  // A cumulative next_seq from the device: frames newly acknowledged (possibly 0), or nullopt
  // when stale (behind the window or ahead of anything sent).
  std::optional<size_t> acknowledge(uint8_t next_seq, Time now);
  // A NAK about a copy sent before the last go-back (the device is still where we went back to).
  bool stale_nak() const { return goback_at_ && acked_ == *goback_at_; }
  // Goes back to the oldest unacknowledged frame. Returns how many times in a row the window went
  // back to this same frame without progress.
  size_t go_back(Time now);
  bool timer_expired(Time now) const;
  // Retransmission timeout: go back, probe with the oldest frame, double the timeout.
  size_t on_timeout(Time now);
  // Restarts the progress timer (an operator pause, a credit wait that was ours).
  void touch(Time now) { last_progress_ = now; }
  Time last_progress() const { return last_progress_; }

  std::chrono::milliseconds rto() const { return rto_; }
  // Figures.
  double srtt_s() const { return srtt_; }
  double max_rto_s() const { return max_rto_s_; }
  size_t min_window() const { return min_window_; }
  size_t go_backs() const { return go_backs_; }
  size_t timeouts() const { return timeouts_; }
  size_t retransmissions() const { return retransmissions_; }

 private:
  std::chrono::milliseconds base_rto() const;
  Options opt_;
  uint8_t seq0_;
  size_t acked_ = 0, sent_ = 0, high_ = 0;
  std::vector<Time> sent_at_;
  std::vector<uint16_t> sends_;
  std::optional<size_t> goback_at_;
  size_t goback_same_ = 0;
  bool probing_ = false;
  double cwnd_, ssthresh_, max_window_;
  double srtt_ = 0.0, rttvar_ = 0.0;
  bool have_rtt_ = false;
  std::chrono::milliseconds rto_;
  Time last_progress_;
  double max_rto_s_ = 0.0;
  size_t min_window_;
  size_t go_backs_ = 0, timeouts_ = 0, retransmissions_ = 0;
};

}  // namespace fpgacnc::link
