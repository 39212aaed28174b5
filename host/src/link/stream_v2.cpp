#include "fpgacnc/link/stream_v2.h"

#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/motion_plan.h"

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

std::optional<v2::Ident> probe_v2(Link& link, milliseconds timeout, uint64_t* bytes_written) {
  StreamV2Report rep;
  FrameIo io(link, rep);
  link.flush_input();
  io.send(v2::hello());
  if (bytes_written) *bytes_written += rep.bytes_written;
  const Time deadline = link.now() + timeout;
  for (;;) {
    const auto f = io.await_type(v2::Type::Ident, deadline);
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

uint32_t machine_hold_ramp(const config::MachineConfig& cfg, size_t n_axes) {
  uint32_t ramp = 0xFFFF'FFFFu;
  for (size_t a = 0; a < n_axes && a < config::kAxes; ++a) {
    const double spm = cfg.steps_per_mm[a];
    const double decel = cfg.hold_decel_mm_s2 > 0.0 ? cfg.hold_decel_mm_s2 : cfg.max_accel_mm_s2[a];
    ramp = std::min(ramp, v2::hold_ramp(decel * spm, cfg.max_feed_mm_min[a] / 60.0 * spm,
                                        static_cast<double>(cfg.clk_hz)));
  }
  return ramp;
}

v2::Motion machine_motion(const config::MachineConfig& cfg, size_t n_axes) {
  v2::Motion m;
  m.ramp = machine_hold_ramp(cfg, n_axes);
  return m;
}

StreamV2Report stream_v2_job(Link& link, const v2::Job& job, const StreamV2Options& options,
                             std::optional<v2::Ident> ident) {
  StreamV2Report rep;
  StreamV2Options opt = options;
  opt.heaters = job.heaters.any() ? &job.heaters : nullptr;
  rep.skipped_heater = job.skipped_heater;
  rep.t_raised = job.t_raised;
  rep.total_t = job.total_t;
  rep.target = job.target;
  rep.lines = job.lines;
  rep.profiles = job.profiles;
  rep.arcs = job.arcs;
  rep.dwells = job.dwells;
  rep.fifo_frames = job.fifo_frames;
  rep.heater_frames = job.heater_frames;
  const auto t0 = clock_type::now();

  // 1. Handshake; the job must fit the device.
  const v2::Ident id = handshake_v2(link, opt, rep, ident);
  check_job_fits(link, id, job);
  const size_t n_axes = id.n_axes;

  // 2. The session: CONFIG_AXIS per device axis, then the job's frames in their order, each
  // pause and message before the frame it precedes in the program.
  V2Session session(link, opt, id, rep);
  session.start();
  if (opt.motion) rep.motion = session.configure_motion(*opt.motion) ? 1 : 0;
  for (size_t a = 0; a < job.config.size() && a < n_axes; ++a) session.push({job.config[a]});
  for (const auto& f : job.travel)
    if (f.payload[0] < n_axes) session.push({f});
  size_t ei = 0;
  auto events_before = [&](size_t frame) {
    for (; ei < job.events.size() && job.events[ei].before_frame <= frame; ++ei) {
      if (const auto* p = std::get_if<gcode::Pause>(&job.events[ei].what)) session.add_pause(p);
      if (const auto* m = std::get_if<gcode::Message>(&job.events[ei].what)) session.add_message(m);
    }
  };
  for (size_t j = 0; j < job.frames.size(); ++j) {
    events_before(j);
    const v2::JobFrame& jf = job.frames[j];
    const heat::HeaterAction* ha =
        jf.heater >= 0 ? &job.heaters.actions.at(static_cast<size_t>(jf.heater)) : nullptr;
    session.push({jf.frame, jf.fifo, jf.fifo ? &jf : nullptr, ha});
  }
  events_before(SIZE_MAX);

  // 3. Until every frame is done (or the caller stops the job).
  while (!session.complete()) {
    session.poll();
    if (opt.on_poll && !opt.on_poll(session)) {
      rep.stopped = true;
      rep.unsent = session.abandon();
      const Time give_up = link.now() + opt.answer_timeout;
      while (!session.settled() && link.now() < give_up) session.poll();
      rep.queued = session.fifo_pushed() - session.fifo_done();
      break;
    }
  }

  // 4. Final status and release.
  FrameIo& io = session.io();
  rep.status_end = query_status(link, io, rep, n_axes, opt, "at the end");
  rep.moved.resize(n_axes);
  rep.position_ok = true;
  for (size_t a = 0; a < n_axes; ++a) {
    const int32_t d = static_cast<int32_t>(static_cast<uint32_t>(rep.status_end.position[a]) -
                                           static_cast<uint32_t>(rep.status_start.position[a]));
    rep.moved[a] = d;
    const int64_t want = a < 4 ? job.target[a] : 0;
    if (static_cast<int32_t>(static_cast<uint32_t>(want)) != d) rep.position_ok = false;
  }
  if (rep.stopped) rep.position_ok = false;
  if (opt.release && !rep.stopped) {
    const uint8_t rseq = static_cast<uint8_t>(rep.status_start.next_seq + session.pushed());
    const Time give_up = link.now() + opt.answer_timeout;
    while (!rep.released && link.now() < give_up) {
      io.send(v2::release(rseq));
      const Time deadline = link.now() + opt.retransmit_timeout;
      while (!rep.released) {
        const auto f = io.receive_until(deadline);
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
  session.finish_report();
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
  for (uint8_t k = 1; k <= spec::kNakReasons.size(); ++k) {
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
