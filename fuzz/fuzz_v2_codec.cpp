// libFuzzer target: the protocol v2 codec (host/include/fpgacnc/protocol/v2.h).
//
// Input byte 0 selects the mode, the rest is the data:
//   even: the data is a raw byte stream from the line: fed to a FrameParser at once and, in a
//         second parser, in chunks whose sizes come from the data itself; both must yield the
//         same frames and counters;
//   odd:  the data is a list of frames (SEQ, TYPE, LEN, payload), encoded with valid CRCs, so
//         that every decoder sees well-formed frames of every type and length; then builder
//         round trips: line/dwell/config_axis/numerators and ack/done/nak/ident/status built
//         from the data decode back to the same fields.
// For every frame a parser yields: payload <= 64 bytes; every decoder (device answers:
// decode_credit, _nak, _ident, _status for 1..4 axes; host frames: decode_line, _dwell,
// _config_axis, _numerators, _motion) returns or throws ProtocolError (anything else escapes and is
// reported as a crash); check_host_frame agrees with the host decoders (no NAK reason exactly
// when the decoder accepts); encode(frame) is 6 + LEN bytes with SYNC, LEN and the CRC-16 of
// bytes 1..3+N, and parsed back gives exactly that frame, with no error counted.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "fpgacnc/protocol/v2.h"

namespace {

namespace v2 = fpgacnc::protocol::v2;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_v2_codec: property violated: %s\n", what.c_str());
  std::abort();
}

bool same(const v2::Frame& a, const v2::Frame& b) {
  return a.seq == b.seq && a.type == b.type && a.payload == b.payload;
}

void run_decoders(const v2::Frame& f) {
  try {
    const auto c = v2::decode_credit(f);
    (void)c;
  } catch (const v2::ProtocolError&) {
  }
  try {
    const auto n = v2::decode_nak(f);
    (void)n;
  } catch (const v2::ProtocolError&) {
  }
  try {
    const auto id = v2::decode_ident(f);
    (void)id;
  } catch (const v2::ProtocolError&) {
  }
  for (size_t axes = 1; axes <= 4; ++axes) {
    try {
      const auto st = v2::decode_status(f, axes);
      if (st.position.size() != axes) fail("decode_status: position size != n_axes");
    } catch (const v2::ProtocolError&) {
    }
  }
  // Host frames: the decoders and check_host_frame (the device's rules) agree.
  for (size_t axes : {size_t{2}, size_t{4}}) {
    const auto reason = v2::check_host_frame(f, axes);
    bool accepted = false;
    bool host_type = true;
    try {
      switch (static_cast<v2::Type>(f.type)) {
        case v2::Type::Line: {
          const auto l = v2::decode_line(f, axes);
          if (l.steps.size() > axes) fail("decode_line: more axes than allowed");
          break;
        }
        case v2::Type::Dwell:
          (void)v2::decode_dwell(f);
          break;
        case v2::Type::LineProfile: {
          const auto l = v2::decode_line_profile(f, axes);
          if (l.steps.size() > axes) fail("decode_line_profile: more axes than allowed");
          if (!v2::line_profile_field_error(l).empty()) fail("decode_line_profile: bad field");
          break;
        }
        case v2::Type::Arc: {
          const auto a = v2::decode_arc(f);
          if (!v2::arc_field_error(a).empty()) fail("decode_arc: bad field accepted");
          // every payload bit is a field: the builder gives the same bytes back
          if (v2::arc(f.seq, a).payload != f.payload) fail("decode_arc: rebuilt payload differs");
          // The board's own rule (a helix or a ZX / YZ plane needs 3 axes) is the field check
          // with n_axes: a frame it breaks is refused like a decoder error.
          if (!v2::arc_field_error(a, axes).empty()) throw v2::ProtocolError("needs 3 axes");
          break;
        }
        case v2::Type::ConfigAxis: {
          const auto c = v2::decode_config_axis(f, axes);
          if (c.axis >= axes) fail("decode_config_axis: axis out of range accepted");
          break;
        }
        case v2::Type::Numerators:
          (void)v2::decode_numerators(f);
          break;
        case v2::Type::Motion: {
          const auto m = v2::decode_motion(f);
          if (!v2::motion_field_error(m).empty()) fail("decode_motion: bad field accepted");
          // every payload bit is a field: the builder gives the same bytes back
          if (v2::motion(m, f.seq).payload != f.payload) fail("decode_motion: rebuilt differs");
          break;
        }
        case v2::Type::Trigger: {
          const auto [mode, mask] = v2::decode_trigger(f, axes);
          if (!v2::trigger_field_error(mode, mask, axes).empty())
            fail("decode_trigger: bad field accepted");
          if (v2::trigger(f.seq, mode, mask, axes).payload != f.payload)
            fail("decode_trigger: rebuilt differs");
          break;
        }
        case v2::Type::SetPosition: {
          const auto [mask, pos] = v2::decode_set_position(f, axes);
          if (pos.size() != axes) fail("decode_set_position: wrong axis count accepted");
          if (v2::set_position(f.seq, mask, pos).payload != f.payload)
            fail("decode_set_position: rebuilt differs");
          break;
        }
        default:
          host_type = false;
      }
      accepted = true;
    } catch (const v2::ProtocolError&) {
    }
    if (host_type && accepted != !reason.has_value()) {
      fail("check_host_frame and the host decoder disagree on type " + std::to_string(f.type) +
           " LEN " + std::to_string(f.payload.size()));
    }
  }
}

// Builders round trip through encode, the parser and the decoders.
template <class T>
T parse_back(const v2::Frame& f, T (*decode)(const v2::Frame&)) {
  v2::FrameParser p;
  p.feed(v2::encode(f));
  const auto g = p.next();
  if (!g || !same(*g, f)) fail("built frame not parsed back");
  return decode(*g);
}

struct Reader {
  std::span<const uint8_t> d;
  size_t i = 0;
  uint32_t u(int bytes) {
    uint32_t v = 0;
    for (int k = 0; k < bytes; ++k) v = (v << 8) | (i < d.size() ? d[i++] : 0u);
    return v;
  }
};

void builders(std::span<const uint8_t> d) {
  Reader r{d};
  const auto seq = static_cast<uint8_t>(r.u(1));
  // LINE
  const auto code = static_cast<uint8_t>(r.u(1) & 3);
  const auto power = static_cast<uint8_t>(r.u(1));
  const uint32_t t = r.u(4);
  const size_t k = r.u(1) % 5;
  const bool shrt = r.u(1) & 1;
  std::vector<int32_t> steps;
  for (size_t a = 0; a < k; ++a) {
    const uint32_t v = r.u(4);
    // Mostly small counts (SHORT), sometimes full int32.
    steps.push_back((v & 0x80000000u) ? static_cast<int32_t>(v) : static_cast<int16_t>(v));
  }
  const v2::Frame lf = v2::line(seq, code, power, t, steps, shrt);
  const v2::Line l = v2::decode_line(lf, 4);
  bool fits = true;
  for (int32_t s : steps) fits = fits && s >= INT16_MIN && s <= INT16_MAX;
  if (l.code != code || l.power != power || l.t != t || l.steps != steps ||
      l.short_steps != (shrt && fits)) {
    fail("line() -> decode_line round trip differs");
  }
  if (v2::check_host_frame(lf, 4)) fail("check_host_frame rejects a built LINE");
  // DWELL, CONFIG_AXIS, NUMERATORS
  const uint32_t dt = r.u(4);
  if (v2::decode_dwell(v2::dwell(seq, dt)) != dt) fail("dwell round trip");
  const v2::ConfigAxis ca{static_cast<uint8_t>(r.u(1) & 3), static_cast<uint16_t>(r.u(2)),
                          static_cast<uint16_t>(r.u(2)), static_cast<uint16_t>(r.u(2)),
                          static_cast<uint16_t>(r.u(2))};
  if (!(v2::decode_config_axis(
            v2::config_axis(seq, ca.axis, ca.step_high, ca.step_low, ca.dir_setup, ca.dir_hold),
            4) == ca)) {
    fail("config_axis round trip");
  }
  const uint32_t nx = r.u(4), ny = r.u(4);
  if (v2::decode_numerators(v2::numerators(seq, nx, ny)) != std::array<uint32_t, 2>{nx, ny}) {
    fail("numerators round trip");
  }
  // Device frames.
  const v2::Credit c{static_cast<uint8_t>(r.u(1)), static_cast<uint16_t>(r.u(2)), r.u(4)};
  if (!(parse_back(v2::ack(seq, c), v2::decode_credit) == c)) fail("ack round trip");
  if (!(parse_back(v2::done(seq, c), v2::decode_credit) == c)) fail("done round trip");
  const v2::Nak n{static_cast<uint8_t>(r.u(1)), static_cast<v2::NakReason>(1 + r.u(1) % 7),
                  static_cast<uint8_t>(r.u(1)), static_cast<uint16_t>(r.u(2))};
  if (!(parse_back(v2::nak(seq, n), v2::decode_nak) == n)) fail("nak round trip");
  v2::Ident id;
  id.n_axes = static_cast<uint8_t>(r.u(1));
  id.fifo_depth = static_cast<uint16_t>(r.u(2));
  id.clk_hz = r.u(4);
  id.baud = r.u(4);
  id.build_id = r.u(4);
  id.next_seq = static_cast<uint8_t>(r.u(1));
  try {
    if (!(parse_back(v2::ident(seq, id), v2::decode_ident) == id)) fail("ident round trip");
  } catch (const v2::ProtocolError&) {
    // decode_ident may refuse field values the device never sends (e.g. 0 axes).
  }
  v2::Status st;
  const size_t axes = 1 + r.u(1) % 4;
  st.state = static_cast<uint8_t>(r.u(1));
  st.faults = static_cast<uint8_t>(r.u(1));
  st.fifo_level = static_cast<uint16_t>(r.u(2));
  st.next_seq = static_cast<uint8_t>(r.u(1));
  st.done = r.u(4);
  for (size_t a = 0; a < axes; ++a) st.position.push_back(static_cast<int32_t>(r.u(4)));
  for (auto& x : st.counters) x = static_cast<uint16_t>(r.u(2));
  v2::FrameParser p;
  const v2::Frame sf = v2::status(seq, st);
  p.feed(v2::encode(sf));
  const auto g = p.next();
  if (!g || !same(*g, sf)) fail("status frame not parsed back");
  if (!(v2::decode_status(*g, axes) == st)) fail("status round trip");
}

void round_trip(const v2::Frame& f) {
  const std::vector<uint8_t> bytes = v2::encode(f);
  if (bytes.size() != 6 + f.payload.size()) fail("encoded size != 6 + LEN");
  if (bytes[0] != v2::kSync || bytes[1] != f.payload.size() || bytes[2] != f.seq ||
      bytes[3] != f.type) {
    fail("encoded header wrong");
  }
  const uint16_t crc = v2::crc16(std::span<const uint8_t>(bytes.data() + 1, bytes.size() - 3));
  if (bytes[bytes.size() - 2] != (crc >> 8) || bytes[bytes.size() - 1] != (crc & 0xFF)) {
    fail("encoded CRC wrong");
  }
  v2::FrameParser p;
  p.feed(bytes);
  const auto g = p.next();
  if (!g) fail("encoded frame not parsed back");
  if (!same(*g, f)) fail("parsed frame differs from the encoded one");
  if (p.next()) fail("one encoded frame parsed as two");
  if (p.crc_errors() || p.bad_length() || p.noise_bytes()) fail("errors counted on a good frame");
}

void check_frame(const v2::Frame& f) {
  if (f.payload.size() > v2::kMaxPayload) fail("frame with payload > 64 bytes");
  run_decoders(f);
  round_trip(f);
}

std::vector<v2::Frame> drain(v2::FrameParser& p) {
  std::vector<v2::Frame> v;
  while (auto f = p.next()) v.push_back(std::move(*f));
  return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const bool frames_mode = data[0] & 1;
  const std::span<const uint8_t> in(data + 1, size - 1);

  if (!frames_mode) {
    v2::FrameParser whole;
    whole.feed(in);
    const auto a = drain(whole);
    // Chunked, draining between chunks; chunk sizes 1..16 from the data.
    v2::FrameParser chunked;
    std::vector<v2::Frame> b;
    size_t i = 0;
    while (i < in.size()) {
      const size_t n = std::min<size_t>(in.size() - i, 1 + (in[i] & 15));
      chunked.feed(in.subspan(i, n));
      for (auto& f : drain(chunked)) b.push_back(std::move(f));
      i += n;
    }
    if (a.size() != b.size()) fail("chunked feeding yields another number of frames");
    for (size_t k = 0; k < a.size(); ++k) {
      if (!same(a[k], b[k])) fail("chunked feeding yields another frame");
    }
    if (whole.crc_errors() != chunked.crc_errors() || whole.bad_length() != chunked.bad_length() ||
        whole.noise_bytes() != chunked.noise_bytes()) {
      fail("chunked feeding counts other errors");
    }
    for (const auto& f : a) check_frame(f);
    return 0;
  }

  // Frames mode.
  std::vector<v2::Frame> frames;
  size_t i = 0;
  while (i + 3 <= in.size()) {
    v2::Frame f;
    f.seq = in[i];
    f.type = in[i + 1];
    const size_t len = in[i + 2] % (v2::kMaxPayload + 1);
    i += 3;
    const size_t n = std::min(len, in.size() - i);
    f.payload.assign(in.begin() + static_cast<std::ptrdiff_t>(i),
                     in.begin() + static_cast<std::ptrdiff_t>(i + n));
    i += n;
    frames.push_back(std::move(f));
  }
  std::vector<uint8_t> stream;
  for (const auto& f : frames) {
    check_frame(f);
    const auto b = v2::encode(f);
    stream.insert(stream.end(), b.begin(), b.end());
  }
  v2::FrameParser p;
  p.feed(stream);
  const auto got = drain(p);
  if (got.size() != frames.size()) fail("a stream of good frames lost or gained frames");
  for (size_t k = 0; k < got.size(); ++k) {
    if (!same(got[k], frames[k])) fail("a stream of good frames parsed differently");
  }
  try {
    builders(in);
  } catch (const v2::ProtocolError& e) {
    fail(std::string("a decoder refused a frame built by the codec: ") + e.what());
  }
  // A payload over 64 bytes is refused.
  v2::Frame big;
  big.payload.resize(v2::kMaxPayload + 1 + (size & 7));
  try {
    (void)v2::encode(big);
    fail("encode accepted a payload over 64 bytes");
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
