// A protocol v2 session built incrementally (docs/protocol.md, "Host streaming"): the IDENT
// handshake, then sequenced frames pushed as they are planned, sent through the go-back-N window
// (send_window.h) as the device's credit allows, with the heater gate (M109/M190), pauses and
// messages at their place. stream_v2_job (stream_v2.h) pushes a whole job and drains it; a line
// front end (fpgacnc grbl) pushes frames as lines arrive and polls.
//
// Counts: pushed() sequenced frames, acked() acknowledged, fifo_pushed() FIFO frames of which
// fifo_done() have completed on the device (`segments done`). Every timer runs in link time.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/link/send_window.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/protocol/v2.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::link {

// Device frames in, host frames out, with the session's byte and parser counters.
class FrameIo {
 public:
  FrameIo(Link& link, StreamV2Report& rep);
  void send(const protocol::v2::Frame& f);
  void send_batch(const std::vector<uint8_t>& bytes, size_t frames);  // several frames, one write
  // Next good device frame by `deadline` (link time; nullopt when none). Duplicates are counted.
  std::optional<protocol::v2::Frame> receive_until(Link::Time deadline);
  std::optional<protocol::v2::Frame> receive(std::chrono::milliseconds timeout);
  // A frame of `type` by `deadline` (others ignored).
  std::optional<protocol::v2::Frame> await_type(protocol::v2::Type type, Link::Time deadline);
  void finish_counters();
  Link::Time last_rx() const { return last_rx_; }
  // After a pause of our own: the silence was ours, not the device's.
  void restart_silence() { last_rx_ = link_.now(); }

 private:
  Link& link_;
  StreamV2Report& rep_;
  protocol::v2::FrameParser parser_;
  std::vector<uint8_t> buf_;
  protocol::v2::Frame last_frame_;
  bool have_last_ = false;
  Link::Time last_rx_;    // link time of the last good device frame
  Link::Time last_byte_;  // link time of the last byte read
};

// STATUS_QUERY until a STATUS arrives (resent every retransmit_timeout); Error after
// answer_timeout naming `when` ("at the start").
protocol::v2::Status query_status(Link& link, FrameIo& io, StreamV2Report& rep, size_t n_axes,
                                  const StreamV2Options& opt, const char* when);

// HELLO -> IDENT (`ident` when already known: no HELLO), checks the version and a FIFO depth.
// Throws Error.
protocol::v2::Ident handshake_v2(Link& link, const StreamV2Options& opt, StreamV2Report& rep,
                                 std::optional<protocol::v2::Ident> ident);
// Whether a packed job fits the device (axes, clock, payload); throws Error naming the link.
void check_job_fits(const Link& link, const protocol::v2::Ident& ident,
                    const protocol::v2::Job& job);

// One sequenced frame of a session. `jf` / `heater` (optional, kept by the caller) name it in
// messages; `source_line` names it when there is no `jf`.
struct SessionItem {
  protocol::v2::Frame frame;
  bool fifo = false;
  const protocol::v2::JobFrame* jf = nullptr;
  const heat::HeaterAction* heater = nullptr;
  int source_line = 0;
};

class V2Session {
 public:
  // `rep` collects the counters (kept by the caller); `opt.heaters` gives the heater gate.
  V2Session(Link& link, const StreamV2Options& opt, const protocol::v2::Ident& ident,
            StreamV2Report& rep);

  // STATUS_QUERY until answered, waiting while a previous job still runs (its DONEs would count
  // into ours); a latched fault is cleared with FAULT_CLEAR (the first frame). Call once.
  const protocol::v2::Status& start();
  // Appends one frame. A heater setpoint with `heater->wait` holds everything after it until the
  // FIFO has drained and the temperature settled (StreamV2Options heater fields).
  void push(SessionItem item);
  // A pause or message before the next pushed frame (pointers kept by the caller).
  void add_pause(const gcode::Pause* p);
  void add_message(const gcode::Message* m);
  // One round: sends what the window and credit allow, handles the answers, runs the timers;
  // waits up to `wait` (link time) for an answer when nothing went out.
  void poll(std::chrono::milliseconds wait = std::chrono::milliseconds(20));
  // Ends the heater wait in progress (the next M109/M190 setpoint pushed; Marlin's M108) at the
  // next STATUS once its setpoint is acknowledged, without waiting for the FIFO or the
  // temperature (the setpoint stays); the wait's report says `cancelled`. False when no wait is
  // pending.
  bool cancel_heater_wait();
  // Everything pushed is acknowledged and done, every wait and pause passed.
  bool complete() const;
  // poll() until complete().
  void drain();
  // A STATUS_QUERY now (unless one is outstanding and `fresh` is false); the answer goes to
  // last_status().
  void request_status(bool fresh = false);
  // A TRIGGER_QUERY now (unsequenced, resent by calling again; docs/protocol.md "TRIGGER_QUERY");
  // its TRIGGER_REPORT goes to last_trigger(), counted by trigger_answers(). TRIGGER and
  // SET_POSITION are pushed as any sequenced frame (push({frame}), not FIFO frames).
  void request_trigger();
  size_t trigger_answers() const { return trigger_answers_; }
  const protocol::v2::TriggerReport& last_trigger() const { return last_trigger_; }
  // Frames sent that the device answers with STATUS (STATUS_QUERY, MOTION) whose answers have not
  // come yet (those older than a retransmission timeout count as lost). The answers come in
  // order: a STATUS that reflects the device after a given moment is the one numbered
  // status_answers() + status_unanswered() right after a fresh request_status() then.
  size_t status_unanswered() const { return status_unanswered_; }
  // MOTION (docs/protocol.md "MOTION": feed hold, resume, feed / rapid rates and the hold ramp;
  // unsequenced, answered with STATUS). configure_motion: right after start(), before anything
  // else is sent: sends `m` and waits for its answer (resent on a lost answer); true when the
  // device took it, false when it answers NAK UNKNOWN_TYPE (a device without the motion rate:
  // no feed hold or overrides there); Error when it refuses the fields or never answers.
  bool configure_motion(const protocol::v2::Motion& m);
  // Sends `m` now (a device that took configure_motion); resent every retransmission timeout
  // until a STATUS shows it: with HOLD the HOLD bit set, with RESUME clear, else any STATUS.
  void send_motion(const protocol::v2::Motion& m);
  bool motion_pending() const { return motion_pending_; }
  // configure_motion() was answered with STATUS: the device has the motion rate.
  bool motion_available() const { return motion_available_; }
  // The last MOTION sent (the rates in effect on the device).
  const protocol::v2::Motion& motion() const { return motion_; }
  // Gives up every pushed frame not yet sent (frames on the line stay in the window until
  // acknowledged); returns how many were dropped. From then on latched faults are not errors
  // (the caller may press the e-stop to drop the board's queue): the session is only left.
  size_t abandon();
  // Everything sent has been acknowledged (after abandon: the session can be left).
  bool settled() const { return win_.acked() == items_.size(); }

  size_t pushed() const { return items_.size(); }
  size_t acked() const { return win_.acked(); }
  size_t unsent() const { return items_.size() - win_.high(); }
  size_t fifo_pushed() const { return fifo_before_.back(); }
  size_t fifo_done() const { return done_count_; }
  size_t status_answers() const { return status_answers_; }
  const protocol::v2::Status& last_status() const { return last_status_; }
  const protocol::v2::Ident& ident() const { return ident_; }
  FrameIo& io() { return io_; }
  // Copies the window's figures and the parser counters into the report.
  void finish_report();

 private:
  void poll_once(std::chrono::milliseconds wait);
  void handle(const protocol::v2::Frame& f);
  bool update(uint8_t next_seq, uint16_t free, std::optional<uint32_t> done);
  void go_back();
  void check_stuck(size_t acked, size_t same) const;  // Error after too many go-backs
  void on_status(const protocol::v2::Status& s);
  void asked_status();  // a frame the device answers with STATUS was sent
  void check_faults(const protocol::v2::Status& s);
  void wait_status(const protocol::v2::Status& s);
  size_t gate() const;
  std::string item_name(size_t i) const;
  std::string current_line() const;
  double plant_now() const;

  Link& link_;
  StreamV2Options opt_;
  protocol::v2::Ident ident_;
  StreamV2Report& rep_;
  FrameIo io_;
  std::string name_;
  const heat::HeaterJob* hj_ = nullptr;
  std::string src_;  // "FILE:" of the heater job for messages

  std::vector<SessionItem> items_;
  std::vector<size_t> fifo_before_{0};  // FIFO frames in [0, i)
  std::vector<size_t> fifo_item_;       // item index of the k-th FIFO frame
  std::vector<size_t> waits_;           // item indices of M109/M190 setpoints
  std::vector<std::pair<size_t, const gcode::Pause*>> pauses_;
  std::vector<std::pair<size_t, const gcode::Message*>> messages_;
  size_t next_wait_ = 0, next_pause_ = 0, next_message_ = 0;
  bool cancel_wait_ = false;  // cancel_heater_wait(): the wait at next_wait_ ends
  size_t clear_items_ = 0;    // faults are checked once these are acknowledged

  SendWindow win_;
  uint32_t done0_ = 0;
  size_t free_slots_ = 0;
  size_t done_count_ = 0;
  bool have_credit_ = true;
  size_t fatal_nak_count_ = 0;
  Link::Time last_poll_{};
  Link::Time last_heater_poll_{};
  Link::Time link_t0_{};
  protocol::v2::Motion motion_;
  bool motion_pending_ = false;
  bool motion_available_ = false;
  Link::Time motion_sent_{};
  size_t status_unanswered_ = 0;
  Link::Time last_status_ask_{};
  bool status_outstanding_ = false;
  Link::Time status_sent_{};
  size_t status_answers_ = 0;
  protocol::v2::Status last_status_;
  size_t trigger_answers_ = 0;
  bool trigger_outstanding_ = false;
  protocol::v2::TriggerReport last_trigger_;
  bool was_complete_ = false;  // complete at the last poll (the caller had nothing to send)
  bool aborting_ = false;
  std::vector<uint8_t> batch_;
  struct WaitState {
    bool started = false;  // setpoint accepted and FIFO drained
    bool in_band = false;
    double band_since = 0.0, start_plant = 0.0, start_c = 0.0;
    std::chrono::steady_clock::time_point start_wall{};
  } ws_;
};

}  // namespace fpgacnc::link
