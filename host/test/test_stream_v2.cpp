// v2 streamer against the in-process fake device (fake_v2_device.h): clean jobs, credit, fault
// injection (corrupted / dropped / duplicated host bytes, lost / corrupted / duplicated answers,
// a line stall), sequence and done-counter wraparound, axis refusal, protocol selection (auto
// falls back to v1 on a device that does not answer HELLO).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <deque>
#include <string>

#include "fake_v2_device.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/hold_control.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/link/v2_session.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/protocol/v2_job.h"
#include "stream_plan.h"

namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
using fpgacnc::test::FakeV2Device;
using std::chrono::milliseconds;

namespace {

uint64_t stream_seed(uint64_t dflt) {
  const char* e = std::getenv("FPGACNC_SEED");
  return e ? std::strtoull(e, nullptr, 10) : dflt;
}

// A square spiral of `n` segments in 0.1 mm steps growing by 0.1 mm per side, with a few Z and
// E moves, a dwell and laser power changes.
std::string spiral_gcode(int n, bool with_ze = true) {
  std::string g = "G21 G90\nM3 S600\nF3000\n";
  double x = 0, y = 0;
  int len = 1;
  int dir = 0;
  for (int i = 0; i < n; ++i) {
    const double d = 0.1 * len;
    if (dir == 0) x += d;
    if (dir == 1) y += d;
    if (dir == 2) x -= d;
    if (dir == 3) y -= d;
    g += fmt::format("G1 X{:.3f} Y{:.3f}\n", x, y);
    if (dir == 1 || dir == 3) ++len;
    dir = (dir + 1) % 4;
    if (with_ze && i % 50 == 25) g += "G1 Z0.5 E0.2\nG1 Z0\n";
    if (i == n / 2) g += "G4 P0.01\nS1000\n";
  }
  g += "M5\nG0 X1 Y-2\n";
  return g;
}

fpgacnc::config::MachineConfig test_cfg() {
  fpgacnc::config::MachineConfig c;
  return c;
}

fpgacnc::plan::Plan plan_of(const std::string& gcode, const fpgacnc::config::MachineConfig& cfg) {
  return fpgacnc::plan::plan_program(fpgacnc::gcode::parse_string(gcode, "job.gcode"), cfg, {});
}

// Clean-line tests: a retransmission timeout long enough that a busy machine never fires it.
lk::StreamV2Options clean_options() {
  lk::StreamV2Options o;
  o.retransmit_timeout = milliseconds(1000);
  o.idle_poll = milliseconds(20);
  o.answer_timeout = milliseconds(5000);
  return o;
}

lk::StreamV2Options fast_options() {
  lk::StreamV2Options o;
  o.retransmit_timeout = milliseconds(60);
  o.idle_poll = milliseconds(60);
  o.answer_timeout = milliseconds(3000);
  return o;
}

// Every FIFO frame of the job executed exactly once, in order (type and payload).
void expect_executed_in_order(const FakeV2Device& dev, const v2::Job& job) {
  const auto& ex = dev.executed();
  ASSERT_EQ(ex.size(), job.frames.size())
      << "device executed " << ex.size() << " FIFO frames, job has " << job.frames.size();
  for (size_t i = 0; i < ex.size(); ++i) {
    ASSERT_EQ(ex[i].type, job.frames[i].frame.type) << "FIFO frame " << i;
    ASSERT_EQ(ex[i].payload, job.frames[i].frame.payload)
        << "FIFO frame " << i << " (segment " << job.frames[i].segment_index << ", line "
        << job.frames[i].source_line << "): expected " << v2::hex(job.frames[i].frame.payload)
        << ", got " << v2::hex(ex[i].payload);
  }
}

}  // namespace

TEST(StreamV2, CleanJobRunsEveryFrameOnceInOrder) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(300), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 16;
  FakeV2Device dev(o);
  std::vector<std::pair<size_t, size_t>> progress;
  auto so = clean_options();
  so.progress = [&](size_t d, size_t t) { progress.emplace_back(d, t); };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  expect_executed_in_order(dev, job);
  ASSERT_EQ(dev.configs().size(), 4u);
  for (uint8_t a = 0; a < 4; ++a) {
    EXPECT_EQ(dev.configs()[a], (v2::ConfigAxis{a, 100, 100, 200, 200}));
  }
  EXPECT_EQ(r.retransmissions, 0u);
  EXPECT_EQ(r.go_backs, 0u);
  EXPECT_EQ(r.min_window, v2::kMaxUnacked);
  for (size_t k = 1; k < 8; ++k)
    EXPECT_EQ(r.naks[k], 0u) << v2::nak_reason_name(static_cast<uint8_t>(k));
  EXPECT_EQ(r.sequenced_frames, 4 + job.frames.size());
  EXPECT_EQ(r.fifo_frames, job.frames.size());
  EXPECT_TRUE(r.position_ok);
  for (size_t a = 0; a < 4; ++a) {
    EXPECT_EQ(r.moved[a], plan.final_steps[a]) << "axis " << a;
    EXPECT_EQ(dev.position()[a], plan.final_steps[a]) << "axis " << a;
  }
  EXPECT_TRUE(r.released);
  EXPECT_FALSE(dev.v2_mode());
  EXPECT_EQ(dev.stats().releases, 1u);
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back(), (std::pair<size_t, size_t>{job.frames.size(), job.frames.size()}));
  // Credit: the device FIFO never overflowed and never refused a frame.
  EXPECT_EQ(dev.stats().fifo_full, 0u);
  EXPECT_LE(dev.stats().max_fifo_level, 16u);
  EXPECT_GE(dev.stats().max_fifo_level, 8u) << "the window should keep the FIFO well filled";
  EXPECT_EQ(r.bytes_written, dev.written().size());
  std::printf("%s", lk::format_report(r).c_str());
}

TEST(StreamV2, TinyFifoAndSlowDeviceNeverOverflow) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(60, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 2;
  o.exec_period = std::chrono::microseconds(2000);
  FakeV2Device dev(o);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, clean_options());
  expect_executed_in_order(dev, job);
  EXPECT_EQ(dev.stats().fifo_full, 0u);
  EXPECT_EQ(dev.stats().max_fifo_level, 2u);
  EXPECT_EQ(r.retransmissions, 0u);
  EXPECT_TRUE(r.position_ok);
}

TEST(StreamV2, LongCreditWaitIsNotATimeout) {
  // Segments longer than the retransmission timeout and a full FIFO: the host waits for credit
  // longer than the timeout with nothing unacknowledged; the frame it then sends starts a fresh
  // timer (regression: it used to time out at once and shrink the window).
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(6, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 2;
  o.exec_period = std::chrono::microseconds(250'000);
  o.line_delay = std::chrono::microseconds(20'000);  // the ACK comes 20 ms after the frame
  FakeV2Device dev(o);
  auto so = clean_options();
  so.retransmit_timeout = milliseconds(100);
  so.idle_poll = milliseconds(100);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  expect_executed_in_order(dev, job);
  EXPECT_EQ(r.timeouts, 0u);
  EXPECT_EQ(r.retransmissions, 0u);
  EXPECT_EQ(r.min_window, v2::kMaxUnacked);
}

TEST(StreamV2, SequenceAndDoneCountersWrapAround) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(400, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.initial_next_seq = 250;
  o.initial_done = 0xFFFFFFF0u;
  FakeV2Device dev(o);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, clean_options());
  expect_executed_in_order(dev, job);
  EXPECT_EQ(dev.done(), static_cast<uint32_t>(0xFFFFFFF0u + job.frames.size()));
  EXPECT_EQ(dev.next_seq(), static_cast<uint8_t>(250 + 4 + job.frames.size() + 1));
  EXPECT_TRUE(r.position_ok);
  EXPECT_EQ(r.retransmissions, 0u);
}

// Faults of every kind at once; the seed (FPGACNC_SEED) is printed.
class StreamV2Faults : public ::testing::TestWithParam<uint64_t> {};

TEST_P(StreamV2Faults, JobCompletesEverySegmentExactlyOnce) {
  const uint64_t seed = stream_seed(GetParam());
  std::printf("seed %llu (FPGACNC_SEED)\n", static_cast<unsigned long long>(seed));
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(600), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 32;
  o.exec_period = std::chrono::microseconds(100);
  o.faults.seed = seed;
  o.faults.host_bit_flip = 2e-4;
  o.faults.host_drop = 2e-4;
  o.faults.host_dup = 2e-4;
  o.faults.answer_lose = 0.03;
  o.faults.answer_corrupt = 0.03;
  o.faults.answer_dup = 0.03;
  o.faults.stall_after_bytes = 3000;
  o.faults.stall = milliseconds(200);
  FakeV2Device dev(o);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, fast_options());
  expect_executed_in_order(dev, job);
  EXPECT_TRUE(r.position_ok);
  const auto& st = dev.stats();
  std::printf(
      "injected: %llu bit flips, %llu dropped, %llu duplicated host bytes; %llu lost, %llu "
      "corrupted, %llu duplicated answers; %llu stall(s)\n",
      (unsigned long long)st.flipped, (unsigned long long)st.dropped,
      (unsigned long long)st.duplicated, (unsigned long long)st.answers_lost,
      (unsigned long long)st.answers_corrupted, (unsigned long long)st.answers_duplicated,
      (unsigned long long)st.stalls);
  std::printf(
      "device: %llu CRC errors, %llu length errors, %llu timeouts, %llu duplicates "
      "re-ACKed, %llu out of order\n",
      (unsigned long long)st.crc_errors, (unsigned long long)st.length_errors,
      (unsigned long long)st.timeouts, (unsigned long long)st.duplicates_acked,
      (unsigned long long)st.out_of_order);
  std::printf("%s", lk::format_report(r).c_str());
  EXPECT_EQ(st.stalls, 1u);
  EXPECT_GT(st.answers_lost + st.answers_corrupted, 0u);
  // Something was lost or corrupted on the way in, so something was sent again.
  if (st.flipped + st.dropped > 0) {
    EXPECT_GT(r.retransmissions, 0u);
  }
  EXPECT_GT(r.rx_crc_errors + r.rx_bad_length, 0u) << "corrupted answers seen by the host parser";
  EXPECT_GT(r.duplicates, 0u);
  EXPECT_LT(r.min_window, v2::kMaxUnacked) << "the window shrinks at go-backs";
}

INSTANTIATE_TEST_SUITE_P(Seeds, StreamV2Faults, ::testing::Values(1u, 2u, 3u));

TEST(StreamV2, StallLongerThanTheRetransmitTimeoutResends) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(200, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.faults.stall_after_bytes = 500;
  o.faults.stall = milliseconds(200);
  FakeV2Device dev(o);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, fast_options());  // 60 ms timeout
  expect_executed_in_order(dev, job);
  EXPECT_GE(r.timeouts, 1u);
  EXPECT_GT(r.retransmissions, 0u);
  EXPECT_GT(dev.stats().duplicates_acked, 0u) << "the held frames arrive twice";
  EXPECT_TRUE(r.position_ok);
}

TEST(StreamV2, WithoutDoneFramesStatusPollsCompleteTheJob) {
  // A device whose DONE frames are all lost: credit and completion come from ACKs (sent when a
  // frame arrives, before it runs) and, once the host has nothing left to send, from STATUS.
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(60, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.send_done = false;
  o.fifo_depth = 8;
  o.exec_period = std::chrono::microseconds(1000);
  FakeV2Device dev(o);
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, clean_options());
  expect_executed_in_order(dev, job);
  EXPECT_GT(r.status_polls, 2u) << "2 are the start and end queries";
  EXPECT_TRUE(r.position_ok);
}

TEST(StreamV2, RefusesAJobWithMoreAxesThanTheDevice) {
  const auto cfg = test_cfg();
  const auto plan = plan_of("G1 X1 Y1 Z1 F600\n", cfg);
  FakeV2Device::Options o;
  o.n_axes = 2;
  FakeV2Device dev(o);
  try {
    fpgacnc::test::stream_plan(dev, plan, cfg, fast_options());
    FAIL() << "a 3-axis job was accepted by a 2-axis device";
  } catch (const lk::Error& e) {
    EXPECT_NE(std::string(e.what()).find("3 axes"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dev.next_seq(), 0) << "a sequenced frame was sent";
  EXPECT_TRUE(dev.executed().empty());
  // The same job in 2 axes is fine.
  const auto plan2 = plan_of("G1 X1 Y1 F600\nG1 X0\n", cfg);
  const auto r = fpgacnc::test::stream_plan(dev, plan2, cfg, fast_options());
  EXPECT_TRUE(r.position_ok);
  EXPECT_EQ(dev.configs().size(), 2u) << "CONFIG_AXIS only for the device's axes";
}

TEST(StreamV2, DeviceWithoutProfilesOrArcsNamesTheConfigKey) {
  // A device built without LINE_PROFILE (or ARC) NAKs them UNKNOWN_TYPE: the job stops at that
  // frame with an error naming the key to change, nothing after it runs; with the key changed the
  // same job runs.
  auto cfg = test_cfg();
  cfg.laser_requires_m3 = false;
  const std::string g = "G1 X1 Y1 F600\nG2 X2 Y0 I1 J0\nG1 X0 Y0\n";
  struct Case {
    uint8_t type;
    const char* key;
  };
  for (const Case& c : {Case{0x12, "motion = \"constant\""}, Case{0x13, "native_arcs = false"}}) {
    FakeV2Device::Options o;
    o.unknown_types = {c.type};
    FakeV2Device dev(o);
    const auto plan = plan_of(g, cfg);
    const auto job = fpgacnc::test::pack_motion(plan, cfg);
    ASSERT_GT(c.type == 0x12 ? job.profiles : job.arcs, 0u);
    try {
      fpgacnc::test::stream_plan(dev, plan, cfg, fast_options());
      FAIL() << "type 0x" << std::hex << int{c.type} << " was refused but the job completed";
    } catch (const lk::Error& e) {
      std::printf("%s\n", e.what());
      EXPECT_NE(std::string(e.what()).find(c.key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("UNKNOWN_TYPE"), std::string::npos) << e.what();
    }
    for (const auto& f : dev.executed()) EXPECT_NE(f.type, c.type);
    auto fixed = cfg;
    if (c.type == 0x12) fixed.motion = "constant";
    if (c.type == 0x13) fixed.native_arcs = false;
    FakeV2Device dev2(o);
    const auto r = fpgacnc::test::stream_plan(dev2, plan_of(g, fixed), fixed, fast_options());
    EXPECT_TRUE(r.position_ok) << c.key;
  }
}

TEST(StreamV2, RefusesAJobPlannedForAnotherClock) {
  auto cfg = test_cfg();
  cfg.clk_hz = 100'000'000;
  FakeV2Device dev(FakeV2Device::Options{});
  try {
    fpgacnc::test::stream_plan(dev, plan_of("G1 X1 F600\n", cfg), cfg, fast_options());
    FAIL() << "a job planned for 100 MHz was sent to a 50 MHz device";
  } catch (const lk::Error& e) {
    EXPECT_NE(std::string(e.what()).find("50000000 Hz"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dev.next_seq(), 0) << "a sequenced frame was sent";
}

TEST(StreamV2, DeviceThatNeverAnswersIsAnError) {
  FakeV2Device::Options o;
  o.answer_hello = false;
  FakeV2Device dev(o);
  auto so = fast_options();
  so.hello_timeout = milliseconds(50);
  EXPECT_THROW(lk::select_protocol(dev, "v2", so), lk::Error);
  EXPECT_EQ(dev.stats().hellos, 3u);
  const auto cfg = test_cfg();
  EXPECT_THROW(fpgacnc::test::stream_plan(dev, plan_of("G1 X1 F600\n", cfg), cfg, so), lk::Error);
}

TEST(SelectProtocol, AutoPicksV2WhenIdentComes) {
  FakeV2Device dev(FakeV2Device::Options{});
  const auto c = lk::select_protocol(dev, "auto", fast_options());
  EXPECT_EQ(c.protocol, "v2");
  ASSERT_TRUE(c.ident.has_value());
  EXPECT_EQ(c.ident->n_axes, 4);
  EXPECT_EQ(c.ident->fifo_depth, 16);
  EXPECT_LT(c.probe_time.count(), 0.3);
  EXPECT_EQ(lk::select_protocol(dev, "v1", fast_options()).protocol, "v1");
  EXPECT_EQ(dev.stats().hellos, 1u) << "v1 must not probe";
}

namespace {

// A v1-only device as the original: any first byte other than 0xFF starts an 11-byte motion
// packet (only bits [1:0] used), 0xFF a 9-byte init; a packet whose bytes stop for 100 ms is
// dropped (watchdog, wall time). 0xAA per motion packet.
class FakeV1Device : public lk::Link {
 public:
  void write(std::span<const uint8_t> bytes) override {
    for (const uint8_t b : bytes) {
      const auto now = clock::now();
      if (!pkt_.empty() && now - last_ > milliseconds(100)) {
        ++dropped_;
        pkt_.clear();
      }
      last_ = now;
      pkt_.push_back(b);
      const size_t want = pkt_[0] == 0xFF ? 9 : 11;
      if (pkt_.size() == want) {
        if (want == 9) {
          ++inits_;
        } else {
          moves_.push_back(pkt_);
          out_.push_back(0xAA);
        }
        pkt_.clear();
      }
    }
  }
  std::optional<uint8_t> read_byte(milliseconds timeout) override {
    if (out_.empty()) {
      std::this_thread::sleep_for(timeout);
      return std::nullopt;
    }
    const uint8_t b = out_.front();
    out_.pop_front();
    return b;
  }
  void flush_input() override { out_.clear(); }
  std::string name() const override { return "fake-v1"; }
  std::vector<std::vector<uint8_t>> moves_;
  size_t inits_ = 0;
  size_t dropped_ = 0;

 private:
  using clock = std::chrono::steady_clock;
  std::vector<uint8_t> pkt_;
  std::deque<uint8_t> out_;
  clock::time_point last_ = clock::now();
};

}  // namespace

TEST(SelectProtocol, AutoFallsBackToV1Cleanly) {
  FakeV1Device dev;
  const auto t0 = std::chrono::steady_clock::now();
  const auto c = lk::select_protocol(dev, "auto", lk::StreamV2Options{});
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(c.protocol, "v1");
  EXPECT_FALSE(c.ident.has_value());
  EXPECT_GE(waited, 0.45) << "300 ms for IDENT + 150 ms for the device watchdog";
  EXPECT_LT(waited, 1.5);
  fpgacnc::config::MachineConfig cfg;
  cfg.laser_requires_m3 = false;
  const auto plan = plan_of("G1 X1 Y2 F600\nG1 X0 Y0\n", cfg);
  lk::StreamOptions so;
  so.ack_timeout = milliseconds(1000);
  const auto r = lk::stream_v1(dev, plan, so);
  EXPECT_EQ(r.moves, 2u);
  EXPECT_EQ(dev.dropped_, 1u) << "the HELLO bytes are dropped by the watchdog";
  EXPECT_EQ(dev.inits_, 1u);
  ASSERT_EQ(dev.moves_.size(), 2u) << "no move made of HELLO bytes";
  const auto job = fpgacnc::protocol::v1::pack_job(plan);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(std::equal(dev.moves_[i].begin(), dev.moves_[i].end(), job.steps[i].packet.begin()))
        << "move " << i;
  }
}

TEST(SelectProtocol, ExplicitV2OnAV1DeviceIsAnError) {
  FakeV1Device dev;
  lk::StreamV2Options so;
  so.hello_attempts = 1;
  try {
    lk::select_protocol(dev, "v2", so);
    FAIL();
  } catch (const lk::Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not speak protocol v2"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(lk::select_protocol(dev, "v3", so), lk::Error);
}

// MOTION at the start (StreamV2Options::motion, docs/protocol.md "MOTION"): a device that takes
// it gets the machine's ramp once; a device without it (NAK UNKNOWN_TYPE) runs the job anyway.
TEST(StreamV2, MotionAtTheStartAndADeviceWithoutIt) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(40, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  for (const bool known : {true, false}) {
    SCOPED_TRACE(known ? "device with MOTION" : "device without MOTION");
    FakeV2Device::Options o;
    if (!known) o.unknown_types = {0x08};
    FakeV2Device dev(o);
    auto so = clean_options();
    so.motion = lk::machine_motion(cfg);
    const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
    EXPECT_EQ(r.motion, known ? 1 : 0);
    if (known) {
      ASSERT_EQ(dev.motions().size(), 1u);
      EXPECT_EQ(dev.motions()[0], lk::machine_motion(cfg));
      EXPECT_EQ(dev.motions()[0].ramp, lk::machine_hold_ramp(cfg));
    } else {
      EXPECT_EQ(r.naks[static_cast<size_t>(v2::NakReason::UnknownType)], 1u);
    }
    expect_executed_in_order(dev, job);
    EXPECT_TRUE(r.position_ok);
  }
}

// A device slow enough that a job outlasts the polls by far (the hold tests act between polls).
FakeV2Device::Options slow_device() {
  FakeV2Device::Options o;
  o.fifo_depth = 16;
  o.exec_period = std::chrono::microseconds(10000);
  return o;
}

// A hold from on_poll (as `fpgacnc stream` sends it on a key or SIGINT): once STATUS shows the
// hold, nothing more completes however long it lasts (counted in STATUS answers, not time); a
// resume runs the rest of the job in order to the plan's end.
TEST(StreamV2, HoldFromOnPollFreezesTheJobAndResumeFinishesIt) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(120, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device dev(slow_device());
  auto so = clean_options();
  so.motion = lk::machine_motion(cfg);
  enum { kRun, kHolding, kHeld, kResumed } phase = kRun;
  size_t done_at_hold = 0, held_answers = 0, answers0 = 0;
  so.on_poll = [&](lk::V2Session& s) {
    switch (phase) {
      case kRun:
        if (s.fifo_done() >= 10) {
          v2::Motion m = s.motion();
          m.hold = true;
          s.send_motion(m);
          phase = kHolding;
        }
        break;
      case kHolding:
        if (!s.motion_pending() && (s.last_status().state & v2::kStateStopped)) {
          done_at_hold = s.fifo_done();
          answers0 = s.status_answers();
          phase = kHeld;
        }
        break;
      case kHeld:
        EXPECT_EQ(s.fifo_done(), done_at_hold) << "a segment completed during the hold";
        s.request_status();
        if (s.status_answers() >= answers0 + 20) {
          held_answers = s.status_answers() - answers0;
          EXPECT_TRUE(dev.held());
          v2::Motion m = s.motion();
          m.hold = false;
          m.resume = true;
          s.send_motion(m);
          phase = kResumed;
        }
        break;
      case kResumed:
        break;
    }
    return true;
  };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  EXPECT_EQ(phase, kResumed);
  EXPECT_GE(held_answers, 20u);
  EXPECT_LT(done_at_hold, job.frames.size());
  ASSERT_EQ(dev.motions().size(), 3u);  // the start's, HOLD, RESUME
  EXPECT_TRUE(dev.motions()[1].hold);
  EXPECT_TRUE(dev.motions()[2].resume);
  EXPECT_FALSE(dev.held());
  expect_executed_in_order(dev, job);
  EXPECT_TRUE(r.position_ok);
  EXPECT_FALSE(r.stopped);
}

// on_poll returning false during a hold stops the job: the frames not yet sent are dropped, the
// device keeps its queue (held), and the report gives both counts and the device position.
TEST(StreamV2, StopDuringAHoldKeepsTheDeviceQueueAndReports) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(200, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device dev(slow_device());
  auto so = clean_options();
  so.motion = lk::machine_motion(cfg);
  bool sent = false;
  so.on_poll = [&](lk::V2Session& s) {
    if (!sent && s.fifo_done() >= 5) {
      v2::Motion m = s.motion();
      m.hold = true;
      s.send_motion(m);
      sent = true;
    }
    return !(sent && !s.motion_pending() && (s.last_status().state & v2::kStateStopped));
  };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  EXPECT_TRUE(r.stopped);
  EXPECT_FALSE(r.position_ok);
  EXPECT_FALSE(r.released);
  EXPECT_TRUE(dev.held());
  EXPECT_GT(r.unsent, 0u);
  EXPECT_EQ(r.queued, dev.fifo_level());
  EXPECT_GT(r.queued, 0u);
  // Every frame is either done, queued on the device or dropped (none lost or doubled).
  EXPECT_EQ(dev.executed().size() + dev.fifo_level() + r.unsent, job.frames.size());
  EXPECT_EQ(r.status_end.position, dev.position());
  EXPECT_EQ(r.status_end.done - r.status_start.done, dev.executed().size());
}

// `fpgacnc stream`'s keys and interrupt (link/hold_control.h) on the fake device: f f f sets
// the feed rate to 70 % (Q1.15 22 938), r r the rapid rate to 25 %, '!' holds, '~' resumes;
// an interrupt holds and asks once the hold is complete; "stop" ends the job there with the
// device's queue kept.
TEST(StreamV2, HoldControlKeysAndInterrupt) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(200, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 16;
  o.exec_period = std::chrono::microseconds(20000);  // the job outlasts the polls by far
  FakeV2Device dev(o);
  std::vector<std::string> said;
  std::vector<std::string> asked;
  lk::HoldControl::Io io;
  io.say = [&](const std::string& l) { said.push_back(l); };
  io.ask = [&](const std::string& where) {
    asked.push_back(where);
    EXPECT_TRUE(dev.held()) << "asked before the device holds";
    return lk::HoldControl::Io::Answer::kKeep;  // stop, the device keeps its queue
  };
  lk::HoldControl hc(cfg, io);
  auto so = clean_options();
  so.motion = lk::machine_motion(cfg);
  int step = 0;
  size_t done_held = 0;
  so.on_poll = [&](lk::V2Session& s) {
    if (step == 0 && s.fifo_done() >= 3) {
      for (char c : std::string("fffrr!")) hc.key(c);
      step = 1;
    } else if (step == 1 && (s.last_status().state & v2::kStateStopped)) {
      done_held = s.fifo_done();
      hc.key('~');
      step = 2;
    } else if (step == 2 && s.fifo_done() >= done_held + 3) {
      hc.interrupt();
      step = 3;
    }
    if (step == 1) s.request_status();
    return hc.poll(s);
  };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  EXPECT_EQ(step, 3);
  EXPECT_TRUE(r.stopped);
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], hc.where(r.status_end));
  // MOTION frames: the start's; f, f, f, r, r (rates only); '!'; '~'; the interrupt's hold.
  const auto& m = dev.motions();
  ASSERT_EQ(m.size(), 9u);
  EXPECT_EQ(m[3].feed, 22'938);  // 70 % of 0x8000, rounded
  EXPECT_EQ(m[3].rapid, 0x8000);
  EXPECT_EQ(m[5].rapid, 0x2000);  // 25 %
  EXPECT_TRUE(m[6].hold);
  EXPECT_TRUE(m[7].resume);
  EXPECT_TRUE(m[8].hold);
  for (size_t i = 1; i < 6; ++i) EXPECT_FALSE(m[i].hold || m[i].resume) << i;
  for (const auto& x : m) EXPECT_EQ(x.ramp, lk::machine_hold_ramp(cfg));
  EXPECT_EQ(hc.feed_pct(), 70);
  EXPECT_EQ(hc.rapid_pct(), 25);
  EXPECT_TRUE(dev.held());
  EXPECT_EQ(dev.executed().size() + dev.fifo_level() + r.unsent, job.frames.size());
  EXPECT_FALSE(said.empty());
}

// A device without MOTION: keys are refused once with a message, the first interrupt goes on,
// the second stops sending.
TEST(StreamV2, HoldControlOnADeviceWithoutMotion) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(200, false), cfg);
  FakeV2Device::Options o;
  o.fifo_depth = 16;
  o.exec_period = std::chrono::microseconds(1000000);  // the job outlasts the polls by far
  o.unknown_types = {0x08};
  FakeV2Device dev(o);
  std::vector<std::string> said;
  lk::HoldControl hc(cfg, {[&](const std::string& l) { said.push_back(l); }, nullptr});
  auto so = clean_options();
  so.motion = lk::machine_motion(cfg);
  int polls = 0;
  so.on_poll = [&](lk::V2Session& s) {
    ++polls;
    if (polls == 2) {
      hc.key('!');
      hc.interrupt();
    }
    if (polls == 5) hc.interrupt();
    return hc.poll(s);
  };
  const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
  EXPECT_EQ(r.motion, 0);
  EXPECT_TRUE(r.stopped);
  EXPECT_EQ(polls, 5);
  EXPECT_TRUE(dev.motions().empty());
  ASSERT_EQ(said.size(), 2u);
  EXPECT_NE(said[0].find("no feed hold"), std::string::npos) << said[0];
  EXPECT_NE(said[1].find("cannot hold"), std::string::npos) << said[1];
}

// "stop" at the question (and no terminal to ask): MOTION CANCEL, the device drops its queue at
// rest, and the job ends once STATUS shows it empty and the hold over; every frame is done,
// dropped by the device or not sent.
TEST(StreamV2, HoldControlStopCancelsTheDeviceQueue) {
  const auto cfg = test_cfg();
  const auto plan = plan_of(spiral_gcode(200, false), cfg);
  const auto job = fpgacnc::test::pack_motion(plan, cfg);
  for (const bool terminal : {true, false}) {
    SCOPED_TRACE(terminal ? "asked" : "no terminal");
    FakeV2Device::Options o;
    o.fifo_depth = 16;
    o.exec_period = std::chrono::microseconds(20'000);  // the job outlasts the polls by far
    FakeV2Device dev(o);
    lk::HoldControl::Io io;
    if (terminal) io.ask = [](const std::string&) { return lk::HoldControl::Io::Answer::kStop; };
    lk::HoldControl hc(cfg, io);
    auto so = clean_options();
    so.motion = lk::machine_motion(cfg);
    bool sent = false;
    so.on_poll = [&](lk::V2Session& s) {
      if (!sent && s.fifo_done() >= 3) {
        hc.interrupt();
        sent = true;
      }
      return hc.poll(s);
    };
    const auto r = fpgacnc::test::stream_plan(dev, plan, cfg, so);
    EXPECT_TRUE(r.stopped);
    EXPECT_TRUE(hc.cancelled());
    ASSERT_EQ(dev.motions().size(), 3u);  // the start's, the hold, the cancel
    EXPECT_TRUE(dev.motions()[2].cancel);
    EXPECT_FALSE(dev.held());
    EXPECT_EQ(dev.fifo_level(), 0u);
    EXPECT_GT(dev.cancelled(), 0u);
    EXPECT_EQ(r.queued, dev.cancelled());
    EXPECT_EQ(dev.executed().size() + dev.cancelled() + r.unsent, job.frames.size());
    EXPECT_EQ(r.status_end.position, dev.position());
  }
}
