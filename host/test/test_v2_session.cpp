// V2Session (link/v2_session.h) alone against the fake device: frames pushed a few at a time
// between polls, as a line front end pushes them, with the counts it reports; a quiet spell and
// more frames; abandon.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "fake_v2_device.h"
#include "fpgacnc/link/v2_session.h"

namespace lk = fpgacnc::link;
namespace v2 = fpgacnc::protocol::v2;
using fpgacnc::test::FakeV2Device;
using std::chrono::milliseconds;

namespace {

lk::StreamV2Options options() {
  lk::StreamV2Options o;
  o.retransmit_timeout = milliseconds(200);
  o.idle_poll = milliseconds(20);
  o.answer_timeout = milliseconds(5000);
  return o;
}

v2::Frame move(int32_t x, int32_t y) {
  const std::array<int32_t, 2> s{x, y};
  return v2::line(0, 1, 0, 4000, s);
}

}  // namespace

TEST(V2Session, FramesPushedBetweenPollsAllRunInOrder) {
  FakeV2Device::Options o;
  o.fifo_depth = 8;
  o.initial_next_seq = 200;  // SEQ wraps during the session
  o.initial_done = 0xFFFFFFF0u;
  o.line_delay = std::chrono::microseconds(50'000);  // answers come well after each write
  FakeV2Device dev(o);
  lk::StreamV2Options opt = options();
  opt.answer_timeout = milliseconds(500);
  lk::StreamV2Report rep;
  const v2::Ident id = lk::handshake_v2(dev, opt, rep, std::nullopt);
  lk::V2Session s(dev, opt, id, rep);
  s.start();
  EXPECT_TRUE(s.complete());
  int64_t x = 0, y = 0;
  for (int batch = 0; batch < 30; ++batch) {
    for (int k = 0; k < 3; ++k) {
      const int32_t dx = (batch + k) % 2 ? 25 : -10, dy = 3;
      s.push({move(dx, dy), true});
      x += dx;
      y += dy;
    }
    EXPECT_FALSE(s.complete());
    s.poll(milliseconds(1));
    EXPECT_LE(s.acked(), s.pushed());
    EXPECT_LE(s.fifo_done(), s.fifo_pushed());
  }
  EXPECT_EQ(s.fifo_pushed(), 90u);
  s.drain();
  EXPECT_TRUE(s.complete());
  EXPECT_EQ(s.acked(), 90u);
  EXPECT_EQ(s.fifo_done(), 90u);
  EXPECT_EQ(dev.position()[0], x);
  EXPECT_EQ(dev.position()[1], y);
  EXPECT_EQ(dev.stats().fifo_full, 0u);  // the credit was respected
  EXPECT_LE(dev.stats().max_fifo_level, 8u);

  // A quiet spell longer than the answer timeout, then more frames: no "no answer" error.
  dev.wait_until(dev.now() + milliseconds(700));
  s.push({move(5, 5), true});
  s.drain();
  EXPECT_EQ(s.fifo_done(), 91u);
  EXPECT_EQ(dev.position()[0], x + 5);

  // A status asked for is answered while nothing else is in flight.
  const size_t answers = s.status_answers();
  s.request_status();
  while (s.status_answers() == answers) s.poll(milliseconds(5));
  EXPECT_EQ(s.last_status().position[0], x + 5);
}

TEST(V2Session, AbandonDropsWhatWasNeverSent) {
  FakeV2Device::Options o;
  o.fifo_depth = 4;
  o.exec_period = std::chrono::microseconds(20'000);  // slow: frames wait for credit
  FakeV2Device dev(o);
  lk::StreamV2Report rep;
  const v2::Ident id = lk::handshake_v2(dev, options(), rep, std::nullopt);
  lk::V2Session s(dev, options(), id, rep);
  s.start();
  for (int i = 0; i < 40; ++i) s.push({move(1, 0), true});
  for (int i = 0; i < 5; ++i) s.poll(milliseconds(1));
  EXPECT_GT(s.unsent(), 0u);
  const size_t dropped = s.abandon();
  EXPECT_GT(dropped, 0u);
  EXPECT_EQ(s.pushed(), 40u - dropped);
  while (!s.settled()) s.poll(milliseconds(5));
  // Every frame that was sent is acknowledged; the rest never reached the device.
  EXPECT_EQ(s.acked(), s.pushed());
  s.drain();
  EXPECT_EQ(dev.position()[0], static_cast<int32_t>(s.pushed()));
  EXPECT_LT(dev.position()[0], 40);
}

// TRIGGER and SET_POSITION go as sequenced frames in order with the moves; TRIGGER_QUERY's
// answer reaches last_trigger(); a SET_POSITION is taken only with the device idle
// (docs/protocol.md "SET_POSITION").
TEST(V2Session, TriggerAndSetPosition) {
  FakeV2Device::Options o;
  o.fifo_depth = 4;
  o.exec_period = std::chrono::microseconds(5'000);
  FakeV2Device dev(o);
  lk::StreamV2Report rep;
  const v2::Ident id = lk::handshake_v2(dev, options(), rep, std::nullopt);
  lk::V2Session s(dev, options(), id, rep);
  s.start();
  s.push({v2::trigger(0, v2::TriggerMode::Home, v2::switch_bit(0, true), id.n_axes)});
  s.drain();
  EXPECT_EQ(s.trigger_answers(), 0u);
  s.request_trigger();
  while (s.trigger_answers() == 0) s.poll(milliseconds(5));
  EXPECT_EQ(s.last_trigger().mode, v2::TriggerMode::Home);
  EXPECT_TRUE(s.last_trigger().armed());
  EXPECT_FALSE(s.last_trigger().done());
  EXPECT_EQ(s.last_trigger().latched.size(), id.n_axes);

  // Moves, then SET_POSITION pushed behind them: the device takes it only once idle (NAK BUSY
  // while they run, resent by the session), so X ends at the value set whatever the timing.
  for (int i = 0; i < 3; ++i) s.push({move(10, 0), true});
  std::vector<int32_t> pos(id.n_axes, 0);
  pos[0] = -160;
  s.push({v2::set_position(0, 0x0001, pos)});
  s.push({v2::trigger(0, v2::TriggerMode::Disarm)});
  s.drain();
  EXPECT_EQ(dev.set_positions(), 1u);
  EXPECT_EQ(dev.position()[0], -160);
  EXPECT_EQ(dev.trigger().mode, v2::TriggerMode::Disarm);
  EXPECT_EQ(dev.trigger().flags, 0);
}
