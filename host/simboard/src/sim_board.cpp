#include "fpgacnc/simboard/sim_board.h"

#include <Vcnc_core_board.h>
#include <Vcnc_core_board_trace.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/eventfd.h>
#include <termios.h>
#include <unistd.h>
#include <verilated.h>
#include <verilated_fst_c.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <random>

#include "fpgacnc/models/ltc2308_model.h"
#include "fpgacnc/models/thermal_plant.h"
#include "fpgacnc/models/uart_bits.h"

namespace fpgacnc::simboard {

// The simulated board's cnc_core: scaled thermal time (host/simboard/CMakeLists.txt).
using Vcnc_core = Vcnc_core_board;
using Vcnc_core_trace = Vcnc_core_board_trace;

// Heater plants on the heater pins and thermistors on the ADC pins (see sim_board.h).
struct ThermalWorld {
  models::thermal::BedPlant bed;
  models::thermal::HotEndPlant hotend;
  models::thermal::DelayedSensor bed_sensor;
  models::thermal::Thermistor ntc;
  models::Ltc2308Model adc;
  std::array<double, 2> sensed;  // thermistor temperature per channel (0 hot end, 1 bed)
  std::array<uint64_t, 2> high{};
  std::array<double, 2> last_duty{};
  std::array<SensorFault, 2> sensor{SensorFault::kNone, SensorFault::kNone};
  std::array<bool, 2> cut{};
  uint64_t tick_clk = 0;  // clocks into the current sub-step
  uint64_t sub = 0;       // sub-steps into the current tick
  uint64_t ticks = 0;
  bool active = false;
  uint8_t estop = 0;

  ThermalWorld(double clk_hz, const std::array<double, 2>& initial)
      : bed({}, initial[1]),
        hotend({}, initial[0]),
        bed_sensor(kSubSteps, initial[1]),  // the reading is one plant second old
        adc(clk_hz),
        sensed{initial[0], initial[1]} {
    adc.source = [this](int ch) {
      if (ch < 0 || ch > 1) return 0.0;
      switch (sensor[static_cast<size_t>(ch)]) {
        case SensorFault::kOpen:
          return ntc.vcc;
        case SensorFault::kShort:
          return 0.0;
        default:
          return ntc.voltage(sensed[static_cast<size_t>(ch)]);
      }
    };
    update_active();
  }
  void update_active() {
    const double amb = 20.0 + 0.5;
    active = high[0] || high[1] || hotend.block_temperature() > amb || hotend.temperature() > amb ||
             bed.temperature() > amb;
  }
  // The plants advance in kSubSteps steps per sample tick (1/16 plant second: the ADC sees a
  // temperature that moves within the tick as on a real board), each with the duty of its clocks.
  static constexpr uint64_t kSubSteps = 16;
  static constexpr uint64_t kSubClks = SimBoard::kSampleClks / kSubSteps;
  void substep() {
    const double dt = 1.0 / static_cast<double>(kSubSteps);
    for (size_t c = 0; c < 2; ++c) {
      last_duty[c] = cut[c] ? 0.0 : static_cast<double>(high[c]) / static_cast<double>(kSubClks);
    }
    sensed[0] = hotend.step(dt, last_duty[0]);
    sensed[1] = bed_sensor.sample(bed.temperature());
    bed.step(dt, last_duty[1]);
    update_active();
    high = {};
    tick_clk = 0;
    if (++sub == kSubSteps) {
      sub = 0;
      ++ticks;
      adc.conversions.clear();
    }
  }
};

struct SimBoard::Model {
  std::unique_ptr<VerilatedContext> ctx;
  std::unique_ptr<Vcnc_core> core;              // untraced (fast)
  std::unique_ptr<Vcnc_core_trace> core_trace;  // traced, when an FST path is given
  std::unique_ptr<VerilatedFstC> fst;
  LineFaultInjector line;  // faults on the serial line (all off by default)
  RxLine driver;           // host -> board bits on the rx pin
  models::UartMonitor monitor;
  models::EdgeRecorder rec;
  uint64_t cycle = 0;        // rising edges since reset release
  uint64_t last_active = 0;  // last cycle with something in flight
  // A tx byte is decoded at the middle of its stop bit; the core may start the next byte of a
  // frame only at the end of that stop bit, so the rest of it counts as activity.
  uint64_t tx_stop_end = 0;
  uint64_t stop_tail = 0;  // clocks from the stop-bit sample to the end of the stop bit (+1)
  uint32_t prev_sig = 0;   // step | dir << 4 | laser << 8 | tx << 9
  uint32_t sig_mask = 0x1ff;
  bool never_active = true;       // nothing happened since reset: quiet
  std::deque<uint8_t> inbox;      // read from the pty, not yet admitted to the rx driver
  std::vector<uint8_t> out;       // decoded tx bytes not yet written to the pty
  std::vector<LineFrame> frames;  // scratch: frames for one host byte
  uint64_t bytes_in = 0, bytes_out = 0;
  uint64_t bytes_to_pty = 0;  // written to the pty master
  uint64_t trace_time = 0;
  ThermalWorld heat;
  // Limit switches: pins as the core's limit_state orders them (bit a min, bit 4 + a max).
  uint8_t lim_manual = 0;   // set_limit()
  uint8_t lim_endstop = 0;  // endstops
  uint8_t lim_pins = 0;     // manual | endstop: what the pins carry
  uint8_t lim_wired = 0;    // the switches LIMIT_ENABLE wires
  std::vector<Endstop> endstops;
  std::array<int64_t, models::kBoardAxes> steps{};  // STEP rising edges counted (endstops)
  std::vector<LimitEvent> lim_events;
  // Switch noise (BoardOptions::switch_noise): each endstop's trip offset (steps), the endstop
  // pins a bounce holds inverted now, the bounce toggles to come (edge, pin bit) in edge order.
  SwitchNoise noise;
  std::mt19937_64 noise_rng;
  std::vector<int64_t> trip_offset;
  std::vector<uint8_t> redraw;  // released: a new offset once the axis is out of the jitter band
  uint8_t lim_flip = 0;
  std::vector<std::pair<uint64_t, uint8_t>> bounces;
  // Probe: the pin is manual | plate; the plate follows the step counts.
  bool probe_manual = false;  // set_probe()
  bool probe_plate = false;   // the plate touches
  bool probe_pin = false;     // what the pin carries
  std::optional<ProbePlate> plate;
  std::vector<ProbeEvent> probe_events;
  bool count_steps = false;  // endstops or a plate: STEP rises are counted
  // Machine buttons: pins held (bit 0 hold, bit 1 cycle start), the edge each is released on,
  // and the clock until which the board runs for them (the filter sees the release).
  uint8_t btn_pins = 0;
  std::array<uint64_t, 2> btn_release{};
  uint64_t btn_settle = 0;

  Model(double clk_hz, double baud, size_t reserve, const LineFaults& faults,
        const std::array<double, 2>& initial_c)
      : ctx(std::make_unique<VerilatedContext>()),
        line(faults),
        driver(clk_hz, baud, &line),
        monitor(clk_hz, baud),
        rec(reserve),
        stop_tail(static_cast<uint64_t>(std::ceil(clk_hz / baud / 2.0)) + 1),
        heat(clk_hz, initial_c) {}
};

namespace {

constexpr uint8_t pin_bit(int axis, bool max_side) {
  return static_cast<uint8_t>(1u << (axis + (max_side ? 4 : 0)));
}

// Drives the limit pins with manual | endstop (inverted where a bounce holds it); records the
// changes, sampled on edge `edge`.
template <class M>
void drive_limits(M& m, SimBoard::Model& s, uint64_t edge, bool by_endstop) {
  const uint8_t pins = static_cast<uint8_t>(s.lim_manual | (s.lim_endstop ^ s.lim_flip));
  uint8_t diff = static_cast<uint8_t>(pins ^ s.lim_pins);
  while (diff) {
    const int b = __builtin_ctz(diff);
    diff = static_cast<uint8_t>(diff & (diff - 1));
    s.lim_events.push_back({edge, b & 3, b >= 4, ((pins >> b) & 1u) != 0, by_endstop});
  }
  s.lim_pins = pins;
  m.limit_min = static_cast<uint8_t>(pins & 0xfu);
  m.limit_max = static_cast<uint8_t>(pins >> 4);
}

// Drives the button pins with s.btn_pins.
template <class M>
void drive_buttons(M& m, const SimBoard::Model& s) {
  m.hold_in = static_cast<uint8_t>(s.btn_pins & 1u);
  m.start_in = static_cast<uint8_t>((s.btn_pins >> 1) & 1u);
}

// Releases the buttons whose press ends at clock edge `edge` (the next one).
template <class M>
void release_buttons(M& m, SimBoard::Model& s, uint64_t edge) {
  for (size_t b = 0; b < 2; ++b) {
    if (((s.btn_pins >> b) & 1u) && s.btn_release[b] == edge)
      s.btn_pins = static_cast<uint8_t>(s.btn_pins & ~(1u << b));
  }
  drive_buttons(m, s);
}

// Switch noise: a new trip offset for endstop i (uniform in -jitter .. +jitter steps).
void draw_trip_offset(SimBoard::Model& s, size_t i) {
  const int64_t j = s.noise.jitter_steps;
  s.trip_offset[i] = j > 0 ? std::uniform_int_distribution<int64_t>(-j, j)(s.noise_rng) : 0;
  s.redraw[i] = 0;
}

// A released endstop draws its next offset once its axis has left the band in which any offset
// would press it (so that it never presses while the axis moves away).
void redraw_when_clear(SimBoard::Model& s, size_t i) {
  const Endstop& es = s.endstops[i];
  const int64_t p = s.steps[static_cast<size_t>(es.axis)], j = s.noise.jitter_steps;
  if (es.max_side ? p < es.position - j : p > es.position + j) draw_trip_offset(s, i);
}

// The level of endstop `bit` changed on edge `edge`: its pending bounce is dropped and a new one
// scheduled (2 * k toggles on edges edge + 1 .. edge + bounce_clks).
void schedule_bounce(SimBoard::Model& s, uint8_t bit, uint64_t edge) {
  std::erase_if(s.bounces, [bit](const auto& b) { return b.second == bit; });
  s.lim_flip = static_cast<uint8_t>(s.lim_flip & ~bit);
  if (s.noise.bounce_clks == 0) return;
  const int k =
      std::uniform_int_distribution<int>(1, std::max(1, s.noise.max_bounces))(s.noise_rng);
  std::uniform_int_distribution<uint64_t> at(edge + 1, edge + s.noise.bounce_clks);
  std::vector<uint64_t> t(static_cast<size_t>(2 * k));
  for (auto& x : t) x = at(s.noise_rng);
  std::sort(t.begin(), t.end());
  for (const uint64_t x : t) s.bounces.emplace_back(x, bit);
  std::stable_sort(s.bounces.begin(), s.bounces.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
}

// The bounce toggles due on edge `edge` (two on one edge cancel).
template <class M>
void apply_bounces(M& m, SimBoard::Model& s, uint64_t edge) {
  size_t n = 0;
  while (n < s.bounces.size() && s.bounces[n].first <= edge) s.lim_flip ^= s.bounces[n++].second;
  s.bounces.erase(s.bounces.begin(), s.bounces.begin() + static_cast<std::ptrdiff_t>(n));
  drive_limits(m, s, edge, true);
}

// Drives the probe pin with manual | plate; records a change, sampled on edge `edge`.
template <class M>
void drive_probe(M& m, SimBoard::Model& s, uint64_t edge, bool by_plate) {
  const bool pin = s.probe_manual || s.probe_plate;
  if (pin != s.probe_pin) s.probe_events.push_back({edge, pin, by_plate});
  s.probe_pin = pin;
  m.probe_in = pin ? 1 : 0;
}

bool plate_touches(const ProbePlate& p, int64_t steps) {
  return p.below ? steps <= p.position : steps >= p.position;
}

// After STEP edges: the step counts and the endstops and the probe plate they press or release.
template <class M>
void update_endstops(M& m, SimBoard::Model& s, uint32_t sig, uint32_t prev, uint64_t cyc) {
  const uint32_t rise = sig & ~prev & 0xfu;
  if (!rise) return;
  for (int a = 0; a < models::kBoardAxes; ++a) {
    if ((rise >> a) & 1u) s.steps[static_cast<size_t>(a)] += ((prev >> (4 + a)) & 1u) ? 1 : -1;
  }
  if (s.plate) {
    const bool t = plate_touches(*s.plate, s.steps[static_cast<size_t>(s.plate->axis)]);
    if (t != s.probe_plate) {
      s.probe_plate = t;
      drive_probe(m, s, cyc + 1, true);
    }
  }
  uint8_t e = 0;
  for (size_t i = 0; i < s.endstops.size(); ++i) {
    if (s.redraw[i]) redraw_when_clear(s, i);
    const Endstop& es = s.endstops[i];
    const int64_t p = s.steps[static_cast<size_t>(es.axis)];
    const int64_t at = es.position + s.trip_offset[i];
    if (es.max_side ? p >= at : p <= at) e |= pin_bit(es.axis, es.max_side);
  }
  if (e == s.lim_endstop) return;
  const uint8_t changed = static_cast<uint8_t>(e ^ s.lim_endstop);
  s.lim_endstop = e;
  for (size_t i = 0; i < s.endstops.size(); ++i) {
    const uint8_t bit = pin_bit(s.endstops[i].axis, s.endstops[i].max_side);
    if (!(changed & bit)) continue;
    if (!(e & bit)) s.redraw[i] = 1;  // released: the next actuation trips elsewhere
    schedule_bounce(s, bit, cyc + 1);
  }
  drive_limits(m, s, cyc + 1, true);
}

[[noreturn]] void sys_fail(const std::string& what) {
  throw BoardError(fmt::format("simulated board: {}: {}", what, std::strerror(errno)));
}

// Half period in trace time units (ps): 50 MHz -> 20 ns period.
constexpr uint64_t kHalfPeriodPs = 10'000;

template <class M>
inline void clock_once(M& m, VerilatedFstC* fst, uint64_t& t) {
  m.clk = 1;
  m.eval();
  if (fst) fst->dump(t += kHalfPeriodPs);
  m.clk = 0;
  m.eval();
  if (fst) fst->dump(t += kHalfPeriodPs);
}

// The hot loop, instantiated for the untraced and the traced model. Stops after `max_cycles`,
// when the board has been quiet for kQuietCycles, or right after a tx byte was decoded (so the
// caller flushes it to the host at once).
template <class M>
uint64_t run_cycles(M& m, SimBoard::Model& s, uint64_t max_cycles, uint64_t quiet_cycles) {
  VerilatedFstC* fst = s.fst.get();
  RxLine& drv = s.driver;
  models::UartMonitor& mon = s.monitor;
  bool drv_idle = drv.idle();
  uint64_t cyc = s.cycle;
  uint64_t last_active = s.last_active;
  uint32_t prev = s.prev_sig;
  const uint32_t mask = s.sig_mask;
  const uint64_t end = cyc + max_cycles;
  bool got_byte = false;
  while (cyc < end) {
    if (s.btn_pins) [[unlikely]]
      release_buttons(m, s, cyc + 1);
    if (!s.bounces.empty() && s.bounces.front().first <= cyc + 1) [[unlikely]]
      apply_bounces(m, s, cyc + 1);
    if (!drv_idle) {
      m.rx = static_cast<uint8_t>(drv.tick(cyc + 1));
      drv_idle = drv.idle();
    }
    clock_once(m, fst, s.trace_time);
    ++cyc;
    // Heaters: the ADC pin model answers the master, the plants integrate the heater pins.
    ThermalWorld& h = s.heat;
    m.adc_sdo = static_cast<uint8_t>(h.adc.tick(m.adc_convst, m.adc_sck, m.adc_sdi));
    h.high[0] += m.heater & 1u;
    h.high[1] += (m.heater >> 1) & 1u;
    if (++h.tick_clk == ThermalWorld::kSubClks) [[unlikely]]
      h.substep();
    const uint32_t tx = m.tx;
    const uint32_t sig =
        (static_cast<uint32_t>(m.step) | (static_cast<uint32_t>(m.dir) << 4) |
         (static_cast<uint32_t>(m.laser) << 8) | (tx << 9) | (static_cast<uint32_t>(m.rx) << 10)) &
        mask;
    if (sig != prev) [[unlikely]] {
      uint32_t diff = sig ^ prev;
      while (diff) {
        const int b = __builtin_ctz(diff);
        diff &= diff - 1;
        s.rec.add(cyc, static_cast<uint8_t>(b), static_cast<uint8_t>((sig >> b) & 1u));
      }
      if (s.count_steps) update_endstops(m, s, sig, prev, cyc);
      prev = sig;
    }
    if (m.seg_done) [[unlikely]]
      s.rec.add_move_done(cyc);
    if (tx == 0 || mon.busy()) {
      if (auto byte = mon.sample(static_cast<int>(tx), cyc)) {
        s.line.to_host(byte->value, cyc, s.out);
        ++s.bytes_out;
        got_byte = true;
        s.tx_stop_end = cyc + s.stop_tail;
      }
    }
    // rx_partial: a packet or frame was cut short; the clock runs on so that the decoder's 100 ms
    // watchdog drops it (and NAKs a v2 frame with TIMEOUT) as on the real board.
    if (m.busy || m.step || m.rx_partial || !drv_idle || tx == 0 || mon.busy() ||
        cyc < s.tx_stop_end || h.active || ((s.lim_pins ^ m.limit_state) & s.lim_wired) ||
        cyc < s.btn_settle || !s.bounces.empty() ||
        (SimBoard::kProbeEnable && s.probe_pin != (m.probe_state != 0))) {
      last_active = cyc;
    } else if (got_byte || cyc - last_active > quiet_cycles) {
      break;
    }
  }
  const uint64_t n = cyc - s.cycle;
  s.cycle = cyc;
  s.last_active = last_active;
  s.prev_sig = prev;
  return n;
}

template <class M>
void reset_and_cfg(M& m, SimBoard::Model& s, const BoardOptions& o) {
  m.rst = 1;
  m.rx = 1;
  m.cfg_wr = 0;
  m.estop = 0;
  m.limit_min = 0;
  m.limit_max = 0;
  m.probe_in = 0;
  m.hold_in = 0;
  m.start_in = 0;
  m.adc_sdo = 0;
  m.clk = 0;
  m.eval();
  for (int i = 0; i < 8; ++i) clock_once(m, s.fst.get(), s.trace_time);
  m.rst = 0;
  clock_once(m, s.fst.get(), s.trace_time);
  if (o.step_timing) {
    for (int a = 0; a < models::kBoardAxes; ++a) {
      const auto& t = (*o.step_timing)[static_cast<size_t>(a)];
      const uint32_t v[4] = {t.step_high, t.step_low, t.dir_setup, t.dir_hold};
      for (int f = 0; f < 4; ++f) {
        m.cfg_wr = 1;
        m.cfg_addr = static_cast<uint8_t>(a * 4 + f);
        m.cfg_wdata = static_cast<uint16_t>(v[f]);
        clock_once(m, s.fst.get(), s.trace_time);
      }
    }
    m.cfg_wr = 0;
    // Let the shadow set become active (the core is idle).
    for (int i = 0; i < 4; ++i) clock_once(m, s.fst.get(), s.trace_time);
  }
  s.prev_sig = (static_cast<uint32_t>(m.step) | (static_cast<uint32_t>(m.dir) << 4) |
                (static_cast<uint32_t>(m.laser) << 8) | (static_cast<uint32_t>(m.tx) << 9) |
                (static_cast<uint32_t>(m.rx) << 10)) &
               s.sig_mask;
  s.cycle = 0;
  s.last_active = 0;
  s.tx_stop_end = 0;
}

template <class M>
void fill_stats(const M& m, BoardStats& st) {
  st.frame_errors = m.frame_errors;
  st.timeouts = m.timeouts;
  st.violations = m.violations;
  for (int a = 0; a < models::kBoardAxes; ++a) {
    st.position[static_cast<size_t>(a)] = static_cast<int32_t>(m.position[a]);
  }
}

}  // namespace

BoardOptions SimBoard::options_from_config(const config::MachineConfig& cfg) {
  BoardOptions o;
  o.clk_hz = static_cast<double>(cfg.clk_hz);
  o.baud = cfg.baud;
  std::array<config::StepTiming, models::kBoardAxes> t;
  t.fill(cfg.step_timing);
  o.step_timing = t;
  return o;
}

SimBoard::SimBoard(BoardOptions options) : opt_(std::move(options)) {
  if (opt_.clk_hz != 50e6) {
    throw BoardError(
        fmt::format("simulated board: clk_hz {} not supported: the Verilated cnc_core is built for "
                    "50000000 Hz",
                    opt_.clk_hz));
  }
  if (opt_.baud != 115200) {
    throw BoardError(fmt::format(
        "simulated board: baud {} not supported: the Verilated cnc_core is built for 115200 "
        "baud",
        opt_.baud));
  }
  if (opt_.step_timing) {
    for (const auto& t : *opt_.step_timing) {
      for (uint32_t v : {t.step_high, t.step_low, t.dir_setup, t.dir_hold}) {
        if (v < 1 || v > 65535) {
          throw BoardError(fmt::format(
              "simulated board: step timing value {} out of range [1, 65535] clocks", v));
        }
      }
    }
  }
  const double frame_clocks = 10.0 * opt_.clk_hz / opt_.baud;
  if (opt_.poll_interval_cycles == 0 || opt_.poll_interval_cycles > frame_clocks / 2) {
    throw BoardError(fmt::format(
        "simulated board: poll interval {} clocks must be in [1, {}] (half a UART frame)",
        opt_.poll_interval_cycles, static_cast<uint64_t>(frame_clocks / 2)));
  }
  try {
    opt_.line_faults.validate();
  } catch (const std::invalid_argument& e) {
    throw BoardError(fmt::format("simulated board: {}", e.what()));
  }
  model_ = std::make_unique<Model>(opt_.clk_hz, opt_.baud, opt_.reserve_edges, opt_.line_faults,
                                   opt_.initial_c);
  model_->sig_mask = 0x1ff;
  model_->lim_wired =
      static_cast<uint8_t>((kLimitEnable & 0xfu) | (((kLimitEnable >> 16) & 0xfu) << 4));
  for (const Endstop& e : opt_.endstops) {
    if (e.axis < 0 || e.axis >= models::kBoardAxes ||
        !((kLimitSwitches >> (e.axis + (e.max_side ? 8 : 0))) & 1u)) {
      throw BoardError(fmt::format(
          "simulated board: endstop on {}: no such limit switch (the Verilated board wires X, Y "
          "and Z min and max)",
          limit_switch_name(e.axis, e.max_side)));
    }
  }
  model_->endstops = opt_.endstops;
  if (opt_.switch_noise.jitter_steps < 0 || opt_.switch_noise.max_bounces < 1)
    throw BoardError("simulated board: switch noise: jitter_steps must be >= 0, max_bounces >= 1");
  model_->noise = opt_.switch_noise;
  model_->noise_rng.seed(opt_.switch_noise.seed);
  model_->trip_offset.assign(opt_.endstops.size(), 0);
  model_->redraw.assign(opt_.endstops.size(), 0);
  for (size_t i = 0; i < opt_.endstops.size(); ++i) draw_trip_offset(*model_, i);
  if (opt_.probe_plate) {
    if (opt_.probe_plate->axis < 0 || opt_.probe_plate->axis >= models::kBoardAxes) {
      throw BoardError(fmt::format("simulated board: probe plate on axis {}: no such axis (0..{})",
                                   opt_.probe_plate->axis, models::kBoardAxes - 1));
    }
    if (!kProbeEnable)
      throw BoardError("simulated board: probe plate: the Verilated core has no probe wired");
  }
  model_->plate = opt_.probe_plate;
  model_->count_steps = !opt_.endstops.empty() || opt_.probe_plate.has_value();
  if (opt_.record_tx) model_->sig_mask |= 1u << models::kTx;
  if (opt_.record_rx) model_->sig_mask |= 1u << models::kRx;
  if (!opt_.fst_path.empty()) {
    model_->ctx->traceEverOn(true);
    model_->core_trace = std::make_unique<Vcnc_core_trace>(model_->ctx.get(), "cnc_core");
    model_->fst = std::make_unique<VerilatedFstC>();
    model_->core_trace->trace(model_->fst.get(), 99);
    model_->fst->set_time_unit("1ps");
    model_->fst->set_time_resolution("1ps");
    model_->fst->open(opt_.fst_path.c_str());
    if (!model_->fst->isOpen()) {
      throw BoardError(fmt::format("{}: error: cannot create FST waveform", opt_.fst_path));
    }
  } else {
    model_->core = std::make_unique<Vcnc_core>(model_->ctx.get(), "cnc_core");
  }
  open_pty();
  reset_and_configure();
  // Endstops the axes already rest on (step counts 0) are pressed from the start.
  uint8_t e = 0;
  for (size_t i = 0; i < opt_.endstops.size(); ++i) {
    const Endstop& es = opt_.endstops[i];
    const int64_t at = es.position + model_->trip_offset[i];
    if (es.max_side ? at <= 0 : at >= 0) e |= pin_bit(es.axis, es.max_side);
  }
  if (e) {
    model_->lim_endstop = e;
    if (model_->core)
      drive_limits(*model_->core, *model_, 1, true);
    else
      drive_limits(*model_->core_trace, *model_, 1, true);
    model_->never_active = false;
  }
  // A plate the tool already rests on (step count 0) touches from the start.
  if (opt_.probe_plate && plate_touches(*opt_.probe_plate, 0)) {
    model_->probe_plate = true;
    if (model_->core)
      drive_probe(*model_->core, *model_, 1, true);
    else
      drive_probe(*model_->core_trace, *model_, 1, true);
    model_->never_active = false;
  }
}

SimBoard::~SimBoard() {
  stop();
  if (model_) {
    if (model_->fst) model_->fst->close();
    if (model_->core) model_->core->final();
    if (model_->core_trace) model_->core_trace->final();
  }
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
  if (wake_ >= 0) ::close(wake_);
}

Board::Board() : progress_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (progress_ < 0) sys_fail("eventfd");
}

Board::~Board() {
  ::close(progress_);
}

uint64_t Board::press_button(Button b) {
  throw BoardError(fmt::format("the {} board has no {} button; use --model rtl",
                               model() == "tlm" ? "twin" : model(),
                               b == Button::kHold ? "feed hold" : "cycle start"));
}

uint64_t Board::set_probe(bool) {
  throw BoardError(fmt::format("the {} board has no probe input; use --model rtl",
                               model() == "tlm" ? "twin" : model()));
}

void Board::notify_progress() const {
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(progress_, &one, sizeof one);
}

BoardPty open_board_pty() {
  BoardPty p;
  p.master = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (p.master < 0) sys_fail("posix_openpt");
  if (::grantpt(p.master) != 0) sys_fail("grantpt");
  if (::unlockpt(p.master) != 0) sys_fail("unlockpt");
  char name[128];
  if (::ptsname_r(p.master, name, sizeof name) != 0) sys_fail("ptsname");
  p.path = name;
  p.slave = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (p.slave < 0) sys_fail(fmt::format("open {}", p.path));
  termios t{};
  if (::tcgetattr(p.slave, &t) != 0) sys_fail("tcgetattr");
  ::cfmakeraw(&t);
  ::cfsetispeed(&t, B115200);
  ::cfsetospeed(&t, B115200);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (::tcsetattr(p.slave, TCSANOW, &t) != 0) sys_fail("tcsetattr");
  const int fl = ::fcntl(p.master, F_GETFL);
  if (fl < 0 || ::fcntl(p.master, F_SETFL, fl | O_NONBLOCK) != 0) sys_fail("fcntl O_NONBLOCK");
  p.wake = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (p.wake < 0) sys_fail("eventfd");
  return p;
}

void SimBoard::open_pty() {
  const BoardPty p = open_board_pty();
  master_ = p.master;
  slave_ = p.slave;
  wake_ = p.wake;
  path_ = p.path;
}

void SimBoard::reset_and_configure() {
  if (model_->core)
    reset_and_cfg(*model_->core, *model_, opt_);
  else
    reset_and_cfg(*model_->core_trace, *model_, opt_);
}

void SimBoard::read_pty() {
  uint8_t buf[4096];
  for (;;) {
    const ssize_t n = ::read(master_, buf, sizeof buf);
    if (n > 0) {
      model_->inbox.insert(model_->inbox.end(), buf, buf + n);
      model_->bytes_in += static_cast<uint64_t>(n);
      if (static_cast<size_t>(n) < sizeof buf) return;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    return;  // EAGAIN (nothing), EIO (no client): nothing to read
  }
}

void SimBoard::flush_out() {
  auto& out = model_->out;
  size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::write(master_, out.data() + done, out.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      model_->bytes_to_pty += static_cast<uint64_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;  // EAGAIN: the client is not reading; keep the rest for later
    }
  }
  out.erase(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(done));
}

void SimBoard::publish_locked() {
  pub_from_host_.store(model_->bytes_in, std::memory_order_release);
  pub_to_host_.store(model_->bytes_to_pty, std::memory_order_release);
  pub_cycle_.store(model_->cycle, std::memory_order_release);
}

void SimBoard::set_host_deadline(int64_t cycle) {
  host_deadline_.store(cycle);
  // Already reached (the board thread may have looked before the store): signal it here.
  if (cycle >= 0 && pub_cycle_.load() >= static_cast<uint64_t>(cycle)) notify_progress();
}

void SimBoard::notify_host(bool quiet) {
  bool signal = false;
  if (quiet && !notified_quiet_) signal = true;
  notified_quiet_ = quiet;
  std::atomic_thread_fence(std::memory_order_seq_cst);  // the cycle published before the look
  const int64_t d = host_deadline_.load();
  if (d >= 0 && d != notified_deadline_ && pub_cycle_.load() >= static_cast<uint64_t>(d)) {
    notified_deadline_ = d;
    signal = true;
  }
  if (signal) notify_progress();
}

bool SimBoard::quiet_locked() const {
  const Model& s = *model_;
  return s.driver.idle() && s.out.empty() && s.inbox.empty() &&
         (s.never_active || s.cycle - s.last_active > kQuietCycles);
}

// Bytes read from the pty start on the line: at once when bytes are already on the line (they
// follow back to back) or something else is in flight; but when only the quiet tail is
// running they wait for its end, so a host that answers an ACK quickly or slowly sees the same
// cycle numbers.
void SimBoard::admit_inbox() {
  Model& s = *model_;
  if (s.inbox.empty()) return;
  const bool tail_done = s.never_active || s.cycle - s.last_active > kQuietCycles;
  if (!s.driver.idle() || tail_done || s.last_active == s.cycle) {
    for (uint8_t b : s.inbox) {
      s.frames.clear();
      s.line.to_board(b, s.frames);
      for (const LineFrame& f : s.frames) s.driver.push(f);
    }
    s.inbox.clear();
    s.never_active = false;
  }
}

uint64_t SimBoard::run_chunk(uint64_t max_cycles) {
  if (model_->core) return run_cycles(*model_->core, *model_, max_cycles, kQuietCycles);
  return run_cycles(*model_->core_trace, *model_, max_cycles, kQuietCycles);
}

// Lock for calls from other threads: announces the wait so that step_loop() yields mu_.
class SimBoard::OtherThreadLock {
 public:
  explicit OtherThreadLock(const SimBoard& b) : b_(b) {
    b_.waiting_.fetch_add(1, std::memory_order_acq_rel);
    b_.mu_.lock();
    b_.waiting_.fetch_sub(1, std::memory_order_acq_rel);
  }
  ~OtherThreadLock() { b_.mu_.unlock(); }
  OtherThreadLock(const OtherThreadLock&) = delete;
  OtherThreadLock& operator=(const OtherThreadLock&) = delete;

 private:
  const SimBoard& b_;
};

void SimBoard::step_loop(int block_ms) {
  while (waiting_.load(std::memory_order_acquire) > 0) std::this_thread::yield();
  bool quiet;
  {
    std::lock_guard<std::mutex> l(mu_);
    if (!paused_) {
      read_pty();
      admit_inbox();
    }
    quiet = paused_ || quiet_locked();
    publish_locked();
  }
  quiet_.store(quiet);
  notify_host(quiet);
  if (quiet) {
    // Nothing in flight: block without advancing clocks until the host writes (or a wake-up).
    pollfd p[2] = {{master_, static_cast<short>(paused_ ? 0 : POLLIN), 0}, {wake_, POLLIN, 0}};
    {
      std::lock_guard<std::mutex> l(mu_);
      if (!paused_ && !model_->out.empty()) p[0].events |= POLLOUT;
    }
    const int r = ::poll(p, 2, block_ms);
    if (r > 0 && (p[1].revents & POLLIN)) {
      uint64_t v;
      [[maybe_unused]] ssize_t n = ::read(wake_, &v, sizeof v);
    }
    if (r > 0 && (p[0].revents & POLLHUP)) {
      // No client has the slave open (we keep one, so this is rare): avoid spinning.
      ::usleep(1000);
    }
    std::lock_guard<std::mutex> l(mu_);
    if (!paused_) flush_out();
    publish_locked();
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> l(mu_);
  if (paused_) return;  // paused since the check above: not one more clock
  run_chunk(opt_.poll_interval_cycles);
  flush_out();
  publish_locked();
  notify_host(false);
  sim_wall_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void SimBoard::start() {
  if (thread_.joinable()) throw BoardError("simulated board: already running");
  stop_ = false;
  if (!started_clock_) {
    t_start_ = std::chrono::steady_clock::now();
    started_clock_ = true;
  }
  thread_live_ = true;
  thread_ = std::thread([this] {
    while (!stop_.load(std::memory_order_relaxed)) step_loop(100);
  });
}

void SimBoard::stop() {
  if (!thread_.joinable()) return;
  stop_ = true;
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  thread_.join();
  thread_live_ = false;
  notify_progress();
}

void SimBoard::pause() {
  paused_ = true;
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  OtherThreadLock l(*this);  // the chunk in progress ends; none follows
  notify_progress();
}

void SimBoard::resume() {
  paused_ = false;
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
}

bool SimBoard::run_until(const std::function<bool(const SimBoard&)>& done,
                         std::chrono::milliseconds wall_timeout) {
  if (thread_.joinable()) throw BoardError("simulated board: run_until while start()ed");
  if (!started_clock_) {
    t_start_ = std::chrono::steady_clock::now();
    started_clock_ = true;
  }
  const auto deadline = std::chrono::steady_clock::now() + wall_timeout;
  for (;;) {
    if (done(*this)) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    step_loop(10);
  }
}

void SimBoard::run_cycles_until_quiet(uint64_t max_cycles) {
  if (thread_.joinable()) throw BoardError("simulated board: run while start()ed");
  std::lock_guard<std::mutex> l(mu_);
  uint64_t n = 0;
  while (n < max_cycles) {
    read_pty();
    admit_inbox();
    if (quiet_locked()) break;
    n += run_chunk(std::min<uint64_t>(opt_.poll_interval_cycles, max_cycles - n));
    flush_out();
  }
  publish_locked();
}

bool SimBoard::wait_quiet(std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    {
      OtherThreadLock l(*this);
      if (quiet_locked()) return true;
    }
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

BoardStats SimBoard::stats() const {
  OtherThreadLock l(*this);
  BoardStats st;
  const Model& s = *model_;
  st.cycles = s.cycle;
  st.wall_s =
      started_clock_
          ? std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start_).count()
          : 0.0;
  st.sim_wall_s = sim_wall_s_;
  st.clocks_per_s = sim_wall_s_ > 0 ? static_cast<double>(s.cycle) / sim_wall_s_ : 0.0;
  st.bytes_in = s.bytes_in;
  st.bytes_out = s.bytes_out;
  st.edges = s.rec.edges().size();
  st.moves_done = s.rec.move_done_cycles().size();
  st.line = s.line.stats();
  if (s.core)
    fill_stats(*s.core, st);
  else
    fill_stats(*s.core_trace, st);
  return st;
}

bool SimBoard::idle_for_host() const {
  OtherThreadLock l(*this);  // after the chunk in progress (its bytes flushed)
  return paused_.load() || !thread_live_.load() || quiet_locked();
}

std::vector<models::Edge> SimBoard::edges() const {
  OtherThreadLock l(*this);
  return model_->rec.edges();
}

std::vector<uint64_t> SimBoard::move_done_cycles() const {
  OtherThreadLock l(*this);
  return model_->rec.move_done_cycles();
}

std::vector<RxFrameRecord> SimBoard::rx_line_log() const {
  OtherThreadLock l(*this);
  return model_->line.rx_log();
}

std::vector<TxByteRecord> SimBoard::tx_line_log() const {
  OtherThreadLock l(*this);
  return model_->line.tx_log();
}

std::array<int64_t, models::kBoardAxes> SimBoard::net_steps() const {
  OtherThreadLock l(*this);
  return model_->rec.net_steps();
}

void SimBoard::write_edges_csv(const std::string& path) const {
  OtherThreadLock l(*this);
  model_->rec.write_csv(path, opt_.clk_hz);
}

std::string SimBoard::stats_line() const {
  const BoardStats s = stats();
  return fmt::format(
             "{} cycles ({:.3f} s simulated) in {:.2f} s of simulation ({:.2f} s wall): {:.2f} M "
             "clocks/s; {} bytes in, {} bytes out, {} edges, {} moves done",
             s.cycles, static_cast<double>(s.cycles) / opt_.clk_hz, s.sim_wall_s, s.wall_s,
             s.clocks_per_s / 1e6, s.bytes_in, s.bytes_out, s.edges, s.moves_done) +
         (opt_.line_faults.any() ? "; line faults: " + describe(s.line) : std::string());
}

}  // namespace fpgacnc::simboard

namespace fpgacnc::simboard {

// ---- Heaters ----

ThermalStats SimBoard::thermal() const {
  OtherThreadLock l(*this);
  const ThermalWorld& h = model_->heat;
  ThermalStats t;
  t.ticks = h.ticks;
  t.plant_c = {h.hotend.temperature(), h.bed.temperature()};
  t.sensed_c = h.sensed;
  t.last_duty = h.last_duty;
  t.adc_violations = h.adc.violations();
  t.adc_first_violation = h.adc.first_violation();
  return t;
}

double SimBoard::plant_seconds() const {
  OtherThreadLock l(*this);
  return static_cast<double>(model_->cycle) / static_cast<double>(kSampleClks);
}

void SimBoard::inject_sensor(int channel, SensorFault f) {
  OtherThreadLock l(*this);
  model_->heat.sensor.at(static_cast<size_t>(channel)) = f;
}

void SimBoard::disconnect_heater(int channel, bool disconnected) {
  OtherThreadLock l(*this);
  model_->heat.cut.at(static_cast<size_t>(channel)) = disconnected;
}

void SimBoard::set_estop(bool pressed) {
  OtherThreadLock l(*this);
  if (model_->core) model_->core->estop = pressed;
  if (model_->core_trace) model_->core_trace->estop = pressed;
}

}  // namespace fpgacnc::simboard

namespace fpgacnc::simboard {

// ---- Limit switches ----

std::string limit_switch_name(int axis, bool max_side) {
  static const char* kAxes[] = {"X", "Y", "Z", "A"};
  const std::string a = axis >= 0 && axis < 4 ? kAxes[axis] : fmt::format("axis {}", axis);
  return a + (max_side ? " max" : " min");
}

uint64_t SimBoard::set_limit(int axis, bool max_side, bool pressed) {
  if (axis < 0 || axis >= models::kBoardAxes ||
      !((kLimitSwitches >> (axis + (max_side ? 8 : 0))) & 1u)) {
    throw BoardError(fmt::format(
        "simulated board: no {} limit switch (the Verilated board wires X, Y and Z min and max)",
        limit_switch_name(axis, max_side)));
  }
  uint64_t edge;
  {
    OtherThreadLock l(*this);
    Model& s = *model_;
    const uint8_t bit = pin_bit(axis, max_side);
    s.lim_manual = static_cast<uint8_t>(pressed ? (s.lim_manual | bit) : (s.lim_manual & ~bit));
    edge = s.cycle + 1;
    if (s.core)
      drive_limits(*s.core, s, edge, false);
    else
      drive_limits(*s.core_trace, s, edge, false);
    s.never_active = false;
    s.last_active = s.cycle;  // the debounce filter runs from here (see the file comment)
  }
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  return edge;
}

int SimBoard::pull_off_endstops() {
  int released = 0;
  {
    OtherThreadLock l(*this);
    Model& s = *model_;
    for (size_t i = 0; i < s.endstops.size(); ++i) {
      const Endstop& es = s.endstops[i];
      const uint8_t bit = pin_bit(es.axis, es.max_side);
      if (!(s.lim_endstop & bit)) continue;
      const int64_t at = es.position + s.trip_offset[i];
      s.steps[static_cast<size_t>(es.axis)] = at + (es.max_side ? -1 : 1);
      s.lim_endstop = static_cast<uint8_t>(s.lim_endstop & ~bit);
      s.redraw[i] = 1;
      schedule_bounce(s, bit, s.cycle + 1);
      ++released;
    }
    if (!released) return 0;
    if (s.core)
      drive_limits(*s.core, s, s.cycle + 1, true);
    else
      drive_limits(*s.core_trace, s, s.cycle + 1, true);
    s.never_active = false;
    s.last_active = s.cycle;
  }
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  return released;
}

std::vector<LimitEvent> SimBoard::limit_events() const {
  OtherThreadLock l(*this);
  return model_->lim_events;
}

uint16_t SimBoard::limit_state() const {
  OtherThreadLock l(*this);
  const uint8_t v = model_->core ? model_->core->limit_state : model_->core_trace->limit_state;
  return static_cast<uint16_t>((v & 0xfu) | ((v >> 4) << 8));
}

}  // namespace fpgacnc::simboard

namespace fpgacnc::simboard {

// ---- Probe ----

uint64_t SimBoard::set_probe(bool contact) {
  if (!kProbeEnable) throw BoardError("simulated board: the Verilated core has no probe wired");
  uint64_t edge;
  {
    OtherThreadLock l(*this);
    Model& s = *model_;
    s.probe_manual = contact;
    edge = s.cycle + 1;
    if (s.core)
      drive_probe(*s.core, s, edge, false);
    else
      drive_probe(*s.core_trace, s, edge, false);
    s.never_active = false;
    s.last_active = s.cycle;  // the probe filter runs from here
  }
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  return edge;
}

std::vector<ProbeEvent> SimBoard::probe_events() const {
  OtherThreadLock l(*this);
  return model_->probe_events;
}

bool SimBoard::probe_state() const {
  OtherThreadLock l(*this);
  return (model_->core ? model_->core->probe_state : model_->core_trace->probe_state) != 0;
}

}  // namespace fpgacnc::simboard

namespace fpgacnc::simboard {

// ---- Machine buttons ----

const char* button_name(Button b) {
  return b == Button::kHold ? "hold" : "start";
}

uint64_t SimBoard::press_button(Button b) {
  uint64_t edge;
  {
    OtherThreadLock l(*this);
    Model& s = *model_;
    const size_t i = static_cast<size_t>(b);
    edge = s.cycle + 1;
    s.btn_pins = static_cast<uint8_t>(s.btn_pins | (1u << i));
    s.btn_release[i] = edge + kButtonPressClks;
    // The pin low reaches the synchronizer on the release edge; the filtered level falls
    // kFilterClks + 1 edges later (input_filter); a few clocks more for margin.
    s.btn_settle = std::max(s.btn_settle, s.btn_release[i] + kFilterClks + 8);
    if (s.core)
      drive_buttons(*s.core, s);
    else
      drive_buttons(*s.core_trace, s);
    s.never_active = false;
    s.last_active = s.cycle;
  }
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
  return edge;
}

BoardPins SimBoard::pins() const {
  OtherThreadLock l(*this);
  const Model& s = *model_;
  BoardPins p;
  p.cycle = s.cycle;
  p.buttons = s.btn_pins;
  p.release_edge = s.btn_release;
  p.limit_pins = static_cast<uint16_t>((s.lim_pins & 0xfu) | ((s.lim_pins >> 4) << 8));
  p.limit_wired = kLimitSwitches;
  const auto fill = [&p](const auto& m) {
    p.estop = m.estop != 0;
    p.limit_filtered = static_cast<uint16_t>((m.limit_state & 0xfu) | ((m.limit_state >> 4) << 8));
    p.faults = m.faults;
    p.probe_filtered = m.probe_state != 0;
  };
  p.probe_pin = s.probe_pin;
  if (s.core)
    fill(*s.core);
  else
    fill(*s.core_trace);
  return p;
}

}  // namespace fpgacnc::simboard
