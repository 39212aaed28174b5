#include "fpgacnc/link/hold_control.h"

#include <fmt/format.h>

#include <algorithm>

namespace fpgacnc::link {
namespace v2 = protocol::v2;

HoldControl::HoldControl(const config::MachineConfig& cfg, Io io) : cfg_(cfg), io_(std::move(io)) {}

void HoldControl::key(char c) {
  keys_.push_back(c);
}

void HoldControl::interrupt() {
  ++interrupts_;
}

void HoldControl::say(const std::string& l) const {
  if (io_.say) io_.say(l);
}

std::string HoldControl::where(const v2::Status& st) const {
  std::string s;
  static constexpr const char* kNames = "XYZ";
  for (size_t a = 0; a < 3 && a < st.position.size(); ++a)
    s += fmt::format("{}{} {:.3f}", a ? " " : "", kNames[a],
                     static_cast<double>(st.position[a]) / cfg_.steps_per_mm[a]);
  return s + " mm";
}

void HoldControl::send(V2Session& s, bool hold, bool resume, bool cancel) {
  v2::Motion m = s.motion();
  m.hold = hold;
  m.resume = resume;
  m.cancel = cancel;
  m.feed = v2::rate_from_percent(std::min(feed_, 100));
  m.rapid = v2::rate_from_percent(rapid_);
  s.send_motion(m);
}

bool HoldControl::poll(V2Session& s) {
  if (!s.motion_available()) {
    if (!keys_.empty() && !told_no_motion_) {
      say("keys: this device has no feed hold or overrides (it refused MOTION)");
      told_no_motion_ = true;
    }
    keys_.clear();
    interrupts_nohold_ += interrupts_;
    if (interrupts_ && interrupts_nohold_ == 1) {
      say("interrupt: this device cannot hold (it refused MOTION); the job goes on. Interrupt "
          "again to stop sending (the board then runs out the frames it has queued)");
    }
    interrupts_ = 0;
    return interrupts_nohold_ < 2;
  }
  if (cancelling_) {
    // Stopped once the board has dropped its queue: at rest, nothing queued, the hold over.
    keys_.clear();
    interrupts_ = 0;
    const auto& st = s.last_status();
    if (!s.motion_pending() && !(st.state & (v2::kStateHold | v2::kStateBusy)) &&
        st.fifo_level == 0) {
      cancelled_ = true;
      return false;
    }
    s.request_status();
    return true;
  }
  const bool board_hold = (s.last_status().state & v2::kStateHold) != 0;
  for (const char c : keys_) {
    switch (c) {
      case '!':
      case ' ':
        if (held_) break;
        held_ = true;
        send(s, true, false);
        say("feed hold (~ or c resumes)");
        break;
      case '~':
      case 'c':
        if (!held_ && !board_hold) break;
        held_ = asking_ = false;
        send(s, false, true);
        say("resume");
        break;
      case 'f':
      case 'F':
      case 'r': {
        if (c == 'r') {
          rapid_ = rapid_ == 100 ? 50 : rapid_ == 50 ? 25 : 100;
        } else {
          feed_ = std::clamp(feed_ + (c == 'F' ? 10 : -10), 10, 200);
        }
        send(s, false, false);
        say(fmt::format("feed {} %, rapid {} %{}", feed_, rapid_,
                        feed_ > 100 ? " (above 100 %: this job was planned before it started and "
                                      "runs at most at its planned speed; --feed-override plans "
                                      "it faster)"
                                    : ""));
        break;
      }
      default:
        break;
    }
  }
  keys_.clear();
  if (interrupts_) {
    interrupts_ = 0;
    asking_ = true;
    if (!held_) {
      held_ = true;
      send(s, true, false);
      say("interrupt: feed hold, decelerating to rest on the path");
    }
  }
  if (asking_) {
    const uint8_t b = s.last_status().state;
    const bool complete = !s.motion_pending() && (b & v2::kStateHold) && (b & v2::kStateStopped);
    if (!complete) {
      s.request_status();
      return true;
    }
    asking_ = false;
    const std::string at = where(s.last_status());
    Io::Answer a = Io::Answer::kStop;
    if (io_.ask) {
      a = io_.ask(at);
    } else {
      say(fmt::format("held at {}; no terminal to ask: stopping here", at));
    }
    if (a == Io::Answer::kKeep) return false;
    if (a == Io::Answer::kStop) {
      cancelling_ = true;
      send(s, false, false, true);
      say("stop: MOTION CANCEL, the board drops its queue at rest, positions kept");
      return true;
    }
    held_ = false;
    send(s, false, true);
    say("resume");
  }
  return true;
}

}  // namespace fpgacnc::link
