// fpgacnc status [--port DEV] [--config F]
//
// One STATUS of a protocol-v2 device, decoded for people: state, faults (with the hard-limit
// alarm and the switch that tripped), the limit switches now, FIFO level, positions and counters
// (docs/protocol.md "STATUS", docs/machine.md). HELLO first (N_AXES from IDENT), then
// STATUS_QUERY; neither is sequenced, so nothing on the device changes. Without --port the
// simulated board (in-process, fresh: idle, no switches).
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "commands.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::cli {
namespace {

namespace v2 = protocol::v2;

struct StatusArgs {
  std::string port;
  CommonOptions common;
  SimOutputOptions sim;
};

// Sends `query` until a frame of `want` comes back (every 300 ms, for 3 s of link time).
v2::Frame ask(link::Link& lk, v2::FrameParser& parser, const v2::Frame& query, v2::Type want) {
  using std::chrono::milliseconds;
  const link::Link::Time give_up = lk.now() + milliseconds(3000);
  while (lk.now() < give_up) {
    lk.write(v2::encode(query));
    const link::Link::Time deadline = lk.now() + milliseconds(300);
    for (;;) {
      if (auto f = parser.next()) {
        if (f->type == static_cast<uint8_t>(want)) return *f;
        continue;
      }
      const auto b = lk.read_byte_until(deadline);
      if (!b) break;
      parser.feed(*b);
    }
  }
  throw link::Error(fmt::format("{}: no {} answer within 3 s", lk.name(),
                                want == v2::Type::Ident ? "IDENT" : "STATUS"));
}

std::string bits(uint8_t v, std::initializer_list<std::pair<uint8_t, const char*>> names) {
  std::string s;
  for (const auto& [m, n] : names) {
    if (v & m) s += (s.empty() ? "" : " ") + std::string(n);
  }
  return s.empty() ? "none" : s;
}

void run_status(const StatusArgs& a, const StreamHooks& hooks) {
  const config::MachineConfig cfg = load_config(a.common);
  const std::string port = a.port.empty() ? cfg.port : a.port;
  std::unique_ptr<link::Link> lk;
  if (port.empty()) {
    lk = hooks.open_default_link(cfg, a.sim);
  } else {
    lk = std::make_unique<link::SerialLink>(port, cfg.baud);
  }
  v2::FrameParser parser;
  const v2::Ident id = v2::decode_ident(ask(*lk, parser, v2::hello(), v2::Type::Ident));
  const v2::Status s =
      v2::decode_status(ask(*lk, parser, v2::status_query(), v2::Type::Status), id.n_axes);
  fmt::print("{}: {} axes, FIFO {} entries\n", lk->name(), id.n_axes, id.fifo_depth);
  fmt::print("state: {}\n", bits(s.state, {{v2::kStateBusy, "BUSY"},
                                           {v2::kStateV2, "V2"},
                                           {v2::kStateFault, "FAULT"},
                                           {v2::kStateEstop, "ESTOP"},
                                           {v2::kStatePosUntrusted, "POSITIONS_NOT_TRUSTED"}}));
  fmt::print("faults: {}\n", bits(s.faults, {{v2::kFaultStepTiming, "STEP_TIMING"},
                                             {spec::kFaultArc, "ARC"},
                                             {v2::kFaultLimit, "LIMIT"},
                                             {v2::kFaultEstop, "ESTOP"},
                                             {v2::kFaultWatchdog, "WATCHDOG"},
                                             {v2::kFaultHotend, "HOTEND"},
                                             {v2::kFaultBed, "BED"}}));
  fmt::print("limits: {}\n", v2::describe_limits(s, id.n_axes));
  fmt::print("FIFO level {}, next_seq {}, segments done {}\n", s.fifo_level, s.next_seq, s.done);
  std::string pos;
  for (const int32_t p : s.position) pos += fmt::format("{}{}", pos.empty() ? "" : " ", p);
  fmt::print("position (steps): {}\n", pos);
  std::string ctr;
  for (size_t i = 0; i < v2::kCounters; ++i) {
    ctr += fmt::format("{}{} {}", i ? ", " : "", v2::counter_name(i), s.counters[i]);
  }
  fmt::print("counters: {}\n", ctr);
}

}  // namespace

void register_status(CLI::App& app, StreamHooks hooks) {
  auto args = std::make_shared<StatusArgs>();
  auto* sub = app.add_subcommand(
      "status", "One STATUS of a v2 device, decoded: state, faults, limit switches, positions");
  sub->add_option("--port", args->port, "serial port (default: the simulated board)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->callback([args, hooks = std::move(hooks)] { run_status(*args, hooks); });
}

}  // namespace fpgacnc::cli
