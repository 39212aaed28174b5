// v2 streamer: the sliding window of docs/protocol.md ("Host streaming").
//
//  1. flush input, HELLO -> IDENT (version 2; a job needing more axes than N_AXES or a frame
//     longer than MAX_PAYLOAD is refused before anything sequenced is sent), STATUS_QUERY ->
//     STATUS (waits while the device is still busy; `segments done` and the position at the
//     start; a latched fault is cleared with FAULT_CLEAR and reported);
//  2. CONFIG_AXIS for each device axis, then the job's frames in the packer's order (heater
//     setup, NUMERATORS, LINE / LINE_PROFILE / ARC / DWELL / OUTPUT, HEATER_SETPOINT) while
//     credit = free - (FIFO frames sent, not yet acknowledged) > 0 and fewer than 127 frames are
//     unacknowledged;
//  3. go-back-N: on a NAK, or when nothing was acknowledged for the retransmission timeout, send
//     again from the device's next_seq. NAKs while the device is still at the last go-back point
//     come from copies sent before it and are ignored. The timeout adapts to the measured
//     frame -> ACK time (a queued line, a slow simulation) and backs off while nothing comes;
//     after a timeout only the oldest frame is resent until something is acknowledged. The
//     window of unacknowledged frames halves at each go-back and grows back (AIMD).
//     Duplicate, lost and corrupted device frames are tolerated: ACK/DONE are cumulative, the
//     parser resyncs, and with nothing unacknowledged a STATUS_QUERY polls the device when it stays
//     silent;
//  4. complete when `segments done` has counted every FIFO frame; then STATUS_QUERY (final
//     position compared with the job's target) and RELEASE (back to auto mode).
// Heaters: the packer (protocol/v2_job.h) has put the heater setup frames and each
// M104/M109/M140/M190's HEATER_SETPOINT in the job's frames; the streamer only gates them.
// After an M109/M190 setpoint nothing more is sent until the FIFO has drained and STATUS shows
// the temperature within the channel's tolerance for its settle time (plant seconds). While a job
// uses heaters STATUS is polled every `heater_poll` (progress line, faults, device watchdog); a
// heater, watchdog or e-stop fault stops the job with an Error naming the G-code line.
// Timers: every timeout and period of StreamV2Options runs in link time (link.h): wall time on a
// serial port, the board's clock on a simulated board (a wait there also ends at once when the
// board is idle for the host). Reports (elapsed, wall_s, probe_time) are wall time.
// Errors: link::Error when the device never answers (answer timeout), refuses a frame for a
// reason a retransmission cannot fix, or cannot take the job (axes, payload, version).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::link {

class V2Session;  // link/v2_session.h

struct StreamV2Options {
  // Link time (see the file comment).
  std::chrono::milliseconds hello_timeout{300};       // IDENT after HELLO
  int hello_attempts = 3;                             // explicit v2 (auto probes once)
  std::chrono::milliseconds retransmit_timeout{300};  // go-back-N when nothing is acknowledged
  std::chrono::milliseconds idle_poll{300};  // STATUS_QUERY when silent with nothing unacked
  std::chrono::milliseconds answer_timeout{10'000};  // no good frame at all: link::Error
  size_t max_unacked = protocol::v2::kMaxUnacked;
  size_t max_goback_same = 200;  // go-backs to one frame without progress before giving up
  bool release = true;           // send RELEASE at the end
  // Called when `segments done` advances: (FIFO frames done, FIFO frames in the job).
  std::function<void(size_t, size_t)> progress;
  // ---- Heaters ----
  // The heater commands of what is streamed (their channels' configuration for the M109/M190
  // waits, the G-code file for messages). stream_v2_job sets it to the job's; a session whose
  // frames are pushed by a front end (V2Session) is given it by that front end. Null or empty:
  // no heater gate.
  const heat::HeaterJob* heaters = nullptr;
  std::chrono::milliseconds heater_poll{250};  // STATUS_QUERY period while heaters are in use
  // Plant time in seconds for M109/M190 settle times and timeouts (the simulated board runs its
  // thermal time faster than its motion clock); unset: link time in seconds.
  std::function<double()> plant_time;
  // Every STATUS decoded during the job (progress line with temperatures).
  std::function<void(const protocol::v2::Status&)> on_status;
  // ---- Pauses and messages (Job::events) ----
  // A pause (M0, M1, M6, M600) holds every frame after it until the machine is at rest (every
  // frame before it done); then this is called and the job goes on when it returns true, or stops
  // there (link::Error "stopped at the pause") when it returns false. Unset: the job goes on at
  // once (a simulated board has no operator).
  std::function<bool(const gcode::Pause&)> on_pause;
  // Each message (M117, M118, M73, (MSG,...)) once the frames before it are done.
  std::function<void(const gcode::Message&)> on_message;
  // ---- Feed hold and overrides (docs/protocol.md "MOTION") ----
  // Sent once the session has started (V2Session::configure_motion): the machine's hold ramp,
  // rates 100 %. A device that answers NAK UNKNOWN_TYPE has no motion rate: the job runs without
  // (StreamV2Report::motion says so). Unset: no MOTION.
  std::optional<protocol::v2::Motion> motion;
  // Called after every poll round while the job runs (keys, signals: it may send MOTION frames
  // through the session). False stops the job there: frames not yet sent are dropped
  // (V2Session::abandon), what the device has stays queued (held when a hold is in effect), the
  // final STATUS is read and stream_v2_job returns with StreamV2Report::stopped set.
  std::function<bool(V2Session&)> on_poll;
};

// One M109/M190 wait as it happened.
struct HeaterWaitReport {
  int mcode = 0;
  int source_line = 0;
  uint8_t channel = 0;
  double target_c = 0.0;
  double start_c = 0.0;      // temperature when the wait began (FIFO drained)
  double plant_s = 0.0;      // plant seconds from the start to the end of the wait
  double end_plant_s = 0.0;  // plant time (StreamV2Options::plant_time) at the end of the wait
  double end_c = 0.0;        // temperature at the end of the wait
  double wall_s = 0.0;
  bool skipped = false;    // above the target already (S waits only when heating)
  bool cancelled = false;  // ended by the host (Marlin's M108) before the temperature settled
};

struct StreamV2Report {
  protocol::v2::Ident ident;
  size_t frames_sent = 0;       // every frame written, HELLO/STATUS_QUERY and resends included
  size_t sequenced_frames = 0;  // distinct sequenced frames of the session (config + FIFO)
  size_t fifo_frames = 0;       // NUMERATORS + LINE + DWELL
  size_t lines = 0;
  size_t profiles = 0;  // LINE_PROFILE frames
  size_t arcs = 0;      // ARC frames
  size_t dwells = 0;
  size_t pauses = 0;           // pauses the job stopped at
  size_t outputs = 0;          // OUTPUT frames (M7-M9, M62-M65, M106/M107)
  size_t retransmissions = 0;  // sequenced frames written more than once (each resend)
  size_t go_backs = 0;         // times the window went back (NAK or timeout)
  size_t timeouts = 0;         // retransmission timeouts
  std::array<size_t, spec::kNakReasons.size() + 1> naks{};  // by reason code (index 0: unused)
  size_t naks_ignored = 0;       // NAKs about copies sent before a go-back (device still there)
  size_t duplicates = 0;         // device frames identical to the previous one (same SEQ)
  size_t stale_answers = 0;      // ACK/NAK/DONE whose next_seq is outside the window
  size_t bad_device_frames = 0;  // good CRC but undecodable (ProtocolError)
  size_t status_polls = 0;       // STATUS_QUERY sent
  double srtt_s = 0.0;           // smoothed time from sending a frame to its ACK
  double max_rto_s = 0.0;        // largest retransmission timeout used (after backoff)
  size_t min_window = protocol::v2::kMaxUnacked;  // smallest window of unacked frames used
  uint64_t bytes_written = 0;
  uint64_t bytes_read = 0;
  uint64_t rx_crc_errors = 0;  // device frames rejected by the host parser
  uint64_t rx_bad_length = 0;
  uint64_t rx_noise_bytes = 0;
  uint64_t rx_abandoned = 0;
  uint8_t faults_cleared = 0;  // fault bits latched before the job (cleared)
  bool released = false;       // RELEASE acknowledged
  size_t skipped_heater = 0;   // heater commands not sent (not packed: PackOptions::heaters)
  size_t heater_frames = 0;    // heater setup + setpoint frames of the session
  std::vector<HeaterWaitReport> heater_waits;
  // MOTION at the start (StreamV2Options::motion): 1 taken, 0 refused (NAK UNKNOWN_TYPE: a
  // device without feed hold), -1 not sent.
  int motion = -1;
  // StreamV2Options::on_poll stopped the job: `unsent` frames were dropped, `queued` FIFO frames
  // (sent, not done) were left on the device.
  bool stopped = false;
  size_t unsent = 0;
  size_t queued = 0;
  size_t t_raised = 0;
  uint64_t total_t = 0;  // sum of T of the job's frames (clocks)
  std::chrono::duration<double> elapsed{0};
  protocol::v2::Status status_start;
  protocol::v2::Status status_end;
  std::vector<int64_t> moved;  // device position change per device axis (end - start)
  plan::Steps4 target{};       // the job's net steps per axis
  bool position_ok = false;    // moved == target on every device axis
  plan::Steps4 final_steps{};
  std::array<double, 4> final_mm{};
};

// Streams a packed job (protocol/v2_job.h): its frames in their order, nothing added. The report's
// final_steps / final_mm are the caller's (the plan's). `ident`: the IDENT already received by
// select_protocol (skips HELLO).
StreamV2Report stream_v2_job(Link& link, const protocol::v2::Job& job,
                             const StreamV2Options& options,
                             std::optional<protocol::v2::Ident> ident = std::nullopt);

// Flushes input, sends HELLO and waits `timeout` (link time) for an IDENT (other frames and bytes
// ignored).
std::optional<protocol::v2::Ident> probe_v2(Link& link, std::chrono::milliseconds timeout,
                                            uint64_t* bytes_written = nullptr);

struct ProtocolChoice {
  std::string protocol;                      // "v1" or "v2"
  std::optional<protocol::v2::Ident> ident;  // v2: the device's IDENT
  std::chrono::duration<double> probe_time{0};
};

// mode "v1": no probe. "v2": HELLO (options.hello_attempts tries), Error when no IDENT. "auto":
// one HELLO; IDENT within options.hello_timeout (300 ms) -> v2; otherwise wait `v1_settle`
// (150 ms: the device's 100 ms watchdog drops the 6 HELLO bytes as a partial v1 packet), flush
// input -> v1. Both waits are link time (on a simulated board: board time).
ProtocolChoice select_protocol(
    Link& link, const std::string& mode, const StreamV2Options& options,
    std::chrono::milliseconds v1_settle = std::chrono::milliseconds(150));

// Options from a machine configuration (retransmit and answer timeouts).
StreamV2Options stream_v2_options(const config::MachineConfig& cfg);

// The MOTION ramp of the machine (docs/timing.md "Feed hold and overrides"): per axis a of the
// first n_axes, ramp_a = 2^32 * 256 * a_hold / (v_max * CLK_HZ) with a_hold its hold
// deceleration (hold_decel_mm_s2, else its max_accel_mm_s2) and v_max its max rate
// (max_feed_mm_min / 60), both in steps (protocol::v2::hold_ramp); the smallest of them, so
// that no axis decelerates harder than its a_hold from any speed up to its max rate.
uint32_t machine_hold_ramp(const config::MachineConfig& cfg, size_t n_axes = config::kAxes);
// MOTION with the machine's ramp and rates 100 %, neither HOLD nor RESUME.
protocol::v2::Motion machine_motion(const config::MachineConfig& cfg,
                                    size_t n_axes = config::kAxes);

// Multi-line human summary of a report (frames, resends, NAKs by reason, device counters).
std::string format_report(const StreamV2Report& r);

}  // namespace fpgacnc::link
