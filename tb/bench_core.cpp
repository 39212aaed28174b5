// Benchmark of the core (not a test): for a fixed seeded run it prints
//   (a) the worst step-time error against the ideal k*T/n schedule and the worst jitter, over
//       random segments driven straight into segment_executor (vexec) with random 1..12-clock
//       timing settings (the UART + cfg path of cnc_core would be ~4 000 clocks per packet);
//   (b) Verilator speed of cnc_core (vcore) in simulated clocks per wall second, idle and while
//       executing a long move received through the UART pins;
//   (c) the maximum aggregate step rate with 1-clock settings: a segment with equal steps on all
//       4 axes at period 2 on vexec (cnc_core's v1 packets carry only X and Y).
// Lines start with "bench:". FPGACNC_SEED overrides the seed. Environment for short runs (e.g.
// under valgrind --tool=callgrind, whose instruction counts per clock do not depend on the load):
//   FPGACNC_BENCH_PARTS   which parts run, any of "accuracy", "speed", "maxrate" (default all);
//   FPGACNC_BENCH_CLOCKS  clocks of (b)'s idle run and at most as many of its move (default
//                         10 000 000 idle and the whole 12.5 M-clock move).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "common/core_pins.h"
#include "common/exec_harness.h"
#include "common/seed.h"
#include "common/step_monitor.h"
#include "verilated.h"

namespace {

using fpgacnc::tb::AxisTiming;
using fpgacnc::tb::kClkHz;
using fpgacnc::tb::mag;
using fpgacnc::tb::Segment;
using Clock = std::chrono::steady_clock;

constexpr int kAxes = fpgacnc::tb::kExecAxes;

// The value of environment variable `name` as an unsigned number, or `fallback`.
uint64_t env_u64(const char* name, uint64_t fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::strtoull(v, nullptr, 0) : fallback;
}

// True when FPGACNC_BENCH_PARTS is unset or names `part`.
bool part_enabled(const char* part) {
  const char* v = std::getenv("FPGACNC_BENCH_PARTS");
  return v == nullptr || *v == '\0' || std::strstr(v, part) != nullptr;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// segment_executor with 1-clock step timing until a bench sets its own.
class Exec : public fpgacnc::tb::ExecHarness {
 public:
  Exec() : ExecHarness(std::vector<AxisTiming>(kAxes, AxisTiming{1, 1, 1, 1})) {}
};

// (a) step-time error and jitter over random segments.
void bench_accuracy(uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uni = [&](uint64_t lo, uint64_t hi) {
    return std::uniform_int_distribution<uint64_t>(lo, hi)(rng);
  };
  Exec e;
  size_t idx[kAxes] = {0, 0, 0, 0};
  double worst_err = 0;
  uint64_t worst_jitter = 0, steps_total = 0, mismatches = 0;
  int segments = 0;
  const auto t0 = Clock::now();
  for (int batch = 0; batch < 40; ++batch) {
    std::vector<AxisTiming> t(kAxes);
    for (auto& at : t) at = fpgacnc::tb::random_timing(uni, 12, 40);
    const uint64_t pmin = fpgacnc::tb::min_period(t);
    e.idle(200);
    e.set_timing(t);
    for (int i = 0; i < 25; ++i) {
      Segment seg;
      for (auto& s : seg.steps) {
        const int64_t n = static_cast<int64_t>(uni(0, 5) == 0 ? 0 : uni(1, 3000));
        s = uni(0, 1) ? n : -n;
      }
      seg.period = pmin + uni(0, pmin);
      const uint64_t T = seg.total();
      const uint64_t R = e.run(seg);
      ++segments;
      for (int a = 0; a < kAxes; ++a) {
        const auto& tr = e.mon().axis(a);
        const uint64_t n = mag(seg.steps[a]);
        if (tr.rises.size() < idx[a] + n) {
          ++mismatches;
          idx[a] = tr.rises.size();
          continue;
        }
        uint64_t min_iv = UINT64_MAX, max_iv = 0;
        for (uint64_t k = 1; k <= n; ++k) {
          const uint64_t rise = tr.rises[idx[a] + k - 1];
          const double ideal = fpgacnc::tb::ideal_rise(R, k, T, n);
          worst_err = std::max(worst_err, std::abs(static_cast<double>(rise) - ideal));
          if (k > 1) {
            const uint64_t iv = rise - tr.rises[idx[a] + k - 2];
            min_iv = std::min(min_iv, iv);
            max_iv = std::max(max_iv, iv);
          }
        }
        if (n > 2) worst_jitter = std::max(worst_jitter, max_iv - min_iv);
        idx[a] += n;
        steps_total += n;
      }
    }
  }
  const double wall = seconds_since(t0);
  std::printf("bench: accuracy source: segment_executor (vexec) driven directly, seed %llu\n",
              static_cast<unsigned long long>(seed));
  std::printf("bench: segments %d, steps %llu, clocks %llu, %.2f s wall\n", segments,
              static_cast<unsigned long long>(steps_total),
              static_cast<unsigned long long>(e.cycle()), wall);
  std::printf("bench: worst step error %.4f clocks (bound: < 1)\n", worst_err);
  std::printf("bench: worst jitter %llu clocks\n", static_cast<unsigned long long>(worst_jitter));
  std::printf("bench: step count mismatches %llu, timing violations %llu\n",
              static_cast<unsigned long long>(mismatches),
              static_cast<unsigned long long>(e.violations()));
}

// (b) Verilator speed of cnc_core, idle and during a long move received on rx.
void bench_core_speed() {
  // Pins only: no STEP/DIR/tx monitors, so the rate is the model's.
  fpgacnc::tb::PinHarness<Vcnc_core> h(fpgacnc::tb::kCoreAxes, fpgacnc::tb::kCorePins, false);
  fpgacnc::tb::reset_core(h);
  auto& m = h.dut();
  auto tick = [&]() { h.tick(); };

  const uint64_t idle_clocks = env_u64("FPGACNC_BENCH_CLOCKS", 10'000'000);
  const uint64_t move_limit = env_u64("FPGACNC_BENCH_CLOCKS", UINT64_MAX);
  auto t0 = Clock::now();
  for (uint64_t i = 0; i < idle_clocks; ++i) tick();
  const double idle_rate = static_cast<double>(idle_clocks) / seconds_since(t0);

  // G1 X 4000 Y -3000 at feed 6000: P = 3125, T = 12.5 M clocks.
  const std::vector<uint8_t> pkt = {0x01, 0x00, 0x00, 0x0F, 0xA0, 0xFF,
                                    0xFF, 0xF4, 0x48, 0x17, 0x70};
  h.queue(pkt);
  while (!h.rx_idle() || !m.running) tick();
  uint64_t steps = 0;
  uint8_t prev_step = 0;
  const uint64_t c0 = h.cycle();
  t0 = Clock::now();
  while (m.running && h.cycle() - c0 < move_limit) {
    tick();
    steps += static_cast<uint64_t>(__builtin_popcount(m.step & ~prev_step & 0xFu));
    prev_step = m.step;
  }
  const double wall = seconds_since(t0);
  const double move_rate = static_cast<double>(h.cycle() - c0) / wall;
  std::printf("bench: cnc_core (vcore, 4 axes) idle: %.2f M clocks/s (%.3f x real time)\n",
              idle_rate / 1e6, idle_rate / kClkHz);
  std::printf(
      "bench: cnc_core (vcore, 4 axes) during a move: %.2f M clocks/s (%.3f x real time), "
      "%llu clocks, %llu steps\n",
      move_rate / 1e6, move_rate / kClkHz, static_cast<unsigned long long>(h.cycle() - c0),
      static_cast<unsigned long long>(steps));
}

// (c) maximum step rate: equal steps on 4 axes, period 2, 1-clock settings.
void bench_max_rate() {
  Exec e;
  const int64_t n = 1'000'000;
  const Segment seg{1, {n, -n, n, -n}, 2};
  const uint64_t before = e.cycle();
  const auto t0 = Clock::now();
  const uint64_t R = e.run(seg);
  const double wall = seconds_since(t0);
  uint64_t total = 0;
  uint64_t first = UINT64_MAX, last = 0;
  for (int a = 0; a < kAxes; ++a) {
    const auto& tr = e.mon().axis(a);
    total += tr.rises.size();
    if (!tr.rises.empty()) {
      first = std::min(first, tr.rises.front());
      last = std::max(last, tr.rises.back());
    }
  }
  // Rate over the segment: n steps per axis in T = 2n clocks.
  const double seconds = static_cast<double>(2 * n) / kClkHz;
  const double per_axis = static_cast<double>(e.mon().axis(0).rises.size()) / seconds;
  std::printf(
      "bench: max rate source: segment_executor (vexec), 4 axes x %lld steps, period 2, "
      "STEP high/low/setup/hold 1 clock\n",
      static_cast<long long>(n));
  std::printf(
      "bench: max rate run start R=%llu, last rise at R+%llu (T=%lld), %llu clocks "
      "simulated in %.2f s, violations %llu\n",
      static_cast<unsigned long long>(R), static_cast<unsigned long long>(last - R),
      static_cast<long long>(2 * n), static_cast<unsigned long long>(e.cycle() - before), wall,
      static_cast<unsigned long long>(e.violations()));
  std::printf("bench: max step rate per axis %.0f steps/s (limit CLK_HZ/2 = %.0f)\n", per_axis,
              kClkHz / 2);
  std::printf("bench: max aggregate step rate %.0f steps/s (%llu steps on 4 axes)\n",
              static_cast<double>(total) / seconds, static_cast<unsigned long long>(total));
}

}  // namespace

int main(int argc, char** argv) {
  Verilated::commandArgs(argc, argv);
  const uint64_t seed = fpgacnc::tb::test_seed(20260503, "bench_core");
  const auto t0 = Clock::now();
  if (part_enabled("accuracy")) bench_accuracy(seed);
  if (part_enabled("speed")) bench_core_speed();
  if (part_enabled("maxrate")) bench_max_rate();
  std::printf("bench: total wall time %.1f s\n", seconds_since(t0));
  return 0;
}
