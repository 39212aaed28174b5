// Twin of rtl/protocol/frame_decoder.v: v1 packets and v2 frames from one byte stream
// (docs/protocol.md "Telling v1 from v2", "Frame", "Host to device", "Sequence numbers", "NAK
// reasons").
//
// Target `bytes`: RxByte valid from the delay's edge b; the decoder takes it on edge
// t = b + kDecoderTake. Between packets (auto mode) 0xFF starts a v1 init, 0x00..0x03 a v1
// motion, 0xA5 a v2 frame, anything else is noise (counted); in v2 mode only 0xA5 starts
// anything. A started packet or frame whose next byte comes more than WATCHDOG_CLKS edges after
// the previous one is dropped on edge previous + WATCHDOG_CLKS (v1: timeouts; v2: also NAK
// TIMEOUT, SEQ as received or 0). v1: a complete packet is written to the command FIFO (an init
// as a numerators entry), or dropped when the FIFO is full (overruns).
// v2 (edges relative to the take edge of the byte that ends the frame):
//   LEN > MAX_PAYLOAD: NAK BAD_LENGTH at the LEN byte, the frame abandoned at once;
//   CRC mismatch: NAK BAD_CRC; a good CRC switches to v2 mode;
//   then TYPE unknown: NAK UNKNOWN_TYPE; LEN wrong for TYPE: NAK BAD_LENGTH; reserved LINE
//   flag bits, an axis >= N_AXES, a LINE_PROFILE, ARC or OUTPUT field rule broken, a heater field
//   out of range: NAK BAD_FIELD;
//   HELLO / STATUS_QUERY (not sequenced): IDENT / STATUS request;
//   MOTION (not sequenced; BAD_FIELD: flag bits 7:3, RESUME with HOLD or CANCEL, a feed or rapid
//   rate outside 1..0x8000, ramp 0): STATUS request, and on_motion(L, the request) (the motion
//   rate takes it on L + 2, feed_rate.h; CANCEL holds there, and its flush at rest is the
//   virtual board's, virtual_board.h);
//   sequenced frames by SEQ against next_seq: equal -> accepted (a FIFO frame only with a free
//   slot, else NAK FIFO_FULL), next_seq + 1, ACK; a duplicate (next_seq - 1 .. - 128) -> ACK
//   only; ahead -> NAK OUT_OF_ORDER. Accepted: LINE / DWELL / NUMERATORS / LINE_PROFILE / ARC
//   (payload bytes 2..62 as received, FifoEntry::arc_raw) / OUTPUT (kind 3, v2 0, t = the three
//   payload bytes) written to the FIFO,
//   CONFIG_AXIS sent on `cfg`, FAULT_CLEAR acts; RELEASE, accepted or a duplicate, returns to
//   auto mode.
//   Soft limits (docs/protocol.md "CONFIG_TRAVEL"): CONFIG_TRAVEL sets an axis's travel (BAD_FIELD:
//   axis >= N_AXES, flag bits 7:1, MIN > MAX while enabled); a new LINE / LINE_PROFILE / ARC whose
//   end (the queued end plus its steps) leaves the travel of an enabled axis is NAK TRAVEL, after
//   the SEQ rules and before FIFO_FULL. The queued end follows every motion entry written (v1
//   included) and is 0 after reset; the twin board has no e-stop or limits, so nothing else
//   flushes the queue.
// Initiators: `fifo` (FIFO write; level read before a write), `resp` (requests to the response
// encoder: a strobe after the delay's edge), `cfg` (CONFIG_AXIS writes). state_after(t): the
// DecoderState after edge t (next_seq, mode, counters), from a history: asked in time order
// (older history is dropped).
#pragma once

#include <deque>
#include <functional>

#include "fpgacnc/twins/tlm_common.h"
#include "fpgacnc/twins/v2_frames.h"

namespace fpgacnc::twins {

// Edges relative to the take edge L of the byte that ends a packet or frame: it is checked in the
// clock after L ("CHECK"): the FIFO's room as it is after edge L, the entry written on L + 1,
// next_seq and the mode change on L + 1, the request and counter strobes are high after L + 1
// (the counters they feed change on L + 2). Noise and an oversized LEN strobe after their own
// take edge; the watchdog fires on the edge WATCHDOG_CLKS after the last byte's.
inline constexpr Cycle kDecoderTake = 1;   // byte valid after edge b -> taken on b + 1
inline constexpr Cycle kDecoderWrite = 1;  // L -> FIFO write / config write edge
inline constexpr Cycle kDecoderResp = 1;   // L -> request strobe (high after this edge)

// Requests to the response encoder.
inline constexpr uint8_t kReqIdent = 0, kReqStatus = 1, kReqNak = 2, kReqAck = 3,
                         kReqFaultClear = 4;
struct RespReq {
  uint8_t kind;
  uint8_t seq = 0, reason = 0;  // NAK
};
struct CfgAxis {  // CONFIG_AXIS accepted: the axis's step timing
  uint8_t axis;
  AxisTiming timing;
};
struct MotionReq {  // an accepted MOTION frame: the first clock of its values (L + 2), its fields
  Cycle from;
  bool hold, resume, cancel;
  uint16_t feed, rapid;
  uint32_t ramp;
  bool operator==(const MotionReq&) const = default;
};
inline constexpr Cycle kMotionTakes = 2;  // L -> the rate's registers hold the frame's values
struct DecoderState {
  uint8_t next_seq = 0;
  bool v2_mode = false;
  // frames ok, CRC errors, length errors, unknown types, timeouts (v1 and v2), overruns, noise
  uint16_t frames_ok = 0, crc_errors = 0, length_errors = 0, unknown_types = 0, timeouts = 0,
           overruns = 0, noise = 0;
};

class FrameDecoderTwin : public sc_core::sc_module {
 public:
  tlm_utils::simple_target_socket<FrameDecoderTwin> bytes;
  tlm_utils::simple_initiator_socket<FrameDecoderTwin> fifo;
  tlm_utils::simple_initiator_socket<FrameDecoderTwin> resp;
  tlm_utils::simple_initiator_socket<FrameDecoderTwin> cfg;

  FrameDecoderTwin(sc_core::sc_module_name name, const CycleClock& clk, const CoreParams& p,
                   uint32_t fifo_depth = v2::kFifoDepth)
      : sc_module(name),
        bytes("bytes"),
        fifo("fifo"),
        resp("resp"),
        cfg("cfg"),
        clk_(clk),
        wd_(static_cast<Cycle>(p.watchdog_clks)),
        depth_(fifo_depth) {
    bytes.register_b_transport(this, &FrameDecoderTwin::on_byte);
  }

  void reset() {
    count_ = 0;
    last_take_ = 0;
    kind_ = Kind::None;
    s_ = DecoderState{};
    mode_before_ = false;
    mode_from_ = 0;
    history_.clear();
    history_.emplace_back(-1'000'000'000, s_);
    packets = frames = fifo_writes = cfg_writes = 0;
    travel_ = {};
    queued_ = {};
    packet_done_cycles.clear();
    v1_packet_cycles.clear();
    naks.clear();
  }
  // Fires the watchdog of a started packet if it expires before edge h (no byte can come
  // earlier than h: the caller knows the host's schedule).
  void advance(Cycle h) {
    if (count_ > 0 && last_take_ + wd_ < h) expire();
  }
  // The edge after which the watchdog of a started packet or frame fires (advance() past it
  // fires it); -1 when no packet is started (cnc_core `rx_partial` low).
  Cycle watchdog_edge() const { return count_ > 0 ? last_take_ + wd_ : -1; }
  const DecoderState& current() const { return s_; }
  DecoderState state_after(Cycle t) {
    while (history_.size() > 1 && history_[1].first <= t) history_.pop_front();
    return history_.front().second;
  }

  uint64_t packets = 0;  // v1 packets written to the FIFO
  uint64_t frames = 0;   // v2 frames with a good CRC
  uint64_t fifo_writes = 0, cfg_writes = 0;
  // v1 packets queued and v2 frames that passed every check (cnc_core packet_count): the edge
  // after which the strobe is high.
  std::vector<Cycle> packet_done_cycles;
  std::vector<Cycle> v1_packet_cycles;                         // v1 packets only
  std::vector<std::pair<Cycle, RespReq>> naks;                 // every NAK request
  std::vector<std::pair<Cycle, DecoderState>>* log = nullptr;  // every state change, when set
  std::function<void(Cycle)> before_write;          // called with the edge of each FIFO write
  std::function<void(const MotionReq&)> on_motion;  // each accepted MOTION frame
  // false: MOTION is an unknown type (NAK UNKNOWN_TYPE), as on a core without the motion rate
  // (the live twin board, virtual_board.h)
  bool accept_motion = true;

 private:
  enum class Kind { None, V1Init, V1Motion, V2 };

  // The state as it is after edge c (history in edge order).
  void commit(Cycle c, const DecoderState& st) {
    if (log) log->emplace_back(c, st);
    if (history_.back().first == c)
      history_.back().second = st;
    else
      history_.emplace_back(c, st);
  }
  void commit(Cycle c) { commit(c, s_); }
  // A CHECK on the clock after edge L: registers change on L + 1, counters on L + 2.
  void commit_check(Cycle l) {
    mode_before_ = history_.back().second.v2_mode;
    mode_from_ = l + 2;
    DecoderState regs = history_.back().second;
    regs.next_seq = s_.next_seq;
    regs.v2_mode = s_.v2_mode;
    commit(l + 1, regs);
    commit(l + 2);
  }
  void request(Cycle c, RespReq r) {
    if (r.kind == kReqNak) naks.emplace_back(c, r);
    transport(resp, gp_, clk_, r, c);
  }

  void expire() {
    const Cycle f = last_take_ + wd_;
    ++s_.timeouts;
    commit(f + 1);
    if (kind_ == Kind::V2)
      request(f, RespReq{kReqNak, count_ > 2 ? seq_ : uint8_t{0}, v2::kTimeout});
    count_ = 0;
    kind_ = Kind::None;
  }

  uint32_t fifo_level(Cycle c) {
    FifoLevel l{0};
    transport(fifo, gp_, clk_, l, c, tlm::TLM_READ_COMMAND);
    return l.level;
  }
  // Written on L + kDecoderWrite if the FIFO has room after edge L.
  bool write_fifo(Cycle l, FifoEntry e) {
    if (fifo_level(l) >= depth_) return false;
    if (before_write) before_write(l + kDecoderWrite);
    transport(fifo, gp_, clk_, e, l + kDecoderWrite);
    ++fifo_writes;
    return true;
  }

  void on_byte(tlm::tlm_generic_payload& gp, sc_core::sc_time& delay) {
    const uint8_t byte = payload<RxByte>(gp).byte;
    const Cycle take = clk_.at(delay) + kDecoderTake;
    gp.set_response_status(tlm::TLM_OK_RESPONSE);
    if (count_ > 0 && take - last_take_ > wd_) expire();
    last_take_ = take;
    if (count_ == 0) {
      // The mode register as it is after edge take - 1 (a CHECK changes it on L + 1).
      const bool v2m = take >= mode_from_ ? s_.v2_mode : mode_before_;
      if (byte == v2::kSync) {
        kind_ = Kind::V2;
      } else if (!v2m && byte == spec::kV1InitByte) {
        kind_ = Kind::V1Init;
      } else if (!v2m && byte <= 3) {
        kind_ = Kind::V1Motion;
        code_ = byte;
      } else {
        ++s_.noise;
        commit(take + 1);
        return;
      }
      count_ = 1;
      return;
    }
    if (kind_ == Kind::V2) {
      v2_byte(take, byte);
      return;
    }
    buf_[count_ - 1] = byte;
    ++count_;
    if (count_ < (kind_ == Kind::V1Init ? 9 : 11)) return;
    v1_packet(take);
  }

  static uint32_t be32(const uint8_t* b) {
    return static_cast<uint32_t>(b[0]) << 24 | static_cast<uint32_t>(b[1]) << 16 |
           static_cast<uint32_t>(b[2]) << 8 | b[3];
  }
  static uint16_t be16(const uint8_t* b) { return static_cast<uint16_t>(b[0] << 8 | b[1]); }
  static uint64_t be48(const uint8_t* b) {
    return static_cast<uint64_t>(be16(b)) << 32 | be32(b + 2);
  }
  uint32_t profile_step(int a, int width) const {
    const uint8_t* p = &payload_[28 + width * a];
    return width == 2 ? static_cast<uint32_t>(static_cast<int32_t>(static_cast<int16_t>(be16(p))))
                      : be32(p);
  }
  // LINE_PROFILE field rules (docs/protocol.md), as frame_decoder.v checks them.
  bool profile_fields_ok(int axes, int width) const {
    bool moves = false;
    for (int a = 0; a < axes; ++a) {
      const auto s = static_cast<int32_t>(profile_step(a, width));
      constexpr int32_t kLim = int32_t{1} << spec::kProfileNDomBits;
      if (s <= -kLim || s >= kLim) return false;
      if (s != 0) moves = true;
    }
    const uint64_t ve = be48(&payload_[2]), vc = be48(&payload_[8]), vx = be48(&payload_[14]);
    const uint32_t acc = be32(&payload_[20]);
    return moves && vc < (uint64_t{1} << spec::kProfileVBits) && ve <= vc && vx <= vc && vx != 0 &&
           (acc != 0 || ve != 0);
  }

  // ARC field rules (docs/protocol.md "ARC", as frame_decoder.v checks them): code 2 or 3, flag
  // bits 7:4 zero, plane (bits 3:2) 0..2 (1, 2 only with 3 axes); start and end not at the centre;
  // |I|, |J|, |DX - I|, |DY - J| < 2^22; DZ != -2^31 (0 with fewer than 3 axes); N_RAMP >= 1; 1 <=
  // C_TOTAL < 2^46; V_cruise < 2^63; V_entry, V_exit <= V_cruise; V_exit >= 1; A >= 1 or V_entry
  // >= 1.
  bool arc_fields_ok() const {
    std::array<uint8_t, spec::kArcRawBytes> raw{};
    std::copy(payload_.begin() + 2, payload_.begin() + 2 + spec::kArcRawBytes, raw.begin());
    const models::arc::Frame f = v2::arc_frame_from_raw(raw, true);
    const int64_t x1 = int64_t{f.g.dx} - f.g.i, y1 = int64_t{f.g.dy} - f.g.j;
    constexpr int64_t kC = int64_t{1} << spec::kArcCoordBits;
    const auto c22 = [](int64_t v) { return v > -kC && v < kC; };
    const int plane = payload_[0] >> 2 & 3;
    return (payload_[0] & 0xF0) == 0 && plane != 3 && (plane == 0 || kAxes >= 3) &&
           (payload_[0] & 2) != 0 && (f.g.i != 0 || f.g.j != 0) && (x1 != 0 || y1 != 0) &&
           c22(f.g.i) && c22(f.g.j) && c22(x1) && c22(y1) && f.dz != INT32_MIN &&
           (kAxes >= 3 || f.dz == 0) && f.n_ramp != 0 && f.c_total != 0 &&
           f.c_total < (uint64_t{1} << spec::kArcCTotalBits) && f.v_cruise < (uint64_t{1} << 63) &&
           f.v_entry <= f.v_cruise && f.v_exit <= f.v_cruise && f.v_exit != 0 &&
           (f.a != 0 || f.v_entry != 0);
  }

  // MOTION field rules (docs/protocol.md "MOTION"): flags bits 7:3 zero, RESUME not with HOLD or
  // CANCEL, feed and rapid 1..0x8000, ramp >= 1.
  bool motion_fields_ok() const {
    const uint8_t f = payload_[0];
    const uint16_t feed = be16(&payload_[1]), rapid = be16(&payload_[3]);
    return (f & spec::kMotionReserved) == 0 &&
           ((f & spec::kMotionResume) == 0 ||
            (f & (spec::kMotionHold | spec::kMotionCancel)) == 0) &&
           feed >= 1 && feed <= spec::kRateOne && rapid >= 1 && rapid <= spec::kRateOne &&
           be32(&payload_[5]) != 0;
  }

  // OUTPUT field rules (docs/protocol.md "OUTPUT"): mask != 0, value bit 2 clear, value only
  // where the mask is set, duty 0 unless mask bit 2.
  bool output_fields_ok() const {
    const uint8_t m = payload_[0], v = payload_[1], d = payload_[2];
    return m != 0 && (v & ~m) == 0 && (v & 0x04) == 0 && ((m & 0x04) != 0 || d == 0);
  }

  // Soft limits: an axis's travel in steps and the queued end position (docs/machine.md).
  struct Travel {
    bool on = false;
    int32_t min = 0, max = 0;
  };
  std::array<Travel, kAxes> travel_{};
  std::array<int32_t, kAxes> queued_{};

  // The steps of the frame being checked, per axis (an ARC's DX, DY, DZ on its plane's axes).
  std::array<int32_t, kAxes> frame_steps(int axes, int width) const {
    std::array<int32_t, kAxes> d{};
    if (type_ == v2::kArc) {
      std::array<uint8_t, spec::kArcRawBytes> raw{};
      std::copy(payload_.begin() + 2, payload_.begin() + 2 + spec::kArcRawBytes, raw.begin());
      const models::arc::Frame f = v2::arc_frame_from_raw(raw, true);
      const int32_t u = f.g.dx, v = f.g.dy, h = f.dz;
      // (u, v, h) per plane: XY (X, Y, Z), ZX (Z, X, Y), YZ (Y, Z, X)
      static constexpr int kU[3] = {0, 2, 1}, kV[3] = {1, 0, 2}, kH[3] = {2, 1, 0};
      const int plane = payload_[0] >> 2 & 3;
      auto put = [&](int axis, int32_t x) {
        if (axis < kAxes) d[static_cast<size_t>(axis)] = x;
      };
      put(kU[plane], u);
      put(kV[plane], v);
      put(kH[plane], h);
      return d;
    }
    const int base = type_ == v2::kLine ? 6 : 28;
    for (int a = 0; a < axes; ++a) {
      const uint8_t* p = &payload_[static_cast<size_t>(base + width * a)];
      d[static_cast<size_t>(a)] =
          width == 2 ? static_cast<int16_t>(be16(p)) : static_cast<int32_t>(be32(p));
    }
    return d;
  }
  bool travel_ok(const std::array<int32_t, kAxes>& d) const {
    for (size_t a = 0; a < kAxes; ++a) {
      const int64_t end = int64_t{queued_[a]} + d[a];
      if (travel_[a].on && (end < travel_[a].min || end > travel_[a].max)) return false;
    }
    return true;
  }
  void follow(const std::array<int32_t, kAxes>& d) {
    for (size_t a = 0; a < kAxes; ++a)
      queued_[a] =
          static_cast<int32_t>(static_cast<uint32_t>(queued_[a]) + static_cast<uint32_t>(d[a]));
  }

  void v1_packet(Cycle take) {
    const bool init = kind_ == Kind::V1Init;
    count_ = 0;
    kind_ = Kind::None;
    FifoEntry e{};
    e.v2 = false;
    e.kind = init ? kEntryNumerators : kEntryMotion;
    e.code = init ? 0 : code_;
    e.power = init ? 0 : 0xFF;
    e.steps[0] = be32(&buf_[0]);
    e.steps[1] = be32(&buf_[4]);
    e.t = init ? 0 : be16(&buf_[8]);
    if (!write_fifo(take, e)) {
      ++s_.overruns;
      commit_check(take);
      return;
    }
    if (!init) follow({static_cast<int32_t>(e.steps[0]), static_cast<int32_t>(e.steps[1])});
    ++packets;
    packet_done_cycles.push_back(take + kDecoderResp);
    v1_packet_cycles.push_back(take + kDecoderResp);
  }

  void v2_byte(Cycle take, uint8_t byte) {
    // count_ bytes so far: 1 SYNC, 2 LEN, 3 SEQ, 4 TYPE, then payload, then CRC.
    if (count_ == 1) {
      len_ = byte;
      if (len_ > v2::kMaxPayload) {  // at once: strobes after this byte's edge
        ++s_.length_errors;
        commit(take + 1);
        request(take, RespReq{kReqNak, 0, v2::kBadLength});
        count_ = 0;
        kind_ = Kind::None;
        return;
      }
    } else if (count_ == 2) {
      seq_ = byte;
    } else if (count_ == 3) {
      type_ = byte;
    } else if (count_ < 4 + len_) {
      payload_[count_ - 4] = byte;
    } else if (count_ == 4 + len_) {
      crc_hi_ = byte;
    }
    ++count_;
    if (count_ < 6 + len_) return;
    // The last CRC byte.
    uint8_t body[3 + v2::kMaxPayload];
    body[0] = static_cast<uint8_t>(len_);
    body[1] = seq_;
    body[2] = type_;
    std::copy(payload_.begin(), payload_.begin() + len_, body + 3);
    const uint16_t crc = crc16_ccitt(body, 3 + static_cast<size_t>(len_));
    if (crc != static_cast<uint16_t>(crc_hi_ << 8 | byte)) {
      count_ = 0;
      kind_ = Kind::None;
      ++s_.crc_errors;
      commit_check(take);
      request(take + kDecoderResp, RespReq{kReqNak, seq_, v2::kBadCrc});
      return;
    }
    ++frames;
    s_.v2_mode = true;
    frame(take);
  }

  // Expected payload length of a type (-1: unknown type; -2: LINE, -3: LINE_PROFILE, -4:
  // THERMISTOR_TABLE, checked apart).
  static int expected_len(uint8_t type) {
    switch (type) {
      case v2::kHello:
      case v2::kStatusQuery:
      case v2::kFaultClear:
      case v2::kRelease:
        return 0;
      case v2::kConfigAxis:
        return static_cast<int>(spec::kLenConfigAxis);
      case v2::kConfigTravel:
        return static_cast<int>(spec::kLenConfigTravel);
      case v2::kNumerators:
        return static_cast<int>(spec::kLenNumerators);
      case v2::kDwell:
        return static_cast<int>(spec::kLenDwell);
      case v2::kLine:
        return -2;
      case v2::kLineProfile:
        return -3;
      case v2::kArc:
        return static_cast<int>(spec::kLenArc);
      case v2::kOutput:
        return static_cast<int>(spec::kLenOutput);
      case spec::kTypeMotion:
        return static_cast<int>(spec::kLenMotion);
      case v2::kHeaterConfig:  // heater frames (docs/protocol.md "Heater frames")
        return static_cast<int>(spec::kLenHeaterConfig);
      case v2::kHeaterSetpoint:
        return static_cast<int>(spec::kLenHeaterSetpoint);
      case v2::kThermistorTable:
        return -4;  // even, within its min..max
      case v2::kHeaterSafety:
        return static_cast<int>(spec::kLenHeaterSafety);
      case v2::kHeaterWatchdog:
        return static_cast<int>(spec::kLenHeaterWatchdog);
      default:
        return -1;
    }
  }

  // Heater frames' BAD_FIELD rules (rtl/protocol/frame_decoder.v): channel > 1; HEATER_CONFIG mode
  // > 4, duty_max or manual > 0x8000; THERMISTOR_TABLE first > 64 or first + n > 65; HEATER_SAFETY
  // Tmin >= Tmax. Other types: true.
  bool heater_fields_ok() const {
    if (type_ < v2::kHeaterConfig || type_ > v2::kHeaterWatchdog) return true;
    auto u16 = [&](int i) { return (payload_[i] << 8) | payload_[i + 1]; };
    if (type_ != v2::kHeaterWatchdog && payload_[0] > 1) return false;
    if (type_ == v2::kHeaterConfig)
      return payload_[1] <= 4 && u16(14) <= 0x8000 && u16(18) <= 0x8000;
    if (type_ == v2::kThermistorTable)
      return payload_[1] <= 64 && payload_[1] + (len_ - 2) / 2 <= 65;
    if (type_ == v2::kHeaterSafety)
      return static_cast<int16_t>(u16(1)) < static_cast<int16_t>(u16(3));
    return true;
  }

  void frame(Cycle take) {
    count_ = 0;
    kind_ = Kind::None;
    const Cycle r = take + kDecoderResp;
    const int want = type_ == spec::kTypeMotion && !accept_motion ? -1 : expected_len(type_);
    if (want == -1) {
      ++s_.unknown_types;
      commit_check(take);
      request(r, RespReq{kReqNak, seq_, v2::kUnknownType});
      return;
    }
    int width = 4, axes = 0;
    if (want == -2 || want == -3) {
      width = (payload_[0] & 0x80) ? 2 : 4;
      const int rest =
          len_ - static_cast<int>(want == -2 ? spec::kLenLineHeader : spec::kLenLineProfileHeader);
      if (rest < 0 || rest % width != 0 || rest / width > kAxes) {
        ++s_.length_errors;
        commit_check(take);
        request(r, RespReq{kReqNak, seq_, v2::kBadLength});
        return;
      }
      axes = rest / width;
    } else if (want == -4) {
      if (len_ < static_cast<int>(spec::kLenThermistorTableMin) ||
          len_ > static_cast<int>(spec::kLenThermistorTableMax) || (len_ & 1)) {
        ++s_.length_errors;
        commit_check(take);
        request(r, RespReq{kReqNak, seq_, v2::kBadLength});
        return;
      }
    } else if (want != len_) {
      ++s_.length_errors;
      commit_check(take);
      request(r, RespReq{kReqNak, seq_, v2::kBadLength});
      return;
    }
    if (((type_ == v2::kLine || type_ == v2::kLineProfile) && (payload_[0] & 0x7C) != 0) ||
        (type_ == v2::kConfigAxis && payload_[0] >= kAxes) ||
        (type_ == v2::kConfigTravel &&
         (payload_[0] >= kAxes || (payload_[1] & 0xFE) != 0 ||
          ((payload_[1] & 1) != 0 &&
           static_cast<int32_t>(be32(&payload_[2])) > static_cast<int32_t>(be32(&payload_[6]))))) ||
        (type_ == v2::kLineProfile && !profile_fields_ok(axes, width)) ||
        (type_ == v2::kArc && !arc_fields_ok()) || (type_ == v2::kOutput && !output_fields_ok()) ||
        (type_ == spec::kTypeMotion && !motion_fields_ok()) || !heater_fields_ok()) {
      commit_check(take);
      request(r, RespReq{kReqNak, seq_, v2::kBadField});
      return;
    }
    if (type_ == v2::kHello || type_ == v2::kStatusQuery || type_ == spec::kTypeMotion) {
      ++s_.frames_ok;
      packet_done_cycles.push_back(r);
      commit_check(take);
      if (type_ == spec::kTypeMotion && on_motion) {
        const uint8_t f = payload_[0];
        on_motion(MotionReq{take + kMotionTakes, (f & spec::kMotionHold) != 0,
                            (f & spec::kMotionResume) != 0, (f & spec::kMotionCancel) != 0,
                            be16(&payload_[1]), be16(&payload_[3]), be32(&payload_[5])});
      }
      request(r, RespReq{type_ == v2::kHello ? kReqIdent : kReqStatus});
      return;
    }
    const SeqClass sc = classify_seq(seq_, s_.next_seq);
    if (sc == SeqClass::Ahead) {
      commit_check(take);
      request(r, RespReq{kReqNak, seq_, v2::kOutOfOrder});
      return;
    }
    if (sc == SeqClass::Duplicate) {
      ++s_.frames_ok;
      packet_done_cycles.push_back(r);
      if (type_ == v2::kRelease) s_.v2_mode = false;
      commit_check(take);
      request(r, RespReq{kReqAck});
      return;
    }
    const bool moves = type_ == v2::kLine || type_ == v2::kLineProfile || type_ == v2::kArc;
    const std::array<int32_t, kAxes> steps =
        moves ? frame_steps(axes, width) : std::array<int32_t, kAxes>{};
    if (moves && !travel_ok(steps)) {
      commit_check(take);
      request(r, RespReq{kReqNak, seq_, v2::kTravel});
      return;
    }
    if (type_ == v2::kLine || type_ == v2::kDwell || type_ == v2::kNumerators ||
        type_ == v2::kLineProfile || type_ == v2::kArc || type_ == v2::kOutput) {
      FifoEntry e{};
      e.v2 = true;
      if (type_ == v2::kOutput) {  // kind 3 with v2 0
        e.v2 = false;
        e.kind = kEntryOutput;
        e.power = 0;
        e.t = static_cast<uint32_t>(payload_[0]) << 16 | static_cast<uint32_t>(payload_[1]) << 8 |
              payload_[2];
      } else if (type_ == v2::kArc) {  // payload bytes 2..62 as received
        e.kind = kEntryMotion;
        e.arc = true;
        e.code = payload_[0] & 3;
        e.power = payload_[1];
        e.t = payload_[0] >> 2 & 3;  // the plane
        std::copy(payload_.begin() + 2, payload_.begin() + 63, e.arc_raw.begin());
      } else if (type_ == v2::kLineProfile) {
        e.kind = kEntryMotion;
        e.prof = true;
        e.code = payload_[0] & 3;
        e.power = payload_[1];
        e.v_entry = be48(&payload_[2]);
        e.v_cruise = be48(&payload_[8]);
        e.v_exit = be48(&payload_[14]);
        e.t = be32(&payload_[20]);
        e.decel_at = be32(&payload_[24]);
        for (int a = 0; a < axes; ++a) e.steps[a] = profile_step(a, width);
      } else if (type_ == v2::kLine) {
        e.kind = kEntryMotion;
        e.code = payload_[0] & 3;
        e.power = payload_[1];
        e.t = be32(&payload_[2]);
        for (int a = 0; a < axes; ++a) {
          const uint8_t* p = &payload_[6 + width * a];
          e.steps[a] =
              width == 2
                  ? static_cast<uint32_t>(static_cast<int32_t>(static_cast<int16_t>(be16(p))))
                  : be32(p);
        }
      } else if (type_ == v2::kDwell) {
        e.kind = kEntryDwell;
        e.t = be32(&payload_[0]);
      } else {
        e.kind = kEntryNumerators;
        e.steps[0] = be32(&payload_[0]);
        e.steps[1] = be32(&payload_[4]);
      }
      if (!write_fifo(take, e)) {
        commit_check(take);
        request(r, RespReq{kReqNak, seq_, v2::kFifoFull});
        return;
      }
      if (moves) follow(steps);
    } else if (type_ == v2::kConfigTravel) {
      const auto a = static_cast<size_t>(payload_[0]);
      travel_[a] = Travel{(payload_[1] & 1) != 0, static_cast<int32_t>(be32(&payload_[2])),
                          static_cast<int32_t>(be32(&payload_[6]))};
    } else if (type_ == v2::kConfigAxis) {
      CfgAxis c{payload_[0], AxisTiming{be16(&payload_[1]), be16(&payload_[3]), be16(&payload_[5]),
                                        be16(&payload_[7])}};
      ++cfg_writes;
      transport(cfg, gp_, clk_, c, take + kDecoderWrite);
    } else if (type_ == v2::kFaultClear) {
      request(r, RespReq{kReqFaultClear});
    } else if (type_ == v2::kRelease) {
      s_.v2_mode = false;
    }
    ++s_.frames_ok;
    packet_done_cycles.push_back(r);
    ++s_.next_seq;
    commit_check(take);
    request(r, RespReq{kReqAck});
  }

  const CycleClock& clk_;
  Cycle wd_;
  uint32_t depth_;
  int count_ = 0;
  Kind kind_ = Kind::None;
  uint8_t code_ = 0;
  std::array<uint8_t, 10> buf_{};
  int len_ = 0;
  uint8_t seq_ = 0, type_ = 0, crc_hi_ = 0;
  std::array<uint8_t, v2::kMaxPayload> payload_{};
  Cycle last_take_ = 0;
  DecoderState s_;
  bool mode_before_ = false;  // the mode before the last CHECK, for a byte taken on L + 1
  Cycle mode_from_ = 0;
  std::deque<std::pair<Cycle, DecoderState>> history_;  // (edge, state after it)
  tlm::tlm_generic_payload gp_;
};

}  // namespace fpgacnc::twins
