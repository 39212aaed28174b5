// The hosts as schedules of UART frames on the rx pin, shared by every harness (virtual board,
// RTL runner, co-simulation) so that both models see the same byte stream at the same cycles.
//
// A host hands out packets (a v1 packet or a v2 frame: UART frames back to back,
// SenderTiming::frame() clocks each) and hears the device's bytes on tx. Its decisions depend
// only on the bytes and their start edges, in this order: next_packet() is asked on the edge
// `ready()` (the end of the previous packet) unless waiting(), after every tx byte whose stop
// bit centre (start + the tx bit timer's 9.5 bits) lies before that edge was given to
// on_tx_byte(); a waiting host is asked again right after the byte that ends its wait.
//
// v1 (StopAndWaitHost): packet i's first frame starts `gap` clocks after the host became ready
// (the end of the previous packet's ACK byte on tx, or the end of the previous packet's last
// frame when it expects no ACK, e.g. the init packet).
// v2 (V2StreamHost): docs/protocol.md "Host streaming" as a schedule, see below.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/twins/timing.h"
#include "fpgacnc/twins/v2_frames.h"

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

class Host {
 public:
  virtual ~Host() = default;
  virtual bool done() const = 0;
  virtual bool waiting() const = 0;
  virtual size_t packets_sent() const = 0;
  virtual Cycle ready() const = 0;
  // Frames of the next packet (empty, and waiting() or done(), when there is none now).
  virtual std::vector<HostFrame> next_packet() = 0;
  // A byte on tx, by its start edge.
  virtual void on_tx_byte(Cycle start, uint8_t byte) = 0;
  // Start edges of the answers the host acted on (v1 ACK bytes, v2 device frames).
  std::vector<Cycle> acks;
  uint64_t unexpected = 0;
};

class StopAndWaitHost : public Host {
 public:
  StopAndWaitHost(std::vector<HostPacket> packets, const SenderTiming& sender, int64_t ack_frame)
      : packets_(std::move(packets)), sender_(sender), ack_frame_(ack_frame) {}

  bool done() const override { return next_ >= packets_.size() && !waiting_; }
  bool waiting() const override { return waiting_; }
  size_t packets_sent() const override { return next_; }
  Cycle ready() const override { return ready_; }
  // Frames of the next packet (empty when waiting for an ACK or done).
  std::vector<HostFrame> next_packet() override {
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
  void on_tx_byte(Cycle start, uint8_t byte) override {
    if (waiting_ && byte == 0xAA) {
      waiting_ = false;
      ready_ = start + ack_frame_;
      acks.push_back(start);
    } else {
      ++unexpected;
    }
  }

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

// A v2 session as a schedule (docs/protocol.md "Host streaming"):
//   HELLO, then wait for IDENT (next_seq, FIFO depth);
//   the sequenced frames in order (SEQ from IDENT's next_seq), each `gap` clocks after the host
//   is ready, while credit = free - (FIFO frames sent, not acknowledged) > 0 for FIFO frames
//   and fewer than 127 frames are unacknowledged; a NAK of any reason goes back to its
//   next_seq (go-back-N); ACK, DONE and NAK carry next_seq and free slots;
//   when every frame is acknowledged and `segments done` counts every FIFO frame (with a MOTION
//   CANCEL among the side frames, which drops frames: when every frame is acknowledged; then
//   the STATUS_QUERY is repeated kRequeryGap clocks after each STATUS that says busy):
//   STATUS_QUERY (wait for STATUS), then RELEASE (wait for its ACK).
// A frame with `corrupt` is sent once with a wrong CRC (the device NAKs BAD_CRC); `pre` bytes go
// out once before it. `side` frames (unsequenced, e.g. MOTION: SEQ 0, no credit needed) go out
// once before it, each `gap` clocks after the host is ready, without waiting for their answers
// (a STATUS is kept in `statuses`; the device answers requests pending together with one STATUS),
// before its `pre` bytes: a feed hold and its resume sent one after the other never wait for
// credit that the hold keeps from coming.
// Waiting for answers, the host acts on each complete device frame: it is ready again at the
// end of that frame's last byte on tx. No retransmission timer: the models never lose bytes.
struct V2Side {
  uint8_t type;
  std::vector<uint8_t> payload;
  int64_t gap = 1;
};
struct V2Item {
  uint8_t type;
  std::vector<uint8_t> payload;
  int64_t gap = 1;
  bool corrupt = false;
  // Bytes sent once, as a packet of their own, before the frame's first transmission (line
  // noise, a frame cut short), and the gap from their end to the frame.
  std::vector<uint8_t> pre{};
  int64_t pre_gap = 1;
  std::vector<V2Side> side{};
  bool fifo() const {
    return type == v2::kLine || type == v2::kLineProfile || type == v2::kArc ||
           type == v2::kDwell || type == v2::kNumerators || type == v2::kOutput;
  }
};
struct V2Script {
  std::vector<V2Item> items;  // sequenced frames
  int64_t hello_gap = 1;
  bool status_at_end = true;
  bool ignore_credit = false;  // send while fewer than 127 are unacknowledged (FIFO_FULL NAKs)
};

class V2StreamHost : public Host {
 public:
  V2StreamHost(V2Script script, const SenderTiming& sender, int64_t byte_frame)
      : s_(std::move(script)), sender_(sender), byte_frame_(byte_frame) {
    V2Item rel{v2::kRelease, {}, 1, false};
    s_.items.push_back(rel);
    for (const V2Item& i : s_.items) fifo_total_ += i.fifo() ? 1 : 0;
    corrupted_.assign(s_.items.size(), false);
    pre_done_.assign(s_.items.size(), false);
    side_done_.assign(s_.items.size(), 0);
    for (const V2Item& i : s_.items) {
      has_side_ = has_side_ || !i.side.empty();
      for (const V2Side& f : i.side)
        if (f.type == spec::kTypeMotion && !f.payload.empty() &&
            (f.payload[0] & spec::kMotionCancel) != 0)
          has_cancel_ = true;
    }
  }

  bool done() const override { return phase_ == Phase::Done; }
  bool waiting() const override { return waiting_; }
  size_t packets_sent() const override { return sent_; }
  Cycle ready() const override { return ready_; }

  std::vector<HostFrame> next_packet() override {
    if (waiting_ || phase_ == Phase::Done) return {};
    switch (phase_) {
      case Phase::Start:
        phase_ = Phase::Hello;
        return send(v2::frame(0, v2::kHello), s_.hello_gap, true);
      case Phase::Stream:
        if (next_ < s_.items.size() && side_done_[next_] < s_.items[next_].side.size()) {
          const V2Side& f = s_.items[next_].side[side_done_[next_]++];
          return send(v2::frame(0, f.type, f.payload), f.gap, false);
        }
        if (can_send()) return send_item();
        if (acked_ + 1 == s_.items.size() && (done_ == fifo_total_ || has_cancel_)) {
          if (s_.status_at_end) {
            phase_ = Phase::Status;
            auto q = send(v2::frame(0, v2::kStatusQuery), 1, true);
            query_last_ = ready_ - sender_.frame();
            return q;
          }
          phase_ = Phase::Release;
          return send_item();
        }
        break;
      case Phase::Status:
        if (requery_) {  // (after a CANCEL) the board still busy: ask again
          requery_ = false;
          auto q = send(v2::frame(0, v2::kStatusQuery), kRequeryGap, true);
          query_last_ = ready_ - sender_.frame();
          return q;
        }
        break;
      case Phase::Release:
        if (can_send()) return send_item();
        break;
      default:
        break;
    }
    waiting_ = true;
    return {};
  }

  void on_tx_byte(Cycle start, uint8_t byte) override {
    if (!frame_start_) frame_start_ = start;
    const auto f = parser_.feed(byte);
    if (parser_.bad + parser_.noise != bad_seen_) {
      bad_seen_ = parser_.bad + parser_.noise;
      ++unexpected;
      frame_start_.reset();
    }
    if (!f) return;
    const Cycle first = *frame_start_;
    acks.push_back(first);
    frame_start_.reset();
    handle(*f, first);
    if (waiting_) {
      waiting_ = false;
      ready_ = start + byte_frame_;
    }
  }

  // Figures for the report.
  uint64_t naks = 0, retransmitted = 0, dones = 0;
  std::vector<v2::DeviceFrame> statuses;
  uint32_t device_done() const { return done_; }

 private:
  enum class Phase { Start, Hello, Stream, Status, Release, Done };

  uint8_t seq_of(size_t i) const { return static_cast<uint8_t>(base_seq_ + i); }
  bool can_send() const {
    if (next_ >= s_.items.size()) return false;
    if (phase_ == Phase::Stream && next_ + 1 == s_.items.size()) return false;  // RELEASE last
    if (next_ - acked_ >= 127) return false;
    if (!s_.items[next_].fifo() || s_.ignore_credit) return true;
    uint32_t in_flight = 0;
    for (size_t i = acked_; i < next_; ++i) in_flight += s_.items[i].fifo() ? 1 : 0;
    return free_ > in_flight;
  }
  std::vector<HostFrame> send(std::vector<uint8_t> bytes, int64_t gap, bool wait_after) {
    std::vector<HostFrame> f;
    Cycle t = ready_ + gap;
    for (uint8_t b : bytes) {
      f.push_back(HostFrame{t, b});
      t += sender_.frame();
    }
    ready_ = t;
    ++sent_;
    waiting_ = wait_after;
    return f;
  }
  std::vector<HostFrame> send_item() {
    const V2Item& it = s_.items[next_];
    int64_t gap = it.gap;
    if (!it.pre.empty() && !pre_done_[next_]) {
      pre_done_[next_] = true;
      after_pre_ = true;
      return send(it.pre, gap, false);
    }
    if (after_pre_) gap = it.pre_gap;
    after_pre_ = false;
    auto bytes = v2::frame(seq_of(next_), it.type, it.payload);
    if (it.corrupt && !corrupted_[next_]) {
      corrupted_[next_] = true;
      bytes.back() ^= 0x5A;
    }
    if (next_ < sent_hi_) ++retransmitted;
    ++next_;
    sent_hi_ = std::max(sent_hi_, next_);
    return send(std::move(bytes), gap, false);
  }
  // Cumulative acknowledgement: next_seq names the first frame not accepted.
  void credit(uint8_t next_seq, uint16_t free) {
    const size_t d = static_cast<uint8_t>(next_seq - seq_of(acked_));
    if (d <= sent_hi_ - acked_) acked_ += d;
    free_ = free;
    if (next_ < acked_) next_ = acked_;
  }
  // f: a device frame whose first byte started on edge `start`.
  void handle(const v2::DeviceFrame& f, Cycle start) {
    if (f.type == v2::kIdent && phase_ == Phase::Hello && f.payload.size() == 18) {
      base_seq_ = f.u8(16);
      free_ = f.u16(2);
      phase_ = Phase::Stream;
    } else if ((f.type == v2::kAck || f.type == v2::kDone) && f.payload.size() == 7) {
      if (f.type == v2::kDone) ++dones;
      credit(f.u8(0), f.u16(1));
      done_ = f.u32(3);

      if (phase_ == Phase::Release && acked_ == s_.items.size()) phase_ = Phase::Done;
    } else if (f.type == v2::kNak && f.payload.size() == 5) {
      ++naks;
      credit(f.u8(2), f.u16(3));
      next_ = acked_;
    } else if (f.type == v2::kStatus && phase_ == Phase::Status && start > query_last_) {
      statuses.push_back(f);
      if (has_cancel_ && !f.payload.empty() && (f.u8(0) & spec::kStateBusy) != 0 &&
          ++requeries_ < kMaxRequeries)
        requery_ = true;
      else
        phase_ = Phase::Release;
    } else if (f.type == v2::kStatus && has_side_) {  // a side frame's answer (or several's)
      statuses.push_back(f);
    } else {
      ++unexpected;
    }
  }

  V2Script s_;
  SenderTiming sender_;
  int64_t byte_frame_;
  Phase phase_ = Phase::Start;
  bool waiting_ = false;
  Cycle ready_ = 0;
  size_t sent_ = 0;
  uint8_t base_seq_ = 0;
  size_t next_ = 0, acked_ = 0, sent_hi_ = 0;
  uint32_t free_ = 0, done_ = 0, fifo_total_ = 0;
  std::vector<bool> corrupted_, pre_done_;
  std::vector<size_t> side_done_;  // side frames sent per item
  bool has_side_ = false;          // the script has side frames
  bool has_cancel_ = false;        // a MOTION CANCEL among them (frames dropped: no DONE)
  bool requery_ = false;           // the final STATUS said busy: another STATUS_QUERY
  uint32_t requeries_ = 0;
  static constexpr int64_t kRequeryGap = 5000;
  static constexpr uint32_t kMaxRequeries = 10'000;
  // The start edge of the final STATUS_QUERY's last byte: a STATUS starting by then answers side
  // frames (one decided later answers every request pending then, the query's too).
  Cycle query_last_ = 0;
  bool after_pre_ = false;
  v2::FrameParser parser_;
  uint64_t bad_seen_ = 0;
  std::optional<Cycle> frame_start_;
};

// A job packed by the host's v2 packer as a session: CONFIG_AXIS for every axis, then its FIFO
// frames (NUMERATORS, LINE, DWELL; at most `max_frames` LINE/DWELL), back to back.
inline V2Script job_script(const protocol::v2::Job& job, size_t max_frames = SIZE_MAX) {
  V2Script s;
  for (const auto& f : job.config) s.items.push_back(V2Item{f.type, f.payload, 1, false});
  size_t motion = 0;
  for (const auto& jf : job.frames) {
    const bool numerators = jf.frame.type == v2::kNumerators;
    if (!numerators && motion++ >= max_frames) break;
    s.items.push_back(V2Item{jf.frame.type, jf.frame.payload, 1, false});
  }
  return s;
}

// How a job is driven: v1 stop-and-wait packets or a v2 session.
// A press of the feed hold (button 0) or cycle-start (button 1) input of cnc_core: asserted on
// the edges from..from + clocks - 1 (the harness's input for those edges), released after it. The
// input filter passes it when it lasts longer than its filter length.
struct ButtonPress {
  int button;
  Cycle from;
  Cycle clocks;
};
struct HostScript {
  std::vector<HostPacket> v1;
  std::optional<V2Script> v2;
  std::vector<ButtonPress> buttons{};  // in time order, per button not overlapping
};
inline std::unique_ptr<Host> make_host(const HostScript& s, const SenderTiming& sender,
                                       int64_t byte_frame) {
  if (s.v2) return std::make_unique<V2StreamHost>(*s.v2, sender, byte_frame);
  return std::make_unique<StopAndWaitHost>(s.v1, sender, byte_frame);
}

}  // namespace fpgacnc::twins
