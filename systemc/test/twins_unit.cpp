// Unit tests of the twins (CTest label unit): the documented arithmetic (docs/protocol.md worked
// examples, docs/timing.md) and small jobs on the virtual board whose edge times follow from
// the documented latencies. Plain checks; exit status 1 on any failure.
#include <fmt/format.h>

#include <systemc>

#include "fpgacnc/protocol/v1.h"
#include "fpgacnc/twins/virtual_board.h"

namespace {

using namespace fpgacnc::twins;
int failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    ++failures;
    fmt::print("FAIL: {}\n", what);
  }
}
template <class A, class B>
void check_eq(const A& a, const B& b, const std::string& what) {
  check(a == static_cast<A>(b), fmt::format("{}: got {}, expected {}", what, a, b));
}

void arithmetic() {
  // docs/protocol.md worked example: X 320, Y -160, feed 1200, NUMERATOR 18 750 000.
  const PreparedTiming t = prepare_timing(320, 160, 18'750'000, 18'750'000, 1200, 62'500, 200);
  check(t.x_dominant, "X dominant");
  check_eq(t.period, 15'625u, "P");
  check_eq(t.total, 5'000'000u, "T");
  for (uint64_t k = 1; k <= 160; ++k) check_eq(dda_tick(k, 160, t.total), k * 31'250, "Y step");
  check_eq(dda_tick(1, 3, 10), 4, "ceil(10/3)");
  check_eq(dda_tick(3, 3, 10), 10, "last step on tick T");
  // feed 0 and the clamp.
  check_eq(prepare_timing(5, 1, 1000, 1000, 0, 62'500, 200).period, 62'500u, "feed 0");
  check_eq(prepare_timing(5, 1, 1000, 1000, 10, 62'500, 200).period, 200u, "clamp");
  check_eq(prepare_timing(1, 5, 1000, 5000, 10, 62'500, 2).period, 500u, "Y dominant");
  // 128-bit product: k * T beyond 64 bits.
  check_eq(dda_tick(2'000'000'000ull, 2'000'000'000ull, 0xFFFF'FFFF'0000'0000ull),
           0xFFFF'FFFF'0000'0000ull, "128-bit DDA");
  // UART timers at 50 MHz / 115200: 434.03 clocks per bit.
  const BitTimer bt(50'000'000, 115'200);
  check_eq(bt.tx_boundary(1), 435, "tx boundary 1 = ceil(434.03)");
  check_eq(bt.tx_boundary(10), 4341, "tx frame");
  check(bt.rx_tick(1) >= 216 && bt.rx_tick(1) <= 218, "rx start check at mid-bit");
  const SenderTiming st{50'000'000, 115'200};
  check_eq(st.frame(), 4340, "sender frame (round(10 * 434.03))");
  check_eq(st.level(0x01, 0), 0, "start bit");
  check_eq(st.level(0x01, 500), 1, "bit 0 of 0x01");
  check_eq(st.level(0x01, 1000), 0, "bit 1 of 0x01");
  check_eq(st.level(0x01, 4339), 1, "stop bit");
}

std::vector<HostPacket> worked_example_job() {
  using namespace fpgacnc::protocol::v1;
  const auto init = pack_init(18'750'000, 18'750'000);
  const auto move = pack_motion(1, 320, -160, 1200);
  return {HostPacket{{init.begin(), init.end()}, false, 1},
          HostPacket{{move.begin(), move.end()}, true, 1}};
}

void worked_example(const RunResult& r) {
  check(r.error.empty(), "host error: " + r.error);
  const SenderTiming st{50'000'000, 115'200};
  const BitTimer bt(50'000'000, 115'200);
  // Init frames from cycle 1, the motion packet 1 clock after them, its last byte 10 frames on.
  const Cycle last_start = 1 + 9 * st.frame() + 1 + 10 * st.frame();
  const Cycle valid = last_start + 2 + bt.rx_tick(10);  // uart_rx: synchronizer + stop sample
  const Cycle a = valid + 2;                            // decoder take + 1, prep accept
  const Cycle A = a + kPrepLatency + 1;                 // executor accept
  const Cycle D = A + 1;                                // X reverses (DIR 0 -> 1), hold long over
  const Cycle R = D + 200;                              // DIR setup
  check_eq(r.packet_done.size(), 2u, "packets");
  check_eq(r.packet_done.back(), valid + 1, "packet_done");
  check_eq(r.seg_start.at(0), R, "run start R");
  check_eq(r.position[0], 320, "X position");
  check_eq(r.position[1], -160, "Y position");
  check_eq(r.acks.size(), 1u, "one ACK");
  check_eq(r.acks.at(0), R + 5'000'000 + 2, "ACK start edge = R + T + 2");
  // Edges: DIR X at D; laser at R; first X step at R + 15625; last steps at R + T.
  std::vector<fpgacnc::simboard::Edge> x_steps, y_steps;
  bool dir_ok = false, laser_ok = false;
  for (const auto& e : r.edges) {
    if (e.signal == 4 && e.cycle == static_cast<uint64_t>(D) && e.value == 1) dir_ok = true;
    if (e.signal == 8 && e.cycle == static_cast<uint64_t>(R) && e.value == 1) laser_ok = true;
    if (e.signal == 0 && e.value == 1) x_steps.push_back(e);
    if (e.signal == 1 && e.value == 1) y_steps.push_back(e);
  }
  check(dir_ok, "DIR X rises at D");
  check(laser_ok, "laser rises at R");
  check_eq(x_steps.size(), 320u, "X pulses");
  check_eq(y_steps.size(), 160u, "Y pulses");
  check_eq(x_steps.front().cycle, static_cast<uint64_t>(R + 15'625), "first X step");
  check_eq(y_steps.front().cycle, static_cast<uint64_t>(R + 31'250), "first Y step");
  check_eq(x_steps.back().cycle, static_cast<uint64_t>(R + 5'000'000), "last X step at R + T");
  check_eq(y_steps.back().cycle, static_cast<uint64_t>(R + 5'000'000), "last Y step at R + T");
}

void zero_move_and_watchdog(const RunResult& r) {
  check(r.error.empty(), "host error: " + r.error);
  check_eq(r.timeouts, 1u, "one watchdog timeout");
  check_eq(r.acks.size(), 1u, "ACK of the zero move");
  check(r.edges.empty(), "a zero move makes no edges");
  // The zero move completes on the executor's accept edge: ACK 2 edges later.
  check_eq(r.acks.at(0), r.seg_done.at(0) + 2, "ACK 2 edges after seg_done");
}

}  // namespace

int sc_main(int, char*[]) {
  arithmetic();
  CoreParams p;
  VirtualBoard board("virtual_board", p);
  std::vector<RunResult> results;
  auto keep = [&](RunResult&& r) { results.push_back(std::move(r)); };
  board.add_job(TwinJob{worked_example_job(), p.timing, keep});
  // A truncated packet (3 bytes), a pause past the watchdog, then a move with no steps.
  const auto zero = fpgacnc::protocol::v1::pack_motion(0, 0, 0, 100);
  board.add_job(TwinJob{{HostPacket{{0x01, 0x00, 0x00}, false, 1},
                         HostPacket{{zero.begin(), zero.end()}, true, 6'000'000}},
                        p.timing,
                        keep});
  sc_core::sc_start();
  if (results.size() == 2) {
    worked_example(results[0]);
    zero_move_and_watchdog(results[1]);
  } else {
    check(false, "both jobs ran");
  }
  fmt::print("twins_unit: {}\n", failures ? "FAILED" : "all checks passed");
  return failures ? 1 : 0;
}
