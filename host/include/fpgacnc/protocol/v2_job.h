// Protocol v2 packer: a planned job (plan/motion_plan.h) -> the frames of a v2 session, in the
// order they are sent (docs/protocol.md, "v2"; docs/architecture.md, "Code flow of a job on the
// host"). The packer plans nothing: it turns what the plan stage gives it into frames.
//
// - A profiled plan (motion = "profile"): every look-ahead block becomes a LINE_PROFILE frame
//   (TYPE 0x12, docs/protocol.md; SHORT and k as for LINE) or an ARC frame; its JobFrame.t is
//   the exact clock count of the hardware recurrence (an ARC frame's: the walk's last-move clock
//   + 2, the segment's length; saturated at UINT32_MAX; total_t sums the exact counts and the DIR
//   hold/setup pauses at reversals, reversal_gap_clocks). The rest of this list is the
//   "constant" mode.
// - Every planned segment becomes a LINE frame: SHORT (int16 steps) when every count fits,
//   else int32; k = axes up to the last moving one, at least 2 (X, Y); Z and E are driven.
// - Laser power: 0 for code 0 (rapid / laser off); else the S word in force scaled by
//   cfg.laser_s_max to 0..255 (S > 0 never rounds to 0; no S given: 255).
// - Frame code (frame_code): the segment's code, but a non-cutting G1/G2/G3 (plan code 0, not
//   rapid) is code 1 with power 0: the laser stays off and the device's feed rate, not its rapid
//   rate, applies to it (MOTION; G0 alone is code 0).
// - T (clocks) = round(length / feed * 60 * clk_hz) at the executed feed (override and axis max
//   feeds applied; rapids at the rapid feed), length over X, Y, Z from the step deltas (E alone:
//   its own length and max feed). A step-file segment (no executed feed) keeps v1's timing:
//   T = floor(NUMERATOR_dom / feed) * n_dom. T is raised to n_dom * min_period when smaller
//   (min_period = STEP high + STEP low, 0 counting as 1: the device would clamp otherwise) and a
//   move whose T exceeds UINT32_MAX (or whose steps exceed int32) is split into equal parts.
// - G4 dwell -> DWELL frames (T = round(seconds * clk_hz), split above UINT32_MAX; 0 s: none).
// - Heater commands (PackOptions::heaters, heat/heater_job.h): validated against the machine's
//   heater channels (line:col errors), the setup frames of the used channels first, then each
//   M104/M109/M140/M190 as a HEATER_SETPOINT frame before the first frame of the segment or
//   dwell that follows it in the program. Heater frames are sequenced but not queued on the
//   device (JobFrame::fifo false); the streamer holds the motion after an M109/M190 setpoint.
// The whole job is packed and validated before the first byte is sent.
#pragma once

#include <array>
#include <cstdint>
#include <variant>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/plan/lookahead.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"

namespace fpgacnc::protocol::v2 {

// One sequenced frame of a job after CONFIG_AXIS (its SEQ is assigned when it is sent).
struct JobFrame {
  Frame frame;
  bool fifo = true;          // queued on the device; false: a heater frame (acted on when received)
  int heater = -1;           // HEATER_SETPOINT: index into Job::heaters.actions
  size_t segment_index = 0;  // plan segment it comes from (NUMERATORS: 0; dwell: next segment)
  int source_line = 0;
  uint32_t t = 0;        // LINE / DWELL length in clocks
  uint8_t axes = 0;      // LINE: k
  bool split = false;    // part of a split move or dwell
  bool profile = false;  // planned motion: LINE_PROFILE or ARC
};

// A pause, a message or an output at its place in the frame list: it happens once every frame
// before frames[before_frame] is sent (pauses: and done).
struct JobEvent {
  size_t before_frame = 0;
  std::variant<gcode::Pause, gcode::Message, gcode::Output> what;
};

struct Job {
  // CONFIG_AXIS for axes 0..3 (the streamer sends those below the device's N_AXES).
  std::vector<Frame> config;
  // CONFIG_TRAVEL for each axis with a [travel] (soft limits, in steps), sent after CONFIG_AXIS
  // (those of axes below the device's N_AXES); empty when the configuration gives none.
  std::vector<Frame> travel;
  // Frames in the order they are sent after CONFIG_AXIS: the heater setup frames (when heater
  // commands are packed), NUMERATORS, then LINE / LINE_PROFILE / ARC / DWELL / OUTPUT with
  // each HEATER_SETPOINT in its place.
  std::vector<JobFrame> frames;
  size_t fifo_frames = 0;  // frames with JobFrame::fifo (the device's `segments done` counts them)
  size_t heater_frames = 0;  // heater setup and setpoint frames
  // The heater commands packed (actions in program order, used channels, the heater
  // configuration for the streamer's M109/M190 waits); empty when none or not packed.
  heat::HeaterJob heaters;
  size_t lines = 0;
  size_t short_lines = 0;
  size_t dwells = 0;          // DWELL frames
  size_t segments = 0;        // plan segments packed
  size_t split_moves = 0;     // segments sent as more than one LINE
  size_t t_raised = 0;        // LINE frames whose T was raised to n_dom * min_period
  size_t skipped_heater = 0;  // heater commands not packed (PackOptions::heaters false)
  // Pauses, messages and outputs in frame order; outputs are also OUTPUT frames (consecutive
  // ones merged: `outputs` counts the frames).
  std::vector<JobEvent> events;
  size_t pauses = 0;
  size_t messages = 0;
  size_t outputs = 0;
  size_t profiles = 0;  // LINE_PROFILE frames (motion = "profile")
  size_t arcs = 0;      // ARC frames (motion = "profile" with an arc walk)
  // motion = "profile": DIR hold/setup pauses at reversals (HOLD/SETUP path), in total_t.
  size_t reversal_gaps = 0;
  uint64_t reversal_gap_clocks = 0;
  plan::ProfileStats profile_stats;
  size_t max_axes = 0;      // largest k of any LINE (the device must have at least that many)
  uint32_t min_period = 0;  // clocks
  uint64_t total_t = 0;     // sum of T of every LINE and DWELL (job time without gaps)
  uint64_t wire_bytes = 0;  // bytes of config + FIFO frames (heater frames not counted)
  plan::Steps4 target{};    // sum of the LINE steps per axis
  std::array<uint32_t, 2> numerator{};
  uint64_t clk_hz = 0;  // clock the T values are counted in (the device must run at it)
};

struct PackOptions {
  // Pack the heater commands (validated; setup and setpoint frames). false: they are counted in
  // Job::skipped_heater and nothing about them is checked (a twin board's job script, whose
  // board has no heater plants).
  bool heaters = true;
};

// Throws std::invalid_argument naming the segment (and line) for something v2 cannot carry
// (step timing over 65535 clocks, motion code > 3, a segment that cannot be split), then
// gcode::Error (FILE:LINE:COL) for a heater command the machine cannot run.
Job pack_job(const plan::MotionPlan& planned, const config::MachineConfig& cfg,
             const PackOptions& options = {});

// The ARC frame of one planned arc (the codec's v2::arc builder, docs/protocol.md "ARC"); throws
// std::invalid_argument for fields the device would reject.
Frame arc_frame(uint8_t seq, uint8_t power, const plan::ArcFields& g, const plan::Recurrence& r);

// The LINE_PROFILE of one planned block (codec: v2::line_profile builds the frame).
LineProfile to_line_profile(uint8_t code, uint8_t power, const plan::ProfileFields& f,
                            std::span<const int32_t> steps);

// The LINE_PROFILE frame of one look-ahead line block (laser power from its S): what pack_job
// makes of a block, for the front ends that plan line by line (frontend/motion.h).
Frame profile_frame(const plan::Profile& p, const config::MachineConfig& cfg);

// DWELL frames for a dwell of `seconds` (several when longer than one frame's 32-bit clocks;
// none for 0 s or a duration out of range), for the front ends.
std::vector<Frame> dwell_frames(double seconds, uint64_t clk_hz);

// The LINE / LINE_PROFILE power byte of a segment (the rule in the file comment: 0 for code 0,
// S scaled by laser_s_max, S > 0 never 0, no S: 255).
uint8_t laser_power(const plan::Segment& s, const config::MachineConfig& cfg);
// The LINE / LINE_PROFILE code of a segment (file comment).
constexpr uint8_t frame_code(uint8_t code, bool rapid) {
  return code != 0 || rapid ? code : 1;
}

// An output command as the OUTPUT frame's fields (merged into `set`: later ones win).
void add_output(OutputSet& set, const gcode::Output& o);

// STEP minimum period of the configuration: max(step_high, 1) + max(step_low, 1).
uint32_t min_period(const config::StepTiming& t);

// The frames a host sends for the job to a device starting at next_seq `first_seq` (after
// HELLO): config (all 4 axes), FIFO frames, RELEASE, each encoded with its SEQ.
std::vector<std::vector<uint8_t>> session_frames(const Job& job, uint8_t first_seq = 0,
                                                 size_t device_axes = 4);

}  // namespace fpgacnc::protocol::v2
