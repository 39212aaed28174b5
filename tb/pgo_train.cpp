// The training run of the profile-guided build of a cnc_core model (tb/CMakeLists.txt,
// fpgacnc_verilated(... PGO)): the model, compiled with -fprofile-generate, runs a v2 session
// through its pins: HELLO, the CONFIG_AXIS frames, then a short job the host plans and packs
// (LINE_PROFILE frames, ARC frames in XY, a laser on and off, a dwell, a Z move) until the
// machine is at rest, with idle clocks before and after: 12 M clocks, about 10 s of the
// instrumented model (33 M and 29 s at the default accelerations, for a profile 1-3 % faster). A
// workload of its own, not the speed bench's v1 move. It exits non-zero (and the build stops) when
// the model did not execute every segment of the job. FPGACNC_PGO_MODEL names the model's class;
// its header is FPGACNC_PGO_HEADER.
#include <cstdio>
#include <string>

#include "common/core_pins.h"
#include "common/pin_harness.h"
#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2.h"
#include "fpgacnc/protocol/v2_job.h"

#define FPGACNC_STR2(x) #x
#define FPGACNC_STR(x) FPGACNC_STR2(x)
#include FPGACNC_STR(FPGACNC_PGO_HEADER)

using Model = FPGACNC_PGO_MODEL;
namespace v2 = fpgacnc::protocol::v2;

int main() {
  // Accelerations 16 times the defaults: the same frames and code paths in a quarter of the
  // clocks (the profile is per clock; the cruise phases it shortens are the executor's loop).
  fpgacnc::config::MachineConfig cfg;
  for (auto& a : cfg.max_accel_mm_s2) a *= 16.0;
  const char* program =
      "G21 G90 G17\nG0 X0.5 Y0.5\nM4 S600\nG1 X1.5 Y0.75 F6000\nG2 X2.5 Y1.75 I0 J1\n"
      "G1 X2.5 Y2 S300\nG3 X1.5 Y3 I-1 J0\nM5\nG4 P0.01\nG0 X0 Y0 Z0.5\nM4 S1000\n"
      "G1 X0.5 Y-0.5 F6000\nG1 X0 Y0\nM5\n";
  const auto prog = fpgacnc::gcode::parse_string(program, "pgo-train");
  const auto plan = fpgacnc::plan::plan_program(prog, cfg, {});
  const auto job = v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg, {.heaters = false});

  fpgacnc::tb::PinHarness<Model> h(fpgacnc::tb::kCoreAxes, fpgacnc::tb::core_pins<Model>(), false);
  fpgacnc::tb::reset_core(h);
  auto run = [&](uint64_t clocks) {
    for (uint64_t i = 0; i < clocks; ++i) h.tick();
  };
  run(200'000);
  h.queue(v2::encode(v2::Frame{0, static_cast<uint8_t>(v2::Type::Hello), {}}));
  run(200'000);
  uint8_t seq = 0;
  size_t frames = 0;
  auto send = [&](const v2::Frame& f) {
    v2::Frame g = f;
    g.seq = seq++;
    h.queue(v2::encode(g));
    ++frames;
  };
  for (const auto& f : job.config) send(f);
  for (const auto& jf : job.frames) send(jf.frame);
  // Until every frame is in and the machine rests (bounded: 20 s of machine time).
  const uint64_t limit = h.cycle() + 1'000'000'000ull;
  while (h.cycle() < limit && (!h.rx_idle() || h.dut().busy)) run(1000);
  run(200'000);
  std::printf("pgo_train: %zu frames, %llu clocks, segments done %u\n", frames,
              static_cast<unsigned long long>(h.cycle()),
              static_cast<unsigned>(h.dut().segments_done));
  return h.dut().segments_done == job.fifo_frames ? 0 : 1;
}
