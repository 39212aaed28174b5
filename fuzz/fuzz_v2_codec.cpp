// libFuzzer target: the protocol v2 codec (host/include/fpgacnc/protocol/v2.h).
//
// Input byte 0 selects the mode, the rest is the data:
//   even: the data is a raw byte stream from the line: fed to a FrameParser at once and, in a
//         second parser, in chunks whose sizes come from the data itself; both must yield the
//         same frames and counters;
//   odd:  the data is a list of frames (SEQ, TYPE, LEN, payload), encoded with valid CRCs, so
//         that every decoder sees well-formed frames of every type and length.
// For every frame a parser yields: payload <= 64 bytes; every decoder (decode_credit, _nak,
// _ident, _status for 1..4 axes) returns or throws ProtocolError (anything else escapes and is
// reported as a crash); encode(frame) is 6 + LEN bytes with SYNC, LEN and the CRC-16 of bytes
// 1..3+N, and parsed back gives exactly that frame, with no error counted.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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
}

void round_trip(const v2::Frame& f) {
  const std::vector<uint8_t> bytes = v2::encode(f);
  if (bytes.size() != 6 + f.payload.size()) fail("encoded size != 6 + LEN");
  if (bytes[0] != v2::kSync || bytes[1] != f.payload.size() || bytes[2] != f.seq ||
      bytes[3] != f.type) {
    fail("encoded header wrong");
  }
  const uint16_t crc =
      v2::crc16(std::span<const uint8_t>(bytes.data() + 1, bytes.size() - 3));
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
