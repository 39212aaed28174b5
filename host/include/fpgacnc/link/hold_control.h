// Feed hold, resume and overrides of a streamed job (`fpgacnc stream`, README.md "Feed
// hold and overrides"): the operator's keys and the interrupt (SIGINT) turned into MOTION frames
// (docs/protocol.md "MOTION") through a running V2Session. No terminal I/O here: the command reads
// the keys and the signal and answers the question through HoldControl::Io.
//
// Keys: '!' or ' ' hold, '~' or 'c' resume, 'f' / 'F' feed override -10 / +10 % (10..200 %),
// 'r' rapid override 100 -> 50 -> 25 -> 100 %. The board's rates are at most 100 % (a segment
// never runs faster than planned): a feed override above 100 % is kept and shown, but a job
// packed before it started runs at its planned speed (--feed-override plans it faster).
// Interrupt: a hold (unless one is in effect), then, once the board reports it complete (HOLD
// and STOPPED), the question: resume; stop (MOTION CANCEL: the board drops its queue at rest,
// positions kept, and the frames not yet sent are dropped); or keep (the frames not yet sent are
// dropped, the board keeps its queue, held). Without a terminal to ask: stop. A device without
// MOTION cannot hold: the first interrupt says so and the job goes on, the second stops sending
// (the board runs out what it has queued).
#pragma once

#include <functional>
#include <string>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/v2_session.h"

namespace fpgacnc::link {

class HoldControl {
 public:
  struct Io {
    std::function<void(const std::string&)> say;  // one line for the operator
    // After an interrupt's hold is complete, `where` the machine is held: the operator's choice.
    // Unset (no terminal): kStop.
    enum class Answer { kResume, kStop, kKeep };
    std::function<Answer(const std::string& where)> ask;
  };
  HoldControl(const config::MachineConfig& cfg, Io io);

  void key(char c);  // acted on at the next poll()
  void interrupt();  // SIGINT seen (call from the polling thread, not the handler)
  // StreamV2Options::on_poll: sends what the keys and the interrupt asked for; false stops the
  // job.
  bool poll(V2Session& s);

  int feed_pct() const { return feed_; }
  int rapid_pct() const { return rapid_; }
  bool holding() const { return held_; }
  // The job was stopped with MOTION CANCEL (the board dropped its queue) rather than kept.
  bool cancelled() const { return cancelled_; }
  // "X 1.000 Y 2.000 Z 0.000 mm" from a STATUS.
  std::string where(const protocol::v2::Status& st) const;

 private:
  void send(V2Session& s, bool hold, bool resume, bool cancel = false);
  void say(const std::string& l) const;

  config::MachineConfig cfg_;
  Io io_;
  std::string keys_;
  int interrupts_ = 0;  // not yet acted on
  int interrupts_nohold_ = 0;
  bool held_ = false;    // a hold of ours is in effect
  bool asking_ = false;  // an interrupt's hold: ask once it is complete
  bool told_no_motion_ = false;
  bool cancelling_ = false;  // MOTION CANCEL sent: the job stops once the board is at rest, empty
  bool cancelled_ = false;
  int feed_ = 100, rapid_ = 100;
};

}  // namespace fpgacnc::link
