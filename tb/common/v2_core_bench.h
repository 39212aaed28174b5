// A Verilated cnc_core driven as a v2 device through its UART at 3 Mbaud: HELLO and CONFIG_AXIS
// (STEP high 5, low 5, DIR setup 10, hold 10 clocks) at construction, then the device frames it
// sends (msgs), every STEP rise with its DIR (rises), the steps counted at the pins per axis
// (pins_pos) and the clocks the hard-limit alarm rose (trip_cycles). A bench adds its own
// observations in observe_more(), called every clock after these.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pin_harness.h"
#include "v2_exchange.h"
#include "v2_frames.h"

namespace fpgacnc::tb {

struct StepRise {
  uint64_t cycle;
  int axis;
  bool dir;
};

template <class Model, int kAxes>
class V2CoreBench : public PinHarness<Model> {
 public:
  explicit V2CoreBench(const PinAccess<Model>& pins)
      : PinHarness<Model>(kAxes, pins, true, 3'000'000.0) {
    this->reset(2, 1);
    this->send(v2::hello());
    EXPECT_TRUE(wait_msg()) << "no IDENT";
    for (uint8_t ax = 0; ax < kAxes; ++ax)
      EXPECT_EQ(exchange(v2::config_axis(seq++, ax, 5, 5, 10, 10)).type, v2::kAck);
  }

  uint8_t seq = 0;
  std::vector<v2::DeviceMsg> msgs;
  std::vector<StepRise> rises;
  std::vector<uint64_t> trip_cycles;
  int64_t pins_pos[kAxes] = {};

  bool wait_msg(uint64_t limit = 200000) { return v2::wait_msg(*this, msgs, limit); }
  // Sends a frame and returns the first answer that is not a DONE.
  v2::DeviceMsg exchange(const std::vector<uint8_t>& f) {
    return v2::exchange(*this, msgs, f, 200000);
  }
  v2::DeviceMsg status() {
    const auto m = exchange(v2::status_query());
    EXPECT_EQ(m.type, v2::kStatus);
    return m;
  }
  uint64_t last_rise() const { return rises.empty() ? 0 : rises.back().cycle; }
  void run_until_idle(uint64_t limit) {
    for (uint64_t i = 0; i < limit && (this->dut().busy || !this->rx_idle()); ++i) this->tick();
  }

 protected:
  virtual void observe_more() {}

  void observe() final {
    const Model& m = this->dut();
    const auto& tx = this->tx_bytes();
    if (tx.size() != tx_seen_) {
      tx_seen_ = tx.size();
      if (auto x = parser_.push(tx.back().value, tx.back().start_cycle)) msgs.push_back(*x);
    }
    for (int a = 0; a < kAxes; ++a) {
      if (((m.step >> a) & 1u) && !((step_prev_ >> a) & 1u)) {
        const bool d = (m.dir >> a) & 1u;
        rises.push_back(StepRise{this->cycle(), a, d});
        pins_pos[a] += d ? 1 : -1;
      }
    }
    step_prev_ = m.step;
    if (m.limit_trip && !trip_prev_) trip_cycles.push_back(this->cycle());
    trip_prev_ = m.limit_trip;
    observe_more();
  }

 private:
  size_t tx_seen_ = 0;
  v2::DeviceParser parser_;
  uint32_t step_prev_ = 0;
  bool trip_prev_ = false;
};

}  // namespace fpgacnc::tb
