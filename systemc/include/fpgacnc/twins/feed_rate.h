// Twin of rtl/motion/feed_rate.v: the motion rate r, its phase accumulator and the executor's
// enable `adv` (docs/timing.md "Feed hold and overrides (the motion rate)").
//
// Registers, with u = t + phase the clock counted from the reset release (p(u) = u mod K,
// K = 2^period_log2): after rst r = 2^32, acc = 0, adv = 1; acc(u+1) = (acc(u) + r(u)) mod
// 2^32; adv(u+1) = carry of acc(u) + r(u); cand(u+1) = r(u) moved toward target(u) by at most
// ramp(u); at the edge ending a period (p(u) = K - 1) r takes cand(u): the step formed from the
// target and ramp of the clock before the period's last one (a change in the last clock counts
// from the next period). target = 0 while hold, else rapid * 2^17 when the segment last accepted
// by the executor has code 0, else feed * 2^17.
//
// Requests (each names the first clock with its new value): motion() (an accepted MOTION frame,
// on edge L + 2 of its last byte), hold_input() / start_input() (the filtered inputs' rising
// levels), segment_code() (the executor accepted a segment: its code from the accept edge on),
// flush() (the clock after the flush clock of a CANCEL). A HOLD and a RESUME in one clock: HOLD
// wins. CANCEL: a hold that also sets `cancel`; while cancel is set a resume (frame or input)
// does not end the hold; a flush clears hold and cancel (a hold or a CANCEL in the same clock
// sets them again). The flush clock itself, the first clock with cancel and r = 0
// (first_stop()), is the caller's to find and hand back with flush().
//
// The twin keeps the rate as pieces of constant r: one per period while r ramps, one per steady
// stretch (until the next request that changes the target), so its cost grows with the ramp
// periods and the requests, never with the clocks. Piece i (clocks s .. e - 1, rate rho, acc(s) =
// a) owns the adv of clocks s + 1 .. e: clocks s + 1 .. s + n hold floor((a + n * rho) / 2^32)
// of them. A request at clock c changes r from the first period boundary b >= c + 2 on: pieces
// computed past it are dropped and computed again when asked for. Asking about a clock later
// than the earliest clock a later request can change makes that answer provisional: the twin
// counts requests that arrive after such an answer (late()); exact users send every request
// before they ask about the clocks it can reach.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "fpgacnc/spec.h"
#include "fpgacnc/twins/timing.h"

namespace fpgacnc::twins {

class FeedRate {
 public:
  static constexpr uint64_t kOne = uint64_t{1} << 32;  // r = 2^32: 100 %
  static constexpr Cycle kNever = std::numeric_limits<Cycle>::max();

  // `phase`: clocks from the reset release (p = 0, acc = 0, r = 2^32, adv = 1) to cycle 0;
  // `period_log2` RATE_PERIOD_LOG2; `ramp` RATE_RAMP (the ramp after rst).
  explicit FeedRate(Cycle phase = 0, uint32_t period_log2 = spec::kDefaultRatePeriodLog2,
                    uint32_t ramp = spec::kDefaultRateRamp)
      : phase_(phase), k_(Cycle{1} << period_log2), ramp0_(ramp) {
    reset();
  }
  void reset() {
    events_.clear();
    hold_events_.clear();
    pieces_.clear();
    Regs r;
    r.ramp = ramp0_;
    pieces_.push_back(Piece{0, kOne, 0, 1, 0, r, -1, Regs{}, kNoScan});
    queried_ = -1;
    late_ = 0;
  }
  void set_phase(Cycle phase) {
    phase_ = phase;
    reset();
  }
  Cycle phase() const { return phase_; }

  // ---- requests (clock t: the first clock with the new value) ----
  void motion(Cycle t, bool hold, bool resume, uint16_t feed, uint16_t rapid, uint32_t ramp,
              bool cancel = false) {
    add(Event{t + phase_,
              cancel   ? kCancel
              : hold   ? kHold
              : resume ? kResume
                       : uint8_t{0},
              true, feed, rapid, ramp, false});
  }
  // The flush of a CANCEL in clock t - 1: hold and cancel clear from clock t.
  void flush(Cycle t) { add(Event{t + phase_, kFlush, false, 0, 0, 0, false}); }
  void hold_input(Cycle t) { add(Event{t + phase_, kHold, false, 0, 0, 0, false}); }
  void start_input(Cycle t) { add(Event{t + phase_, kResume, false, 0, 0, 0, false}); }
  void segment_code(Cycle t, uint8_t code) {
    add(Event{t + phase_, kCode, false, 0, 0, 0, code == 0});
  }
  // Requests that arrived after an answer about a clock they could change (see above).
  uint64_t late() const { return late_; }
  // No request is ever sent: r = 2^32, every clock has adv high (the fast path of the users).
  bool trivial() const { return events_.empty(); }

  // ---- answers ----
  // adv in clock t (cycles).
  bool adv(Cycle t) { return ticks_in(t, t) == 1; }
  // The number of clocks with adv high in clocks a .. b (cycles, inclusive).
  uint64_t ticks_in(Cycle a, Cycle b) {
    if (b < a) return 0;
    return through(b + phase_) - through(a - 1 + phase_);
  }
  // The clock of the k-th clock with adv high at or after clock t0 (k >= 1); kNever when the rate
  // stays 0 before it.
  Cycle tick_clock(Cycle t0, uint64_t k) {
    if (trivial()) return t0 + static_cast<Cycle>(k) - 1;
    const uint64_t m = through(t0 - 1 + phase_) + k;
    const Cycle u = inverse(m);
    return u == kNever ? kNever : u - phase_;
  }
  // The edge of tick j of a run started on edge R (docs/timing.md: the j-th clock with adv high
  // from the clock after R, "edge R + j" the edge after it); j = 0 is R itself.
  Cycle tick_edge(Cycle r, uint64_t j) {
    if (j == 0) return r;
    const Cycle c = tick_clock(r, j);
    return c == kNever ? kNever : c + 1;
  }
  // r in clock t.
  uint64_t rate(Cycle t) {
    const Piece& p = piece_at(t + phase_);
    note(t + phase_);
    return p.rho;
  }
  // The hold register in clock t.
  bool hold(Cycle t) const {
    Regs r;
    size_t i = 0;
    apply_group(r, hold_events_, i, t + phase_);
    return r.hold;
  }
  // The first clock in t .. t + horizon - 1 with r = 0 (kNever: none). Its cost is that of the
  // pieces up to it: one per ramp period.
  Cycle first_stop(Cycle t, Cycle horizon = Cycle{1} << 40) {
    const auto s = stopped(t, t + horizon);
    return s.empty() ? kNever : std::max(s.front().first, t);
  }
  // The spans [a, b) of clocks with r = 0 that overlap clocks from .. to - 1 (b = kNever: for
  // good), in order.
  std::vector<std::pair<Cycle, Cycle>> stopped(Cycle from, Cycle to) {
    std::vector<std::pair<Cycle, Cycle>> out;
    if (trivial() || to <= from) return out;
    const Cycle uf = from + phase_, ut = to + phase_;
    size_t i = index_at(uf);
    note(ut - 1);
    for (;; ++i) {
      const Piece& p = pieces_[i];
      if (p.start >= ut) break;
      const Cycle e = end_of(i);
      if (p.rho == 0 && e > uf) {
        const Cycle a = std::max(p.start, uf) - phase_, b = e == kNever ? kNever : e - phase_;
        if (!out.empty() && out.back().second == a)
          out.back().second = b;
        else
          out.emplace_back(a, b);
      }
      if (e == kNever || e >= ut) break;
      next_piece(i);
    }
    return out;
  }
  size_t pieces() const { return pieces_.size(); }

 private:
  static constexpr uint8_t kHold = 1, kResume = 2, kCode = 3, kCancel = 4, kFlush = 5;
  struct Event {
    Cycle clock;   // u
    uint8_t kind;  // 0, kHold, kResume, kCancel (a MOTION frame may carry one), kCode, kFlush
    bool frame;    // a MOTION frame: sets feed, rapid, ramp
    uint16_t feed, rapid;
    uint32_t ramp;
    bool code0;
  };
  struct Regs {
    bool hold = false;
    bool cancel = false;
    uint16_t feed = 0x8000, rapid = 0x8000;
    uint32_t ramp = 0;
    bool code0 = true;  // the code register after rst is 0 (rapid)
    uint64_t target() const { return hold ? 0 : uint64_t{code0 ? rapid : feed} << 17; }
  };
  struct Piece {
    Cycle start;   // u of its first clock
    uint64_t rho;  // r in its clocks
    uint32_t acc;  // acc in its first clock
    uint64_t cnt;  // clocks with adv high in u = 0 .. start
    size_t ev;     // events with clock <= start - 2 (applied to regs)
    Regs regs;     // registers in clock start - 2 (those its r was formed from)
    Cycle end;     // u of the next piece's first clock; -1 unknown yet; kNever: for good
    // A steady last piece: the registers after every event so far (their count in scan_ev;
    // kNoScan: none), so that a request appended later continues the scan from there.
    Regs scan{};
    size_t scan_ev = kNoScan;
  };
  static constexpr size_t kNoScan = std::numeric_limits<size_t>::max();

  void add(const Event& e) {
    if (e.clock < 0) throw std::invalid_argument("feed_rate twin: a request before the reset");
    // A request at u changes r from boundary(u), adv from the clock after it.
    const Cycle reach = boundary(e.clock) + 1;
    if (queried_ > reach) ++late_;
    auto later = [](Cycle c, const Event& x) { return c < x.clock; };
    auto it = std::upper_bound(events_.begin(), events_.end(), e.clock, later);
    const bool appended = it == events_.end();
    events_.insert(it, e);
    if (e.kind == kHold || e.kind == kResume || e.kind == kCancel || e.kind == kFlush)
      hold_events_.insert(
          std::upper_bound(hold_events_.begin(), hold_events_.end(), e.clock, later), e);
    // Pieces starting after the request are computed again; the one holding it gets a new end
    // (a steady one continues its scan when the request comes after every other).
    bool popped = false;
    while (pieces_.size() > 1 && pieces_.back().start > e.clock) {
      pieces_.pop_back();
      popped = true;
    }
    Piece& last = pieces_.back();
    if (!appended || popped) last.scan_ev = kNoScan;
    last.end = -1;
  }
  static void apply_group(Regs& r, const std::vector<Event>& ev, size_t& i, Cycle upto) {
    while (i < ev.size() && ev[i].clock <= upto) {
      const Cycle c = ev[i].clock;
      bool set = false, clr = false, cancel = false, flush = false;
      for (; i < ev.size() && ev[i].clock == c; ++i) {
        const Event& e = ev[i];
        if (e.frame) {
          r.feed = e.feed;
          r.rapid = e.rapid;
          r.ramp = e.ramp;
        }
        if (e.kind == kCode) r.code0 = e.code0;
        set = set || e.kind == kHold || e.kind == kCancel;
        cancel = cancel || e.kind == kCancel;
        flush = flush || e.kind == kFlush;
        clr = clr || (e.kind == kResume && !r.cancel);  // cancel in the clock of the request
      }
      r.hold = set || (r.hold && !(clr || flush));
      r.cancel = cancel || (r.cancel && !flush);
    }
  }
  // The first period boundary b (r's first clock of a period) whose r a change of the target or
  // ramp in clock u reaches: cand(b - 1) is formed in clock b - 2, so b >= u + 2.
  Cycle boundary(Cycle u) const { return ((u + 1) / k_ + 1) * k_; }
  // The end of piece i (computed when unknown).
  Cycle end_of(size_t i) {
    Piece& p = pieces_[i];
    if (p.end >= 0) return p.end;
    Regs r = p.regs;
    size_t ev = p.ev;
    Cycle b = (p.start / k_ + 1) * k_;  // the first boundary after its first clock
    bool resume = false;
    if (p.scan_ev != kNoScan) {  // steady through every event before scan_ev
      r = p.scan;
      ev = p.scan_ev;
      resume = true;
    }
    for (;;) {
      if (!resume) {
        apply_group(r, events_, ev, b - 2);
        if (r.target() != p.rho) break;
      }
      resume = false;
      if (ev == events_.size()) {
        b = kNever;
        p.scan = r;
        p.scan_ev = ev;
        break;
      }
      b = boundary(events_[ev].clock);
    }
    p.end = b;
    return b;
  }
  // Appends piece i + 1 when i is the last one (its end must be finite).
  void next_piece(size_t i) {
    if (i + 1 < pieces_.size()) return;
    const Cycle e = end_of(i);
    if (e == kNever) throw std::logic_error("feed_rate twin: no piece after a final one");
    const Piece& p = pieces_[i];
    Regs r = p.regs;
    size_t ev = p.ev;
    apply_group(r, events_, ev, e - 2);
    const uint64_t tgt = r.target();
    uint64_t rho = p.rho;
    if (tgt > rho)
      rho = tgt - rho <= r.ramp ? tgt : rho + r.ramp;
    else
      rho = rho - tgt <= r.ramp ? tgt : rho - r.ramp;
    const unsigned __int128 sum =
        static_cast<unsigned __int128>(p.acc) + static_cast<unsigned __int128>(e - p.start) * p.rho;
    pieces_.push_back(Piece{e, rho, static_cast<uint32_t>(sum & 0xffffffffu),
                            p.cnt + static_cast<uint64_t>(sum >> 32), ev, r, -1, Regs{}, kNoScan});
  }
  // The index of the piece holding clock u (u >= 0), computing pieces up to it.
  size_t index_at(Cycle u) {
    if (u < 0) u = 0;
    for (;;) {
      const size_t last = pieces_.size() - 1;
      if (pieces_[last].start <= u) {
        const Cycle e = end_of(last);
        if (e == kNever || u < e) break;
        next_piece(last);
        continue;
      }
      break;
    }
    const auto it = std::upper_bound(pieces_.begin(), pieces_.end(), u,
                                     [](Cycle c, const Piece& p) { return c < p.start; });
    return static_cast<size_t>(it - pieces_.begin()) - 1;
  }
  const Piece& piece_at(Cycle u) { return pieces_[index_at(u)]; }
  void note(Cycle u) { queried_ = std::max(queried_, u); }
  // Clocks with adv high in u = 0 .. u (0 for u < 0).
  uint64_t through(Cycle u) {
    if (u < 0) return 0;
    note(u);
    const Piece& p = piece_at(u);
    const unsigned __int128 sum =
        static_cast<unsigned __int128>(p.acc) + static_cast<unsigned __int128>(u - p.start) * p.rho;
    return p.cnt + static_cast<uint64_t>(sum >> 32);
  }
  // The first clock u with through(u) >= m (m >= 1).
  Cycle inverse(uint64_t m) {
    if (m <= pieces_[0].cnt) return 0;
    // the piece i with cnt_i < m <= count through its end
    size_t i =
        static_cast<size_t>(std::lower_bound(pieces_.begin(), pieces_.end(), m,
                                             [](const Piece& p, uint64_t v) { return p.cnt < v; }) -
                            pieces_.begin());
    i = i == 0 ? 0 : i - 1;
    for (;;) {
      const Cycle e = end_of(i);
      if (e == kNever) break;
      next_piece(i);
      if (pieces_[i + 1].cnt >= m) break;
      ++i;
    }
    const Piece& p = pieces_[i];
    if (p.rho == 0) return kNever;
    const unsigned __int128 need = (static_cast<unsigned __int128>(m - p.cnt) << 32) - p.acc;
    const auto n = static_cast<Cycle>((need + p.rho - 1) / p.rho);
    note(p.start + n);
    return p.start + n;
  }

  Cycle phase_;
  Cycle k_;
  uint32_t ramp0_;
  std::vector<Event> events_;  // in clock order
  // The events that set or clear hold and cancel (hold(): a segment's code does not), in order.
  std::vector<Event> hold_events_;
  std::vector<Piece> pieces_;
  Cycle queried_ = -1;  // the latest clock an answer depended on
  uint64_t late_ = 0;
};

}  // namespace fpgacnc::twins
