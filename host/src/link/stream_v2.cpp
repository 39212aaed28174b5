#include "fpgacnc/link/stream_v2.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace fpgacnc::link {
namespace v2 = protocol::v2;
// Reports (elapsed, wall_s, probe_time) are wall time; every timer runs in link time
// (Link::now(): the wall clock on a port, board clocks on a simulated board; link.h).
using clock_type = std::chrono::steady_clock;
using Time = Link::Time;
using std::chrono::milliseconds;

namespace {

// Silence (link time) after which a partial device frame at the head of the parser is given up
// (a LEN corrupted upwards would otherwise hold back the frames behind it).
constexpr milliseconds kPartialGiveUp{200};
// Longest single wait of the receive loop, so that partial frames are given up in time.
constexpr milliseconds kReceiveSlice{20};

// One v2 session over a link: reads device frames, writes host frames, keeps the counters.
class Session {
 public:
  Session(Link& link, StreamV2Report& rep)
      : link_(link), rep_(rep), last_rx_(link.now()), last_byte_(last_rx_) {}

  void send(const v2::Frame& f) {
    buf_.clear();
    v2::encode_to(f, buf_);
    link_.write(buf_);
    rep_.bytes_written += buf_.size();
    ++rep_.frames_sent;
  }
  // Several frames in one write.
  void send_batch(const std::vector<uint8_t>& bytes, size_t frames) {
    if (bytes.empty()) return;
    link_.write(bytes);
    rep_.bytes_written += bytes.size();
    rep_.frames_sent += frames;
  }

  // Next good device frame by `deadline` (link time; nullopt when none). Duplicates are
  // counted.
  std::optional<v2::Frame> receive_until(Time deadline) {
    for (;;) {
      if (auto f = parser_.next()) {
        last_rx_ = link_.now();
        if (have_last_ && *f == last_frame_) {
          ++rep_.duplicates;
        }
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
  // Same, within `timeout` of link time from now.
  std::optional<v2::Frame> receive(milliseconds timeout) {
    return receive_until(link_.now() + timeout);
  }

  void finish_counters() {
    rep_.rx_crc_errors = parser_.crc_errors();
    rep_.rx_bad_length = parser_.bad_length();
    rep_.rx_noise_bytes = parser_.noise_bytes();
    rep_.rx_abandoned = parser_.abandoned();
  }

  Time last_rx() const { return last_rx_; }
  // After an operator pause: the silence was ours, not the device's.
  void restart_silence() { last_rx_ = link_.now(); }
  void reset_parser() { parser_.reset(); }

 private:
  Link& link_;
  StreamV2Report& rep_;
  v2::FrameParser parser_;
  std::vector<uint8_t> buf_;
  v2::Frame last_frame_;
  bool have_last_ = false;
  Time last_rx_;    // link time of the last good device frame
  Time last_byte_;  // link time of the last byte read
};

// Waits for a frame of `type` until `deadline` (link time; others ignored); nullopt on timeout.
std::optional<v2::Frame> await_type(Session& s, v2::Type type, Time deadline) {
  for (;;) {
    const auto f = s.receive_until(deadline);
    if (!f) return std::nullopt;
    if (f->type == static_cast<uint8_t>(type)) return f;
  }
}

v2::Status query_status(Link& link, Session& s, StreamV2Report& rep, size_t n_axes,
                        const StreamV2Options& opt, const std::string& name, const char* when) {
  const Time give_up = link.now() + opt.answer_timeout;
  while (link.now() < give_up) {
    s.send(v2::status_query());
    ++rep.status_polls;
    const auto f = await_type(s, v2::Type::Status, link.now() + opt.retransmit_timeout);
    if (!f) continue;
    try {
      return v2::decode_status(*f, n_axes);
    } catch (const v2::ProtocolError&) {
      ++rep.bad_device_frames;
    }
  }
  throw Error(fmt::format("{}: no STATUS {} within {:.3g} s{} (STATUS_QUERY every {} ms)", name,
                          when, static_cast<double>(opt.answer_timeout.count()) / 1000.0,
                          link.board_clock() ? " of board time" : "",
                          opt.retransmit_timeout.count()));
}

std::string frame_name(const v2::Frame& f, const v2::JobFrame* jf,
                       const heat::HeaterAction* ha = nullptr) {
  if (ha) {
    return fmt::format("{} (M{} S{:g}, line {})", v2::type_name(f.type), ha->mcode, ha->target_c,
                       ha->source_line);
  }
  if (!jf) return v2::type_name(f.type);
  return fmt::format("{} of segment {} (line {})", v2::type_name(f.type), jf->segment_index,
                     jf->source_line);
}

}  // namespace

std::optional<v2::Ident> probe_v2(Link& link, milliseconds timeout, uint64_t* bytes_written) {
  StreamV2Report rep;
  Session s(link, rep);
  link.flush_input();
  s.send(v2::hello());
  if (bytes_written) *bytes_written += rep.bytes_written;
  const Time deadline = link.now() + timeout;
  for (;;) {
    const auto f = await_type(s, v2::Type::Ident, deadline);
    if (!f) return std::nullopt;
    try {
      return v2::decode_ident(*f);
    } catch (const v2::ProtocolError&) {
    }
  }
}

ProtocolChoice select_protocol(Link& link, const std::string& mode, const StreamV2Options& options,
                               milliseconds v1_settle) {
  ProtocolChoice c;
  const auto t0 = clock_type::now();
  if (mode == "v1") {
    c.protocol = "v1";
    return c;
  }
  if (mode == "v2") {
    for (int i = 0; i < std::max(options.hello_attempts, 1) && !c.ident; ++i) {
      c.ident = probe_v2(link, options.hello_timeout);
    }
    if (!c.ident) {
      throw Error(fmt::format(
          "{}: no IDENT answer to {} HELLO frames ({} ms each): the device does not speak "
          "protocol v2 (try --protocol v1 or auto)",
          link.name(), std::max(options.hello_attempts, 1), options.hello_timeout.count()));
    }
    c.protocol = "v2";
  } else if (mode == "auto") {
    c.ident = probe_v2(link, options.hello_timeout);
    if (c.ident) {
      c.protocol = "v2";
    } else {
      // The 6 HELLO bytes are a partial v1 packet for a v1-only device: its 100 ms watchdog
      // drops them. Wait past it, then start v1 from a clean line.
      link.wait_until(link.now() + v1_settle);
      link.flush_input();
      c.protocol = "v1";
    }
  } else {
    throw Error(fmt::format("unknown protocol '{}' (expected auto, v1 or v2)", mode));
  }
  c.probe_time = clock_type::now() - t0;
  return c;
}

StreamV2Options stream_v2_options(const config::MachineConfig& cfg) {
  StreamV2Options o;
  o.retransmit_timeout =
      milliseconds(std::max<long long>(1, std::llround(cfg.retransmit_timeout_s * 1000.0)));
  o.idle_poll = o.retransmit_timeout;
  o.answer_timeout = milliseconds(std::max<long long>(1, std::llround(cfg.ack_timeout_s * 1000.0)));
  return o;
}

StreamV2Report stream_v2(Link& link, const plan::Plan& plan, const config::MachineConfig& cfg,
                         const StreamV2Options& options, std::optional<v2::Ident> ident) {
  const v2::Job job = v2::pack_job(plan, cfg);  // throws before any byte
  // Heater commands: validated (line:col errors) and placed before any byte is sent.
  const heat::HeaterJob heaters = heat::make_heater_job(plan, job, cfg);
  StreamV2Options opt = options;
  opt.heaters = &heaters;
  StreamV2Report r = stream_v2_job(link, job, opt, ident);
  r.final_steps = plan.final_steps;
  r.final_mm = plan.final_mm;
  return r;
}

StreamV2Report stream_v2_job(Link& link, const v2::Job& job, const StreamV2Options& opt,
                             std::optional<v2::Ident> ident) {
  StreamV2Report rep;
  const heat::HeaterJob* hj = opt.heaters && opt.heaters->any() ? opt.heaters : nullptr;
  rep.skipped_heater = hj ? 0 : job.skipped_heater;
  rep.t_raised = job.t_raised;
  rep.total_t = job.total_t;
  rep.target = job.target;
  rep.lines = job.lines;
  rep.profiles = job.profiles;
  rep.arcs = job.arcs;
  rep.dwells = job.dwells;
  rep.fifo_frames = job.frames.size();
  const auto t0 = clock_type::now();
  Session s(link, rep);
  const std::string name = link.name();

  // 1. Handshake.
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
  if (job.max_axes > ident->n_axes) {
    throw Error(fmt::format("{}: the job moves {} axes, the device has {} (N_AXES)", name,
                            job.max_axes, ident->n_axes));
  }
  if (job.clk_hz && ident->clk_hz && job.clk_hz != ident->clk_hz) {
    throw Error(fmt::format(
        "{}: the device runs at {} Hz, the job was planned for clk_hz = {} Hz (segment times "
        "would be wrong: fix clk_hz in the machine configuration)",
        name, ident->clk_hz, job.clk_hz));
  }
  size_t max_payload = 0;
  for (const auto& jf : job.frames) max_payload = std::max(max_payload, jf.frame.payload.size());
  if (max_payload > ident->max_payload) {
    throw Error(fmt::format("{}: the job needs frames of {} payload bytes, the device takes {}",
                            name, max_payload, ident->max_payload));
  }
  if (ident->fifo_depth == 0)
    throw Error(fmt::format("{}: device reports a FIFO depth of 0", name));
  const size_t n_axes = ident->n_axes;

  // Wait until a previous job has drained (its DONEs would count into ours).
  v2::Status st = query_status(link, s, rep, n_axes, opt, name, "at the start");
  const Time busy_limit = link.now() + opt.answer_timeout;
  while (st.state & v2::kStateBusy) {
    if (link.now() > busy_limit) {
      throw Error(fmt::format("{}: device still busy (FIFO level {}) after {:.3g} s{}", name,
                              st.fifo_level,
                              static_cast<double>(opt.answer_timeout.count()) / 1000.0,
                              link.board_clock() ? " of board time" : ""));
    }
    link.wait_until(link.now() + milliseconds(20));
    st = query_status(link, s, rep, n_axes, opt, name, "at the start");
  }
  rep.status_start = st;

  // 2. The sequenced frames of the session.
  struct Item {
    v2::Frame frame;
    bool fifo;
    const v2::JobFrame* jf;
    const heat::HeaterAction* heater = nullptr;  // HEATER_SETPOINT of an M104/M109/M140/M190
  };
  std::vector<Item> items;
  if (st.faults) {
    items.push_back({v2::fault_clear(0), false, nullptr});
    rep.faults_cleared = st.faults;
  }
  const size_t clear_items = items.size();  // faults are checked once these are acknowledged
  for (size_t a = 0; a < job.config.size() && a < n_axes; ++a) {
    items.push_back({job.config[a], false, nullptr});
  }
  // Heaters: setup frames, then each setpoint before the FIFO frame it precedes in the program.
  std::vector<size_t> waits;       // item indices of M109/M190 setpoints
  std::vector<size_t> frame_item;  // item index of job.frames[j]
  {
    size_t ai = 0;
    auto actions_before = [&](size_t frame) {
      if (!hj) return;
      for (; ai < hj->actions.size() && hj->actions[ai].before_frame <= frame; ++ai) {
        const auto& a = hj->actions[ai];
        if (a.wait) waits.push_back(items.size());
        items.push_back({v2::heater_setpoint(0, a.channel, a.target_q4), false, nullptr, &a});
        ++rep.heater_frames;
      }
    };
    if (hj) {
      for (const auto& f : hj->setup) items.push_back({f, false, nullptr});
      rep.heater_frames += hj->setup.size();
    }
    for (size_t j = 0; j < job.frames.size(); ++j) {
      actions_before(j);
      frame_item.push_back(items.size());
      items.push_back({job.frames[j].frame, true, &job.frames[j]});
    }
    actions_before(SIZE_MAX);
  }
  const size_t n = items.size();
  rep.sequenced_frames = n;
  std::vector<size_t> fifo_before(n + 1, 0);  // FIFO frames in [0, i)
  for (size_t i = 0; i < n; ++i) fifo_before[i + 1] = fifo_before[i] + (items[i].fifo ? 1 : 0);
  const size_t total_fifo = fifo_before[n];

  const uint8_t seq0 = st.next_seq;
  const uint32_t done0 = st.done;
  auto seq_of = [seq0](size_t i) { return static_cast<uint8_t>(seq0 + i); };
  size_t acked = 0;  // frames [0, acked) acknowledged
  size_t sent = 0;   // next frame to send
  size_t high = 0;   // frames [0, high) sent at least once
  size_t free_slots = st.fifo_level >= ident->fifo_depth ? 0 : ident->fifo_depth - st.fifo_level;
  size_t done_count = 0;  // FIFO frames completed (this job)
  bool have_credit = true;
  std::optional<size_t> goback_at;  // index of the last go-back, while its old copies drain
  size_t goback_same = 0;
  size_t fatal_nak_count = 0;
  Time last_progress = link.now();
  Time last_poll = last_progress;
  // Retransmission timeout: at least opt.retransmit_timeout, and above the measured time from
  // sending a frame to its ACK (RFC 6298 estimator, Karn's rule: only frames sent once), so a
  // line with many bytes queued (a slow simulated board, a long window) is not mistaken for a
  // loss. Doubled on each timeout while nothing is acknowledged.
  std::vector<Time> sent_at(n);
  std::vector<uint16_t> sends(n, 0);
  double srtt = 0.0, rttvar = 0.0;  // seconds
  bool have_rtt = false;
  auto base_rto = [&]() {
    const auto est = std::chrono::duration<double>(srtt + 4.0 * rttvar);
    return std::max(opt.retransmit_timeout,
                    std::chrono::duration_cast<milliseconds>(have_rtt ? est : est.zero()));
  };
  milliseconds rto = opt.retransmit_timeout;
  rep.max_rto_s = std::chrono::duration<double>(rto).count();
  // After a timeout only the oldest unacknowledged frame is sent again until something is
  // acknowledged: when the line was only slow or stalled, the cumulative ACK then covers the
  // frames still on their way and nothing else is resent; when they were lost, sending resumes
  // from the device's next_seq.
  bool probing = false;
  // Window of unacknowledged frames (AIMD, as TCP congestion control): full (max_unacked) on a
  // clean line; halved at each go-back, grown by one frame per window of acknowledged frames (by
  // one per frame below ssthresh). On a noisy line go-back-N then resends a few frames per error
  // instead of a whole FIFO's worth.
  const double max_window = static_cast<double>(std::max<size_t>(opt.max_unacked, 1));
  double cwnd = max_window;
  double ssthresh = max_window;

  auto update = [&](uint8_t next_seq, uint16_t free, std::optional<uint32_t> done) -> bool {
    const size_t delta = static_cast<uint8_t>(next_seq - seq_of(acked));
    if (delta > high - acked) {  // behind us, or ahead of anything ever sent
      ++rep.stale_answers;
      return false;
    }
    if (delta > 0) {
      acked += delta;
      if (sent < acked) sent = acked;  // acknowledged beyond a go-back point
      last_progress = link.now();
      if (sends[acked - 1] == 1) {
        const double r = std::chrono::duration<double>(last_progress - sent_at[acked - 1]).count();
        if (!have_rtt) {
          srtt = r;
          rttvar = r / 2.0;
          have_rtt = true;
        } else {
          rttvar = 0.75 * rttvar + 0.25 * std::fabs(srtt - r);
          srtt = 0.875 * srtt + 0.125 * r;
        }
        rep.srtt_s = srtt;
      }
      rto = base_rto();
      rep.max_rto_s = std::max(rep.max_rto_s, std::chrono::duration<double>(rto).count());
      probing = false;
      for (size_t k = 0; k < delta; ++k) cwnd += cwnd < ssthresh ? 1.0 : 1.0 / cwnd;
      cwnd = std::min(cwnd, max_window);
      goback_same = 0;
      fatal_nak_count = 0;
      if (goback_at && acked > *goback_at) goback_at.reset();
    }
    free_slots = free;
    have_credit = true;
    if (done) {
      const size_t d = static_cast<uint32_t>(*done - done0);
      if (d > done_count && d <= total_fifo) {
        done_count = d;
        if (opt.progress) opt.progress(done_count, total_fifo);
      }
    }
    return true;
  };
  auto go_back = [&]() {
    if (acked == (goback_at ? *goback_at : SIZE_MAX)) {
      if (++goback_same > opt.max_goback_same) {
        const auto* jf = items[acked].jf;
        throw Error(fmt::format(
            "{}: {} (seq {}) refused {} times without progress (NAKs: {} BAD_CRC, {} "
            "BAD_LENGTH, {} UNKNOWN_TYPE, {} TIMEOUT, {} OUT_OF_ORDER, {} FIFO_FULL, {} BAD_FIELD)",
            name, frame_name(items[acked].frame, jf, items[acked].heater), seq_of(acked),
            goback_same, rep.naks[1], rep.naks[2], rep.naks[3], rep.naks[4], rep.naks[5],
            rep.naks[6], rep.naks[7]));
      }
    }
    sent = acked;
    goback_at = acked;
    ++rep.go_backs;
    ssthresh = std::max(2.0, cwnd / 2.0);
    cwnd = ssthresh;
    rep.min_window = std::min(rep.min_window, static_cast<size_t>(cwnd));
    last_progress = link.now();
  };

  // ---- Heaters: M109/M190 gates, STATUS polling, faults ----
  const Time link_t0 = link.now();
  const auto plant_now = [&]() -> double {
    if (opt.plant_time) return opt.plant_time();
    return seconds(link.now() - link_t0);
  };
  size_t next_wait = 0;  // index into `waits` of the wait in force
  // Items up to and including the pending wait's setpoint may be sent, nothing after it.
  // Pauses and messages: the item index they come before (n: after everything).
  std::vector<std::pair<size_t, const gcode::Pause*>> pauses;
  std::vector<std::pair<size_t, const gcode::Message*>> messages;
  for (const auto& ev : job.events) {
    const size_t at = ev.before_frame < frame_item.size() ? frame_item[ev.before_frame] : n;
    if (const auto* p = std::get_if<gcode::Pause>(&ev.what)) pauses.emplace_back(at, p);
    if (const auto* m = std::get_if<gcode::Message>(&ev.what)) messages.emplace_back(at, m);
  }
  size_t next_pause = 0, next_message = 0;
  auto gate = [&]() {
    const size_t h = next_wait < waits.size() ? waits[next_wait] + 1 : n;
    return next_pause < pauses.size() ? std::min(h, pauses[next_pause].first) : h;
  };
  struct WaitState {
    bool started = false;  // setpoint accepted and FIFO drained
    bool in_band = false;
    double band_since = 0.0, start_plant = 0.0, start_c = 0.0;
    clock_type::time_point start_wall{};
  } ws;
  Time last_heater_poll = link.now();
  bool status_outstanding = false;
  std::vector<size_t> fifo_item;  // item index of the k-th FIFO frame
  for (size_t i = 0; i < n; ++i) {
    if (items[i].fifo) fifo_item.push_back(i);
  }
  const std::string src = hj && !hj->source.empty() ? hj->source + ":" : std::string();
  auto current_line = [&]() -> std::string {
    if (next_wait < waits.size() && ws.started) {
      const auto* a = items[waits[next_wait]].heater;
      return fmt::format("{}{} (M{} S{:g}, waiting)", src, a->source_line, a->mcode, a->target_c);
    }
    if (done_count < fifo_item.size()) {
      std::string l = fmt::format("{}{}", src, items[fifo_item[done_count]].jf->source_line);
      if (next_wait < waits.size() && acked > waits[next_wait]) {  // a wait once it has drained
        const auto* a = items[waits[next_wait]].heater;
        l += fmt::format(" (M{} S{:g} at line {} waits for it)", a->mcode, a->target_c,
                         a->source_line);
      }
      return l;
    }
    return "the end of the job";
  };
  auto check_faults = [&](const v2::Status& stt) {
    if (acked < clear_items) return;  // faults of a previous job, FAULT_CLEAR not yet taken
    const uint8_t bad =
        stt.faults & (v2::kFaultEstop | v2::kFaultWatchdog | v2::kFaultHotend | v2::kFaultBed);
    if (!bad) return;
    const std::string what = heat::describe_faults(stt, bad);
    throw Error(
        fmt::format("{}: job stopped at G-code line {}: {} (the device switched the heaters "
                    "off and latched the fault; the next job clears it)",
                    name, current_line(), what));
  };
  auto wait_status = [&](const v2::Status& stt) {
    if (next_wait >= waits.size()) return;
    const size_t w = waits[next_wait];
    if (acked <= w || done_count < fifo_before[w]) return;  // not accepted or FIFO not drained
    const auto* a = items[w].heater;
    if (stt.heaters.size() <= a->channel) {
      throw Error(fmt::format("{}: M{} at line {}{}: the device reports no heaters in STATUS", name,
                              a->mcode, src, a->source_line));
    }
    const auto& h = stt.heaters[a->channel];
    const auto& hc = hj->config.ch[a->channel];
    const double now = plant_now();
    const double temp = h.temp_c();
    bool done = false, skipped = false;
    if (!ws.started) {
      ws.started = true;
      ws.start_plant = now;
      ws.start_c = temp;
      ws.start_wall = clock_type::now();
      // S waits only when heating (Marlin): off, or already above the target.
      if (a->target_c <= 0.0 || temp > a->target_c + hc.wait_tolerance_c) done = skipped = true;
    }
    if (!done) {
      if (std::fabs(temp - a->target_c) <= hc.wait_tolerance_c) {
        if (!ws.in_band) {
          ws.in_band = true;
          ws.band_since = now;
        }
        done = now - ws.band_since >= hc.wait_settle_s;
      } else {
        ws.in_band = false;
      }
    }
    if (!done && now - ws.start_plant > hc.wait_timeout_s) {
      throw Error(fmt::format(
          "{}: M{} S{:g} at line {}{}: the {} is at {:.1f} degC after {:.0f} s (from {:.1f} degC; "
          "heater.{}.wait_timeout_s = {:g}, wait_tolerance_c = {:g}); job stopped",
          name, a->mcode, a->target_c, src, a->source_line, heat::kChannelNames[a->channel], temp,
          now - ws.start_plant, ws.start_c, heat::kChannelNames[a->channel], hc.wait_timeout_s,
          hc.wait_tolerance_c));
    }
    if (done) {
      HeaterWaitReport r;
      r.mcode = a->mcode;
      r.source_line = a->source_line;
      r.channel = a->channel;
      r.target_c = a->target_c;
      r.start_c = ws.start_c;
      r.plant_s = now - ws.start_plant;
      r.end_plant_s = now;
      r.end_c = temp;
      r.wall_s = std::chrono::duration<double>(clock_type::now() - ws.start_wall).count();
      r.skipped = skipped;
      rep.heater_waits.push_back(r);
      ++next_wait;
      ws = WaitState{};
      last_progress = link.now();
    }
  };

  auto handle = [&](const v2::Frame& frame) {
    const v2::Frame* f = &frame;
    try {
      switch (static_cast<v2::Type>(f->type)) {
        case v2::Type::Ack:
        case v2::Type::Done: {
          const v2::Credit c = v2::decode_credit(*f);
          update(c.next_seq, c.free, c.done);
          break;
        }
        case v2::Type::Nak: {
          const v2::Nak k = v2::decode_nak(*f);
          ++rep.naks[static_cast<size_t>(k.reason)];
          if (!update(k.next_seq, k.free, std::nullopt)) break;
          // A refusal of the frame's content (BAD_FIELD, UNKNOWN_TYPE) is the same for every
          // copy, including those sent before a go-back: three of them for the oldest unacked
          // frame end the job.
          if ((k.reason == v2::NakReason::BadField || k.reason == v2::NakReason::UnknownType) &&
              acked < n && k.seq == seq_of(acked) && ++fatal_nak_count >= 3) {
            std::string hint;
            if (k.reason == v2::NakReason::UnknownType) {
              const auto t = static_cast<v2::Type>(items[acked].frame.type);
              if (t == v2::Type::LineProfile) {
                hint =
                    " (a device built without trapezoid profiles: set motion = \"constant\" "
                    "in the machine configuration)";
              } else if (t == v2::Type::Arc) {
                hint =
                    " (a device built without the circular DDA: set native_arcs = false in "
                    "the machine configuration)";
              } else if (items[acked].heater) {
                hint = " (a device built without heaters: remove the heater M-codes)";
              }
            }
            throw Error(
                fmt::format("{}: device refuses {} (seq {}): NAK {}{}", name,
                            frame_name(items[acked].frame, items[acked].jf, items[acked].heater),
                            k.seq, v2::nak_reason_name(static_cast<uint8_t>(k.reason)), hint));
          }
          if (goback_at && acked == *goback_at) {
            // The device is still where we went back to: NAKs of the copies sent before the
            // go-back (out of order, or corrupted on the way) until the new copies arrive. A
            // lost new copy is recovered by the retransmission timeout.
            ++rep.naks_ignored;
            break;
          }
          if (acked < n) {
            go_back();
            probing = false;
          }
          break;
        }
        case v2::Type::Status: {
          const v2::Status stt = v2::decode_status(*f, n_axes);
          const size_t depth = ident->fifo_depth;
          const uint16_t fr =
              static_cast<uint16_t>(stt.fifo_level >= depth ? 0 : depth - stt.fifo_level);
          update(stt.next_seq, fr, stt.done);
          status_outstanding = false;
          rep.status_end = stt;
          if (opt.on_status) opt.on_status(stt);
          check_faults(stt);
          if (hj) wait_status(stt);
          break;
        }
        default:
          break;  // IDENT (late), anything else: ignored
      }
    } catch (const v2::ProtocolError&) {
      ++rep.bad_device_frames;
    }
  };

  std::vector<uint8_t> batch;
  for (;;) {
    // Complete?
    if (acked == n && done_count == total_fifo && next_wait == waits.size() &&
        next_pause == pauses.size())
      break;

    // Send what the window and the credit allow.
    batch.clear();
    size_t batch_frames = 0;
    const size_t limit = std::min(probing ? std::min(n, acked + 1) : n, gate());
    const size_t window = static_cast<size_t>(cwnd);
    while (sent < limit && sent - acked < window) {
      if (items[sent].fifo) {
        const size_t in_flight = fifo_before[sent] - fifo_before[acked];
        if (!have_credit || free_slots <= in_flight) break;
      }
      v2::Frame f = items[sent].frame;
      f.seq = seq_of(sent);
      v2::encode_to(f, batch);
      ++batch_frames;
      if (sent < high) ++rep.retransmissions;
      sent_at[sent] = link.now();
      if (sends[sent] < UINT16_MAX) ++sends[sent];
      ++sent;
      high = std::max(high, sent);
      if (batch.size() >= 256) break;  // keep reading answers while a long window goes out
    }
    s.send_batch(batch, batch_frames);

    // Answers already there (read before any timer: a host that was not scheduled for a while
    // must not take answers waiting in its input for a silence).
    while (const auto f = s.receive(milliseconds(0))) handle(*f);
    // Messages whose frames before are done; a pause once the machine is at rest before it.
    while (next_message < messages.size() && acked >= messages[next_message].first &&
           done_count >= fifo_before[messages[next_message].first]) {
      if (opt.on_message) opt.on_message(*messages[next_message].second);
      ++next_message;
    }
    if (next_pause < pauses.size() && acked >= pauses[next_pause].first &&
        done_count >= fifo_before[pauses[next_pause].first]) {
      const gcode::Pause& pz = *pauses[next_pause].second;
      ++rep.pauses;
      if (opt.on_pause && !opt.on_pause(pz))
        throw Error(
            fmt::format("{}: job stopped at the pause of line {} ({}): the machine is at "
                        "rest there",
                        name, pz.line, pz.prompt));
      ++next_pause;
      s.restart_silence();
      last_progress = link.now();
      continue;
    }
    if (acked == n && done_count == total_fifo && next_wait == waits.size()) break;

    // Timers (link time).
    const Time now = link.now();
    if (now - s.last_rx() > opt.answer_timeout) {
      const std::string last = acked == 0 ? std::string("none")
                                          : frame_name(items[acked - 1].frame, items[acked - 1].jf,
                                                       items[acked - 1].heater);
      throw Error(fmt::format(
          "{}: no answer from the device for {:.3g} s{} ({} of {} frames acknowledged, {} of {} "
          "FIFO frames done; last acknowledged: {})",
          name, static_cast<double>(opt.answer_timeout.count()) / 1000.0,
          link.board_clock() ? " of board time" : "", acked, n, done_count, total_fifo, last));
    }
    // The timer runs from the later of the last progress and the (last) sending of the oldest
    // unacknowledged frame: a frame sent after a long credit wait starts a fresh timer.
    if (sent > acked && now - std::max(last_progress, sent_at[acked]) > rto) {
      ++rep.timeouts;
      go_back();
      probing = true;
      // Back off while nothing comes back (a slow or stalled line), up to 8x.
      rto = std::min(rto * 2, base_rto() * 8);
      rep.max_rto_s = std::max(rep.max_rto_s, std::chrono::duration<double>(rto).count());
      continue;
    }
    // Heaters: progress, faults, watchdog. One STATUS_QUERY outstanding at a time (answered or
    // given up after the retransmission timeout): polls must not queue up on a slow line.
    if (hj && now - last_heater_poll > opt.heater_poll &&
        (!status_outstanding || now - last_heater_poll > opt.retransmit_timeout)) {
      status_outstanding = true;
      s.send(v2::status_query());
      ++rep.status_polls;
      last_heater_poll = now;
      last_poll = now;
    } else if (sent == acked && now - s.last_rx() > opt.idle_poll &&
               now - last_poll > opt.idle_poll) {
      s.send(v2::status_query());
      ++rep.status_polls;
      last_poll = now;
    }
    if (batch_frames) continue;
    if (const auto f = s.receive(milliseconds(20))) handle(*f);
  }

  // 4. Final status and release.
  rep.status_end = query_status(link, s, rep, n_axes, opt, name, "at the end");
  rep.moved.resize(n_axes);
  rep.position_ok = true;
  for (size_t a = 0; a < n_axes; ++a) {
    const int32_t d = static_cast<int32_t>(static_cast<uint32_t>(rep.status_end.position[a]) -
                                           static_cast<uint32_t>(rep.status_start.position[a]));
    rep.moved[a] = d;
    const int64_t want = a < 4 ? job.target[a] : 0;
    if (static_cast<int32_t>(static_cast<uint32_t>(want)) != d) rep.position_ok = false;
  }
  if (opt.release) {
    const uint8_t rseq = seq_of(n);
    const Time give_up = link.now() + opt.answer_timeout;
    while (!rep.released && link.now() < give_up) {
      s.send(v2::release(rseq));
      const Time deadline = link.now() + opt.retransmit_timeout;
      while (!rep.released) {
        const auto f = s.receive_until(deadline);
        if (!f) break;
        try {
          if (f->type == static_cast<uint8_t>(v2::Type::Ack)) {
            if (v2::decode_credit(*f).next_seq == static_cast<uint8_t>(rseq + 1)) {
              rep.released = true;
            }
          }
        } catch (const v2::ProtocolError&) {
          ++rep.bad_device_frames;
        }
      }
    }
  }
  s.finish_counters();
  rep.elapsed = clock_type::now() - t0;
  return rep;
}

std::string format_report(const StreamV2Report& r) {
  std::string s;
  s += fmt::format("v2 device: N_AXES {}, FIFO {}, clk {} Hz, baud {}, build 0x{:08X}\n",
                   r.ident.n_axes, r.ident.fifo_depth, r.ident.clk_hz, r.ident.baud,
                   r.ident.build_id);
  s += fmt::format(
      "frames: {} sequenced ({} FIFO: {} LINE, {} LINE_PROFILE, {} ARC, {} DWELL), {} written in "
      "all, {} retransmitted, {} go-backs, {} retransmission timeouts, {} status polls\n",
      r.sequenced_frames, r.fifo_frames, r.lines, r.profiles, r.arcs, r.dwells, r.frames_sent,
      r.retransmissions, r.go_backs, r.timeouts, r.status_polls);
  s += "NAKs:";
  size_t total = 0;
  for (uint8_t k = 1; k <= 7; ++k) {
    s += fmt::format(" {} {}", v2::nak_reason_name(k), r.naks[k]);
    total += r.naks[k];
  }
  s += fmt::format(" (total {}, {} about copies sent before a go-back, ignored)\n", total,
                   r.naks_ignored);
  s += fmt::format(
      "round trip frame -> ACK {:.1f} ms (smoothed), largest retransmission timeout {:.0f} ms, "
      "smallest window {} frames\n",
      r.srtt_s * 1000.0, r.max_rto_s * 1000.0, r.min_window);
  s += fmt::format(
      "device frames: {} duplicates, {} stale, {} undecodable; host parser: {} CRC errors, {} "
      "bad lengths, {} noise bytes, {} abandoned\n",
      r.duplicates, r.stale_answers, r.bad_device_frames, r.rx_crc_errors, r.rx_bad_length,
      r.rx_noise_bytes, r.rx_abandoned);
  s += fmt::format("bytes: {} written, {} read; {:.2f} s; job time without gaps {:.3f} s\n",
                   r.bytes_written, r.bytes_read, r.elapsed.count(),
                   static_cast<double>(r.total_t) / std::max<uint32_t>(r.ident.clk_hz, 1));
  s += "device counters:";
  for (size_t i = 0; i < v2::kCounters; ++i) {
    s += fmt::format(" {} {}", v2::counter_name(i), r.status_end.counters[i]);
  }
  s += fmt::format("; faults 0x{:02X}", r.status_end.faults);
  if (r.faults_cleared)
    s += fmt::format(" (0x{:02X} latched before the job, cleared)", r.faults_cleared);
  s += "\n";
  s += "device moved:";
  for (size_t a = 0; a < r.moved.size(); ++a) {
    s += fmt::format(" {} {}", a < 4 ? config::kAxisNames[a] : '?', r.moved[a]);
  }
  s += fmt::format(" steps: {}\n", r.position_ok ? "matches the plan" : "DOES NOT match the plan");
  bool heaters_used = r.heater_frames > 0;
  for (const auto& h : r.status_end.heaters) heaters_used |= h.enabled() || h.faults;
  if (heaters_used) {
    s += fmt::format("heaters: {} heater frames", r.heater_frames);
    const std::string h = heat::format_heaters(r.status_end);
    if (!h.empty()) s += "; at the end " + h;
    s += "\n";
    for (const auto& w : r.heater_waits) {
      if (w.skipped) {
        s += fmt::format("  M{} S{:g} (line {}): no wait, {} at {:.1f} degC already\n", w.mcode,
                         w.target_c, w.source_line, heat::kChannelNames[w.channel], w.start_c);
      } else {
        s += fmt::format(
            "  M{} S{:g} (line {}): {} {:.1f} -> {:g} degC settled in {:.0f} s plant time ({:.2f} "
            "s wall)\n",
            w.mcode, w.target_c, w.source_line, heat::kChannelNames[w.channel], w.start_c,
            w.target_c, w.plant_s, w.wall_s);
      }
    }
  }
  if (!r.released) s += "warning: RELEASE not acknowledged (the device stays in v2 mode)\n";
  return s;
}

}  // namespace fpgacnc::link
