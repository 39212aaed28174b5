// Line fault injection of the simulated board (label system): the injector and the rx line on
// their own (exact counts and bit patterns at fixed seeds), then through the Verilated cnc_core
// with v1 traffic (a raw client on the pty, the board in the test's thread, so cycle numbers
// are exact): faults off change nothing, each fault kind has the expected counts and effect on
// the bytes, a stall delays the next byte by exactly its length.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdlib>
#include <random>

#include "fpgacnc/models/uart_bits.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/line_faults.h"
#include "fpgacnc/simboard/sim_board.h"

namespace sb = fpgacnc::simboard;
namespace models = fpgacnc::models;
using namespace std::chrono_literals;

namespace {

// Seed of the randomized parts: FPGACNC_TEST_SEED or a fixed default; printed.
uint64_t test_seed() {
  static const uint64_t seed = [] {
    const char* e = std::getenv("FPGACNC_TEST_SEED");
    const uint64_t s = e ? std::strtoull(e, nullptr, 0) : 20240607;
    fmt::print("line fault tests: seed {} (FPGACNC_TEST_SEED)\n", s);
    return s;
  }();
  return seed;
}

std::vector<uint8_t> random_bytes(size_t n, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::vector<uint8_t> v(n);
  for (auto& b : v) b = static_cast<uint8_t>(g());
  return v;
}

// |got - expected| within 6 standard deviations of a binomial(n, p) count.
void expect_binomial(uint64_t got, uint64_t n, double p, const char* what) {
  const double mean = static_cast<double>(n) * p;
  const double sd = std::sqrt(static_cast<double>(n) * p * (1 - p));
  EXPECT_NEAR(static_cast<double>(got), mean, 6 * sd + 1)
      << what << ": expected about " << mean << " of " << n << ", got " << got;
}

// Protocol v2 worked examples (docs/protocol.md): device ACK and NAK frames.
const std::vector<uint8_t> kAckFrame = {0xA5, 0x07, 0x00, 0x80, 0x08, 0x00, 0x3F,
                                        0x00, 0x00, 0x00, 0x05, 0xAA, 0x5D};
const std::vector<uint8_t> kNakFrame = {0xA5, 0x05, 0x01, 0x81, 0x09, 0x01,
                                        0x08, 0x00, 0x3F, 0xE0, 0xB4};
// v1 worked examples.
const std::vector<uint8_t> kInit = {0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30};
const std::vector<uint8_t> kMotion = {0x01, 0x00, 0x00, 0x01, 0x40, 0xFF,
                                      0xFF, 0xFF, 0x60, 0x04, 0xB0};
// A v1 motion with no steps: completes at once and is acknowledged.
const std::vector<uint8_t> kZeroMotion(11, 0x00);

constexpr double kClk = 50e6, kBaud = 115200;

// ---------------------------------------------------------------------------------------------
// Injector and rx line alone.

TEST(LineFaultInjector, OffIsTransparent) {
  sb::LineFaults f;
  EXPECT_FALSE(f.any());
  EXPECT_EQ(f.describe(), "none");
  sb::LineFaultInjector inj(f);
  const auto in = random_bytes(5000, test_seed());
  std::vector<sb::LineFrame> frames;
  std::vector<uint8_t> host;
  for (uint8_t b : in) {
    inj.to_board(b, frames);
    inj.to_host(b, 0, host);
  }
  ASSERT_EQ(frames.size(), in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    ASSERT_EQ(frames[i].byte, in[i]) << i;
    ASSERT_EQ(frames[i].flip, 0) << i;
    ASSERT_FALSE(frames[i].duplicate) << i;
  }
  EXPECT_EQ(host, in);
  EXPECT_EQ(inj.stats().injected(), 0u);
  EXPECT_EQ(inj.stats().bytes_to_board, in.size());
  EXPECT_EQ(inj.stats().bytes_from_board, in.size());
}

TEST(LineFaultInjector, DropAndDuplicate) {
  sb::LineFaults f;
  f.seed = test_seed();
  f.drop = 0.05;
  f.dup = 0.03;
  sb::LineFaultInjector inj(f);
  const auto in = random_bytes(20000, test_seed() + 1);
  uint64_t dropped = 0, duplicated = 0;
  std::vector<sb::LineFrame> all;
  for (uint8_t b : in) {
    std::vector<sb::LineFrame> out;
    inj.to_board(b, out);
    ASSERT_LE(out.size(), 2u);
    for (size_t k = 0; k < out.size(); ++k) {
      ASSERT_EQ(out[k].byte, b);
      ASSERT_EQ(out[k].flip, 0);
      ASSERT_EQ(out[k].duplicate, k == 1);
    }
    dropped += out.empty();
    duplicated += out.size() == 2;
    all.insert(all.end(), out.begin(), out.end());
  }
  EXPECT_EQ(inj.stats().bytes_dropped, dropped);
  EXPECT_EQ(inj.stats().bytes_duplicated, duplicated);
  EXPECT_EQ(all.size(), in.size() - dropped + duplicated);
  expect_binomial(dropped, in.size(), f.drop, "dropped bytes");
  expect_binomial(duplicated, in.size() - dropped, f.dup, "duplicated bytes");
  // Same seed, same faults; another seed, other faults.
  sb::LineFaultInjector again(f);
  f.seed += 1;
  sb::LineFaultInjector other(f);
  std::vector<sb::LineFrame> a2, o2;
  for (uint8_t b : in) {
    again.to_board(b, a2);
    other.to_board(b, o2);
  }
  ASSERT_EQ(a2.size(), all.size());
  for (size_t i = 0; i < all.size(); ++i) ASSERT_EQ(a2[i].duplicate, all[i].duplicate) << i;
  EXPECT_NE(other.stats().bytes_dropped * 100000 + other.stats().bytes_duplicated,
            dropped * 100000 + duplicated);
}

TEST(LineFaultInjector, BitErrorsBothWays) {
  sb::LineFaults f;
  f.seed = test_seed();
  f.ber_to_board = 0.01;
  f.ber_to_host = 0.02;
  sb::LineFaultInjector inj(f);
  const auto in = random_bytes(20000, test_seed() + 2);
  std::vector<sb::LineFrame> frames;
  std::vector<uint8_t> host;
  for (uint8_t b : in) {
    inj.to_board(b, frames);
    inj.to_host(b, 0, host);
  }
  ASSERT_EQ(frames.size(), in.size());
  ASSERT_EQ(host.size(), in.size());
  uint64_t bits = 0, corrupted = 0, hbits = 0, hcorrupted = 0;
  std::array<uint64_t, 10> per_bit{};
  for (size_t i = 0; i < in.size(); ++i) {
    ASSERT_EQ(frames[i].byte, in[i]);
    ASSERT_EQ(frames[i].flip >> 10, 0) << "only the 10 UART bits may flip";
    bits += static_cast<uint64_t>(std::popcount(frames[i].flip));
    corrupted += frames[i].flip != 0;
    for (int b = 0; b < 10; ++b) per_bit[static_cast<size_t>(b)] += (frames[i].flip >> b) & 1;
    const auto d = static_cast<uint8_t>(host[i] ^ in[i]);
    hbits += static_cast<uint64_t>(std::popcount(d));
    hcorrupted += d != 0;
  }
  EXPECT_EQ(inj.stats().bits_flipped_to_board, bits);
  EXPECT_EQ(inj.stats().frames_flipped_to_board, corrupted);
  EXPECT_EQ(inj.stats().bits_flipped_to_host, hbits);
  EXPECT_EQ(inj.stats().bytes_flipped_to_host, hcorrupted);
  expect_binomial(bits, in.size() * 10, f.ber_to_board, "bits flipped to board");
  expect_binomial(hbits, in.size() * 8, f.ber_to_host, "bits flipped to host");
  // Start, data and stop bits are all hit.
  for (size_t b = 0; b < 10; ++b) {
    expect_binomial(per_bit[b], in.size(), f.ber_to_board, "flips of one UART bit position");
  }
}

// Device frames: v2 frames by SYNC/LEN, v1 bytes and noise as one-byte frames, a LEN > 64
// ending the frame at the LEN byte. A lost frame loses every byte, a kept one none.
TEST(LineFaultInjector, LosesWholeDeviceFrames) {
  std::vector<std::vector<uint8_t>> frames;
  std::mt19937_64 g(test_seed());
  for (int i = 0; i < 3000; ++i) {
    switch (g() % 5) {
      case 0:
        frames.push_back(kAckFrame);
        break;
      case 1:
        frames.push_back(kNakFrame);
        break;
      case 2:
        frames.push_back({0xAA});
        break;
      case 3:
        frames.push_back({0xA5, 0x41});  // LEN 65 > MAX_PAYLOAD
        break;
      default:
        frames.push_back({0xA5, 0x00, 0x03, 0x82, 0x12, 0x34});  // LEN 0
    }
  }
  sb::LineFaults f;
  f.seed = test_seed();
  f.lose_frames = 0.25;
  f.log = true;
  sb::LineFaultInjector inj(f);
  std::vector<uint8_t> host, expected;
  uint64_t cycle = 0;
  size_t lost = 0, lost_bytes = 0;
  for (const auto& fr : frames) {
    const size_t before = inj.tx_log().size();
    for (uint8_t b : fr) inj.to_host(b, ++cycle, host);
    const auto& log = inj.tx_log();
    ASSERT_EQ(log.size(), before + fr.size());
    const bool l = log[before].lost;
    for (size_t k = before; k < log.size(); ++k) {
      ASSERT_EQ(log[k].lost, l) << "frame " << &fr - frames.data() << " lost only in part";
    }
    if (l) {
      ++lost;
      lost_bytes += fr.size();
    } else {
      expected.insert(expected.end(), fr.begin(), fr.end());
    }
  }
  EXPECT_EQ(host, expected);
  EXPECT_EQ(inj.stats().device_frames, frames.size());
  EXPECT_EQ(inj.stats().device_frames_lost, lost);
  EXPECT_EQ(inj.stats().device_bytes_lost, lost_bytes);
  expect_binomial(lost, frames.size(), f.lose_frames, "lost device frames");
}

// Levels of an rx line from cycle 1 until idle, and the start cycle of each frame.
struct LineTrace {
  std::vector<int> level;  // level[c] for cycle c (level[0] unused)
  std::vector<uint64_t> starts;
};
LineTrace run_line(sb::RxLine& line, sb::LineFaultInjector& inj) {
  LineTrace t;
  t.level.push_back(1);
  for (uint64_t c = 1; !line.idle(); ++c) t.level.push_back(line.tick(c));
  for (const auto& r : inj.rx_log()) t.starts.push_back(r.start_cycle);
  return t;
}

// The level at the centre of bit `bit` of a frame starting at `start`.
int bit_at(const std::vector<int>& level, uint64_t start, int bit) {
  const double cpb = kClk / kBaud;
  return level[static_cast<size_t>(start + static_cast<uint64_t>((bit + 0.5) * cpb))];
}

TEST(RxLine, FlippedBitsReachThePin) {
  sb::LineFaults f;
  f.log = true;
  sb::LineFaultInjector inj(f);
  sb::RxLine line(kClk, kBaud, &inj);
  const std::vector<sb::LineFrame> frames = {
      {0x55, 0, false}, {0x55, 1u << 0, false}, {0x0F, 1u << 9, false}, {0xF0, 0x1FE, false}};
  for (const auto& fr : frames) line.push(fr);
  const auto t = run_line(line, inj);
  ASSERT_EQ(t.starts.size(), frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(t.starts[i], 1 + i * 4340) << "frames follow back to back";
    for (int b = 0; b < 10; ++b) {
      const int clean = b == 0 ? 0 : b == 9 ? 1 : (frames[i].byte >> (b - 1)) & 1;
      EXPECT_EQ(bit_at(t.level, t.starts[i], b), clean ^ ((frames[i].flip >> b) & 1))
          << "frame " << i << " bit " << b;
    }
  }
}

TEST(RxLine, StallsDelayTheNextByteExactly) {
  const auto bytes = random_bytes(8, test_seed());
  auto trace = [&](const std::vector<sb::LineStall>& stalls, sb::LineFaultStats* st) {
    sb::LineFaults f;
    f.log = true;
    f.stalls = stalls;
    sb::LineFaultInjector inj(f);
    sb::RxLine line(kClk, kBaud, &inj);
    for (uint8_t b : bytes) line.push(b);
    auto t = run_line(line, inj);
    if (st) *st = inj.stats();
    return t;
  };
  const auto base = trace({}, nullptr);
  ASSERT_EQ(base.starts.size(), bytes.size());
  constexpr uint64_t kD = 123457;
  using T = sb::LineStall::Trigger;
  struct Case {
    sb::LineStall stall;
    size_t first_delayed;  // first frame delayed (bytes.size(): none)
    uint64_t delay;
  };
  const uint64_t s3 = base.starts[3];
  const std::vector<Case> cases = {
      {{T::kBytes, 3, kD}, 3, kD},               // before the 4th byte on the line
      {{T::kCycle, s3, kD}, 3, kD},              // at the cycle the 4th byte would start
      {{T::kCycle, s3 - 100, kD}, 3, kD - 100},  // mid-frame: held until at + clocks
      {{T::kCycle, 0, 1}, 0, 0},                 // window over before the first byte: no effect
      {{T::kBytes, 100, kD}, bytes.size(), 0},   // never reached
  };
  for (const auto& c : cases) {
    sb::LineFaultStats st;
    const auto t = trace({c.stall}, &st);
    ASSERT_EQ(t.starts.size(), bytes.size());
    for (size_t i = 0; i < bytes.size(); ++i) {
      const uint64_t want = base.starts[i] + (i >= c.first_delayed ? c.delay : 0);
      EXPECT_EQ(t.starts[i], want) << "stall at " << c.stall.at << ": frame " << i;
      for (int b = 0; b < 10; ++b) {
        ASSERT_EQ(bit_at(t.level, t.starts[i], b), bit_at(base.level, base.starts[i], b));
      }
    }
    EXPECT_EQ(st.stalls, c.delay ? 1u : 0u);
    EXPECT_EQ(st.stall_clocks, c.delay);
    // The line stays high (idle) while held.
    if (c.delay && c.first_delayed < bytes.size()) {
      const uint64_t from = base.starts[c.first_delayed - 1] + 4340;
      for (uint64_t x = from; x < t.starts[c.first_delayed]; ++x) ASSERT_EQ(t.level[x], 1) << x;
    }
  }
}

TEST(LineFaultOptions, ParseAndReject) {
  sb::LineFaults f;
  EXPECT_TRUE(sb::parse_line_fault_option("--line-ber", "1e-4", f));
  EXPECT_EQ(f.ber_to_board, 1e-4);
  EXPECT_EQ(f.ber_to_host, 1e-4);
  EXPECT_TRUE(sb::parse_line_fault_option("line-ber", "0.001,0.25", f));
  EXPECT_EQ(f.ber_to_board, 0.001);
  EXPECT_EQ(f.ber_to_host, 0.25);
  EXPECT_TRUE(sb::parse_line_fault_option("--line-drop", "0.01", f));
  EXPECT_TRUE(sb::parse_line_fault_option("--line-dup", "0.02", f));
  EXPECT_TRUE(sb::parse_line_fault_option("--line-lose-frames", "0.1", f));
  EXPECT_TRUE(sb::parse_line_fault_option("--line-seed", "42", f));
  EXPECT_TRUE(sb::parse_line_fault_option("--line-stall", "5000:10000000", f));
  EXPECT_TRUE(sb::parse_line_fault_option("--line-stall", "b20:100", f));
  EXPECT_EQ(f.drop, 0.01);
  EXPECT_EQ(f.dup, 0.02);
  EXPECT_EQ(f.lose_frames, 0.1);
  EXPECT_EQ(f.seed, 42u);
  ASSERT_EQ(f.stalls.size(), 2u);
  EXPECT_EQ(f.stalls[0].trigger, sb::LineStall::Trigger::kCycle);
  EXPECT_EQ(f.stalls[0].at, 5000u);
  EXPECT_EQ(f.stalls[0].clocks, 10000000u);
  EXPECT_EQ(f.stalls[1].trigger, sb::LineStall::Trigger::kBytes);
  EXPECT_EQ(f.stalls[1].at, 20u);
  EXPECT_TRUE(f.any());
  EXPECT_NE(f.describe().find("stall at cycle 5000 for 10000000 clocks"), std::string::npos)
      << f.describe();
  EXPECT_FALSE(sb::parse_line_fault_option("--port", "x", f));
  for (const auto& [n, v] :
       std::vector<std::pair<const char*, const char*>>{{"--line-ber", "2"},
                                                        {"--line-ber", "x"},
                                                        {"--line-ber", "0.1,"},
                                                        {"--line-drop", "-0.1"},
                                                        {"--line-seed", "1.5"},
                                                        {"--line-stall", "100"},
                                                        {"--line-stall", "100:0"},
                                                        {"--line-stall", "b:5"}}) {
    EXPECT_THROW(sb::parse_line_fault_option(n, v, f), std::invalid_argument) << n << " " << v;
  }
  EXPECT_EQ(sb::line_fault_options().size(), 6u);
  sb::BoardOptions o;
  o.line_faults.drop = 1.5;
  EXPECT_THROW({ sb::SimBoard b(o); }, sb::BoardError);
}

// ---------------------------------------------------------------------------------------------
// Through the Verilated core.

struct RawRun {
  sb::BoardStats stats;
  std::vector<models::Edge> edges;
  std::vector<uint64_t> move_done;
  std::vector<sb::RxFrameRecord> rx_log;
  std::vector<sb::TxByteRecord> tx_log;
  std::vector<uint8_t> received;  // what the host read
};

// Writes `bytes` at once on the pty, runs the board in this thread until it has decoded
// `tx_bytes` bytes from tx and gone quiet (or `max_cycles` more clocks: corrupted traffic can
// make the core start long moves), reads what reached the host.
RawRun run_raw(sb::BoardOptions o, const std::vector<uint8_t>& bytes, uint64_t tx_bytes,
               uint64_t max_cycles = 100'000'000) {
  o.line_faults.log = true;
  o.record_rx = true;
  sb::SimBoard board(o);
  const int fd = ::open(board.path().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  EXPECT_GE(fd, 0);
  size_t off = 0;
  while (off < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + off, bytes.size() - off);
    if (n > 0) {
      off += static_cast<size_t>(n);
    } else {
      board.run_until([](const sb::SimBoard&) { return false; }, 5ms);  // let it read
    }
  }
  RawRun r;
  // Decided on board clocks: the bytes from tx, or `max_cycles` clocks. The wall-time limit is a
  // safety net for a hung simulation only (100 M clocks take about 2 minutes at 0.7 M clocks/s).
  board.run_until(
      [&](const sb::SimBoard& b) {
        // Keep the pty drained so the board can always write.
        uint8_t buf[256];
        ssize_t n;
        while ((n = ::read(fd, buf, sizeof buf)) > 0)
          r.received.insert(r.received.end(), buf, buf + n);
        return b.stats().bytes_out >= tx_bytes || b.cycle() >= max_cycles;
      },
      900s);
  EXPECT_GE(board.stats().bytes_out, tx_bytes)
      << "bytes decoded from tx by cycle " << board.cycle() << " (limit " << max_cycles << ")";
  board.run_cycles_until_quiet(max_cycles);
  // Everything the board wrote to the pty, counted (a timed poll could miss bytes still inside
  // the pty on a loaded machine).
  const auto give_up = std::chrono::steady_clock::now() + 30s;  // safety net: a broken pty
  while (r.received.size() < board.bytes_to_host() && std::chrono::steady_clock::now() < give_up) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 10) != 1) continue;
    uint8_t buf[256];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) r.received.insert(r.received.end(), buf, buf + n);
  }
  EXPECT_EQ(r.received.size(), board.bytes_to_host()) << "bytes the board wrote to the pty";
  ::close(fd);
  r.stats = board.stats();
  r.edges = board.edges();
  r.move_done = board.move_done_cycles();
  r.rx_log = board.rx_line_log();
  r.tx_log = board.tx_line_log();
  return r;
}

std::vector<uint8_t> zero_moves(size_t n) {
  std::vector<uint8_t> v;
  for (size_t i = 0; i < n; ++i) v.insert(v.end(), kZeroMotion.begin(), kZeroMotion.end());
  return v;
}

std::vector<uint8_t> example_job() {
  std::vector<uint8_t> v = kInit;
  v.insert(v.end(), kMotion.begin(), kMotion.end());
  return v;
}

std::vector<models::Edge> without_rx(const std::vector<models::Edge>& e) {
  std::vector<models::Edge> r;
  std::copy_if(e.begin(), e.end(), std::back_inserter(r),
               [](const models::Edge& x) { return x.signal != models::kRx; });
  return r;
}

// Level of the rx pin at `cycle` from the recorded rx edges (high before the first edge).
class RxPin {
 public:
  explicit RxPin(const std::vector<models::Edge>& e) {
    for (const auto& x : e)
      if (x.signal == models::kRx) edges_.push_back(x);
  }
  int at(uint64_t cycle) const {
    auto it = std::upper_bound(edges_.begin(), edges_.end(), cycle,
                               [](uint64_t c, const models::Edge& x) { return c < x.cycle; });
    return it == edges_.begin() ? 1 : std::prev(it)->value;
  }

 private:
  std::vector<models::Edge> edges_;
};

void expect_same_edges(const std::vector<models::Edge>& a, const std::vector<models::Edge>& b,
                       int64_t shift) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(static_cast<int64_t>(b[i].cycle), static_cast<int64_t>(a[i].cycle) + shift)
        << "edge " << i << " (" << models::signal_name(a[i].signal) << ")";
    ASSERT_EQ(a[i].signal, b[i].signal) << i;
    ASSERT_EQ(a[i].value, b[i].value) << i;
  }
}

// Faults off (default options, or a seed and a log with every rate 0): the same cycles, edges,
// ACK as the board without the injector's involvement, and nothing injected.
TEST(BoardLineFaults, OffIsIdentical) {
  sb::BoardOptions plain;
  const auto a = run_raw(plain, example_job(), 1);
  sb::BoardOptions zero;
  zero.line_faults.seed = test_seed();
  const auto b = run_raw(zero, example_job(), 1);
  for (const auto* r : {&a, &b}) {
    EXPECT_EQ(r->received, std::vector<uint8_t>{0xAA});
    EXPECT_EQ(r->stats.line.injected(), 0u);
    EXPECT_EQ(r->stats.line.frames_to_board, 20u);
    EXPECT_EQ(r->stats.line.device_frames, 1u);
    EXPECT_EQ(r->stats.frame_errors, 0);
    EXPECT_EQ(r->stats.moves_done, 1u);
    ASSERT_EQ(r->rx_log.size(), 20u);
    // Bytes back to back from cycle 1, 4340 clocks each (10 bits of 434.03 clocks).
    for (size_t i = 0; i < 20; ++i) EXPECT_EQ(r->rx_log[i].start_cycle, 1 + 4340 * i) << i;
  }
  EXPECT_EQ(a.stats.cycles, b.stats.cycles);
  EXPECT_EQ(a.move_done, b.move_done);
  expect_same_edges(a.edges, b.edges, 0);
  EXPECT_EQ(a.stats.position[0], 320);
  EXPECT_EQ(a.stats.position[1], -160);
}

// Bit errors host -> board: every frame on the rx pin carries exactly the logged flips, and a
// flipped data bit is seen by a UART receiver as a different byte (checked up to the first
// frame whose start or stop bit was hit: from there the receiver may lose the frame alignment).
// The core counts framing errors when stop bits were hit.
TEST(BoardLineFaults, BitErrorsToBoardReachThePin) {
  sb::BoardOptions o;
  o.line_faults.seed = test_seed();
  o.line_faults.ber_to_board = 0.004;
  const size_t n = 60;
  const auto bytes = zero_moves(n);
  // Some ACKs get lost in the noise: wait for the line to go quiet, not for n ACKs.
  const auto r = run_raw(o, bytes, 0, bytes.size() * 4340 + 100'000);
  ASSERT_EQ(r.rx_log.size(), bytes.size());
  const RxPin pin(r.edges);
  uint64_t flipped = 0, frames_hit = 0, stop_hits = 0;
  for (size_t i = 0; i < r.rx_log.size(); ++i) {
    const auto& x = r.rx_log[i];
    ASSERT_EQ(x.frame.byte, bytes[i]);
    for (int b = 0; b < 10; ++b) {
      const int clean = b == 0 ? 0 : b == 9 ? 1 : (x.frame.byte >> (b - 1)) & 1;
      const uint64_t centre = x.start_cycle + static_cast<uint64_t>((b + 0.5) * kClk / kBaud);
      ASSERT_EQ(pin.at(centre), clean ^ ((x.frame.flip >> b) & 1))
          << "frame " << i << " bit " << b << " at cycle " << centre;
    }
    flipped += static_cast<uint64_t>(std::popcount(x.frame.flip));
    frames_hit += x.frame.flip != 0;
    stop_hits += (x.frame.flip >> 9) & 1;
  }
  EXPECT_EQ(r.stats.line.bits_flipped_to_board, flipped);
  EXPECT_EQ(r.stats.line.frames_flipped_to_board, frames_hit);
  ASSERT_GT(frames_hit, 0u) << "seed " << o.line_faults.seed << " flipped nothing";
  // Decode the pin as a receiver would.
  models::UartMonitor mon(kClk, kBaud);
  std::vector<models::UartMonitor::Byte> seen;
  const uint64_t end = r.rx_log.back().start_cycle + 5000;
  for (uint64_t c = 1; c < end; ++c) {
    if (auto b = mon.sample(pin.at(c), c)) seen.push_back(*b);
  }
  size_t data_hits = 0;
  for (size_t i = 0; i < r.rx_log.size() && i < seen.size(); ++i) {
    const auto& x = r.rx_log[i];
    if (x.frame.flip & 0x201) break;  // start or stop bit hit
    const auto want = static_cast<uint8_t>(x.frame.byte ^ ((x.frame.flip >> 1) & 0xFF));
    ASSERT_EQ(seen[i].value, want) << "frame " << i;
    ASSERT_TRUE(seen[i].framing_ok) << "frame " << i;
    data_hits += x.frame.flip != 0;
  }
  fmt::print(
      "BER {:g} host->board over {} frames: {} frames hit ({} bits, {} stop bits), {} data-only "
      "hits decoded as other bytes before the first start/stop hit; core: {} framing errors, "
      "{} moves, {} ACKs back\n",
      o.line_faults.ber_to_board, bytes.size(), frames_hit, flipped, stop_hits, data_hits,
      r.stats.frame_errors, r.stats.moves_done, r.received.size());
  if (stop_hits) {
    EXPECT_GT(r.stats.frame_errors, 0) << "stop bits flipped, no framing error";
  }
}

// Dropped and duplicated host bytes: the bytes on the rx pin are the host's with exactly the
// logged drops and duplicates.
TEST(BoardLineFaults, DroppedAndDuplicatedBytes) {
  sb::BoardOptions o;
  o.line_faults.seed = test_seed();
  o.line_faults.drop = 0.03;
  o.line_faults.dup = 0.03;
  const auto bytes = random_bytes(400, test_seed() + 7);
  const auto r = run_raw(o, bytes, 0, bytes.size() * 2 * 4340);
  // Align the log with the host bytes.
  size_t j = 0, dropped = 0, dups = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (j < r.rx_log.size() && !r.rx_log[j].frame.duplicate && r.rx_log[j].frame.byte == bytes[i]) {
      ++j;
      if (j < r.rx_log.size() && r.rx_log[j].frame.duplicate) {
        ASSERT_EQ(r.rx_log[j].frame.byte, bytes[i]) << "duplicate of host byte " << i;
        ++j;
        ++dups;
      }
    } else {
      ++dropped;
    }
  }
  ASSERT_EQ(j, r.rx_log.size()) << "rx frames not explained by drops and duplicates";
  EXPECT_EQ(r.stats.line.bytes_dropped, dropped);
  EXPECT_EQ(r.stats.line.bytes_duplicated, dups);
  EXPECT_GT(dropped, 0u);
  EXPECT_GT(dups, 0u);
  // The pin carries exactly the logged frames.
  const RxPin pin(r.edges);
  models::UartMonitor mon(kClk, kBaud);
  std::vector<uint8_t> seen;
  const uint64_t end = r.rx_log.back().start_cycle + 5000;
  for (uint64_t c = 1; c < end; ++c) {
    if (auto b = mon.sample(pin.at(c), c)) seen.push_back(b->value);
  }
  ASSERT_EQ(seen.size(), r.rx_log.size());
  for (size_t k = 0; k < seen.size(); ++k) ASSERT_EQ(seen[k], r.rx_log[k].frame.byte) << k;
  fmt::print("{} host bytes: {} dropped, {} duplicated, {} frames on rx\n", bytes.size(), dropped,
             dups, r.rx_log.size());
}

// Board -> host: lost ACKs and flipped bits in the ACK bytes, counted exactly.
TEST(BoardLineFaults, LostAndCorruptedAcks) {
  const size_t n = 80;
  sb::BoardOptions o;
  o.line_faults.seed = test_seed();
  o.line_faults.lose_frames = 0.25;
  o.line_faults.ber_to_host = 0.05;
  const auto r = run_raw(o, zero_moves(n), n);
  EXPECT_EQ(r.stats.moves_done, n);
  EXPECT_EQ(r.stats.bytes_out, n) << "one 0xAA per move from the core";
  EXPECT_EQ(r.stats.line.device_frames, n);
  const auto& l = r.stats.line;
  ASSERT_EQ(r.received.size(), n - l.device_frames_lost);
  EXPECT_EQ(l.device_bytes_lost, l.device_frames_lost);
  uint64_t bits = 0, bad = 0;
  for (uint8_t b : r.received) {
    bits += static_cast<uint64_t>(std::popcount(static_cast<uint8_t>(b ^ 0xAA)));
    bad += b != 0xAA;
  }
  EXPECT_EQ(l.bytes_flipped_to_host, bad);
  EXPECT_EQ(l.bits_flipped_to_host, bits);
  EXPECT_GT(l.device_frames_lost, 0u);
  EXPECT_LT(l.device_frames_lost, n);
  EXPECT_GT(bad, 0u);
  // The log: each lost byte was not delivered, each kept one as received.
  size_t k = 0;
  for (const auto& t : r.tx_log) {
    EXPECT_EQ(t.byte, 0xAA);
    if (!t.lost) {
      ASSERT_LT(k, r.received.size());
      EXPECT_EQ(t.delivered, r.received[k++]);
    }
  }
  fmt::print("{} ACKs sent: {} lost, {} of {} delivered corrupted ({} bits)\n", n,
             l.device_frames_lost, bad, r.received.size(), bits);
}

// A 200 ms stall between the init and the motion packet delays the move by exactly the stall:
// every STEP/DIR/LASER edge and the ACK come 10 000 000 clocks later. The same stall in the
// middle of the motion packet (at the cycle its 4th byte would start) makes the core's 100 ms
// watchdog drop the cut packet.
TEST(BoardLineFaults, StallDelaysTheNextByteExactly) {
  constexpr uint64_t kD = 1'000'000;    // 20 ms at 50 MHz: between packets
  constexpr uint64_t kMid = 6'000'000;  // 120 ms: mid-packet, past the 100 ms watchdog
  const auto base = run_raw(sb::BoardOptions{}, example_job(), 1);
  ASSERT_EQ(base.rx_log.size(), 20u);

  sb::BoardOptions o;
  o.line_faults.stalls = {{sb::LineStall::Trigger::kBytes, 9, kD}};
  const auto s = run_raw(o, example_job(), 1);
  ASSERT_EQ(s.rx_log.size(), 20u);
  for (size_t i = 0; i < 20; ++i) {
    EXPECT_EQ(s.rx_log[i].start_cycle, base.rx_log[i].start_cycle + (i >= 9 ? kD : 0)) << i;
  }
  EXPECT_EQ(s.rx_log[9].held, kD);
  EXPECT_EQ(s.stats.line.stalls, 1u);
  EXPECT_EQ(s.stats.line.stall_clocks, kD);
  EXPECT_EQ(s.received, std::vector<uint8_t>{0xAA});
  expect_same_edges(without_rx(base.edges), without_rx(s.edges), static_cast<int64_t>(kD));
  ASSERT_EQ(s.move_done.size(), 1u);
  EXPECT_EQ(s.move_done[0], base.move_done[0] + kD);
  EXPECT_EQ(s.stats.cycles, base.stats.cycles + kD) << "simulated time runs through the stall";
  EXPECT_EQ(s.stats.timeouts, 0);

  // Mid-packet, by cycle.
  sb::BoardOptions m;
  const uint64_t c12 = base.rx_log[12].start_cycle;
  m.line_faults.stalls = {{sb::LineStall::Trigger::kCycle, c12, kMid}};
  const auto t = run_raw(m, example_job(), 0);
  ASSERT_EQ(t.rx_log.size(), 20u);
  EXPECT_EQ(t.rx_log[11].start_cycle, base.rx_log[11].start_cycle);
  EXPECT_EQ(t.rx_log[12].start_cycle, c12 + kMid);
  EXPECT_EQ(t.stats.line.stall_clocks, kMid);
  EXPECT_GE(t.stats.timeouts, 1) << "the 100 ms watchdog drops the cut packet";
  EXPECT_EQ(t.stats.moves_done, 0u);
  EXPECT_TRUE(t.received.empty());
  fmt::print(
      "stall of {} clocks between packets: the move starts {} clocks later; a stall of {} "
      "clocks mid-packet: the core's watchdog fired {} time(s)\n",
      kD, s.move_done[0] - base.move_done[0], kMid, t.stats.timeouts);
}

}  // namespace
