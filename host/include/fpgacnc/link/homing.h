// The homing cycle on a protocol v2 board (docs/machine.md "Homing and probing (host)"): grbl
// 1.1's sequence built from TRIGGER HOME, moves, TRIGGER_QUERY and SET_POSITION
// (docs/protocol.md). Per cycle (config::Homing::cycles: Z, then X and Y together), for the
// axes with a switch wired on their homing side:
//   1. a switch of theirs already pressed: pull off it first (still pressed: ALARM 8);
//   2. seek: TRIGGER HOME with their switches, one move toward them of 1.5 x max travel at the
//      seek feed (every axis at that rate); the move ends without the trigger DONE: ALARM 9;
//   3. pull off by the pull-off distance at the seek feed (still pressed: ALARM 8);
//   4. locate: TRIGGER HOME again, a move of 2 x pull-off toward the switches at the locate
//      feed (not DONE: ALARM 9); the positions latched here are the result;
//   5. pull off again, SET_POSITION so that the pulled-off position is grbl's (homing toward max:
//      -pull-off; toward min: -max travel + pull-off), DISARM.
// Non-blocking: step() advances it and returns at once (or after one session poll). The cycle
// opens a new session (through the caller, which sends its own first frames) at the start and
// after each trigger fired, since the board drops the move it ended without a DONE. Device soft
// limits are switched off (CONFIG_TRAVEL) in the cycle's sessions; the caller's next session
// sends them again.
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

// An axis homed: its switch, the position latched at the switch's filtered edge in the locate
// move (in machine steps after homing, i.e. after the SET_POSITION), and where it was set.
struct HomedAxis {
  size_t axis = 0;
  bool max_side = true;
  int32_t latched = 0;      // machine steps (the new coordinates)
  int32_t latched_raw = 0;  // the device's position counter when latched (before SET_POSITION)
  int32_t home = 0;         // machine steps of the pulled-off position (SET_POSITION value)
};

struct HomingResult {
  bool ok = false;
  int alarm = 0;        // grbl's alarm code on failure: 8 (switch not released), 9 (not found)
  std::string message;  // on failure: what happened, naming the axes
  std::vector<HomedAxis> axes;
};

// The machine's max travel of axis a (mm): config::Homing::max_travel_mm, else [travel]'s
// extent, else 200 (grbl's default).
double homing_max_travel(const config::MachineConfig& cfg, size_t axis);
// The switch mask the cycle `axes` (bit a = axis a) homes to (bits as STATUS's switches):
// each axis's min switch when dir_invert_mask has its bit, else its max switch; only switches in
// `wired`.
uint16_t homing_switches(const config::MachineConfig& cfg, uint32_t axes, uint16_t wired);
// The machine position (steps) of the pulled-off position of axis a after homing.
int32_t homing_home_steps(const config::MachineConfig& cfg, size_t axis);

class HomingCycle {
 public:
  // `open_session`: a new session on the board, started (V2Session::start) with the caller's
  // first frames pushed; the cycle pushes its own after them. `wired`: the board's switches.
  HomingCycle(Link& link, const config::MachineConfig& cfg, const protocol::v2::Ident& ident,
              uint16_t wired, std::function<V2Session&()> open_session);
  // Advances the cycle; waits up to `wait` (link time) in the session's poll. True once finished.
  // Throws link::Error when the session fails (e.g. a hard limit of a switch not armed).
  bool step(std::chrono::milliseconds wait);
  bool finished() const { return phase_ == Phase::kFinished; }
  const HomingResult& result() const { return result_; }
  // Nothing to home: no cycle axis has a switch wired on its homing side.
  bool empty() const { return groups_.empty(); }

 private:
  enum class Phase {
    kOpen,
    kPrePull,
    kSeek,
    kPull1,
    kLocate,
    kPull2,
    kSetPosition,
    kDisarm,
    kFinished
  };
  enum class Wait { kNone, kMoveDone, kStatus, kTrigger, kTriggerFinal };
  struct Group {
    uint32_t axes = 0;      // bit a = axis a
    uint16_t switches = 0;  // their homing switches
  };

  V2Session& s() { return *session_; }
  void open();
  void move(uint32_t axes, bool toward, const std::array<double, 3>& dist_mm, double feed);
  void arm(uint16_t switches);
  void ask_status();
  bool status_fresh() const { return status_.fresh(*session_); }
  void enter(Phase p);
  void fail(int alarm, std::string msg);
  uint32_t axes_of(uint16_t switches) const;
  std::string names(uint16_t switches) const;

  Link& link_;
  config::MachineConfig cfg_;                    // travel off (the seek leaves it)
  std::array<bool, config::kAxes> travel_on_{};  // the device's soft limits the cycle turns off
  protocol::v2::Ident ident_;
  std::function<V2Session&()> open_session_;
  V2Session* session_ = nullptr;
  std::vector<Group> groups_;
  size_t group_ = 0;
  Phase phase_ = Phase::kOpen;
  Wait wait_ = Wait::kNone;
  StatusWait status_;
  TriggerWatch watch_;    // the TRIGGER HOME of the seek or locate
  uint16_t pressed_ = 0;  // pre-pull: the switches pressed at the start of the group
  std::vector<protocol::v2::TriggerReport> locate_;  // per group: the locate's report
  HomingResult result_;
};

}  // namespace fpgacnc::link
