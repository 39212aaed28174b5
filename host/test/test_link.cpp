// SerialLink over a pseudo-terminal, with a fake v1 device thread on the master side.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/protocol/v1.h"

namespace lk = fpgacnc::link;
namespace v1 = fpgacnc::protocol::v1;

namespace {

// Fake v1 device: collects every byte; after the 9-byte init, answers 0xAA per 11-byte packet
// (optionally a junk byte first, and it stops answering after `ack_limit` moves).
class FakeDevice {
 public:
  explicit FakeDevice(size_t ack_limit = SIZE_MAX, bool junk_first = false)
      : ack_limit_(ack_limit), junk_first_(junk_first) {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
    EXPECT_GE(master_, 0);
    EXPECT_EQ(::grantpt(master_), 0);
    EXPECT_EQ(::unlockpt(master_), 0);
    slave_path_ = ::ptsname(master_);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeDevice() {
    stop_ = true;
    thread_.join();
    ::close(master_);
  }
  const std::string& path() const { return slave_path_; }
  std::vector<uint8_t> bytes() {
    std::lock_guard<std::mutex> l(m_);
    return bytes_;
  }

 private:
  void run() {
    size_t acks = 0;
    while (!stop_) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0 || !(p.revents & POLLIN)) continue;
      uint8_t buf[256];
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n <= 0) continue;
      size_t total;
      {
        std::lock_guard<std::mutex> l(m_);
        bytes_.insert(bytes_.end(), buf, buf + n);
        total = bytes_.size();
      }
      const size_t moves = total >= 9 ? (total - 9) / 11 : 0;
      while (acks < moves && acks < ack_limit_) {
        if (junk_first_ && acks == 0) {
          const uint8_t j = 0x55;
          (void)!::write(master_, &j, 1);
        }
        const uint8_t a = 0xAA;
        (void)!::write(master_, &a, 1);
        ++acks;
      }
    }
  }
  int master_ = -1;
  std::string slave_path_;
  size_t ack_limit_;
  bool junk_first_;
  std::atomic<bool> stop_{false};
  std::mutex m_;
  std::vector<uint8_t> bytes_;
  std::thread thread_;
};

fpgacnc::plan::Plan small_plan() {
  fpgacnc::config::MachineConfig c;
  c.laser_requires_m3 = false;
  return fpgacnc::plan::plan_program(
      fpgacnc::gcode::parse_string("G0 X1 Y1\nG1 X2 F600\nG4 P0.05\nG1 Y3\nG1 X0 Y0\n", "s.gcode"),
      c, {});
}

}  // namespace

TEST(SerialLink, OpensAPtyAndExchangesBytes) {
  FakeDevice dev;
  lk::SerialLink link(dev.path(), 115200);
  link.flush_input();
  const auto init = v1::pack_init(1, 2);
  link.write(init);
  const auto m = v1::pack_motion(1, 3, 4, 5);
  link.write(m);
  const auto b = link.read_byte(std::chrono::milliseconds(2000));
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(*b, 0xAA);
  EXPECT_FALSE(link.read_byte(std::chrono::milliseconds(50)).has_value());
  std::vector<uint8_t> want(init.begin(), init.end());
  want.insert(want.end(), m.begin(), m.end());
  EXPECT_EQ(dev.bytes(), want);
  if (link.using_posix_fallback()) {
    std::cerr << "note: libserialport refused the pty, POSIX termios fallback in use\n";
  }
}

// A real port has no board clock: link time is the wall clock, and a wait of T blocks for T of
// wall time (lower bounds only: a loaded machine can only make the waits longer).
TEST(SerialLink, TimersRunOnTheWallClock) {
  using namespace std::chrono_literals;
  FakeDevice dev;  // answers only after an init packet: silent here
  lk::SerialLink link(dev.path(), 115200);
  EXPECT_FALSE(link.board_clock().has_value());
  const auto w0 = std::chrono::steady_clock::now();
  const lk::Link::Time t0 = link.now();
  EXPECT_FALSE(link.read_byte_until(t0 + 100ms).has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - w0, 100ms);
  EXPECT_GE(link.now() - t0, 100ms);
  const auto w1 = std::chrono::steady_clock::now();
  link.wait_until(link.now() + 50ms);
  EXPECT_GE(std::chrono::steady_clock::now() - w1, 50ms);
  const auto w2 = std::chrono::steady_clock::now();
  EXPECT_FALSE(link.read_byte(30ms).has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - w2, 30ms);
}

TEST(SerialLink, MissingPortIsAClearError) {
  try {
    lk::SerialLink link("/dev/does-not-exist-fpgacnc", 115200);
    FAIL();
  } catch (const lk::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/does-not-exist-fpgacnc"), std::string::npos)
        << e.what();
  }
}

TEST(StreamV1, StreamsAJobOverAPty) {
  FakeDevice dev(SIZE_MAX, /*junk_first=*/true);
  lk::SerialLink link(dev.path(), 115200);
  const auto plan = small_plan();
  std::vector<std::pair<size_t, size_t>> progress;
  lk::StreamOptions o;
  o.ack_timeout = std::chrono::milliseconds(2000);
  o.progress = [&](size_t d, size_t t) { progress.emplace_back(d, t); };
  const auto r = lk::stream_v1(link, plan, o);
  EXPECT_EQ(r.moves, 4u);
  EXPECT_EQ(r.acks, 4u);
  EXPECT_EQ(r.warnings, 1u);  // the junk byte
  EXPECT_EQ(r.dwells, 1u);
  EXPECT_GE(r.elapsed.count(), 0.05);
  EXPECT_EQ(r.bytes_written, 9u + 4 * 11u);
  EXPECT_EQ(r.final_steps, plan.final_steps);
  ASSERT_EQ(progress.size(), 4u);
  EXPECT_EQ(progress.back(), (std::pair<size_t, size_t>{4, 4}));
  // Give the device a moment to have read everything (it already acked it all).
  EXPECT_EQ(dev.bytes(), v1::job_bytes(plan));
}

TEST(StreamV1, TimeoutNamesLastAcknowledgedMove) {
  FakeDevice dev(/*ack_limit=*/2);
  lk::SerialLink link(dev.path(), 115200);
  lk::StreamOptions o;
  o.ack_timeout = std::chrono::milliseconds(200);
  const auto w0 = std::chrono::steady_clock::now();
  try {
    lk::stream_v1(link, small_plan(), o);
    FAIL();
  } catch (const lk::Error& e) {
    const std::string w = e.what();
    // Wall-clock timer on a port: at least the 200 ms, and not called board time.
    EXPECT_GE(std::chrono::steady_clock::now() - w0, std::chrono::milliseconds(200));
    EXPECT_NE(w.find("within 0.2 s for"), std::string::npos) << w;
    // Third move (segment 2, line 4) times out; last acknowledged: segment 1 (line 2).
    EXPECT_NE(w.find("segment 2 (line 4)"), std::string::npos) << w;
    EXPECT_NE(w.find("last acknowledged move: segment 1 (line 2)"), std::string::npos) << w;
  }
}

TEST(StreamV1, BadJobWritesZeroBytes) {
  FakeDevice dev;
  lk::SerialLink link(dev.path(), 115200);
  const auto path = (std::filesystem::temp_directory_path() / "fpgacnc_bad_job.gcode").string();
  {
    std::ofstream f(path);
    f << "G0 X1\nG1 X2 F100\nG1 X3 Q7\nG1 X4\n";
  }
  lk::StreamOptions o;
  o.ack_timeout = std::chrono::milliseconds(500);
  EXPECT_THROW(lk::stream_file_v1(link, path, {}, o), fpgacnc::gcode::Error);
  // A plan v1 cannot carry: rejected by the packer, before the init packet.
  fpgacnc::plan::Plan bad = small_plan();
  std::get<fpgacnc::plan::Segment>(bad.items.back()).steps[0] = int64_t{1} << 40;
  EXPECT_THROW(lk::stream_v1(link, bad, o), std::invalid_argument);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_TRUE(dev.bytes().empty());
  std::filesystem::remove(path);
}
