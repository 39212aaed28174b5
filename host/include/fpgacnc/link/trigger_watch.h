// The TRIGGER_QUERY side of a host cycle that watches one TRIGGER (link::HomingCycle,
// link::ProbeCycle; docs/machine.md "Homing and probing (host)"): a query is sent only once that
// TRIGGER is acknowledged (an answer to a query ahead of it would show the previous trigger's
// state) and again when no answer came within kResend of link time; answered() tells when the
// TRIGGER_REPORT of the query in flight has arrived (V2Session::last_trigger()). StatusWait is
// the STATUS side of the same cycles: a STATUS newer than a point of the session, and the board
// at rest after a move it dropped.
#pragma once

#include <chrono>
#include <cstddef>

#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::link {

class TriggerWatch {
 public:
  static constexpr std::chrono::milliseconds kResend{300};

  // The TRIGGER just pushed on `s` is the one to watch; no query in flight.
  void armed(const V2Session& s) {
    item_ = s.pushed() - 1;
    asked_ = false;
  }
  // Sends a TRIGGER_QUERY on `s` if one is due at link time `now`.
  void ask(V2Session& s, Link::Time now) {
    if (s.acked() <= item_) return;
    if (asked_ && now - asked_at_ < kResend) return;
    target_ = s.trigger_answers() + 1;
    s.request_trigger();
    asked_ = true;
    asked_at_ = now;
  }
  // A query is in flight.
  bool asked() const { return asked_; }
  // The answer to the query in flight has come (true once; no query in flight afterwards).
  bool answered(const V2Session& s) {
    if (!asked_ || s.trigger_answers() < target_) return false;
    asked_ = false;
    return true;
  }

 private:
  size_t item_ = 0;    // the session item of the TRIGGER
  size_t target_ = 0;  // trigger_answers() once the query in flight is answered
  bool asked_ = false;
  Link::Time asked_at_{};
};

class StatusWait {
 public:
  // Asks for a STATUS now; fresh() once it (and every STATUS owed before it) has come.
  void ask(V2Session& s) {
    s.request_status(true);
    target_ = s.status_answers() + s.status_unanswered();
  }
  bool fresh(const V2Session& s) const { return s.status_answers() >= target_; }
  // After ask() behind a move the board drops: true once a fresh STATUS shows the session
  // settled and the motion idle; otherwise polls, or asks again while the board is busy.
  bool at_rest(V2Session& s) {
    if (!fresh(s) || !s.settled()) {
      s.request_status();
      return false;
    }
    if (s.last_status().state & protocol::v2::kStateBusy) {
      ask(s);
      return false;
    }
    return true;
  }

 private:
  size_t target_ = 0;  // status_answers() once the STATUS asked has come
};

}  // namespace fpgacnc::link
