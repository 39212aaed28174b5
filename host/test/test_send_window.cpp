// The go-back-N send window alone (send_window.h), against a fake link: a device that takes
// sequenced frames in order and answers with cumulative ACKs, over a line that loses frames both
// ways with a fixed delay, all in fake time.
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "fpgacnc/link/send_window.h"

namespace lk = fpgacnc::link;
using std::chrono::milliseconds;
using Time = lk::SendWindow::Time;

namespace {

struct InFlight {
  Time arrives;
  uint8_t seq;  // host -> device: the frame's SEQ; device -> host: next_seq
};

// The fake link: delay each way, loss probability each way, a device that accepts frame SEQ
// next_seq and NAKs (answers next_seq) anything else.
struct FakeLine {
  Time delay{milliseconds(5)};
  double loss = 0.0;
  std::mt19937_64 rng{1};
  std::deque<InFlight> to_device, to_host;
  uint8_t device_next = 0;
  std::vector<uint8_t> accepted;  // SEQs the device accepted, in order
  bool lost() { return std::uniform_real_distribution<double>(0, 1)(rng) < loss; }
  void send(Time now, uint8_t seq) {
    if (!lost()) to_device.push_back({now + delay, seq});
  }
  // Delivers everything due by `now`; returns the answers due at the host.
  std::vector<uint8_t> advance(Time now) {
    while (!to_device.empty() && to_device.front().arrives <= now) {
      const auto f = to_device.front();
      to_device.pop_front();
      if (f.seq == device_next) {
        accepted.push_back(f.seq);
        ++device_next;
      }
      if (!lost()) to_host.push_back({f.arrives + delay, device_next});
    }
    std::vector<uint8_t> out;
    while (!to_host.empty() && to_host.front().arrives <= now) {
      out.push_back(to_host.front().seq);
      to_host.pop_front();
    }
    return out;
  }
};

// Sends `n` frames through the window over `line`; returns the fake time it took.
Time run(lk::SendWindow& w, FakeLine& line, size_t n, uint8_t seq0) {
  Time now{0};
  const Time step{milliseconds(1)};
  for (int guard = 0; guard < 1'000'000 && w.acked() < n; ++guard) {
    while (w.may_send(n)) {
      line.send(now, w.seq_of(w.sent()));
      w.mark_sent(now);
    }
    for (uint8_t next : line.advance(now)) {
      const auto d = w.acknowledge(next, now);
      // An answer that does not move the window while frames are out means the device saw a
      // frame out of order: go back (the NAK path).
      if (d && *d == 0 && w.sent() > w.acked() && !w.stale_nak()) w.go_back(now);
    }
    if (w.timer_expired(now)) w.on_timeout(now);
    now += step;
  }
  (void)seq0;
  return now;
}

}  // namespace

TEST(SendWindow, CleanLineDeliversInOrderWithoutResends) {
  FakeLine line;
  lk::SendWindow w({milliseconds(50), 16}, 250, Time{0});  // SEQ wraps past 255
  line.device_next = 250;
  run(w, line, 600, 250);
  ASSERT_EQ(w.acked(), 600u);
  ASSERT_EQ(line.accepted.size(), 600u);
  for (size_t i = 0; i < line.accepted.size(); ++i)
    EXPECT_EQ(line.accepted[i], static_cast<uint8_t>(250 + i));
  EXPECT_EQ(w.retransmissions(), 0u);
  EXPECT_EQ(w.go_backs(), 0u);
  EXPECT_EQ(w.window(), 16u);
  // Round trip: 5 ms each way on a 1 ms tick.
  EXPECT_NEAR(w.srtt_s(), 0.010, 0.002);
  EXPECT_GE(w.rto(), milliseconds(50));  // never below the floor
}

TEST(SendWindow, LossyLineRecoversEveryFrameOnceInOrder) {
  FakeLine line;
  line.loss = 0.05;
  lk::SendWindow w({milliseconds(30), 32}, 0, Time{0});
  run(w, line, 2000, 0);
  ASSERT_EQ(w.acked(), 2000u);
  ASSERT_EQ(line.accepted.size(), 2000u);  // the device took each frame exactly once
  for (size_t i = 0; i < line.accepted.size(); ++i)
    ASSERT_EQ(line.accepted[i], static_cast<uint8_t>(i));
  EXPECT_GT(w.retransmissions(), 0u);
  EXPECT_GT(w.go_backs(), 0u);
  EXPECT_LT(w.min_window(), 32u);  // AIMD halved it
}

TEST(SendWindow, StaleAndFutureAnswersAreRefused) {
  lk::SendWindow w({milliseconds(30), 8}, 10, Time{0});
  for (int i = 0; i < 4; ++i) w.mark_sent(Time{0});
  EXPECT_FALSE(w.acknowledge(20, Time{0}).has_value());  // ahead of anything sent
  EXPECT_FALSE(w.acknowledge(9, Time{0}).has_value());   // behind the window
  EXPECT_EQ(w.acknowledge(12, Time{milliseconds(1)}).value(), 2u);
  EXPECT_EQ(w.acked(), 2u);
  EXPECT_EQ(w.acknowledge(12, Time{milliseconds(1)}).value(), 0u);  // duplicate: no progress
}

TEST(SendWindow, TimeoutProbesWithTheOldestFrameAndBacksOff) {
  lk::SendWindow w({milliseconds(30), 8}, 0, Time{0});
  while (w.may_send(8)) w.mark_sent(Time{0});
  EXPECT_EQ(w.sent(), 8u);
  EXPECT_FALSE(w.timer_expired(Time{milliseconds(30)}));
  EXPECT_TRUE(w.timer_expired(Time{milliseconds(31)}));
  w.on_timeout(Time{milliseconds(31)});
  EXPECT_TRUE(w.probing());
  EXPECT_EQ(w.sent(), 0u);
  EXPECT_TRUE(w.may_send(8));
  w.mark_sent(Time{milliseconds(31)});
  EXPECT_FALSE(w.may_send(8));  // only the oldest frame while probing
  EXPECT_EQ(w.rto(), milliseconds(60));
  EXPECT_EQ(w.window(), 4u);
  // Progress ends the probe.
  EXPECT_EQ(w.acknowledge(1, Time{milliseconds(40)}).value(), 1u);
  EXPECT_FALSE(w.probing());
  EXPECT_TRUE(w.may_send(8));
}

TEST(SendWindow, GoBacksToTheSameFrameAreCounted) {
  lk::SendWindow w({milliseconds(30), 8}, 0, Time{0});
  while (w.may_send(8)) w.mark_sent(Time{0});
  EXPECT_EQ(w.go_back(Time{0}), 0u);
  EXPECT_TRUE(w.stale_nak());
  EXPECT_EQ(w.go_back(Time{0}), 1u);
  EXPECT_EQ(w.go_back(Time{0}), 2u);
  w.mark_sent(Time{0});
  w.acknowledge(1, Time{0});
  EXPECT_FALSE(w.stale_nak());
  EXPECT_EQ(w.go_back(Time{0}), 0u);
}
