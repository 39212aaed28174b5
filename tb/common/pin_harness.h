// PinHarness<Model>: drives a Verilated top through its pins, one clock per tick(): rx from a
// UartDriver, tx decoded by a UartMonitor, STEP/DIR sampled into a StepMonitor. The model-specific
// parts (reset polarity, how STEP/DIR are packed, extra idle inputs) come from a PinAccess of
// small captureless lambdas, so the same harness serves cnc_core (rst, step/dir buses) and the
// DE1-SoC top (rst_n, step_x/dir_x ...). A bench adds its own per-clock checks by overriding
// observe().
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "common/step_monitor.h"
#include "fpgacnc/models/uart_bits.h"
#include "verilated.h"

namespace fpgacnc::tb {

inline constexpr double kClkHz = 50e6;
inline constexpr double kBaud = 115200;

template <class Model>
struct PinAccess {
  void (*set_reset)(Model&, bool asserted);  // drives the reset input at its active level
  uint32_t (*step)(const Model&);            // STEP pins, axis a at bit a
  uint32_t (*dir)(const Model&);             // DIR pins, axis a at bit a
  void (*idle_inputs)(Model&) = nullptr;     // other inputs to their idle level, before clock 1
};

template <class Model>
class PinHarness {
 public:
  // monitors = false: tick() only drives rx and the clock (no STEP/DIR/tx sampling, no observe()),
  // for speed measurements. baud: the model's BAUD parameter (rx driver and tx monitor).
  PinHarness(int axes, const PinAccess<Model>& pins, bool monitors = true, double baud = kBaud)
      : pins_(pins),
        ctx_(std::make_unique<VerilatedContext>()),
        drv_(kClkHz, baud),
        umon_(kClkHz, baud),
        mon_(axes),
        monitors_(monitors) {
    m_ = std::make_unique<Model>(ctx_.get());
    m_->rx = 1;
    if (pins_.idle_inputs) pins_.idle_inputs(*m_);
    pins_.set_reset(*m_, false);
  }
  virtual ~PinHarness() { m_->final(); }
  PinHarness(const PinHarness&) = delete;
  PinHarness& operator=(const PinHarness&) = delete;

  // Reset asserted for `held` clocks, then released and `after` more clocks run.
  void reset(uint64_t held, uint64_t after) {
    pins_.set_reset(*m_, true);
    idle(held);
    pins_.set_reset(*m_, false);
    idle(after);
  }

  void tick() {
    m_->rx = static_cast<uint8_t>(drv_.tick());
    m_->clk = 0;
    m_->eval();
    m_->clk = 1;
    m_->eval();
    ++cycle_;
    if (!monitors_) return;
    mon_.sample(cycle_, pins_.step(*m_), pins_.dir(*m_));
    if (auto b = umon_.sample(m_->tx, cycle_)) tx_bytes_.push_back(*b);
    observe();
  }
  void idle(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) tick();
  }

  // Queues bytes on rx and runs until the last stop bit has been driven.
  void send(const std::vector<uint8_t>& bytes) {
    queue(bytes);
    while (!drv_.idle()) tick();
  }
  void queue(const std::vector<uint8_t>& bytes) {
    for (uint8_t b : bytes) drv_.push(b);
  }
  bool rx_idle() const { return drv_.idle(); }

  // Runs until the number of bytes received on tx exceeds `n` or `limit` clocks pass.
  bool wait_bytes(size_t n, uint64_t limit) {
    for (uint64_t i = 0; i < limit && tx_bytes_.size() <= n; ++i) tick();
    return tx_bytes_.size() > n;
  }

  Model& dut() { return *m_; }
  StepMonitor& mon() { return mon_; }
  uint64_t cycle() const { return cycle_; }
  const std::vector<models::UartMonitor::Byte>& tx_bytes() const { return tx_bytes_; }

 protected:
  // Called after every sampled clock edge.
  virtual void observe() {}

 private:
  PinAccess<Model> pins_;
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> m_;
  models::UartDriver drv_;
  models::UartMonitor umon_;
  StepMonitor mon_;
  bool monitors_;
  uint64_t cycle_ = 0;
  std::vector<models::UartMonitor::Byte> tx_bytes_;
};

}  // namespace fpgacnc::tb
