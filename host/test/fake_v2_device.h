// In-process fake protocol-v2 device for the streamer tests: a link::Link that implements the
// device rules of docs/protocol.md at frame level (no UART, no RTL):
//  - decoder: hunts for 0xA5; LEN > 64 -> NAK BAD_LENGTH at once; CRC -> NAK BAD_CRC; type,
//    length and field checks -> NAK; after an error the hunt restarts at the byte after the one
//    that ended the bad frame; a frame cut short for `watchdog` (wall time) -> NAK TIMEOUT;
//  - SEQ rules: = next_seq accepted (FIFO frames only with a free slot, else NAK FIFO_FULL),
//    next_seq - 1 .. - 128 re-ACKed and not executed, otherwise NAK OUT_OF_ORDER;
//  - answers are not queued: one pending flag per kind (IDENT > STATUS > NAK > ACK > DONE), the
//    frame is filled in from the live state when the host starts reading it;
//  - a FIFO of `fifo_depth` entries executed one every `exec_period` of wall time (NUMERATORS at
//    once), `segments done` counted per entry; every executed entry is recorded.
// Faults (seeded): bit flips / drops / duplicates on host bytes, lost / corrupted / duplicated
// device frames, and a line stall (host bytes held back for a while, the device keeps running).
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "fpgacnc/link/link.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::test {

namespace v2 = protocol::v2;

struct FakeFaults {
  uint64_t seed = 1;
  double host_bit_flip = 0.0;      // per host byte: one random bit flipped
  double host_drop = 0.0;          // per host byte: lost
  double host_dup = 0.0;           // per host byte: received twice
  double answer_lose = 0.0;        // per device frame: lost entirely
  double answer_corrupt = 0.0;     // per device frame: one random bit flipped
  double answer_dup = 0.0;         // per device frame: sent twice
  uint64_t stall_after_bytes = 0;  // 0: no stall; else hold host bytes once this many arrived
  std::chrono::milliseconds stall{0};
};

struct FakeStats {
  uint64_t flipped = 0, dropped = 0, duplicated = 0;
  uint64_t answers_lost = 0, answers_corrupted = 0, answers_duplicated = 0;
  uint64_t stalls = 0;
  uint64_t frames_ok = 0, crc_errors = 0, length_errors = 0, timeouts = 0, noise = 0;
  uint64_t naks = 0, duplicates_acked = 0, out_of_order = 0, fifo_full = 0;
  uint64_t hellos = 0, status_queries = 0, releases = 0;
  size_t max_fifo_level = 0;
};

class FakeV2Device : public link::Link {
 public:
  struct Options {
    uint8_t n_axes = 4;
    uint16_t fifo_depth = 16;
    std::chrono::microseconds exec_period{200};
    std::chrono::milliseconds watchdog{100};
    uint8_t initial_next_seq = 0;
    uint32_t initial_done = 0;
    bool answer_hello = true;  // false: a v2 device that never answers (or a dead line)
    bool send_done = true;     // false: DONE frames are never sent (ACK and STATUS still are)
    std::chrono::microseconds line_delay{0};  // host bytes reach the decoder this much later
    FakeFaults faults;
    // Heaters: STATUS carries the heater block; each enabled channel's temperature
    // approaches its setpoint exponentially with `heater_tau` of wall time (from `ambient_c`).
    bool heaters = false;
    std::chrono::microseconds heater_tau{50'000};
    double ambient_c = 20.0;
    // Latch fault bits `inject_fault` on channel `inject_channel` once it has been enabled for
    // `inject_after` (0 bits: never).
    uint8_t inject_fault = 0;
    uint8_t inject_channel = 1;
    std::chrono::microseconds inject_after{0};
    // Frame types this device does not know (a device built without them): NAK UNKNOWN_TYPE.
    std::vector<uint8_t> unknown_types;
  };
  // A sequenced non-FIFO heater frame as accepted, with the device state at that moment.
  struct HeaterEvent {
    v2::Frame frame;
    size_t fifo_accepted = 0;  // FIFO frames accepted before it
    uint32_t done = 0;
    size_t fifo_level = 0;
    std::array<double, 2> temp{};
  };
  struct FifoEvent {  // every accepted FIFO frame, with the heater temperatures then
    size_t index = 0;
    std::array<double, 2> temp{};
    size_t fifo_level = 0;
  };

  explicit FakeV2Device(Options o) : o_(o), rng_(o.faults.seed) {
    next_seq_ = o.initial_next_seq;
    done_ = o.initial_done;
    position_.assign(o.n_axes, 0);
    temp_ = {o.ambient_c, o.ambient_c};
    last_in_ = clock::now();
  }

  // ---- Link ----
  void write(std::span<const uint8_t> bytes) override {
    advance();
    for (const uint8_t b0 : bytes) {
      ++host_bytes_;
      written_.push_back(b0);
      if (o_.faults.stall_after_bytes && !stall_done_ &&
          host_bytes_ >= o_.faults.stall_after_bytes) {
        stall_done_ = true;
        stall_until_ = clock::now() + o_.faults.stall;
        ++st_.stalls;
      }
      if (chance(o_.faults.host_drop)) {
        ++st_.dropped;
        continue;
      }
      uint8_t b = b0;
      if (chance(o_.faults.host_bit_flip)) {
        b ^= static_cast<uint8_t>(1u << (rng_() % 8));
        ++st_.flipped;
      }
      const auto ready = clock::now() + o_.line_delay;
      inbox_.push_back({b, ready});
      if (chance(o_.faults.host_dup)) {
        inbox_.push_back({b, ready});
        ++st_.duplicated;
      }
    }
    advance();
  }

  std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) override {
    const auto deadline = clock::now() + timeout;
    for (;;) {
      advance();
      if (out_.empty()) start_answer();
      if (!out_.empty()) {
        const uint8_t b = out_.front();
        out_.pop_front();
        return b;
      }
      if (clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }

  void flush_input() override {
    advance();
    out_.clear();
  }
  std::string name() const override { return "fake-v2"; }

  // ---- inspection ----
  const std::vector<v2::Frame>& executed() const { return executed_; }
  const std::vector<v2::ConfigAxis>& configs() const { return configs_; }
  const std::vector<v2::Motion>& motions() const { return motions_; }  // MOTION frames taken
  // TRIGGER and SET_POSITION: the trigger's state as TRIGGER_REPORT gives it (armed by a HOME or
  // PROBE, nothing ever fires here) and the positions set.
  const v2::TriggerReport& trigger() const { return trigger_; }
  size_t set_positions() const { return set_positions_; }
  bool held() const { return hold_; }
  size_t cancelled() const { return cancelled_; }
  size_t fifo_level() const { return fifo_.size(); }
  const std::vector<uint8_t>& written() const { return written_; }
  const FakeStats& stats() const { return st_; }
  bool v2_mode() const { return v2_mode_; }
  uint8_t next_seq() const { return next_seq_; }
  uint32_t done() const { return done_; }
  const std::vector<int32_t>& position() const { return position_; }
  const std::vector<HeaterEvent>& heater_events() const { return heater_events_; }
  const std::vector<FifoEvent>& fifo_events() const { return fifo_events_; }
  double heater_temp(size_t c) const { return temp_[c]; }

 private:
  using clock = std::chrono::steady_clock;

  bool chance(double p) {
    return p > 0.0 && std::uniform_real_distribution<double>(0, 1)(rng_) < p;
  }

  uint16_t free_slots() const { return static_cast<uint16_t>(o_.fifo_depth - fifo_.size()); }

  void advance_heaters(clock::time_point now) {
    const double dt = std::chrono::duration<double>(now - heat_last_).count();
    heat_last_ = now;
    if (!o_.heaters) return;
    const double tau = std::chrono::duration<double>(o_.heater_tau).count();
    for (size_t c = 0; c < 2; ++c) {
      const double target = enabled_[c] ? setpoint_[c] : o_.ambient_c;
      temp_[c] += (target - temp_[c]) * std::min(1.0, dt / tau);
      if (enabled_[c] && o_.inject_fault && c == o_.inject_channel &&
          now - enabled_at_[c] >= o_.inject_after) {
        heater_faults_[c] |= o_.inject_fault;
        enabled_[c] = false;
      }
    }
  }
  void heater_frame(const v2::Frame& f) {
    heater_events_.push_back({f, fifo_accepted_, done_, fifo_.size(), temp_});
    if (f.type == static_cast<uint8_t>(v2::Type::HeaterSetpoint)) {
      const auto [c, q] = v2::decode_heater_setpoint(f);
      setpoint_[c] = q / 16.0;
      const bool on = q > 0 && !heater_faults_[c];
      if (on && !enabled_[c]) enabled_at_[c] = clock::now();
      enabled_[c] = on;
    }
  }

  void advance() {
    const auto now = clock::now();
    advance_heaters(now);
    // Feed hold (MOTION HOLD): the running entry is frozen (its end moves with the time held),
    // nothing starts until MOTION RESUME.
    if (hold_ && running_) run_end_ += now - last_advance_;
    last_advance_ = now;
    // Execution.
    while (!hold_ && !fifo_.empty()) {
      if (!running_) {
        running_ = true;
        run_end_ = now + (fifo_.front().type == static_cast<uint8_t>(v2::Type::Numerators)
                              ? clock::duration::zero()
                              : clock::duration(o_.exec_period));
      }
      if (now < run_end_) break;
      complete(fifo_.front());
      fifo_.pop_front();
      running_ = false;
      if (!fifo_.empty()) {
        // The next entry starts where the last one ended (zero gap).
        running_ = true;
        run_end_ = run_end_ + (fifo_.front().type == static_cast<uint8_t>(v2::Type::Numerators)
                                   ? clock::duration::zero()
                                   : clock::duration(o_.exec_period));
      }
    }
    // Line: bytes reach the decoder unless stalled.
    if (stall_done_ && now < stall_until_) return;
    if (!inbox_.empty() && inbox_.front().second <= now) {
      last_in_ = now;
      while (!inbox_.empty() && inbox_.front().second <= now) {
        const uint8_t b = inbox_.front().first;
        inbox_.pop_front();
        rx(b);
      }
    } else if (inbox_.empty() && in_frame_ && now - last_in_ > o_.watchdog) {
      ++st_.timeouts;
      nak(frame_seq_, v2::NakReason::Timeout);
      in_frame_ = false;
    }
  }

  void complete(const v2::Frame& f) {
    executed_.push_back(f);
    if (f.type == static_cast<uint8_t>(v2::Type::Line)) {
      const auto l = v2::decode_line(f, o_.n_axes);
      for (size_t a = 0; a < l.steps.size(); ++a) position_[a] += l.steps[a];
    } else if (f.type == static_cast<uint8_t>(v2::Type::LineProfile)) {
      const auto l = v2::decode_line_profile(f, o_.n_axes);
      for (size_t a = 0; a < l.steps.size(); ++a) position_[a] += l.steps[a];
    } else if (f.type == static_cast<uint8_t>(v2::Type::Arc)) {
      const auto a = v2::decode_arc(f);
      position_[0] += a.dx;
      position_[1] += a.dy;
      position_[2] += a.dz;
    }
    ++done_;
    pend_done_ = o_.send_done;
  }

  // Decoder: one byte.
  void rx(uint8_t b) {
    if (!in_frame_) {
      if (b == v2::kSync) {
        in_frame_ = true;
        hdr_.clear();
      } else {
        ++st_.noise;
      }
      return;
    }
    hdr_.push_back(b);
    if (hdr_.size() == 1 && b > v2::kMaxPayload) {
      ++st_.length_errors;
      nak(0, v2::NakReason::BadLength);
      in_frame_ = false;
      return;
    }
    if (hdr_.size() == 2) frame_seq_ = b;
    if (hdr_.size() < 3 + static_cast<size_t>(hdr_[0]) + 2) return;
    in_frame_ = false;
    const size_t len = hdr_[0];
    const uint16_t want = v2::crc16(std::span<const uint8_t>(hdr_.data(), 3 + len));
    const uint16_t got = static_cast<uint16_t>((hdr_[3 + len] << 8) | hdr_[4 + len]);
    if (want != got) {
      ++st_.crc_errors;
      nak(hdr_[1], v2::NakReason::BadCrc);
      return;
    }
    v2::Frame f;
    f.seq = hdr_[1];
    f.type = hdr_[2];
    f.payload.assign(hdr_.begin() + 3, hdr_.begin() + 3 + static_cast<std::ptrdiff_t>(len));
    handle(f);
  }

  void handle(const v2::Frame& f) {
    v2_mode_ = true;
    if (const auto r = v2::check_host_frame(f, o_.n_axes)) {
      if (*r == v2::NakReason::BadLength) ++st_.length_errors;
      nak(f.seq, *r);
      return;
    }
    if (std::find(o_.unknown_types.begin(), o_.unknown_types.end(), f.type) !=
        o_.unknown_types.end()) {
      nak(f.seq, v2::NakReason::UnknownType);
      return;
    }
    ++st_.frames_ok;
    const auto type = static_cast<v2::Type>(f.type);
    if (type == v2::Type::Hello) {
      ++st_.hellos;
      if (o_.answer_hello) pend_ident_ = true;
      return;
    }
    if (type == v2::Type::StatusQuery) {
      ++st_.status_queries;
      pend_status_ = true;
      return;
    }
    if (type == v2::Type::TriggerQuery) {
      pend_trigger_ = true;
      return;
    }
    if (type == v2::Type::Motion) {  // unsequenced, answered with STATUS
      const v2::Motion m = v2::decode_motion(f);
      motions_.push_back(m);
      if (m.hold) hold_ = true;
      if (m.resume) hold_ = false;
      if (m.cancel) {  // a hold (at rest at once here), the queue dropped without DONE, hold ends
        cancelled_ += fifo_.size();
        fifo_.clear();
        running_ = false;
        hold_ = false;
      }
      pend_status_ = true;
      return;
    }
    const uint8_t behind = static_cast<uint8_t>(next_seq_ - f.seq);
    if (f.seq != next_seq_) {
      if (behind >= 1 && behind <= 128) {
        ++st_.duplicates_acked;
        pend_ack_ = true;
      } else {
        ++st_.out_of_order;
        nak(f.seq, v2::NakReason::OutOfOrder);
      }
      return;
    }
    if (v2::is_fifo(f.type)) {
      if (fifo_.size() >= o_.fifo_depth) {
        ++st_.fifo_full;
        nak(f.seq, v2::NakReason::FifoFull);
        return;
      }
      fifo_.push_back(f);
      fifo_events_.push_back({fifo_accepted_++, temp_, fifo_.size()});
      st_.max_fifo_level = std::max(st_.max_fifo_level, fifo_.size());
    } else if (type == v2::Type::ConfigAxis) {
      configs_.push_back(v2::decode_config_axis(f, o_.n_axes));
    } else if (type == v2::Type::Trigger) {
      const auto [mode, mask] = v2::decode_trigger(f, o_.n_axes);
      if (mode != v2::TriggerMode::Disarm) {  // arming clears what was latched
        trigger_.fired = 0;
        trigger_.latched.assign(o_.n_axes, 0);
      }
      trigger_.mode = mode;
      trigger_.flags = mode == v2::TriggerMode::Disarm ? 0 : v2::kTriggerArmed;
    } else if (type == v2::Type::SetPosition) {
      if (!fifo_.empty() || running_) {  // only while the motion is idle
        nak(f.seq, v2::NakReason::Busy);
        return;
      }
      const auto [mask, pos] = v2::decode_set_position(f, o_.n_axes);
      for (size_t a = 0; a < pos.size() && a < position_.size(); ++a)
        if ((mask >> a) & 1u) position_[a] = pos[a];
      ++set_positions_;
    } else if (f.type >= 0x20 && f.type <= 0x24) {
      heater_frame(f);
    } else if (type == v2::Type::FaultClear) {
      heater_faults_ = {};
    } else if (type == v2::Type::Release) {
      ++st_.releases;
      v2_mode_ = false;
    }
    ++next_seq_;
    pend_ack_ = true;
  }

  void nak(uint8_t seq, v2::NakReason r) {
    ++st_.naks;
    pend_nak_ = true;
    nak_seq_ = seq;
    nak_reason_ = r;
  }

  void start_answer() {
    v2::Frame f;
    if (pend_ident_) {
      pend_ident_ = false;
      f = v2::ident(dev_seq_, v2::Ident{v2::kVersion, o_.n_axes, o_.fifo_depth, spec::kDefaultClkHz,
                                        spec::kDefaultBaud, spec::kBuildId, next_seq_,
                                        static_cast<uint8_t>(v2::kMaxPayload)});
    } else if (pend_status_) {
      pend_status_ = false;
      v2::Status s;
      // A hold stops at once here: HOLD and STOPPED together.
      s.state = static_cast<uint8_t>((fifo_.empty() ? 0 : v2::kStateBusy) |
                                     (v2_mode_ ? v2::kStateV2 : 0) |
                                     (hold_ ? v2::kStateHold | v2::kStateStopped : 0));
      s.fifo_level = static_cast<uint16_t>(fifo_.size());
      s.next_seq = next_seq_;
      s.done = done_;
      s.position = position_;
      s.counters[v2::kFramesOk] = static_cast<uint16_t>(st_.frames_ok);
      s.counters[v2::kCrcErrors] = static_cast<uint16_t>(st_.crc_errors);
      s.counters[v2::kLengthErrors] = static_cast<uint16_t>(st_.length_errors);
      s.counters[v2::kTimeouts] = static_cast<uint16_t>(st_.timeouts);
      s.counters[v2::kNoiseBytes] = static_cast<uint16_t>(st_.noise);
      if (o_.heaters) {
        for (size_t c = 0; c < 2; ++c) {
          v2::HeaterStatus h;
          h.temp_q4 = static_cast<int16_t>(std::lround(temp_[c] * 16.0));
          h.setpoint_q4 = static_cast<int16_t>(std::lround(setpoint_[c] * 16.0));
          h.duty_q15 = enabled_[c] && temp_[c] < setpoint_[c] ? 0x4000 : 0;
          h.mode = static_cast<uint8_t>(4 | (enabled_[c] ? 0x80 : 0));
          h.faults = heater_faults_[c];
          if (heater_faults_[c]) s.faults |= c == 0 ? v2::kFaultHotend : v2::kFaultBed;
          s.heaters.push_back(h);
        }
      }
      f = v2::status(dev_seq_, s);
    } else if (pend_trigger_) {
      pend_trigger_ = false;
      v2::TriggerReport r = trigger_;
      r.latched.resize(o_.n_axes);
      f = v2::trigger_report(dev_seq_, r);
    } else if (pend_nak_) {
      pend_nak_ = false;
      f = v2::nak(dev_seq_, v2::Nak{nak_seq_, nak_reason_, next_seq_, free_slots()});
    } else if (pend_ack_ || pend_done_) {
      const bool is_ack = pend_ack_;
      pend_ack_ = pend_done_ = false;  // an ACK also stands for a pending DONE
      const v2::Credit c{next_seq_, free_slots(), done_};
      f = is_ack ? v2::ack(dev_seq_, c) : v2::done(dev_seq_, c);
    } else {
      return;
    }
    ++dev_seq_;
    auto bytes = v2::encode(f);
    if (chance(o_.faults.answer_lose)) {
      ++st_.answers_lost;
      return;
    }
    if (chance(o_.faults.answer_corrupt)) {
      bytes[rng_() % bytes.size()] ^= static_cast<uint8_t>(1u << (rng_() % 8));
      ++st_.answers_corrupted;
    }
    out_.insert(out_.end(), bytes.begin(), bytes.end());
    if (chance(o_.faults.answer_dup)) {
      out_.insert(out_.end(), bytes.begin(), bytes.end());
      ++st_.answers_duplicated;
    }
  }

  Options o_;
  std::mt19937_64 rng_;
  FakeStats st_;
  // line
  std::deque<std::pair<uint8_t, clock::time_point>> inbox_;  // byte, when it reaches the decoder
  std::deque<uint8_t> out_;
  std::vector<uint8_t> written_;
  uint64_t host_bytes_ = 0;
  bool stall_done_ = false;
  clock::time_point stall_until_{};
  clock::time_point last_in_{};
  // decoder
  bool in_frame_ = false;
  std::vector<uint8_t> hdr_;  // LEN SEQ TYPE payload CRC
  uint8_t frame_seq_ = 0;
  bool v2_mode_ = false;
  bool hold_ = false;     // MOTION HOLD until MOTION RESUME
  size_t cancelled_ = 0;  // FIFO frames dropped by MOTION CANCEL
  std::vector<v2::Motion> motions_;
  v2::TriggerReport trigger_;
  size_t set_positions_ = 0;
  bool pend_trigger_ = false;
  clock::time_point last_advance_ = clock::now();
  uint8_t next_seq_ = 0;
  // answers
  bool pend_ident_ = false, pend_status_ = false, pend_nak_ = false, pend_ack_ = false,
       pend_done_ = false;
  uint8_t nak_seq_ = 0;
  v2::NakReason nak_reason_ = v2::NakReason::BadCrc;
  uint8_t dev_seq_ = 0;
  // executor
  std::deque<v2::Frame> fifo_;
  bool running_ = false;
  clock::time_point run_end_{};
  uint32_t done_ = 0;
  std::vector<int32_t> position_;
  std::vector<v2::Frame> executed_;
  std::vector<v2::ConfigAxis> configs_;
  // heaters
  clock::time_point heat_last_ = clock::now();
  std::array<double, 2> temp_{20.0, 20.0};
  std::array<double, 2> setpoint_{};
  std::array<bool, 2> enabled_{};
  std::array<clock::time_point, 2> enabled_at_{};
  std::array<uint8_t, 2> heater_faults_{};
  size_t fifo_accepted_ = 0;
  std::vector<HeaterEvent> heater_events_;
  std::vector<FifoEvent> fifo_events_;
};

}  // namespace fpgacnc::test
