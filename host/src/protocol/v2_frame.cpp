// The v2 frame itself (docs/protocol.md "Frame"): CRC-16/CCITT-FALSE, the encoder, the
// resyncing parser of a byte stream, the names of types, NAK reasons and counters from the
// specification table, and hex dumps. Every frame family builds on these.
#include <fmt/format.h>

#include <algorithm>

#include "fpgacnc/protocol/v2.h"
#include "v2_bytes.h"

namespace fpgacnc::protocol::v2 {
using detail::put16;

namespace {

// Precomputed table for the MSB-first CRC (one lookup per byte).
struct CrcTable {
  std::array<uint16_t, 256> t{};
  constexpr CrcTable() {
    for (unsigned i = 0; i < 256; ++i) {
      uint16_t c = static_cast<uint16_t>(i << 8);
      for (int b = 0; b < 8; ++b) {
        c = (c & 0x8000) ? static_cast<uint16_t>((c << 1) ^ 0x1021) : static_cast<uint16_t>(c << 1);
      }
      t[i] = c;
    }
  }
};
constexpr CrcTable kCrcTable;

}  // namespace

namespace detail {
void expect(const Frame& f, Type type, size_t len) {
  if (f.type != static_cast<uint8_t>(type)) {
    throw ProtocolError(fmt::format("expected a {} frame, got {}",
                                    type_name(static_cast<uint8_t>(type)), type_name(f.type)));
  }
  if (f.payload.size() != len) {
    throw ProtocolError(fmt::format("{}: payload of {} bytes, expected {}", type_name(f.type),
                                    f.payload.size(), len));
  }
}
}  // namespace detail

namespace {
// The TYPE table of spec/protocol.toml (fpgacnc/spec.h).
const spec::TypeInfo* type_info(uint8_t type) {
  for (const auto& t : spec::kTypes)
    if (t.value == type) return &t;
  return nullptr;
}
}  // namespace

std::string type_name(uint8_t type) {
  if (const auto* t = type_info(type)) return std::string(t->name);
  return fmt::format("type 0x{:02X}", type);
}

std::string nak_reason_name(uint8_t reason) {
  for (const auto& r : spec::kNakReasons)
    if (r.value == reason) return std::string(r.name);
  return fmt::format("reason {}", reason);
}

std::string counter_name(size_t index) {
  return index < kCounters ? std::string(spec::kCounterNames[index])
                           : fmt::format("counter {}", index);
}

bool is_sequenced(uint8_t type) {
  const auto* t = type_info(type);
  return t && t->host && t->sequenced;
}

bool is_fifo(uint8_t type) {
  const auto* t = type_info(type);
  return t && t->host && t->fifo;
}

uint16_t crc16(std::span<const uint8_t> data) {
  uint16_t c = 0xFFFF;
  for (const uint8_t b : data) {
    c = static_cast<uint16_t>((c << 8) ^ kCrcTable.t[((c >> 8) ^ b) & 0xFF]);
  }
  return c;
}

void encode_to(const Frame& f, std::vector<uint8_t>& out) {
  if (f.payload.size() > kMaxPayload) {
    throw std::invalid_argument(fmt::format("{} frame: payload of {} bytes exceeds {}",
                                            type_name(f.type), f.payload.size(), kMaxPayload));
  }
  const size_t start = out.size();
  out.push_back(kSync);
  out.push_back(static_cast<uint8_t>(f.payload.size()));
  out.push_back(f.seq);
  out.push_back(f.type);
  out.insert(out.end(), f.payload.begin(), f.payload.end());
  const uint16_t c =
      crc16(std::span<const uint8_t>(out.data() + start + 1, out.size() - start - 1));
  put16(out, c);
}

std::vector<uint8_t> encode(const Frame& f) {
  std::vector<uint8_t> out;
  out.reserve(kOverhead + f.payload.size());
  encode_to(f, out);
  return out;
}

// ---- FrameParser ----

void FrameParser::feed(std::span<const uint8_t> bytes) {
  compact();
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

void FrameParser::compact() {
  if (pos_ > 4096 || (pos_ > 0 && pos_ == buf_.size())) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(pos_));
    pos_ = 0;
  }
}

std::optional<Frame> FrameParser::next() {
  for (;;) {
    // Hunt for a sync byte.
    while (pos_ < buf_.size() && buf_[pos_] != kSync) {
      ++noise_bytes_;
      ++pos_;
    }
    if (buf_.size() - pos_ < 2) return std::nullopt;
    const size_t len = buf_[pos_ + 1];
    if (len > kMaxPayload) {
      ++bad_length_;
      ++pos_;  // reject this sync byte only
      continue;
    }
    if (buf_.size() - pos_ < kOverhead + len) return std::nullopt;
    const uint8_t* p = buf_.data() + pos_;
    const uint16_t want = crc16(std::span<const uint8_t>(p + 1, 3 + len));
    const uint16_t got = static_cast<uint16_t>((p[4 + len] << 8) | p[5 + len]);
    if (want != got) {
      ++crc_errors_;
      ++pos_;
      continue;
    }
    Frame f;
    f.seq = p[2];
    f.type = p[3];
    f.payload.assign(p + 4, p + 4 + len);
    pos_ += kOverhead + len;
    ++frames_;
    compact();
    return f;
  }
}

bool FrameParser::abandon_partial() {
  // next() leaves the buffer at a sync byte (or empty) whenever it returns nullopt.
  if (pos_ >= buf_.size() || buf_[pos_] != kSync) return false;
  ++abandoned_;
  ++pos_;
  return true;
}

void FrameParser::reset() {
  buf_.clear();
  pos_ = 0;
}

std::string hex(std::span<const uint8_t> bytes) {
  std::string s;
  s.reserve(bytes.size() * 3);
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (i) s += ' ';
    s += fmt::format("{:02X}", bytes[i]);
  }
  return s;
}

}  // namespace fpgacnc::protocol::v2
