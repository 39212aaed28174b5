// The TRIGGER_QUERY side of a host cycle that watches one TRIGGER (link::HomingCycle,
// link::ProbeCycle; docs/machine.md "Homing and probing (host)"): a query is sent only once that
// TRIGGER is acknowledged (an answer to a query ahead of it would show the previous trigger's
// state) and again when no answer came within kResend of link time; answered() tells when the
// TRIGGER_REPORT of the query in flight has arrived (V2Session::last_trigger()).
#pragma once

#include <chrono>
#include <cstddef>

#include "fpgacnc/link/v2_session.h"

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

}  // namespace fpgacnc::link
