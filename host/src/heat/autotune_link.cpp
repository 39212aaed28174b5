#include "fpgacnc/heat/autotune_link.h"

#include <fmt/format.h>

#include <cmath>
#include <functional>

#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/stream_v2.h"

namespace fpgacnc::heat {
namespace v2 = protocol::v2;
// Timers (answers, polls) run in link time (link::Link::now(): wall time on a port, board
// clocks on a simulated board); wall_s is a report.
using clock_type = std::chrono::steady_clock;
using Time = link::Link::Time;
using std::chrono::milliseconds;

namespace {

// A minimal stop-and-wait v2 session: sequenced frames one at a time, STATUS polls.
class MiniSession {
 public:
  MiniSession(link::Link& l, milliseconds timeout) : l_(l), timeout_(timeout) {}

  std::optional<v2::Frame> receive_until(Time deadline) {
    for (;;) {
      if (auto f = parser_.next()) return f;
      if (auto b = l_.read_byte_until(deadline)) {
        parser_.feed(*b);
      } else {
        return std::nullopt;
      }
    }
  }
  void write(const v2::Frame& f) { l_.write(v2::encode(f)); }

  // `stamp` (if set) is called right before each STATUS_QUERY goes out: the device fills STATUS
  // from its live state when the answer starts, a fixed few bytes later, while the host may read
  // the answer late (scheduling), so the time of the query is the better time stamp.
  v2::Status status(size_t n_axes, const std::function<void()>& stamp = {}) {
    const Time give_up = l_.now() + timeout_;
    while (l_.now() < give_up) {
      if (stamp) stamp();
      write(v2::status_query());
      const Time deadline = l_.now() + kRetry;
      for (;;) {
        const auto f = receive_until(deadline);
        if (!f) break;
        if (f->type == static_cast<uint8_t>(v2::Type::Status)) {
          try {
            return v2::decode_status(*f, n_axes);
          } catch (const v2::ProtocolError&) {
          }
        }
      }
    }
    throw link::Error(fmt::format("{}: autotune: no STATUS answer within {:.3g} s{}", l_.name(),
                                  static_cast<double>(timeout_.count()) / 1000.0,
                                  l_.board_clock() ? " of board time" : ""));
  }

  // Sends `f` with SEQ next_seq_ until an ACK moves next_seq past it.
  void send(v2::Frame f) {
    f.seq = next_seq_;
    const Time give_up = l_.now() + timeout_;
    while (l_.now() < give_up) {
      write(f);
      const Time deadline = l_.now() + kRetry;
      for (;;) {
        const auto r = receive_until(deadline);
        if (!r) break;
        try {
          if (r->type == static_cast<uint8_t>(v2::Type::Ack)) {
            if (v2::decode_credit(*r).next_seq == static_cast<uint8_t>(f.seq + 1)) {
              ++next_seq_;
              return;
            }
          } else if (r->type == static_cast<uint8_t>(v2::Type::Nak)) {
            const auto k = v2::decode_nak(*r);
            if (k.reason == v2::NakReason::BadField || k.reason == v2::NakReason::UnknownType ||
                k.reason == v2::NakReason::BadLength) {
              throw link::Error(fmt::format("{}: device refuses {}: NAK {}", l_.name(),
                                            v2::type_name(f.type),
                                            v2::nak_reason_name(static_cast<uint8_t>(k.reason))));
            }
            break;
          }
        } catch (const v2::ProtocolError&) {
        }
      }
    }
    throw link::Error(fmt::format(
        "{}: autotune: {} not acknowledged within {:.3g} s{}", l_.name(), v2::type_name(f.type),
        static_cast<double>(timeout_.count()) / 1000.0, l_.board_clock() ? " of board time" : ""));
  }
  uint8_t next_seq_ = 0;

 private:
  static constexpr milliseconds kRetry{300};  // resend after this long without the answer

  link::Link& l_;
  milliseconds timeout_;
  v2::FrameParser parser_;
};

}  // namespace

AutotuneLinkResult run_relay_test(link::Link& lk, const config::MachineConfig& cfg,
                                  const AutotuneLinkOptions& o) {
  if (o.channel >= kChannels) throw link::Error("autotune: channel must be 0 (hotend) or 1 (bed)");
  const HeaterConfig& hc = cfg.heaters.ch[o.channel];
  if (o.relay.u_low != 0.0) throw link::Error("autotune: the device relay goes from 0 (u_low 0)");
  if (!(o.relay.u_high > 0.0) || o.relay.u_high > hc.supply_v) {
    throw link::Error(fmt::format("autotune: relay output {:g} V outside (0, {:g}] (supply_v)",
                                  o.relay.u_high, hc.supply_v));
  }
  if (o.relay.setpoint_c >= hc.max_temp_c) {
    throw link::Error(fmt::format("autotune: setpoint {:g} degC at or above max_temp_c {:g}",
                                  o.relay.setpoint_c, hc.max_temp_c));
  }
  const auto t0 = clock_type::now();
  const Time link_t0 = lk.now();
  auto plant_now = [&]() {
    return o.plant_time ? o.plant_time() : link::seconds(lk.now() - link_t0);
  };
  const auto ident = link::probe_v2(lk, milliseconds(300));
  if (!ident) throw link::Error(fmt::format("{}: no IDENT answer to HELLO (v2 needed)", lk.name()));
  MiniSession s(lk, o.answer_timeout);
  const size_t n_axes = ident->n_axes;
  v2::Status st = s.status(n_axes);
  if (st.heaters.size() <= o.channel) {
    throw link::Error(fmt::format("{}: the device reports no heaters in STATUS", lk.name()));
  }
  s.next_seq_ = st.next_seq;
  if (st.faults) s.send(v2::fault_clear(0));

  // Relay = ON_OFF mode, duty_max = u_high / supply, the relay hysteresis.
  HeaterConfig relay = hc;
  relay.mode = Mode::kOnOff;
  relay.u_max_v = o.relay.u_high;
  relay.hysteresis_c = o.relay.hysteresis_c;
  s.send(v2::heater_config(0, config_frame(relay, o.channel)));
  s.send(v2::heater_safety(0, safety_frame(hc, o.channel)));
  const auto table = thermistor_table(hc);
  for (size_t i = 0; i < table.size(); i += v2::kThermistorChunk) {
    v2::ThermistorChunk ch{o.channel, static_cast<uint8_t>(i), {}};
    ch.entries.assign(table.begin() + static_cast<std::ptrdiff_t>(i),
                      table.begin() + static_cast<std::ptrdiff_t>(
                                          std::min(table.size(), i + v2::kThermistorChunk)));
    s.send(v2::thermistor_table(0, ch));
  }
  s.send(v2::heater_watchdog(0, ticks(cfg.heaters.watchdog_s, hc.sample_s)));
  s.send(v2::heater_setpoint(0, o.channel, to_q4(o.relay.setpoint_c)));

  AutotuneLinkResult r;
  const double p0 = plant_now();
  auto finish = [&]() {
    // Heater off, configured mode back.
    s.send(v2::heater_setpoint(0, o.channel, 0));
    s.send(v2::heater_config(0, config_frame(hc, o.channel)));
    s.send(v2::release(0));
  };
  try {
    for (;;) {
      double t_query = 0.0;
      const auto h = s.status(n_axes, [&] { t_query = plant_now(); });
      const auto& hs = h.heaters.at(o.channel);
      const double t = t_query - p0;
      const uint8_t bad =
          h.faults & (v2::kFaultWatchdog | v2::kFaultEstop | v2::kFaultHotend | v2::kFaultBed);
      if (hs.faults || bad) {
        throw link::Error(fmt::format("{}: autotune stopped after {:.0f} s: {}", lk.name(), t,
                                      describe_faults(h, bad)));
      }
      RelaySample smp{t, hs.temp_c(), hs.duty() * hc.supply_v};
      r.samples.push_back(smp);
      r.setpoints.push_back(hs.setpoint_c());
      if (o.on_sample) o.on_sample(smp, hs);
      if (r.samples.size() % 8 == 0) {
        r.result = analyse_relay(r.samples, o.relay);
        if (r.result.ok) break;
      }
      if (t > o.max_plant_s) {
        r.result = analyse_relay(r.samples, o.relay);
        if (!r.result.ok) {
          throw link::Error(fmt::format("{}: autotune: no result after {:.0f} s: {}", lk.name(), t,
                                        r.result.message));
        }
        break;
      }
      lk.wait_until(lk.now() + o.poll);
    }
  } catch (...) {
    try {
      finish();
    } catch (...) {
    }
    throw;
  }
  finish();
  r.plant_s = plant_now() - p0;
  r.wall_s = std::chrono::duration<double>(clock_type::now() - t0).count();
  return r;
}

}  // namespace fpgacnc::heat
