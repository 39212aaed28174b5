// The probing cycle on a protocol v2 board (docs/machine.md "Homing and probing (host)"): grbl
// 1.1's G38.2 .. G38.5 built from TRIGGER PROBE, one move and TRIGGER_QUERY (docs/protocol.md):
//   1. a new session; its first STATUS's PROBE bit (state bit 7) must be the opposite of the
//      level the cycle waits for: G38.2 / G38.3 (toward contact) with the probe already touching,
//      or G38.4 / G38.5 (away, to the release) with it not touching, is grbl's ALARM 4 (the
//      trigger fires only on an edge); nothing moves;
//   2. TRIGGER PROBE (mode 2 contact, 3 release), then one LINE_PROFILE from the board's position
//      to the target at the feed; TRIGGER_QUERY while it runs (no STATUS polls: see step());
//   3. DONE: the board latched every axis at the clock of the probe's filtered edge and cancels
//      the move with its deceleration ramp (the move is dropped, positions kept); once STATUS
//      shows it at rest, a new session (DISARM in it) whose STATUS is where the machine stopped,
//      past the latched point by the stopping distance;
//   4. the move's DONE without the trigger's (one more TRIGGER_QUERY after it): no edge within
//      the move; DISARM (an armed PROBE would end a later move); ALARM 5 when the request says
//      so (G38.2, G38.4), else a result with found = false (G38.3, G38.5).
// Non-blocking as link::HomingCycle: step() advances it and returns at once (or after one
// session poll); the sessions come from the caller (`open_session`), which pushes its own first
// frames. The caller's last session is the one open when the cycle finishes (settled, complete).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/trigger_watch.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::link {

struct ProbeRequest {
  std::array<double, 3> target_mm{};  // machine position (X, Y, Z) the move ends at
  double feed_mm_min = 0.0;           // > 0
  bool toward = true;                 // G38.2 / G38.3: contact; else the release (G38.4 / G38.5)
  bool error_on_miss = true;          // G38.2 / G38.4: no edge within the move is ALARM 5
};

struct ProbeResult {
  bool ok = false;      // no alarm
  bool found = false;   // the trigger fired (grbl's PRB success flag)
  int alarm = 0;        // 4: the probe already at the level at the start; 5: no edge (G38.2/.4)
  std::string message;  // on an alarm: what happened
  // Per device axis (steps, the board's counters): the start, the position latched at the probe's
  // filtered edge (found; else where the move ended, as grbl reports a miss) and where the
  // machine is at rest after the cycle.
  std::vector<int32_t> start, latched, final_position;
  // Steps of the move the cycle sent (per X, Y, Z); all 0 after ALARM 4.
  std::array<int64_t, 3> move_steps{};
};

class ProbeCycle {
 public:
  ProbeCycle(Link& link, const config::MachineConfig& cfg, const protocol::v2::Ident& ident,
             ProbeRequest request, std::function<V2Session&()> open_session);
  // Advances the cycle; waits up to `wait` (link time) in the session's poll. True once finished.
  // Throws link::Error when the session fails (e.g. the board refuses TRIGGER: NAK).
  bool step(std::chrono::milliseconds wait);
  bool finished() const { return phase_ == Phase::kFinished; }
  const ProbeResult& result() const { return result_; }

 private:
  enum class Phase { kOpen, kMove, kFinal, kRest, kDisarm, kFinished };

  V2Session& s() { return *session_; }
  void start();
  void ask_status() { status_.ask(s()); }
  bool status_fresh() const { return status_.fresh(*session_); }
  std::vector<int32_t> position() const;

  Link& link_;
  config::MachineConfig cfg_;  // travel off: the move is planned from 0 (relative)
  protocol::v2::Ident ident_;
  ProbeRequest req_;
  std::function<V2Session&()> open_session_;
  V2Session* session_ = nullptr;
  Phase phase_ = Phase::kOpen;
  StatusWait status_;
  TriggerWatch watch_;         // the TRIGGER PROBE
  bool status_asked_ = false;  // kRest / kDisarm: the fresh STATUS asked
  ProbeResult result_;
};

}  // namespace fpgacnc::link
