// Unit tests of the motion-rate twin (feed_rate.h, CTest label unit, in twins_unit): its closed
// form against a clock-by-clock reference written from the register table of docs/timing.md
// "Feed hold and overrides" (random ramps, rates, periods, hold / resume times, code changes and
// reset phases), and its cost (pieces per ramp period and request, none per steady clock).
#include <gtest/gtest.h>

#include <random>

#include "feed_rate_ref.h"
#include "fpgacnc/twins/feed_rate.h"

namespace {

using fpgacnc::twins::Cycle;
using fpgacnc::twins::FeedRate;
using fpgacnc::twins::test::Reference;
using fpgacnc::twins::test::Req;

struct Case {
  std::vector<Req> reqs;
  Cycle phase;
  uint32_t log2k, ramp0;
};

Case random_case(std::mt19937_64& g, Cycle n) {
  Case c;
  c.log2k = std::uniform_int_distribution<uint32_t>(1, 8)(g);
  c.phase = std::uniform_int_distribution<Cycle>(0, 600)(g);
  c.ramp0 = std::uniform_int_distribution<uint32_t>(1, 3)(g) == 1
                ? 0x3'5AFE
                : std::uniform_int_distribution<uint32_t>(1, 0xffffffffu)(g);
  auto ramp = [&]() -> uint32_t {
    switch (std::uniform_int_distribution<int>(0, 3)(g)) {
      case 0:
        return std::uniform_int_distribution<uint32_t>(1, 1000)(g);
      case 1:
        return std::uniform_int_distribution<uint32_t>(1, 1u << 26)(g);
      case 2:
        return std::uniform_int_distribution<uint32_t>(1u << 26, 1u << 30)(g);
      default:
        return std::uniform_int_distribution<uint32_t>(1, 0xffffffffu)(g);
    }
  };
  auto rate = [&]() -> uint16_t {
    return std::uniform_int_distribution<int>(0, 4)(g) == 0
               ? uint16_t{0x8000}
               : static_cast<uint16_t>(std::uniform_int_distribution<int>(1, 0x8000)(g));
  };
  const int reqs = std::uniform_int_distribution<int>(0, 14)(g);
  for (int i = 0; i < reqs; ++i) {
    Req q{};
    q.t = std::uniform_int_distribution<Cycle>(0, n - 1)(g);
    q.kind = std::uniform_int_distribution<int>(0, 3)(g);
    if (q.kind == 0) {
      const int f = std::uniform_int_distribution<int>(0, 2)(g);
      q.hold = f == 1;
      q.resume = f == 2;
      q.feed = rate();
      q.rapid = rate();
      q.ramp = ramp();
    }
    q.code = static_cast<uint8_t>(std::uniform_int_distribution<int>(0, 3)(g));
    c.reqs.push_back(q);
  }
  // now and then a request on the same clock as another (a HOLD wins over a RESUME)
  if (reqs > 1 && std::uniform_int_distribution<int>(0, 2)(g) == 0) c.reqs[1].t = c.reqs[0].t;
  return c;
}

void send(FeedRate& f, const Req& q) {
  switch (q.kind) {
    case 0:
      f.motion(q.t, q.hold, q.resume, q.feed, q.rapid, q.ramp, q.cancel);
      break;
    case 1:
      f.hold_input(q.t);
      break;
    case 2:
      f.start_input(q.t);
      break;
    default:
      f.segment_code(q.t, q.code);
  }
}

// Every answer of the twin against the reference, for clocks 0 .. n - 1.
void compare(FeedRate& f, const Reference& ref, Cycle n, std::mt19937_64& g, const char* what,
             int seed) {
  SCOPED_TRACE(testing::Message() << what << " seed " << seed);
  std::vector<uint64_t> cum(static_cast<size_t>(n) + 1, 0);  // adv-high clocks in 0 .. t - 1
  for (Cycle t = 0; t < n; ++t)
    cum[static_cast<size_t>(t) + 1] = cum[static_cast<size_t>(t)] + ref.adv[static_cast<size_t>(t)];
  for (Cycle t = 0; t < n; ++t) {
    ASSERT_EQ(f.adv(t), ref.adv[static_cast<size_t>(t)] != 0) << "adv in clock " << t;
    ASSERT_EQ(f.rate(t), ref.r[static_cast<size_t>(t)]) << "r in clock " << t;
    ASSERT_EQ(f.hold(t), ref.hold[static_cast<size_t>(t)] != 0) << "hold in clock " << t;
  }
  std::uniform_int_distribution<Cycle> clk(0, n - 1);
  for (int i = 0; i < 400; ++i) {
    Cycle a = clk(g), b = clk(g);
    if (a > b) std::swap(a, b);
    ASSERT_EQ(f.ticks_in(a, b), cum[static_cast<size_t>(b) + 1] - cum[static_cast<size_t>(a)])
        << "ticks in clocks " << a << " .. " << b;
  }
  for (int i = 0; i < 400; ++i) {
    const Cycle t0 = clk(g);
    const uint64_t k = std::uniform_int_distribution<uint64_t>(1, 3000)(g);
    // the reference's k-th adv-high clock at or after t0
    Cycle want = -1;
    for (Cycle t = t0; t < n; ++t)
      if (cum[static_cast<size_t>(t) + 1] - cum[static_cast<size_t>(t0)] == k) {
        want = t;
        break;
      }
    const Cycle got = f.tick_clock(t0, k);
    if (want >= 0)
      ASSERT_EQ(got, want) << "tick " << k << " from clock " << t0;
    else
      ASSERT_GE(got, n) << "tick " << k << " from clock " << t0 << " (beyond the reference)";
  }
  // the spans with r = 0
  std::vector<std::pair<Cycle, Cycle>> want;
  for (Cycle t = 0; t < n; ++t) {
    if (ref.r[static_cast<size_t>(t)] != 0) continue;
    if (!want.empty() && want.back().second == t)
      ++want.back().second;
    else
      want.emplace_back(t, t + 1);
  }
  auto got = f.stopped(0, n);
  for (auto& s : got) s.second = std::min(s.second, n);
  ASSERT_EQ(got, want) << "spans with r = 0";
}

TEST(FeedRate, ClosedFormAgainstClockByClock) {
  constexpr Cycle kN = 30'000;
  for (int seed = 0; seed < 60; ++seed) {
    std::mt19937_64 g(static_cast<uint64_t>(seed) * 7919 + 1);
    const Case c = random_case(g, kN);
    const Reference ref(c.reqs, c.phase, c.log2k, c.ramp0, kN);
    // every request up front
    FeedRate f(c.phase, c.log2k, c.ramp0);
    for (const Req& q : c.reqs) send(f, q);
    compare(f, ref, kN, g, "requests up front", seed);
    // requests in time order, each sent before any question about a clock it can change (as the
    // executor sends its segment codes): the answers are the same and none is provisional
    std::vector<Req> sorted = c.reqs;
    std::stable_sort(sorted.begin(), sorted.end(),
                     [](const Req& a, const Req& b) { return a.t < b.t; });
    FeedRate h(c.phase, c.log2k, c.ramp0);
    for (const Req& q : sorted) {
      if (q.t > 0) h.ticks_in(0, q.t - 1);
      send(h, q);
    }
    EXPECT_EQ(h.late(), 0u) << "seed " << seed;
    compare(h, ref, kN, g, "requests in time order", seed);
  }
}

// CANCEL: random cases with one to three MOTION frames turned into CANCELs (and resumes and
// holds around them); the twin finds each flush clock (first_stop from the CANCEL's clock, the
// one of a CANCEL within a cancel in progress skipped) and is told it (flush), as the virtual board
// does; every answer and every flush clock against the reference.
TEST(FeedRate, CancelFlushAgainstClockByClock) {
  constexpr Cycle kN = 30'000;
  int flushes = 0, ignored_resumes = 0;
  for (int seed = 0; seed < 60; ++seed) {
    std::mt19937_64 g(static_cast<uint64_t>(seed) * 104'729 + 3);
    Case c = random_case(g, kN);
    std::vector<size_t> motions;
    for (size_t i = 0; i < c.reqs.size(); ++i)
      if (c.reqs[i].kind == 0) motions.push_back(i);
    if (motions.empty()) {
      Req q{};
      q.t = std::uniform_int_distribution<Cycle>(0, kN / 2)(g);
      q.ramp = std::uniform_int_distribution<uint32_t>(1u << 24, 0xffffffffu)(g);
      c.reqs.push_back(q);
      motions.push_back(c.reqs.size() - 1);
    }
    const int n = std::uniform_int_distribution<int>(1, 3)(g);
    for (int i = 0; i < n; ++i) {
      Req& q = c.reqs[motions[std::uniform_int_distribution<size_t>(0, motions.size() - 1)(g)]];
      q.cancel = true;
      q.resume = false;
      q.hold = std::uniform_int_distribution<int>(0, 3)(g) == 0;  // HOLD with CANCEL is allowed
      // a resume soon after it (often while the cancel is in progress: ignored)
      Req r{};
      r.t = q.t + std::uniform_int_distribution<Cycle>(1, 3000)(g);
      r.kind = std::uniform_int_distribution<int>(0, 1)(g) == 0 ? 0 : 2;
      r.resume = true;
      r.ramp = q.ramp;
      c.reqs.push_back(r);
    }
    const Reference ref(c.reqs, c.phase, c.log2k, c.ramp0, kN);
    FeedRate f(c.phase, c.log2k, c.ramp0);
    for (const Req& q : c.reqs) send(f, q);
    std::vector<Req> cancels;
    for (const Req& q : c.reqs)
      if (q.kind == 0 && q.cancel) cancels.push_back(q);
    std::stable_sort(cancels.begin(), cancels.end(),
                     [](const Req& a, const Req& b) { return a.t < b.t; });
    std::vector<Cycle> got;
    Cycle last = -1;
    for (const Req& q : cancels) {
      if (q.t <= last) continue;  // within the cancel in progress: the same flush
      const Cycle fc = f.first_stop(q.t, kN - q.t);
      if (fc == FeedRate::kNever || fc >= kN) break;
      got.push_back(fc);
      f.flush(fc + 1);
      last = fc;
    }
    // only the flushes within the reference's clocks (a later one needs no answer here)
    std::vector<Cycle> want = ref.flushes;
    ASSERT_EQ(got, want) << "flush clocks, seed " << seed;
    flushes += static_cast<int>(want.size());
    for (const Req& q : c.reqs)
      if (q.resume && q.t < kN && ref.hold[static_cast<size_t>(q.t)] != 0) ++ignored_resumes;
    compare(f, ref, kN, g, "with CANCELs", seed);
  }
  // not vacuous: flushes happened, and resumes came while a cancel was in progress
  EXPECT_GT(flushes, 30);
  EXPECT_GT(ignored_resumes, 5);
  std::printf("60 cases: %d flushes, %d resumes with the hold still set after them\n", flushes,
              ignored_resumes);
}

TEST(FeedRate, NoRequestIsFullRate) {
  FeedRate f(21);
  EXPECT_TRUE(f.trivial());
  EXPECT_EQ(f.tick_clock(100, 1), 100);
  EXPECT_EQ(f.tick_edge(100, 7), 107);
  EXPECT_EQ(f.ticks_in(0, 999'999), 1'000'000u);
  EXPECT_TRUE(f.stopped(0, 1'000'000).empty());
}

TEST(FeedRate, HoldStopsAndResumeRestarts) {
  // With ramp 2^31 a hold from 100 % takes two periods: r = 2^31 in the first, 0 from the second.
  FeedRate f(0, 8, 0x8000'0000u);
  f.hold_input(1000);   // r changes at the boundaries 1024 and 1280
  f.start_input(5000);  // from the boundary 5120: 2^31, from 5376: 2^32
  EXPECT_EQ(f.rate(1023), uint64_t{1} << 32);
  EXPECT_EQ(f.rate(1024), uint64_t{1} << 31);
  EXPECT_EQ(f.rate(1280), 0u);
  EXPECT_EQ(f.rate(5119), 0u);
  EXPECT_EQ(f.rate(5120), uint64_t{1} << 31);
  EXPECT_EQ(f.rate(5376), uint64_t{1} << 32);
  // 1024 ticks in clocks 0 .. 1023 (adv(0) after rst and 1023 carries of 2^32); in 1024 .. 1280
  // the last carry of 2^32 and 128 of the half rate (acc 0 -> 2^31 -> 0 ...); none while stopped
  EXPECT_EQ(f.ticks_in(0, 1023), 1024u);
  EXPECT_EQ(f.ticks_in(1024, 1280), 129u);
  EXPECT_EQ(f.ticks_in(1281, 5120), 0u);
  const auto s = f.stopped(0, 10'000);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0], std::make_pair(Cycle{1280}, Cycle{5120}));
  EXPECT_TRUE(f.hold(1000));
  EXPECT_TRUE(f.hold(4999));
  EXPECT_FALSE(f.hold(5000));
  // a hold never resumed: ticks after the stop never come
  FeedRate g(0, 8, 0x8000'0000u);
  g.hold_input(0);
  EXPECT_EQ(g.tick_clock(0, 10'000), FeedRate::kNever);
}

TEST(FeedRate, CostGrowsWithPeriodsNotClocks) {
  // A 50 % feed override on a feed segment, 10^9 clocks later a hold and a resume: a ramp of 2^26
  // per period takes 32 periods from 100 % to 50 %, 32 to 0 and 64 back to 100 %.
  FeedRate f(0, 8, 1u << 26);
  f.segment_code(0, 1);
  f.motion(10, false, false, 0x4000, 0x8000, 1u << 26);
  f.motion(1'000'000'000, true, false, 0x4000, 0x8000, 1u << 26);
  f.motion(2'000'000'000, false, true, 0x8000, 0x8000, 1u << 26);
  EXPECT_EQ(f.tick_clock(0, 3'000'000'000ull) > 2'000'000'000, true);
  EXPECT_LE(f.pieces(), 32u + 32u + 64u + 4u);
  // at 50 % every second clock is a tick: 10^6 ticks take 2 * 10^6 clocks (give or take one)
  const Cycle a = f.tick_clock(100'000, 1), b = f.tick_clock(100'000, 1'000'001);
  EXPECT_EQ(b - a, 2'000'000);
}

}  // namespace
