// Protocol benchmark (make bench, not a test): v1 stop-and-wait against the v2 sliding window,
// through the pins of the Verilated cnc_core at 115 200 and at 1 000 000 baud, with the host's
// own streamers (link::stream_v1, link::stream_v2) talking to the model through an in-process
// link whose time is the model's clock: write() queues bytes on the rx pin, read_byte() runs
// clocks until a byte has come back on tx (at most the timeout, in simulated time). No pty, no
// threads: the figures are cycle-exact and the same on every machine.
//
// Two jobs per baud and protocol:
//   short:  N moves of 0.1 mm (16 steps) along X at 3 000 mm/min (2 ms each): real-feed segments;
//   tiny:   N moves of 1 step (6.25 um) along X at 60 000 mm/min: the link is the bottleneck.
// Printed per run: segments per second sustained (between the completion of the first and the
// last segment, simulated time), bytes on the wire per segment each way (everything the session
// wrote and read, v2's HELLO/STATUS/CONFIG/RELEASE included, divided by the segments), and for v2
// the rx line utilisation over the same interval (fraction of clocks the UART line carries a
// frame bit) and the line's limit in LINE frames per second (baud / 10 / mean LINE frame bytes).
#include <fmt/format.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "Vcnc_core.h"
#include "Vcnc_core_1m.h"
#include "common/core_pins.h"
#include "common/pin_harness.h"
#include "fpgacnc/config/machine.h"
#include "fpgacnc/gcode/interpreter.h"
#include "fpgacnc/link/link.h"
#include "fpgacnc/link/stream_v1.h"
#include "fpgacnc/link/stream_v2.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"

namespace {

using namespace fpgacnc;
using std::chrono::milliseconds;

// PinHarness that also records segment completions and rx line activity.
template <class Model>
class RecordingHarness : public tb::PinHarness<Model> {
 public:
  RecordingHarness(double baud)
      : tb::PinHarness<Model>(tb::kCoreAxes, tb::core_pins<Model>(), true, baud) {}
  std::vector<uint64_t> done_cycles;
  std::vector<uint64_t> rx_busy_prefix;  // rx busy clocks up to each done (for utilisation)
  uint64_t rx_busy = 0;

 protected:
  void observe() override {
    if (!this->rx_idle()) ++rx_busy;
    if (this->dut().seg_done) {
      done_cycles.push_back(this->cycle());
      rx_busy_prefix.push_back(rx_busy);
    }
  }
};

template <class Model>
class ModelLink final : public link::Link {
 public:
  explicit ModelLink(double baud) : h_(baud) { tb::reset_core(h_); }
  void write(std::span<const uint8_t> bytes) override {
    h_.queue(std::vector<uint8_t>(bytes.begin(), bytes.end()));
    written_ += bytes.size();
  }
  std::optional<uint8_t> read_byte(milliseconds timeout) override {
    if (next_ < h_.tx_bytes().size()) return h_.tx_bytes()[next_++].value;
    const uint64_t limit = static_cast<uint64_t>(timeout.count()) * 50'000;  // clocks
    if (limit == 0) return std::nullopt;
    if (!h_.wait_bytes(next_, limit)) return std::nullopt;
    return h_.tx_bytes()[next_++].value;
  }
  void flush_input() override { next_ = h_.tx_bytes().size(); }
  std::string name() const override { return "in-process cnc_core"; }

  RecordingHarness<Model>& harness() { return h_; }
  uint64_t written() const { return written_; }
  uint64_t read() const { return h_.tx_bytes().size(); }

 private:
  RecordingHarness<Model> h_;
  size_t next_ = 0;
  uint64_t written_ = 0;
};

plan::Plan make_plan(const config::MachineConfig& cfg, int moves, double step_mm, double feed) {
  std::ostringstream g;
  g << "G21 G91\n";
  for (int i = 0; i < moves; ++i) g << fmt::format("G1 X{:.5f} F{:.0f}\n", step_mm, feed);
  const auto program = gcode::parse_string(g.str(), "<bench>");
  return plan::plan_program(program, cfg, {});
}

struct Figures {
  double seg_per_s = 0;
  double down_per_seg = 0;
  double up_per_seg = 0;
  double utilisation = 0;  // v2 only
  size_t segments = 0;
};

template <class Model>
Figures run(double baud, const std::string& protocol, const plan::Plan& plan,
            const config::MachineConfig& cfg) {
  ModelLink<Model> link(baud);
  size_t segments = 0;
  if (protocol == "v1") {
    link::StreamOptions opt;
    const auto rep = link::stream_v1(link, plan, opt);
    segments = rep.moves;
  } else {
    auto opt = link::stream_v2_options(cfg);
    opt.release = true;
    const auto job = protocol::v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
    const auto rep = link::stream_v2_job(link, job, opt);
    if (!rep.position_ok)
      throw std::runtime_error("v2 bench: final position differs from the plan");
    segments = rep.lines;
  }
  auto& h = link.harness();
  Figures f;
  f.segments = segments;
  const auto& d = h.done_cycles;
  if (d.size() != segments)
    throw std::runtime_error(fmt::format("{} segments done of {}", d.size(), segments));
  const double span = static_cast<double>(d.back() - d.front());
  f.seg_per_s = static_cast<double>(d.size() - 1) / span * tb::kClkHz;
  f.down_per_seg = static_cast<double>(link.written()) / static_cast<double>(segments);
  f.up_per_seg = static_cast<double>(link.read()) / static_cast<double>(segments);
  f.utilisation = static_cast<double>(h.rx_busy_prefix.back() - h.rx_busy_prefix.front()) / span;
  return f;
}

double line_frame_bytes(const plan::Plan& plan, const config::MachineConfig& cfg) {
  const auto job = protocol::v2::pack_job(fpgacnc::plan::plan_motion(plan, cfg), cfg);
  double bytes = 0;
  size_t lines = 0;
  for (const auto& jf : job.frames) {
    if (jf.frame.type != static_cast<uint8_t>(protocol::v2::Type::Line)) continue;
    bytes += static_cast<double>(protocol::v2::encode(jf.frame).size());
    ++lines;
  }
  return bytes / static_cast<double>(lines);
}

}  // namespace

int main(int argc, char** argv) {
  const int moves = argc > 1 ? std::stoi(argv[1]) : 400;
  config::MachineConfig cfg;
  // Both protocols at constant feed (v2 LINE frames, as v1's moves): the comparison is of the
  // links, not of planning.
  cfg.motion = "constant";
  const auto short_plan = make_plan(cfg, moves, 0.1, 3000);
  const auto tiny_plan = make_plan(cfg, moves, 1.0 / 160.0, 60000);
  fmt::print("protocol bench: {} moves per run, cnc_core at 50 MHz\n", moves);
  for (const char* job : {"short", "tiny"}) {
    const auto& plan = std::string(job) == "short" ? short_plan : tiny_plan;
    for (double baud : {115200.0, 1e6}) {
      Figures v1, v2;
      if (baud == 115200.0) {
        v1 = run<Vcnc_core>(baud, "v1", plan, cfg);
        v2 = run<Vcnc_core>(baud, "v2", plan, cfg);
      } else {
        v1 = run<Vcnc_core_1m>(baud, "v1", plan, cfg);
        v2 = run<Vcnc_core_1m>(baud, "v2", plan, cfg);
      }
      // LINE frames per second the line can carry: 10 bits per byte, the job's mean LINE frame.
      const double v2_limit = baud / 10.0 / line_frame_bytes(plan, cfg);
      fmt::print(
          "bench: {} job at {:.0f} baud: v1 {:.1f} segments/s ({:.1f} B down + {:.1f} B up per "
          "segment), v2 {:.1f} segments/s ({:.1f} B down + {:.1f} B up), v2/v1 {:.2f}x, v2 line "
          "utilisation {:.1f}% (line limit {:.1f} LINE frames/s)\n",
          job, baud, v1.seg_per_s, v1.down_per_seg, v1.up_per_seg, v2.seg_per_s, v2.down_per_seg,
          v2.up_per_seg, v2.seg_per_s / v1.seg_per_s, 100.0 * v2.utilisation, v2_limit);
    }
  }
  return 0;
}
