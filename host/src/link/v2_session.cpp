#include "fpgacnc/link/v2_session.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace fpgacnc::link {
namespace v2 = protocol::v2;
using clock_type = std::chrono::steady_clock;
using Time = Link::Time;
using std::chrono::milliseconds;

namespace {

// Silence (link time) after which a partial device frame at the head of the parser is given up
// (a LEN corrupted upwards would otherwise hold back the frames behind it).
constexpr milliseconds kPartialGiveUp{200};
// Longest single wait of the receive loop, so that partial frames are given up in time.
constexpr milliseconds kReceiveSlice{20};

std::string frame_name(const v2::Frame& f, const v2::JobFrame* jf, const heat::HeaterAction* ha,
                       int source_line) {
  if (ha) {
    return fmt::format("{} (M{} S{:g}, line {})", v2::type_name(f.type), ha->mcode, ha->target_c,
                       ha->source_line);
  }
  if (jf) {
    return fmt::format("{} of segment {} (line {})", v2::type_name(f.type), jf->segment_index,
                       jf->source_line);
  }
  if (source_line > 0) return fmt::format("{} (line {})", v2::type_name(f.type), source_line);
  return v2::type_name(f.type);
}

}  // namespace

v2::Status query_status(Link& link, FrameIo& io, StreamV2Report& rep, size_t n_axes,
                        const StreamV2Options& opt, const char* when) {
  const Time give_up = link.now() + opt.answer_timeout;
  while (link.now() < give_up) {
    io.send(v2::status_query());
    ++rep.status_polls;
    const auto f = io.await_type(v2::Type::Status, link.now() + opt.retransmit_timeout);
    if (!f) continue;
    try {
      return v2::decode_status(*f, n_axes);
    } catch (const v2::ProtocolError&) {
      ++rep.bad_device_frames;
    }
  }
  throw Error(
      fmt::format("{}: no STATUS {} within {:.3g} s{} (STATUS_QUERY every {} ms)", link.name(),
                  when, static_cast<double>(opt.answer_timeout.count()) / 1000.0,
                  link.board_clock() ? " of board time" : "", opt.retransmit_timeout.count()));
}

// ---- FrameIo ----

FrameIo::FrameIo(Link& link, StreamV2Report& rep)
    : link_(link), rep_(rep), last_rx_(link.now()), last_byte_(last_rx_) {}

void FrameIo::send(const v2::Frame& f) {
  buf_.clear();
  v2::encode_to(f, buf_);
  link_.write(buf_);
  rep_.bytes_written += buf_.size();
  ++rep_.frames_sent;
}

void FrameIo::send_batch(const std::vector<uint8_t>& bytes, size_t frames) {
  if (bytes.empty()) return;
  link_.write(bytes);
  rep_.bytes_written += bytes.size();
  rep_.frames_sent += frames;
}

std::optional<v2::Frame> FrameIo::receive_until(Time deadline) {
  for (;;) {
    if (auto f = parser_.next()) {
      last_rx_ = link_.now();
      if (have_last_ && *f == last_frame_) ++rep_.duplicates;
      last_frame_ = *f;
      have_last_ = true;
      return f;
    }
    // Take what is there without waiting, then wait in slices until the deadline.
    auto b = link_.read_byte_until(Time::zero());
    if (!b) {
      const Time now = link_.now();
      if (now >= deadline) {
        // Silence: a header whose LEN was corrupted upwards would wait forever.
        if (now - last_byte_ > kPartialGiveUp) parser_.abandon_partial();
        return std::nullopt;
      }
      b = link_.read_byte_until(std::min(deadline, now + Time(kReceiveSlice)));
      if (!b) {
        const Time after = link_.now();
        if (after - last_byte_ > kPartialGiveUp && parser_.abandon_partial()) continue;
        if (after >= deadline) return std::nullopt;
        continue;
      }
    }
    ++rep_.bytes_read;
    last_byte_ = link_.now();
    parser_.feed(*b);
  }
}

std::optional<v2::Frame> FrameIo::receive(milliseconds timeout) {
  return receive_until(link_.now() + timeout);
}

std::optional<v2::Frame> FrameIo::await_type(v2::Type type, Time deadline) {
  for (;;) {
    const auto f = receive_until(deadline);
    if (!f) return std::nullopt;
    if (f->type == static_cast<uint8_t>(type)) return f;
  }
}

void FrameIo::finish_counters() {
  rep_.rx_crc_errors = parser_.crc_errors();
  rep_.rx_bad_length = parser_.bad_length();
  rep_.rx_noise_bytes = parser_.noise_bytes();
  rep_.rx_abandoned = parser_.abandoned();
}

// ---- Handshake ----

v2::Ident handshake_v2(Link& link, const StreamV2Options& opt, StreamV2Report& rep,
                       std::optional<v2::Ident> ident) {
  const std::string name = link.name();
  if (!ident) {
    for (int i = 0; i < std::max(opt.hello_attempts, 1) && !ident; ++i) {
      ident = probe_v2(link, opt.hello_timeout, &rep.bytes_written);
      ++rep.frames_sent;
    }
    if (!ident) {
      throw Error(
          fmt::format("{}: no IDENT answer to HELLO: the device does not speak protocol v2", name));
    }
  }
  rep.ident = *ident;
  if (ident->version != v2::kVersion) {
    throw Error(fmt::format("{}: device speaks protocol version {}, this host speaks {}", name,
                            ident->version, v2::kVersion));
  }
  if (ident->fifo_depth == 0)
    throw Error(fmt::format("{}: device reports a FIFO depth of 0", name));
  return *ident;
}

void check_job_fits(const Link& link, const v2::Ident& ident, const v2::Job& job) {
  const std::string name = link.name();
  if (job.max_axes > ident.n_axes) {
    throw Error(fmt::format("{}: the job moves {} axes, the device has {} (N_AXES)", name,
                            job.max_axes, ident.n_axes));
  }
  if (job.clk_hz && ident.clk_hz && job.clk_hz != ident.clk_hz) {
    throw Error(fmt::format(
        "{}: the device runs at {} Hz, the job was planned for clk_hz = {} Hz (segment times "
        "would be wrong: fix clk_hz in the machine configuration)",
        name, ident.clk_hz, job.clk_hz));
  }
  size_t max_payload = 0;
  for (const auto& jf : job.frames) max_payload = std::max(max_payload, jf.frame.payload.size());
  if (max_payload > ident.max_payload) {
    throw Error(fmt::format("{}: the job needs frames of {} payload bytes, the device takes {}",
                            name, max_payload, ident.max_payload));
  }
}

// ---- V2Session ----

V2Session::V2Session(Link& link, const StreamV2Options& opt, const v2::Ident& ident,
                     StreamV2Report& rep)
    : link_(link),
      opt_(opt),
      ident_(ident),
      rep_(rep),
      io_(link, rep),
      name_(link.name()),
      hj_(opt.heaters && opt.heaters->any() ? opt.heaters : nullptr),
      win_({opt.retransmit_timeout, opt.max_unacked}, 0, link.now()) {
  if (hj_ && !hj_->source.empty()) src_ = hj_->source + ":";
}

const v2::Status& V2Session::start() {
  const size_t n_axes = ident_.n_axes;
  v2::Status st = query_status(link_, io_, rep_, n_axes, opt_, "at the start");
  const Time busy_limit = link_.now() + opt_.answer_timeout;
  while (st.state & v2::kStateBusy) {
    if (link_.now() > busy_limit) {
      throw Error(fmt::format("{}: device still busy (FIFO level {}) after {:.3g} s{}", name_,
                              st.fifo_level,
                              static_cast<double>(opt_.answer_timeout.count()) / 1000.0,
                              link_.board_clock() ? " of board time" : ""));
    }
    link_.wait_until(link_.now() + milliseconds(20));
    st = query_status(link_, io_, rep_, n_axes, opt_, "at the start");
  }
  rep_.status_start = st;
  last_status_ = st;
  win_ = SendWindow({opt_.retransmit_timeout, opt_.max_unacked}, st.next_seq, link_.now());
  done0_ = st.done;
  free_slots_ = st.fifo_level >= ident_.fifo_depth ? 0 : ident_.fifo_depth - st.fifo_level;
  link_t0_ = link_.now();
  last_poll_ = last_heater_poll_ = link_t0_;
  rep_.max_rto_s = win_.max_rto_s();
  if (st.faults) {
    push({v2::fault_clear(0), false});
    rep_.faults_cleared = st.faults;
  }
  clear_items_ = items_.size();
  return rep_.status_start;
}

bool V2Session::configure_motion(const v2::Motion& m) {
  const v2::Frame fr = v2::motion(m);
  constexpr int kAttempts = 5;
  // A STATUS may answer an earlier STATUS_QUERY (one resent at the start): a device that refuses
  // MOTION sends its NAK right behind any pending STATUS (NAK ranks below STATUS), so after a
  // STATUS the line is watched a little longer for that NAK.
  const auto settle = std::max(milliseconds(20), opt_.retransmit_timeout / 4);
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    io_.send(fr);
    Time deadline = link_.now() + opt_.retransmit_timeout;
    std::optional<v2::Status> answer;
    bool resend = false;
    while (const auto f = io_.receive_until(deadline)) {
      try {
        if (f->type == static_cast<uint8_t>(v2::Type::Status)) {
          answer = v2::decode_status(*f, ident_.n_axes);
          deadline = std::min(deadline, link_.now() + settle);
          continue;
        }
        if (f->type != static_cast<uint8_t>(v2::Type::Nak)) continue;
        const v2::Nak k = v2::decode_nak(*f);
        ++rep_.naks[static_cast<size_t>(k.reason)];
        if (k.reason == v2::NakReason::UnknownType) {
          if (answer) on_status(*answer);
          return false;
        }
        if (k.reason == v2::NakReason::BadField || k.reason == v2::NakReason::BadLength) {
          throw Error(fmt::format("{}: device refuses MOTION (NAK {}): {}", name_,
                                  v2::nak_reason_name(static_cast<uint8_t>(k.reason)),
                                  v2::hex(v2::encode(fr))));
        }
        resend = true;  // corrupted on the way (BAD_CRC, TIMEOUT): send it again
        break;
      } catch (const v2::ProtocolError&) {
        ++rep_.bad_device_frames;
      }
    }
    if (answer && !resend) {
      motion_ = m;
      on_status(*answer);
      motion_available_ = true;
      return true;
    }
  }
  throw Error(fmt::format("{}: no answer to MOTION after {} attempts ({} ms each)", name_,
                          kAttempts, opt_.retransmit_timeout.count()));
}

void V2Session::send_motion(const v2::Motion& m) {
  motion_ = m;
  motion_pending_ = true;
  motion_sent_ = link_.now();
  io_.send(v2::motion(m));
  asked_status();
  // Its answer is a STATUS: no STATUS_QUERY of ours is needed meanwhile.
  status_outstanding_ = true;
  status_sent_ = motion_sent_;
}

void V2Session::push(SessionItem item) {
  if (was_complete_ && complete()) {
    // Resuming after a quiet spell of our own (the caller had nothing to send).
    io_.restart_silence();
    win_.touch(link_.now());
  }
  was_complete_ = false;
  if (item.heater && item.heater->wait) waits_.push_back(items_.size());
  if (item.fifo) fifo_item_.push_back(items_.size());
  fifo_before_.push_back(fifo_before_.back() + (item.fifo ? 1 : 0));
  items_.push_back(std::move(item));
  rep_.sequenced_frames = items_.size();
}

void V2Session::add_pause(const gcode::Pause* p) {
  pauses_.emplace_back(items_.size(), p);
}
void V2Session::add_message(const gcode::Message* m) {
  messages_.emplace_back(items_.size(), m);
}

bool V2Session::cancel_heater_wait() {
  if (next_wait_ >= waits_.size()) return false;
  cancel_wait_ = true;
  return true;
}

bool V2Session::complete() const {
  return win_.acked() == items_.size() && done_count_ == fifo_before_.back() &&
         next_wait_ == waits_.size() && next_pause_ == pauses_.size();
}

size_t V2Session::gate() const {
  const size_t n = items_.size();
  const size_t h = next_wait_ < waits_.size() ? waits_[next_wait_] + 1 : n;
  return next_pause_ < pauses_.size() ? std::min(h, pauses_[next_pause_].first) : h;
}

std::string V2Session::item_name(size_t i) const {
  const auto& it = items_[i];
  return frame_name(it.frame, it.jf, it.heater, it.source_line);
}

double V2Session::plant_now() const {
  if (opt_.plant_time) return opt_.plant_time();
  return seconds(link_.now() - link_t0_);
}

std::string V2Session::current_line() const {
  if (next_wait_ < waits_.size() && ws_.started) {
    const auto* a = items_[waits_[next_wait_]].heater;
    return fmt::format("{}{} (M{} S{:g}, waiting)", src_, a->source_line, a->mcode, a->target_c);
  }
  if (done_count_ < fifo_item_.size()) {
    const auto& it = items_[fifo_item_[done_count_]];
    std::string l = fmt::format("{}{}", src_, it.jf ? it.jf->source_line : it.source_line);
    if (next_wait_ < waits_.size() && win_.acked() > waits_[next_wait_]) {
      const auto* a = items_[waits_[next_wait_]].heater;
      l += fmt::format(" (M{} S{:g} at line {} waits for it)", a->mcode, a->target_c,
                       a->source_line);
    }
    return l;
  }
  return "the end of the job";
}

bool V2Session::update(uint8_t next_seq, uint16_t free, std::optional<uint32_t> done) {
  const auto delta = win_.acknowledge(next_seq, link_.now());
  if (!delta) {
    ++rep_.stale_answers;
    return false;
  }
  if (*delta > 0) {
    // Acknowledged frames are never sent again: their bytes go (a long line session keeps only
    // the bookkeeping of each frame).
    for (size_t i = win_.acked() - *delta; i < win_.acked(); ++i)
      std::vector<uint8_t>().swap(items_[i].frame.payload);
    rep_.srtt_s = win_.srtt_s();
    rep_.max_rto_s = std::max(rep_.max_rto_s, win_.max_rto_s());
    fatal_nak_count_ = 0;
  }
  free_slots_ = free;
  have_credit_ = true;
  if (done) {
    const size_t d = static_cast<uint32_t>(*done - done0_);
    const size_t total_fifo = fifo_before_.back();
    if (d > done_count_ && d <= total_fifo) {
      done_count_ = d;
      if (opt_.progress) opt_.progress(done_count_, total_fifo);
    }
  }
  return true;
}

void V2Session::go_back() {
  const size_t acked = win_.acked();
  check_stuck(acked, win_.go_back(link_.now()));
  rep_.go_backs = win_.go_backs();
  rep_.min_window = std::min(rep_.min_window, win_.min_window());
}

void V2Session::check_stuck(size_t acked, size_t same) const {
  if (same <= opt_.max_goback_same) return;
  throw Error(fmt::format(
      "{}: {} (seq {}) refused {} times without progress (NAKs: {} BAD_CRC, {} "
      "BAD_LENGTH, {} UNKNOWN_TYPE, {} TIMEOUT, {} OUT_OF_ORDER, {} FIFO_FULL, {} BAD_FIELD, {} "
      "TRAVEL)",
      name_, item_name(acked), win_.seq_of(acked), same, rep_.naks[1], rep_.naks[2], rep_.naks[3],
      rep_.naks[4], rep_.naks[5], rep_.naks[6], rep_.naks[7], rep_.naks[8]));
}

void V2Session::check_faults(const v2::Status& stt) {
  if (aborting_) return;                    // abandoned: the caller pressed the e-stop itself
  if (win_.acked() < clear_items_) return;  // faults of a previous job, FAULT_CLEAR not yet taken
  const uint8_t bad = stt.faults & (v2::kFaultEstop | v2::kFaultWatchdog | v2::kFaultHotend |
                                    v2::kFaultBed | v2::kFaultLimit);
  if (!bad) return;
  const std::string what = heat::describe_faults(stt, bad);
  // A hard limit alone leaves the heaters on (docs/machine.md).
  const bool heaters_off = (bad & ~v2::kFaultLimit) != 0;
  throw Error(
      fmt::format("{}: job stopped at G-code line {}: {} (the device {}latched the fault; "
                  "the next job clears it)",
                  name_, current_line(), what, heaters_off ? "switched the heaters off and " : ""));
}

void V2Session::wait_status(const v2::Status& stt) {
  if (next_wait_ >= waits_.size()) return;
  const size_t w = waits_[next_wait_];
  // Not accepted yet, or the FIFO not drained (a cancelled wait ends once accepted).
  if (win_.acked() <= w || (!cancel_wait_ && done_count_ < fifo_before_[w])) return;
  const auto* a = items_[w].heater;
  if (stt.heaters.size() <= a->channel) {
    throw Error(fmt::format("{}: M{} at line {}{}: the device reports no heaters in STATUS", name_,
                            a->mcode, src_, a->source_line));
  }
  const auto& h = stt.heaters[a->channel];
  const auto& hc = hj_->config.ch[a->channel];
  const double now = plant_now();
  const double temp = h.temp_c();
  bool done = cancel_wait_, skipped = false;
  if (!ws_.started) {
    ws_.started = true;
    ws_.start_plant = now;
    ws_.start_c = temp;
    ws_.start_wall = clock_type::now();
    // S waits only when heating (Marlin): off, or already above the target.
    if (!done && (a->target_c <= 0.0 || temp > a->target_c + hc.wait_tolerance_c))
      done = skipped = true;
  }
  if (!done) {
    if (std::fabs(temp - a->target_c) <= hc.wait_tolerance_c) {
      if (!ws_.in_band) {
        ws_.in_band = true;
        ws_.band_since = now;
      }
      done = now - ws_.band_since >= hc.wait_settle_s;
    } else {
      ws_.in_band = false;
    }
  }
  if (!done && now - ws_.start_plant > hc.wait_timeout_s) {
    throw Error(fmt::format(
        "{}: M{} S{:g} at line {}{}: the {} is at {:.1f} degC after {:.0f} s (from {:.1f} degC; "
        "heater.{}.wait_timeout_s = {:g}, wait_tolerance_c = {:g}); job stopped",
        name_, a->mcode, a->target_c, src_, a->source_line, heat::kChannelNames[a->channel], temp,
        now - ws_.start_plant, ws_.start_c, heat::kChannelNames[a->channel], hc.wait_timeout_s,
        hc.wait_tolerance_c));
  }
  if (done) {
    HeaterWaitReport r;
    r.mcode = a->mcode;
    r.source_line = a->source_line;
    r.channel = a->channel;
    r.target_c = a->target_c;
    r.start_c = ws_.start_c;
    r.plant_s = now - ws_.start_plant;
    r.end_plant_s = now;
    r.end_c = temp;
    r.wall_s = std::chrono::duration<double>(clock_type::now() - ws_.start_wall).count();
    r.skipped = skipped;
    r.cancelled = cancel_wait_;
    rep_.heater_waits.push_back(r);
    ++next_wait_;
    cancel_wait_ = false;
    ws_ = WaitState{};
    win_.touch(link_.now());
  }
}

void V2Session::on_status(const v2::Status& stt) {
  const size_t depth = ident_.fifo_depth;
  const uint16_t fr = static_cast<uint16_t>(stt.fifo_level >= depth ? 0 : depth - stt.fifo_level);
  update(stt.next_seq, fr, stt.done);
  status_outstanding_ = false;
  if (status_unanswered_) --status_unanswered_;
  if (motion_pending_) {
    // HOLD / RESUME are seen in the HOLD bit; rates alone in any STATUS after them.
    const bool held = (stt.state & v2::kStateHold) != 0;
    if ((!motion_.hold && !motion_.resume) || (motion_.hold && held) || (motion_.resume && !held))
      motion_pending_ = false;
  }
  ++status_answers_;
  last_status_ = stt;
  rep_.status_end = stt;
  if (opt_.on_status) opt_.on_status(stt);
  check_faults(stt);
  if (hj_) wait_status(stt);
}

void V2Session::handle(const v2::Frame& f) {
  try {
    switch (static_cast<v2::Type>(f.type)) {
      case v2::Type::Ack:
      case v2::Type::Done: {
        const v2::Credit c = v2::decode_credit(f);
        update(c.next_seq, c.free, c.done);
        break;
      }
      case v2::Type::Nak: {
        const v2::Nak k = v2::decode_nak(f);
        ++rep_.naks[static_cast<size_t>(k.reason)];
        if (!update(k.next_seq, k.free, std::nullopt)) break;
        const size_t acked = win_.acked();
        const size_t n = items_.size();
        // The device's soft limits (docs/machine.md "Soft limits"): the frame's end leaves the
        // travel it was given; every copy would be refused the same way, so never retried.
        if (k.reason == v2::NakReason::Travel && acked < n && k.seq == win_.seq_of(acked)) {
          throw Error(fmt::format(
              "{}: the device refused {} (seq {}): its end leaves the travel of an axis (NAK "
              "TRAVEL: the device's soft limits, CONFIG_TRAVEL; the host's [travel] or its idea of "
              "the machine position differs from the device's)",
              name_, item_name(acked), k.seq));
        }
        // A refusal of the frame's content (BAD_FIELD, UNKNOWN_TYPE) is the same for every
        // copy, including those sent before a go-back: three of them for the oldest unacked
        // frame end the job.
        if ((k.reason == v2::NakReason::BadField || k.reason == v2::NakReason::UnknownType) &&
            acked < n && k.seq == win_.seq_of(acked) && ++fatal_nak_count_ >= 3) {
          std::string hint;
          if (k.reason == v2::NakReason::UnknownType) {
            const auto t = static_cast<v2::Type>(items_[acked].frame.type);
            if (t == v2::Type::LineProfile) {
              hint =
                  " (a device built without trapezoid profiles: set motion = \"constant\" "
                  "in the machine configuration)";
            } else if (t == v2::Type::Arc) {
              hint =
                  " (a device built without the circular DDA: set native_arcs = false in "
                  "the machine configuration)";
            } else if (items_[acked].heater) {
              hint = " (a device built without heaters: remove the heater M-codes)";
            }
          }
          throw Error(fmt::format("{}: device refuses {} (seq {}): NAK {}{}", name_,
                                  item_name(acked), k.seq,
                                  v2::nak_reason_name(static_cast<uint8_t>(k.reason)), hint));
        }
        if (win_.stale_nak()) {
          // The device is still where we went back to: NAKs of the copies sent before the
          // go-back (out of order, or corrupted on the way) until the new copies arrive. A
          // lost new copy is recovered by the retransmission timeout.
          ++rep_.naks_ignored;
          break;
        }
        if (acked < n) go_back();
        break;
      }
      case v2::Type::Status:
        on_status(v2::decode_status(f, ident_.n_axes));
        break;
      case v2::Type::TriggerReport:
        last_trigger_ = v2::decode_trigger_report(f, ident_.n_axes);
        ++trigger_answers_;
        trigger_outstanding_ = false;
        break;
      default:
        break;  // IDENT (late), anything else: ignored
    }
  } catch (const v2::ProtocolError&) {
    ++rep_.bad_device_frames;
  }
}

void V2Session::asked_status() {
  const Time now = link_.now();
  // Answers not seen for a retransmission timeout are lost: no longer waited for.
  if (now - last_status_ask_ > opt_.retransmit_timeout) status_unanswered_ = 0;
  ++status_unanswered_;
  last_status_ask_ = now;
}

void V2Session::request_status(bool fresh) {
  const Time now = link_.now();
  if (!fresh && status_outstanding_ && now - status_sent_ <= opt_.retransmit_timeout) return;
  status_outstanding_ = true;
  status_sent_ = now;
  io_.send(v2::status_query());
  asked_status();
  ++rep_.status_polls;
  last_poll_ = now;
}

void V2Session::request_trigger() {
  io_.send(v2::trigger_query());
  trigger_outstanding_ = true;
}

void V2Session::poll(milliseconds wait) {
  poll_once(wait);
  if (complete()) was_complete_ = true;
}

void V2Session::poll_once(milliseconds wait) {
  const size_t n = items_.size();
  // Send what the window and the credit allow.
  batch_.clear();
  size_t batch_frames = 0;
  const size_t limit = gate();
  while (win_.may_send(limit)) {
    const size_t i = win_.sent();
    if (items_[i].fifo) {
      const size_t in_flight = fifo_before_[i] - fifo_before_[win_.acked()];
      if (!have_credit_ || free_slots_ <= in_flight) break;
    }
    v2::Frame f = items_[i].frame;
    f.seq = win_.seq_of(i);
    v2::encode_to(f, batch_);
    ++batch_frames;
    win_.mark_sent(link_.now());
    if (batch_.size() >= 256) break;  // keep reading answers while a long window goes out
  }
  rep_.retransmissions = win_.retransmissions();
  io_.send_batch(batch_, batch_frames);

  // Answers already there (read before any timer: a host that was not scheduled for a while
  // must not take answers waiting in its input for a silence).
  while (const auto f = io_.receive(milliseconds(0))) handle(*f);
  // A MOTION whose effect no STATUS has shown yet (lost on the way, or its answer lost).
  if (motion_pending_ && link_.now() - motion_sent_ > opt_.retransmit_timeout) {
    motion_sent_ = link_.now();
    io_.send(v2::motion(motion_));
    asked_status();
    status_outstanding_ = true;
    status_sent_ = motion_sent_;
  }
  // Messages whose frames before are done; a pause once the machine is at rest before it.
  while (next_message_ < messages_.size() && win_.acked() >= messages_[next_message_].first &&
         done_count_ >= fifo_before_[messages_[next_message_].first]) {
    if (opt_.on_message) opt_.on_message(*messages_[next_message_].second);
    ++next_message_;
  }
  if (next_pause_ < pauses_.size() && win_.acked() >= pauses_[next_pause_].first &&
      done_count_ >= fifo_before_[pauses_[next_pause_].first]) {
    const gcode::Pause& pz = *pauses_[next_pause_].second;
    ++rep_.pauses;
    if (opt_.on_pause && !opt_.on_pause(pz))
      throw Error(
          fmt::format("{}: job stopped at the pause of line {} ({}): the machine is at "
                      "rest there",
                      name_, pz.line, pz.prompt));
    ++next_pause_;
    io_.restart_silence();
    win_.touch(link_.now());
    return;
  }
  if (complete()) {
    // Nothing in flight but a STATUS_QUERY, MOTION or TRIGGER_QUERY of the caller's: wait for
    // its answer.
    if (status_outstanding_ || trigger_outstanding_) {
      if (const auto f = io_.receive(wait)) handle(*f);
    }
    return;
  }

  // Timers (link time).
  const Time now = link_.now();
  if (now - io_.last_rx() > opt_.answer_timeout) {
    const size_t acked = win_.acked();
    const std::string last = acked == 0 ? std::string("none") : item_name(acked - 1);
    throw Error(fmt::format(
        "{}: no answer from the device for {:.3g} s{} ({} of {} frames acknowledged, {} of {} "
        "FIFO frames done; last acknowledged: {})",
        name_, static_cast<double>(opt_.answer_timeout.count()) / 1000.0,
        link_.board_clock() ? " of board time" : "", acked, n, done_count_, fifo_before_.back(),
        last));
  }
  // The timer runs from the later of the last progress and the (last) sending of the oldest
  // unacknowledged frame: a frame sent after a long credit wait starts a fresh timer.
  if (win_.timer_expired(now)) {
    const size_t acked = win_.acked();
    const size_t same = win_.on_timeout(now);
    rep_.timeouts = win_.timeouts();
    rep_.go_backs = win_.go_backs();
    rep_.min_window = std::min(rep_.min_window, win_.min_window());
    rep_.max_rto_s = std::max(rep_.max_rto_s, win_.max_rto_s());
    check_stuck(acked, same);
    return;
  }
  // Heaters: progress, faults, watchdog. One STATUS_QUERY outstanding at a time (answered or
  // given up after the retransmission timeout): polls must not queue up on a slow line.
  if (hj_ && now - last_heater_poll_ > opt_.heater_poll &&
      (!status_outstanding_ || now - last_heater_poll_ > opt_.retransmit_timeout)) {
    status_outstanding_ = true;
    status_sent_ = now;
    io_.send(v2::status_query());
    asked_status();
    ++rep_.status_polls;
    last_heater_poll_ = now;
    last_poll_ = now;
  } else if (win_.sent() == win_.acked() && now - io_.last_rx() > opt_.idle_poll &&
             now - last_poll_ > opt_.idle_poll) {
    io_.send(v2::status_query());
    asked_status();
    ++rep_.status_polls;
    last_poll_ = now;
  }
  if (batch_frames) return;
  if (const auto f = io_.receive(wait)) handle(*f);
}

void V2Session::drain() {
  while (!complete()) poll();
}

size_t V2Session::abandon() {
  aborting_ = true;
  const size_t keep = std::max(win_.high(), clear_items_);
  const size_t dropped = items_.size() - std::min(items_.size(), keep);
  if (!dropped) return 0;
  items_.resize(keep);
  fifo_before_.resize(keep + 1);
  while (!fifo_item_.empty() && fifo_item_.back() >= keep) fifo_item_.pop_back();
  while (!waits_.empty() && waits_.back() >= keep) waits_.pop_back();
  auto cut = [keep](auto& v) {
    while (!v.empty() && v.back().first > keep) v.pop_back();
  };
  cut(pauses_);
  cut(messages_);
  next_wait_ = std::min(next_wait_, waits_.size());
  next_pause_ = std::min(next_pause_, pauses_.size());
  next_message_ = std::min(next_message_, messages_.size());
  rep_.sequenced_frames = items_.size();
  return dropped;
}

void V2Session::finish_report() {
  rep_.retransmissions = win_.retransmissions();
  rep_.go_backs = win_.go_backs();
  rep_.timeouts = win_.timeouts();
  rep_.srtt_s = win_.srtt_s();
  rep_.max_rto_s = std::max(rep_.max_rto_s, win_.max_rto_s());
  rep_.min_window = std::min(rep_.min_window, win_.min_window());
  io_.finish_counters();
}

}  // namespace fpgacnc::link
