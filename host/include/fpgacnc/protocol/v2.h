// Protocol v2 codec (docs/protocol.md, "v2"): CRC-16/CCITT-FALSE, frame encoder, a resyncing
// byte-stream parser, decoders of the device's answers and builders of the host's frames.
// Byte-exact with the worked examples of docs/protocol.md (host/test/test_v2_codec.cpp).
// Independent of the planner: the fuzz targets (fuzz/) link the codec alone. Its sources, one per
// frame family, are host/src/protocol/v2_frame.cpp (framing), v2_control.cpp (control frames and
// the device's answers), v2_motion.cpp (FIFO frames), v2_heater.cpp and v2_check.cpp (the
// device's field rules); host/sources.cmake lists them.
//
// Frame: A5 LEN SEQ TYPE payload[LEN] CRC_hi CRC_lo, CRC over LEN..payload, LEN <= 64.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "fpgacnc/spec.h"

namespace fpgacnc::protocol::v2 {

// The numbers come from spec/protocol.toml (fpgacnc/spec.h, generated).
constexpr uint8_t kSync = spec::kSync;
constexpr size_t kMaxPayload = spec::kMaxPayload;
constexpr size_t kOverhead = spec::kOverhead;  // sync, LEN, SEQ, TYPE, CRC x2
constexpr size_t kMaxFrame = kMaxPayload + kOverhead;
constexpr uint8_t kVersion = spec::kVersion;
constexpr size_t kMaxUnacked =
    spec::kMaxUnacked;                         // host: never more sequenced frames unacknowledged
constexpr size_t kCounters = spec::kCounters;  // STATUS counters

enum class Type : uint8_t {
  Hello = spec::kTypeHello,
  StatusQuery = spec::kTypeStatusQuery,
  FaultClear = spec::kTypeFaultClear,
  ConfigAxis = spec::kTypeConfigAxis,
  ConfigTravel = spec::kTypeConfigTravel,  // soft limits of one axis
  Motion = spec::kTypeMotion,              // feed hold, resume, rates (unsequenced)
  Trigger = spec::kTypeTrigger,            // homing / probing trigger (sequenced, not queued)
  SetPosition = spec::kTypeSetPosition,    // position counters (sequenced, not queued)
  TriggerQuery = spec::kTypeTriggerQuery,  // asks for TRIGGER_REPORT (unsequenced)
  Numerators = spec::kTypeNumerators,
  Release = spec::kTypeRelease,
  Line = spec::kTypeLine,
  Dwell = spec::kTypeDwell,
  LineProfile = spec::kTypeLineProfile,
  Arc = spec::kTypeArc,        // circular DDA
  Output = spec::kTypeOutput,  // machine outputs in order with the motion
  // Heaters: sequenced, not queued.
  HeaterConfig = spec::kTypeHeaterConfig,
  HeaterSetpoint = spec::kTypeHeaterSetpoint,
  ThermistorTable = spec::kTypeThermistorTable,
  HeaterSafety = spec::kTypeHeaterSafety,
  HeaterWatchdog = spec::kTypeHeaterWatchdog,
  Ack = spec::kTypeAck,
  Nak = spec::kTypeNak,
  Done = spec::kTypeDone,
  Status = spec::kTypeStatus,
  Ident = spec::kTypeIdent,
  TriggerReport = spec::kTypeTriggerReport
};

enum class NakReason : uint8_t {
  BadCrc = spec::kNakBadCrc,
  BadLength = spec::kNakBadLength,
  UnknownType = spec::kNakUnknownType,
  Timeout = spec::kNakTimeout,
  OutOfOrder = spec::kNakOutOfOrder,
  FifoFull = spec::kNakFifoFull,
  BadField = spec::kNakBadField,
  Travel = spec::kNakTravel,  // the frame's end leaves the travel (CONFIG_TRAVEL): never retried
  Busy = spec::kNakBusy       // a SET_POSITION while the motion is not idle: resent when idle
};

// "HELLO", "ACK", ..., or "0x12" for a value not in the table.
std::string type_name(uint8_t type);
// "BAD_CRC", ..., or "reason 10" for a value not in the table.
std::string nak_reason_name(uint8_t reason);
// Host frames the device sequences (FAULT_CLEAR, CONFIG_AXIS, NUMERATORS, RELEASE,
// CONFIG_TRAVEL, TRIGGER, SET_POSITION, LINE, DWELL, LINE_PROFILE, ARC, OUTPUT, the heater
// frames: spec/protocol.toml's `sequenced`).
bool is_sequenced(uint8_t type);
// Host frames that go to the command FIFO (NUMERATORS, LINE, DWELL, LINE_PROFILE, ARC, OUTPUT).
bool is_fifo(uint8_t type);

// A decoder was given a frame of the wrong type or length, or a field out of range.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final XOR.
uint16_t crc16(std::span<const uint8_t> data);

struct Frame {
  uint8_t seq = 0;
  uint8_t type = 0;
  std::vector<uint8_t> payload;
  bool operator==(const Frame&) const = default;
};

// 6 + payload bytes. Throws std::invalid_argument if the payload is longer than kMaxPayload.
std::vector<uint8_t> encode(const Frame& f);
// Appends the encoded frame to `out` (same check).
void encode_to(const Frame& f, std::vector<uint8_t>& out);

// Byte stream -> frames. A frame starts at a 0xA5; a LEN > 64 or a CRC mismatch rejects that
// 0xA5 only and the search for the next 0xA5 restarts at the byte after it (so a good frame
// hidden behind a corrupted header is still found). Bytes outside frames are counted as noise.
class FrameParser {
 public:
  void feed(std::span<const uint8_t> bytes);
  void feed(uint8_t byte) { feed(std::span<const uint8_t>(&byte, 1)); }
  // The next complete good frame, or nullopt when more bytes are needed.
  std::optional<Frame> next();
  // Gives up on a partial frame at the head of the buffer (e.g. after a read timeout: its LEN
  // may have been corrupted upwards): drops its 0xA5 and rescans the rest. Counted in
  // `abandoned`. Returns whether there was a partial frame.
  bool abandon_partial();
  // Bytes received but not yet returned or discarded.
  size_t buffered() const { return buf_.size() - pos_; }
  void reset();

  uint64_t crc_errors() const { return crc_errors_; }
  uint64_t bad_length() const { return bad_length_; }
  uint64_t noise_bytes() const { return noise_bytes_; }
  uint64_t frames() const { return frames_; }
  uint64_t abandoned() const { return abandoned_; }

 private:
  void compact();
  std::vector<uint8_t> buf_;
  size_t pos_ = 0;
  uint64_t crc_errors_ = 0;
  uint64_t bad_length_ = 0;
  uint64_t noise_bytes_ = 0;
  uint64_t frames_ = 0;
  uint64_t abandoned_ = 0;
};

// ---- Device -> host payloads ----

struct Credit {  // ACK and DONE: 7 bytes
  uint8_t next_seq = 0;
  uint16_t free = 0;
  uint32_t done = 0;
  bool operator==(const Credit&) const = default;
};

struct Nak {  // 5 bytes
  uint8_t seq = 0;
  NakReason reason = NakReason::BadCrc;
  uint8_t next_seq = 0;
  uint16_t free = 0;
  bool operator==(const Nak&) const = default;
};

struct Ident {  // 18 bytes
  uint8_t version = kVersion, n_axes = 0;
  uint16_t fifo_depth = 0;
  uint32_t clk_hz = 0, baud = 0, build_id = 0;
  uint8_t next_seq = 0, max_payload = kMaxPayload;
  bool operator==(const Ident&) const = default;
};

// STATUS state bits.
constexpr uint8_t kStateBusy = spec::kStateBusy;
constexpr uint8_t kStateV2 = spec::kStateV2;
constexpr uint8_t kStateFault = spec::kStateFault;
constexpr uint8_t kStateEstop = spec::kStateEstop;  // the e-stop input is active now
constexpr uint8_t kStatePosUntrusted =
    spec::kStatePosUntrusted;  // a hard limit tripped since reset
constexpr uint8_t kStateHold =
    spec::kStateHold;  // a feed hold is in effect (MOTION HOLD, hold pin)
constexpr uint8_t kStateStopped = spec::kStateStopped;  // the motion rate is 0: motion frozen
// STATUS fault bits.
constexpr uint8_t kFaultStepTiming = spec::kFaultStepTiming;
constexpr uint8_t kFaultLimit = spec::kFaultLimit;  // hard limit (Status::limit names the switch)
constexpr uint8_t kFaultEstop = spec::kFaultEstop;
constexpr uint8_t kFaultWatchdog = spec::kFaultWatchdog;  // heater watchdog (host silent)
constexpr uint8_t kFaultHotend = spec::kFaultHotend;  // channel 0 fault (its own byte says which)
constexpr uint8_t kFaultBed = spec::kFaultBed;        // channel 1 fault
// STATUS counters, in order.
enum Counter : size_t {
  kFramesOk = spec::kCounterFramesOk,
  kCrcErrors = spec::kCounterCrcErrors,
  kLengthErrors = spec::kCounterLengthErrors,
  kUnknownTypes = spec::kCounterUnknownTypes,
  kTimeouts = spec::kCounterTimeouts,
  kUartFramingErrors = spec::kCounterUartFramingErrors,
  kOverruns = spec::kCounterOverruns,
  kNoiseBytes = spec::kCounterNoiseBytes,
  kClamped = spec::kCounterClamped
};
// "frames_ok", "crc_errors", ...
std::string counter_name(size_t index);

// STATUS heater block, one per channel (0 hot end, 1 bed), 8 bytes each.
struct HeaterStatus {
  int16_t temp_q4 = 0;      // Q11.4 degC
  int16_t setpoint_q4 = 0;  // Q11.4 degC
  uint16_t duty_q15 = 0;    // Q1.15, 0x8000 = 100 %
  uint8_t mode = 0;         // bits 2..0 mode, bit 6 holding, bit 7 enabled
  uint8_t faults = 0;       // kHeaterMinTemp ...
  double temp_c() const { return temp_q4 / 16.0; }
  double setpoint_c() const { return setpoint_q4 / 16.0; }
  double duty() const { return duty_q15 / 32768.0; }
  bool enabled() const { return (mode & 0x80) != 0; }
  bool holding() const { return (mode & 0x40) != 0; }
  bool operator==(const HeaterStatus&) const = default;
};
constexpr uint8_t kHeaterMinTemp = spec::kHeaterFaultMintemp;
constexpr uint8_t kHeaterMaxTemp = spec::kHeaterFaultMaxtemp;
constexpr uint8_t kHeaterRunaway = spec::kHeaterFaultRunaway;
constexpr uint8_t kHeaterHeating = spec::kHeaterFaultHeating;
constexpr size_t kHeaterChannels = spec::kStatusHeaterChannels;
constexpr size_t kHeaterStatusBytes = spec::kStatusHeaterChannelBytes;
// "MINTEMP|RUNAWAY" (or "none").
std::string heater_fault_names(uint8_t faults);

struct Status {  // 30 + 4 * n_axes bytes, + 16 with the heater block
  uint8_t state = 0, faults = 0;
  uint16_t fifo_level = 0;
  uint8_t next_seq = 0;
  uint32_t done = 0;
  std::vector<int32_t> position;
  std::array<uint16_t, kCounters> counters{};
  uint8_t limit = 0;      // the switch of the last hard-limit trip: bits 3..0 axis, bit 4 max
  uint16_t switches = 0;  // filtered limit switches now: bit a min of axis a, bit 8 + a max
  std::vector<HeaterStatus> heaters;  // empty: the device sent no heater block
  bool operator==(const Status&) const = default;
};

// "X max" for a limit byte (axes named X Y Z A B C U V W, then by number).
std::string limit_switch_name(uint8_t limit);
// The hard-limit part of a STATUS for people: "LIMIT alarm: X max" when latched, the switches
// asserted now ("switches: X max, Y min" or "switches: none") and "positions not trusted" when
// a limit tripped since reset. n_axes: the device's (IDENT).
std::string describe_limits(const Status& s, size_t n_axes);

// Without the heater block; decode_status accepts this size or this + 16.
size_t status_payload_size(size_t n_axes);

// Decoders: throw ProtocolError naming the frame type and what is wrong (type, length, field).
Credit decode_credit(const Frame& f);  // ACK or DONE
Nak decode_nak(const Frame& f);        // reason must be 1..7
Ident decode_ident(const Frame& f);
Status decode_status(const Frame& f, size_t n_axes);

// Device frame builders (fake devices, tests, fuzzers).
Frame ack(uint8_t dev_seq, const Credit& c);
Frame done(uint8_t dev_seq, const Credit& c);
Frame nak(uint8_t dev_seq, const Nak& n);
Frame ident(uint8_t dev_seq, const Ident& i);
Frame status(uint8_t dev_seq, const Status& s);

// ---- Host -> device ----

// Builders. `line`: code 0..3, steps for axes 0..k-1 (k = steps.size(), 0..14); SHORT (int16)
// when `short_if_fits` and every count fits int16, else int32. Throws std::invalid_argument for a
// code > 3 or a payload over 64 bytes.
Frame hello(uint8_t seq = 0);
Frame status_query(uint8_t seq = 0);
Frame fault_clear(uint8_t seq);
Frame release(uint8_t seq);
Frame config_axis(uint8_t seq, uint8_t axis, uint16_t step_high, uint16_t step_low,
                  uint16_t dir_setup, uint16_t dir_hold);
// CONFIG_TRAVEL: axis `axis`'s travel [min, max] in signed steps, soft limits on (`enable`) or off.
Frame config_travel(uint8_t seq, uint8_t axis, bool enable, int32_t min, int32_t max);
Frame numerators(uint8_t seq, uint32_t numerator_x, uint32_t numerator_y);
Frame line(uint8_t seq, uint8_t code, uint8_t power, uint32_t t, std::span<const int32_t> steps,
           bool short_if_fits = true);
Frame dwell(uint8_t seq, uint32_t t);

// LINE_PROFILE (TYPE 0x12): a line run with a trapezoidal speed profile (docs/protocol.md,
// "LINE_PROFILE"). Velocities are UQ0.48 dominant-axis steps per clock, the acceleration is in
// 2^-48 dominant steps per clock^2, decel_at (D) is the dominant step count at which deceleration
// starts. Device limits (else NAK BAD_FIELD): 1 <= n_dom = max|steps| < 2^24, v_cruise < 2^47,
// v_entry <= v_cruise, v_exit <= v_cruise, v_exit >= 1, accel >= 1 or v_entry >= 1.
constexpr uint64_t kProfileOne = uint64_t{1} << 48;  // 1 dominant step per clock (never reached)
constexpr uint64_t kProfileVMax = uint64_t{1} << spec::kProfileVBits;     // v_cruise must be below
constexpr uint32_t kProfileNDomMax = (1u << spec::kProfileNDomBits) - 1;  // largest n_dom
struct LineProfile {
  uint8_t code = 0;
  uint8_t power = 0;
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;  // u48
  uint32_t accel = 0;
  uint32_t decel_at = 0;
  bool short_steps = false;    // decoded: the frame used int16 steps
  std::vector<int32_t> steps;  // k axes
  bool operator==(const LineProfile&) const = default;
};
// Empty when the fields satisfy the device limits above, else the rule broken (for messages).
std::string line_profile_field_error(const LineProfile& p);
// Builder: SHORT (int16) when `short_if_fits` and every count fits int16 (p.short_steps is
// ignored). Throws std::invalid_argument for a code > 3, a payload over 64 bytes or a field the
// device would reject (line_profile_field_error).
Frame line_profile(uint8_t seq, const LineProfile& p, bool short_if_fits = true);

constexpr uint8_t kLineShort = spec::kLineShort;

struct Line {
  uint8_t code = 0;
  uint8_t power = 0;
  uint32_t t = 0;
  bool short_steps = false;
  std::vector<int32_t> steps;  // k axes
  bool operator==(const Line&) const = default;
};
struct ConfigAxis {
  uint8_t axis = 0;
  uint16_t step_high = 0, step_low = 0, dir_setup = 0, dir_hold = 0;
  bool operator==(const ConfigAxis&) const = default;
};

// Host frame decoders (the fake device and the fuzzers use them): length and field rules as the
// device checks them (reserved flag bits -> "BAD_FIELD", LEN -> "BAD_LENGTH"; the message
// names the rule). `n_axes` bounds k and the axis number (0: no bound beyond the payload).
Line decode_line(const Frame& f, size_t n_axes = 0);
uint32_t decode_dwell(const Frame& f);
LineProfile decode_line_profile(const Frame& f, size_t n_axes = 0);
ConfigAxis decode_config_axis(const Frame& f, size_t n_axes = 0);
std::array<uint32_t, 2> decode_numerators(const Frame& f);
// The NAK reason the device gives a good-CRC host frame with these type/length/fields, or
// nullopt when it is well formed (sequence and FIFO rules not included).
std::optional<NakReason> check_host_frame(const Frame& f, size_t n_axes);

// ---- Heaters (docs/protocol.md "Heater frames", docs/heater.md formats) ----

struct HeaterConfigFrame {  // HEATER_CONFIG, 20 bytes
  uint8_t channel = 0;
  uint8_t mode = 0;                 // 0 OFF, 1 MANUAL, 2 ON_OFF, 3 P, 4 PID
  uint32_t kp = 0, ki = 0, kd = 0;  // Q8.24 duty per degC
  uint16_t duty_max = 0x8000;       // Q1.15
  uint16_t hysteresis_q4 = 16;      // Q12.4 degC
  uint16_t manual = 0;              // Q1.15
  bool operator==(const HeaterConfigFrame&) const = default;
};
struct HeaterSafetyFrame {  // HEATER_SAFETY, 13 bytes
  uint8_t channel = 0;
  int16_t tmin_q4 = 0, tmax_q4 = 0;
  uint16_t runaway_band_q4 = 0, runaway_ticks = 0;
  uint16_t watch_rise_q4 = 0, watch_ticks = 0;
  bool operator==(const HeaterSafetyFrame&) const = default;
};
struct ThermistorChunk {  // THERMISTOR_TABLE, 2 + 2n bytes
  uint8_t channel = 0;
  uint8_t first = 0;
  std::vector<int16_t> entries;  // 1..8, Q11.4
  bool operator==(const ThermistorChunk&) const = default;
};
constexpr size_t kThermistorEntries = spec::kThermistorEntries;  // entry i: at ADC code 64 * i
constexpr size_t kThermistorChunk = spec::kThermistorChunk;

// Builders (throw std::invalid_argument for a field the device would refuse).
Frame heater_config(uint8_t seq, const HeaterConfigFrame& c);
Frame heater_setpoint(uint8_t seq, uint8_t channel, int16_t setpoint_q4);
Frame thermistor_table(uint8_t seq, const ThermistorChunk& c);
Frame heater_safety(uint8_t seq, const HeaterSafetyFrame& c);
Frame heater_watchdog(uint8_t seq, uint16_t ticks);
// Decoders (fake devices, tests): the device's LEN and field rules (ProtocolError naming them).
HeaterConfigFrame decode_heater_config(const Frame& f);
std::pair<uint8_t, int16_t> decode_heater_setpoint(const Frame& f);
ThermistorChunk decode_thermistor_table(const Frame& f);
HeaterSafetyFrame decode_heater_safety(const Frame& f);
uint16_t decode_heater_watchdog(const Frame& f);

// ARC (TYPE 0x13, 63-byte payload): a circular / helical arc run by the hardware circular DDA
// (docs/protocol.md "ARC", docs/motion.md "Arcs") in one of three planes (flags bits 3:2): the
// walk's (u, v) axes and the helix axis are XY / Z (G17, plane 0), ZX / Y (G18, 1), YZ / X (G19,
// 2). Geometry in steps relative to the start, in (u, v): centre (i, j), end (dx, dy; 0, 0 = full
// circle), dz steps of the helix axis over the arc (G18: i, dx along Z, j, dy along X). n_ramp and
// c_total come from the reference walk (fpgacnc::models::arc::plan in
// models/include/fpgacnc/models/arc_walk.h). Speeds in UQ16.48 cost units per clock, accel in 2^-48
// cost units per clock^2, decel_at (D) in cost units.
constexpr size_t kArcPayload = spec::kLenArc;
constexpr int32_t kArcCoordLimit = 1 << spec::kArcCoordBits;  // |i|, |j|, |dx - i|, |dy - j| below
constexpr uint32_t kArcNRampMax = (1u << spec::kArcNRampBits) - 1;
constexpr uint64_t kArcCTotalLimit = uint64_t{1} << spec::kArcCTotalBits;  // c_total below
constexpr uint64_t kArcU48Max = (uint64_t{1} << 48) - 1;
enum class ArcPlane : uint8_t { XY = 0, ZX = 1, YZ = 2 };  // G17, G18, G19
struct Arc {
  uint8_t code = 3;  // 2 = G2 (CW), 3 = G3 (CCW), seen from the helix axis's positive side
  uint8_t power = 0;
  ArcPlane plane = ArcPlane::XY;         // flags bits 3:2 (ZX and YZ need a board with 3 axes)
  int32_t i = 0, j = 0, dx = 0, dy = 0;  // int24 on the wire
  int32_t dz = 0;
  uint32_t n_ramp = 1;                             // u24
  uint64_t c_total = 0;                            // u48
  uint64_t v_entry = 0, v_cruise = 0, v_exit = 0;  // u64
  uint64_t accel = 0;                              // u48
  uint64_t decel_at = 0;                           // u48
  bool operator==(const Arc&) const = default;
};
// Empty when the fields satisfy the device limits (docs/protocol.md "ARC"), else the rule broken.
// n_axes (0: no bound): ZX / YZ need 3 axes, a helix in XY too.
std::string arc_field_error(const Arc& a, size_t n_axes = 0);
// Builder; throws std::invalid_argument for fields the device would reject (arc_field_error).
Frame arc(uint8_t seq, const Arc& a);
// Decoder (length / field rules as the device checks them; ProtocolError otherwise).
Arc decode_arc(const Frame& f);

// OUTPUT (TYPE 0x15, 3-byte payload: mask, value, fan duty; docs/protocol.md "OUTPUT"): machine
// outputs set in order with the motion, on the edge the segment queued before the frame ends
// (no gap in the motion); answered ACK, later DONE. Each field left empty keeps its output as it
// is, so one frame can set several: M8 flood = true; M7 mist = true; M9 flood = mist = false;
// M106 S<s> fan = s (0..255, 255 = always on); M107 fan = 0; M62/M64 P<n> dout[n] = true,
// M63/M65 P<n> dout[n] = false (n = 0..3); M4 laser_dyn = true (the laser / spindle power scaled
// with the actual speed, docs/machine.md "Laser and spindle PWM"), M3 laser_dyn = false.
constexpr size_t kOutputPayload = spec::kLenOutput;
constexpr size_t kDigitalOutputs = spec::kDigitalOutputs;
constexpr uint8_t kOutFlood = spec::kOutFlood;  // mask / value bits
constexpr uint8_t kOutMist = spec::kOutMist;
constexpr uint8_t kOutFan = spec::kOutFan;            // mask only: the duty is byte 2
constexpr uint8_t kOutDout0 = spec::kOutDout0;        // dout[n]: kOutDout0 << n
constexpr uint8_t kOutLaserDyn = spec::kOutLaserDyn;  // M4 dynamic laser power (value 1) / M3
struct OutputSet {
  std::optional<bool> flood, mist;
  std::optional<uint8_t> fan;  // PWM duty, 255 = always on
  std::array<std::optional<bool>, kDigitalOutputs> dout{};
  std::optional<bool> laser_dyn;  // true: M4 dynamic power, false: M3 constant
  bool empty() const;
  bool operator==(const OutputSet&) const = default;
};
// Builder; throws std::invalid_argument for an empty set (the device answers NAK BAD_FIELD).
Frame output_frame(uint8_t seq, const OutputSet& o);
// Decoder (LEN 3, mask != 0, reserved bits 0, value bits only where the mask is set, duty 0
// without the fan bit; ProtocolError naming the rule otherwise).
OutputSet decode_output(const Frame& f);

// MOTION (TYPE 0x08, 9-byte payload; docs/protocol.md "MOTION", docs/timing.md "Feed hold and
// overrides"): unsequenced like STATUS_QUERY, answered with STATUS. Flags bit 0 HOLD (ramp the
// motion rate to 0 and keep it there), bit 1 RESUME (end the hold), not both; bit 2 CANCEL (a
// hold that, at rate 0, drops the running segment and the queue, positions kept, no fault, then
// ends the hold; the dropped frames send no DONE), not with RESUME; the feed rate
// (segments with a code other than 0) and the rapid rate (code 0) in Q1.15, 0x8000 = 100 % =
// the planned speed, 1 .. 0x8000; the ramp: the rate's largest change per 256-clock period in
// 2^-32 (>= 1). Every MOTION sets all three rates; a frame with neither flag changes only them.
// STATUS: kStateHold while the hold is in effect, kStateStopped while the rate is 0 (grbl's
// Hold:1 = HOLD without STOPPED, Hold:0 = both).
constexpr size_t kMotionPayload = spec::kLenMotion;
constexpr uint16_t kRateOne = static_cast<uint16_t>(spec::kRateOne);  // 100 %
constexpr uint8_t kMotionHold = static_cast<uint8_t>(spec::kMotionHold);
constexpr uint8_t kMotionResume = static_cast<uint8_t>(spec::kMotionResume);
constexpr uint8_t kMotionCancel = static_cast<uint8_t>(spec::kMotionCancel);
struct Motion {
  bool hold = false;
  bool resume = false;
  bool cancel = false;
  uint16_t feed = kRateOne;   // Q1.15
  uint16_t rapid = kRateOne;  // Q1.15
  uint32_t ramp = spec::kDefaultRateRamp;
  bool operator==(const Motion&) const = default;
};
// Empty when the device accepts the fields, else the rule broken (for messages).
std::string motion_field_error(const Motion& m);
// Builder (SEQ is not checked by the device; 0 as for STATUS_QUERY). Throws std::invalid_argument
// for fields the device would refuse (motion_field_error).
Frame motion(const Motion& m, uint8_t seq = 0);
// Decoder (LEN 9, reserved flag bits 0, RESUME with neither HOLD nor CANCEL, rates 1..0x8000,
// ramp >= 1;
// ProtocolError naming the rule otherwise).
Motion decode_motion(const Frame& f);
// A percentage (0 < pct <= 100) as a Q1.15 rate, rounded to nearest, at least 1.
uint16_t rate_from_percent(double pct);
// The ramp for a hold deceleration (docs/timing.md "Feed hold and overrides"):
// ramp = 2^32 * 2^RATE_PERIOD_LOG2 * a_hold / (v_max * clk_hz), a_hold and v_max in steps/s^2
// and steps/s of the fastest axis (v_max: the largest max rate in steps/s); rounded down (the
// hold never decelerates harder than a_hold), clamped to 1 .. 2^32 - 1. Throws
// std::invalid_argument for a non-positive or non-finite argument.
uint32_t hold_ramp(double a_hold_steps_s2, double v_max_steps_s, double clk_hz);

// TRIGGER (TYPE 0x0A, 3 bytes), SET_POSITION (0x0B, 2 + 4 N_AXES), TRIGGER_QUERY (0x0C, 0) and
// the device's TRIGGER_REPORT (0x85, 4 + 4 N_AXES): docs/protocol.md "TRIGGER" .. "TRIGGER_REPORT",
// docs/machine.md "Homing and probing (hardware)". Switch masks as STATUS's switches: bit a the
// min switch of axis a, bit 8 + a its max switch.
enum class TriggerMode : uint8_t {
  Disarm = spec::kTriggerDisarm,
  Home = spec::kTriggerHome,
  Probe = spec::kTriggerProbe,                // fires when the probe becomes asserted
  ProbeRelease = spec::kTriggerProbeRelease,  // fires when it becomes released
};
constexpr uint8_t kTriggerArmed = spec::kTriggerArmed;  // TRIGGER_REPORT flags
constexpr uint8_t kTriggerDone = spec::kTriggerDone;
constexpr uint8_t kStateProbe = spec::kStateProbe;  // STATUS state bit 7: the probe touches
// The switch bit of axis `axis`'s min or max switch.
constexpr uint16_t switch_bit(size_t axis, bool max_side) {
  return static_cast<uint16_t>(1u << (axis + (max_side ? 8 : 0)));
}
// Empty when the device accepts a TRIGGER with these fields, else the rule broken: HOME needs a
// non-zero mask of switches of axes < n_axes (n_axes 0: axes 0..7); the other modes a mask of 0.
std::string trigger_field_error(TriggerMode mode, uint16_t switches, size_t n_axes = 0);
// Builder; throws std::invalid_argument for fields the device would refuse (trigger_field_error).
Frame trigger(uint8_t seq, TriggerMode mode, uint16_t switches = 0, size_t n_axes = 0);
// SET_POSITION: the axes in `mask` take `position[a]` (position.size() = N_AXES, every axis sent).
// Throws std::invalid_argument for a mask of 0, bits of axes >= position.size(), or no axis.
Frame set_position(uint8_t seq, uint16_t mask, std::span<const int32_t> position);
Frame trigger_query(uint8_t seq = 0);

struct TriggerReport {  // TRIGGER_REPORT payload
  TriggerMode mode = TriggerMode::Disarm;
  uint8_t flags = 0;             // kTriggerArmed, kTriggerDone
  uint16_t fired = 0;            // HOME: the switches fired (bits as the mask)
  std::vector<int32_t> latched;  // per axis: the position at its edge (0: not latched)
  bool armed() const { return (flags & kTriggerArmed) != 0; }
  bool done() const { return (flags & kTriggerDone) != 0; }
  bool operator==(const TriggerReport&) const = default;
};
// Decoder: LEN 4 + 4 n_axes, mode <= 3, flags bits 7..2 0 (ProtocolError naming the rule).
TriggerReport decode_trigger_report(const Frame& f, size_t n_axes);
// Device frame builder (fake devices, tests).
Frame trigger_report(uint8_t dev_seq, const TriggerReport& r);
// Host frame decoders (fake devices, tests): the device's LEN and field rules.
std::pair<TriggerMode, uint16_t> decode_trigger(const Frame& f, size_t n_axes = 0);
std::pair<uint16_t, std::vector<int32_t>> decode_set_position(const Frame& f, size_t n_axes);

// Hex dump "A5 0A 07 10 ..." (upper case, space separated).
std::string hex(std::span<const uint8_t> bytes);

}  // namespace fpgacnc::protocol::v2
