// SimBoard: the Verilated cnc_core behind a pseudo-terminal, the embedded stand-in for the
// DE1-SoC board. Any serial client (the host's SerialLink, a terminal, pyserial) opens path()
// (/dev/pts/N) and talks to the RTL exactly as to the real board over a USB-UART:
//   - bytes written to the pty reach the core's `rx` pin as 8N1 UART bits at the baud rate
//     (models::UartDriver, fractional bit timing: 434.03 clocks per bit at 50 MHz / 115200);
//   - `tx` is sampled every clock (models::UartMonitor) and each decoded byte is written back to
//     the pty master;
//   - every STEP/DIR/LASER edge (and TX edges when asked) is recorded with its clock cycle;
//   - with an FST path the traced model (Vcnc_core_trace) writes a waveform.
//
// Time policy. Simulated time advances clock by clock while anything is in flight: rx bits
// queued or being sent, the core busy (a move prepared, queued or running), a STEP pulse high,
// tx sending, the decoder holding a started packet or frame (`rx_partial`: a cut one is then
// dropped by its 100 ms watchdog, and a v2 frame NAKed with TIMEOUT, as on the real board); it
// keeps running `kQuietCycles` clocks past the last activity. When all is quiet the board blocks in
// poll() on the pty master WITHOUT advancing clocks, so simulated time does not depend on how fast
// or slow the host is: a stop-and-wait host (v1) writes its next packet only after it has received
// the ACK, which the board flushes the moment the byte's stop bit is decoded, so every packet finds
// the board quiet and starts on the next clock; edge timestamps are reproducible run to run. While
// busy, the pty is read (non-blocking) every `poll_interval_cycles` clocks (1024 by default, well
// under one UART frame of 4340 clocks), and everything read is queued in the rx driver, so a packet
// whose bytes are already written never sees a gap on the line because of the polling. Bytes
// written while the board is busy start at the next poll boundary (or right after the bytes already
// queued); bytes that arrive while only the quiet tail (kQuietCycles after the last activity) is
// running wait for its end, so a host that answers an ACK fast or slow gets the same cycle numbers.
// The one race left is a host that writes a packet in pieces without waiting (the v1 streamer
// writes the init packet and the first move back to back): a piece that arrives while earlier bytes
// are still on the line follows them at once, one that arrives after the line went idle starts
// after the quiet tail (32 clocks later). From the first ACK on, a stop-and-wait job is
// cycle-reproducible.
//
// Threads: start() runs the board in its own thread until stop() (the destructor stops it);
// run_until() runs the same loop in the caller's thread. pause() freezes the board (no clocks,
// no bytes read or answered; the pty stays open) to model a board that stopped answering.
// Accessors (stats(), edges(), ...) are safe while the thread runs (they lock between clock
// chunks and copy).
//
// Line faults (BoardOptions::line_faults, line_faults.h; off by default): bytes read from the pty
// pass the injector when they are admitted to the line (drops, duplicates, bit flips on the rx
// pin), bytes decoded from tx pass it before they are queued for the pty (lost device frames, bit
// flips). A stall holds the rx line idle while the board keeps running: the held line counts as
// activity, so simulated time advances through it exactly as through a byte on the line.
//
// Heaters (docs/heater.md "Simulated board"). The Verilated core is built with a scaled
// thermal time base: one sample tick every kSampleClks = 102 400 clocks (2.048 ms of board time)
// instead of 50 000 000, and the heater PWM at 1024 clocks per period (HEAT_PWM_DIV 1), so one
// plant second passes every 2.048 ms of simulated time (488x faster than the board's motion time;
// at about 5 M clocks/s one plant second is about 20 ms of wall time). The plants of
// models/include/fpgacnc/models/thermal_plant.h are attached to the heater pins (duty = share of
// high clocks over the tick; bed: the reference FOPDT with its sensor one tick old; hot end: the 40
// W model) and the thermistors (100k/3950, 4.7k to 3.3 V) to the LTC2308 pin model
// (models/include/fpgacnc/models/ltc2308_model.h) on the ADC pins: channel 0 the hot end, 1 the
// bed. The plants advance once per tick. While a heater pin has been high during the last tick or a
// plant is more than 0.5 degC above ambient, the board counts as active (its clock runs without
// host traffic), so temperatures evolve as on a real board; at ambient with the heaters off it is
// quiet as before. Faults can be injected: a sensor open (the ADC reads the divider supply) or
// short (0 V), a heater disconnected (its pin no longer heats), the e-stop input.
//
// Limit switches (docs/machine.md "Simulated board"). The Verilated core is built with the X, Y
// and Z min and max switches wired (LIMIT_ENABLE = kLimitEnable, spec/protocol.toml
// sim.simboard_limit_enable; the board's default filter and polarity: a pin high is a switch
// pressed). Nothing drives them unless asked, so the board behaves as before. set_limit() presses
// or releases one from outside; BoardOptions::endstops place simulated endstops at travel ends:
// an endstop's pin is high while its axis's step count (the STEP rising edges counted at the pins)
// is at or beyond its position (pull_off_endstops() moves a carriage off by hand). A pin changed
// between clock chunks or after a STEP edge reaches the core's synchronizer on the next clock edge
// (limit_events() records that edge, "p" in docs/machine.md "Timing"). While a wired switch's pin
// differs from the core's filtered level the board counts as active (its clock runs through the
// debounce filter without host traffic).
//
// Probe (docs/machine.md "Simulated board"). The Verilated core is built with the probe input
// wired (PROBE_ENABLE = kProbeEnable, spec/protocol.toml sim.simboard_probe_enable; the default
// filter PROBE_FILTER_CLKS and polarity: a pin high is contact). set_probe() touches or lifts it
// from outside; BoardOptions::probe_plate places a plate: the pin is high while the plate's
// axis's step count (STEP rises counted at the pins, as for the endstops) is at or beyond the
// plate's position. probe_events() records each pin change with the first edge that samples it.
// While the pin differs from the core's filtered level the board counts as active.
//
// Machine buttons (docs/machine.md "Simulated board"). press_button() drives cnc_core's hold_in or
// start_in high for kButtonPressClks board clocks and then low again; the release happens inside
// the clock loop on its exact edge, and the board's clock runs through the press and the filter's
// release so that the next press is seen as a new rise.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/models/edges.h"
#include "fpgacnc/simboard/line_faults.h"
#include "fpgacnc/spec.h"

namespace fpgacnc::simboard {

// Thrown for a bad board option (clock, baud), a pty or file failure.
class BoardError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A simulated endstop: the switch (axis 0..3, min or max) is pressed while the axis's step count
// is at or below (min) / at or above (max) `position` steps.
struct Endstop {
  int axis = 0;
  bool max_side = false;
  int64_t position = 0;
};

// What makes simulated endstops imperfect (BoardOptions::switch_noise, docs/machine.md "Simulated
// board"). Trigger jitter: an endstop trips at its position plus an offset, uniform in
// -jitter_steps .. +jitter_steps and drawn again each time the switch releases (every actuation
// trips somewhere else). Bounce: each time an endstop's level changes, its pin toggles 2 * k more
// times (k uniform in 1 .. max_bounces) on random clock edges within bounce_clks of the change
// and then stays at the new level. Seeded: a run is reproducible.
struct SwitchNoise {
  uint64_t bounce_clks = 0;  // 0: no bounce
  int max_bounces = 3;
  int64_t jitter_steps = 0;  // 0: every actuation at the position
  uint64_t seed = 1;
};

// A limit pin changed: `cycle` is the first clock edge that samples the new level (the pin
// reaches the synchronizer on that edge).
struct LimitEvent {
  uint64_t cycle = 0;
  int axis = 0;
  bool max_side = false;
  bool pressed = false;
  bool endstop = false;  // by an endstop (else by set_limit)
};

// A simulated probe plate: the probe pin is high (contact) while the step count of `axis`
// (0..3) is at or below `position` (below: a plate under the tool, probed toward min) or, with
// below false, at or above it.
struct ProbePlate {
  int axis = 2;
  bool below = true;
  int64_t position = 0;
};

// The probe pin changed: `cycle` is the first clock edge that samples the new level.
struct ProbeEvent {
  uint64_t cycle = 0;
  bool contact = false;
  bool plate = false;  // by the plate (else by set_probe)
};

// "X min", "Z max": a switch's name as STATUS messages and the CLI write it.
std::string limit_switch_name(int axis, bool max_side);

// The machine buttons of cnc_core (hold_in, start_in): feed hold and cycle start (resume).
enum class Button { kHold = 0, kStart = 1 };
const char* button_name(Button b);  // "hold", "start"

// What the Verilated board's input pins carry now (SimBoard::pins()).
struct BoardPins {
  uint64_t cycle = 0;                      // clocks since reset release
  bool estop = false;                      // the e-stop pin (high = pressed)
  uint8_t buttons = 0;                     // buttons held now: bit 0 hold, bit 1 cycle start
  std::array<uint64_t, 2> release_edge{};  // a held button: the first edge sampling it released
  uint16_t limit_pins = 0;      // switch pins pressed (set_limit or an endstop), bits as STATUS
  uint16_t limit_filtered = 0;  // the core's filtered switch levels, same bits
  uint16_t limit_wired = 0;     // the switches wired (limit_switches())
  uint8_t faults = 0;           // the core's latched faults (STATUS byte 1)
  bool probe_pin = false;       // the probe pin (set_probe or the plate): contact
  bool probe_filtered = false;  // the core's filtered probe (STATUS state bit 7)
};

struct BoardOptions {
  // The Verilated model is built for 50 MHz and 115200 baud (cnc_core parameters): any other
  // value is rejected by the constructor with a BoardError.
  double clk_hz = 50e6;
  uint32_t baud = 115200;
  // Step timing per axis written through the cfg port after reset (address axis * 4 + field).
  // Unset: the RTL defaults (100/100/200/200 clocks).
  std::optional<std::array<config::StepTiming, models::kBoardAxes>> step_timing;
  std::string fst_path;    // "" = no waveform (untraced model, fastest)
  bool record_tx = false;  // also record TX pin edges
  bool record_rx = false;  // also record RX pin edges (the line as the core sees it)
  size_t reserve_edges = size_t{1} << 20;
  uint32_t poll_interval_cycles = 1024;
  LineFaults line_faults;  // serial line fault injection (default: none)
  // Heaters: plant temperatures at reset (0 hot end, 1 bed), degC; ambient is 20 degC.
  std::array<double, 2> initial_c{20.0, 20.0};
  // Simulated endstops at travel ends (see the file comment); SimBoard only.
  std::vector<Endstop> endstops;
  SwitchNoise switch_noise;  // their bounce and trigger jitter (default: none)
  // A simulated probe plate (see the file comment); SimBoard only.
  std::optional<ProbePlate> probe_plate;
};

enum class SensorFault { kNone, kOpen, kShort };

// Heater state of the simulated board (plant side).
struct ThermalStats {
  uint64_t ticks = 0;                 // sample ticks since reset (= plant seconds)
  std::array<double, 2> plant_c{};    // plant temperature (bed: the bed; hot end: the thermistor)
  std::array<double, 2> sensed_c{};   // what the thermistor reads now (bed: one tick old)
  std::array<double, 2> last_duty{};  // duty over the last tick
  uint64_t adc_violations = 0;        // LTC2308 timing rule violations by the master
  std::string adc_first_violation;
};

struct BoardStats {
  uint64_t cycles = 0;        // clocks simulated since reset release
  double wall_s = 0.0;        // wall time since start (or since the first run_until)
  double sim_wall_s = 0.0;    // wall time spent advancing clocks (not blocked while quiet)
  double clocks_per_s = 0.0;  // cycles / sim_wall_s
  uint64_t bytes_in = 0;      // read from the pty (host -> board)
  uint64_t bytes_out = 0;     // decoded from tx and written to the pty (board -> host)
  uint64_t edges = 0;
  uint64_t moves_done = 0;    // seg_done strobes
  uint16_t frame_errors = 0;  // core counters
  uint16_t timeouts = 0;
  uint16_t violations = 0;
  std::array<int64_t, models::kBoardAxes> position{};  // core's position registers
  LineFaultStats line;                                 // injected line faults (all 0 when off)
};

// The pseudo-terminal of a simulated board: the master side (non-blocking) that the board reads
// and writes, a slave descriptor of the board's own in raw mode at 115200 (8-bit clean; the
// master never sees a hang-up between clients, and FIONREAD on it tells how many answer bytes
// the client has not read yet), its path (/dev/pts/N), and an eventfd that wakes the board's
// poll() for stop or pause. Throws BoardError naming the call that failed.
struct BoardPty {
  int master = -1, slave = -1, wake = -1;
  std::string path;
};
BoardPty open_board_pty();

// A simulated board behind a pseudo-terminal, whatever model runs behind it: SimBoard (the
// Verilated cnc_core) or twins::TwinBoard (the SystemC twins, systemc/). Both serve the same
// pty protocol with the same time policy (see SimBoard above) and record the same edges.
class Board {
 public:
  Board();  // creates the progress eventfd (BoardError on failure)
  virtual ~Board();
  Board(const Board&) = delete;
  Board& operator=(const Board&) = delete;
  virtual const std::string& path() const = 0;  // slave side of the pty (/dev/pts/N)
  virtual void start() = 0;                     // own thread; throws BoardError if running
  virtual void stop() = 0;                      // joins the thread; the pty stays open
  virtual uint64_t cycle() const = 0;           // clocks since reset release
  virtual double clk_hz() const = 0;
  virtual BoardStats stats() const = 0;
  virtual std::vector<models::Edge> edges() const = 0;  // sorted by (cycle, signal)
  virtual std::array<int64_t, models::kBoardAxes> net_steps() const = 0;
  virtual void set_estop(bool pressed) = 0;  // throws BoardError when the model has no e-stop
  // Presses (or releases) the limit switch of `axis` (0..3) on its min or max side; returns the
  // first clock edge that samples the new pin level. Throws BoardError when the model has no
  // limit switches or that switch is not wired (limit_switches()).
  virtual uint64_t set_limit(int axis, bool max_side, bool pressed) = 0;
  // The switches wired, bits as STATUS's switch u16: bit a the min switch of axis a, bit 8 + a
  // its max switch (0: none).
  virtual uint16_t limit_switches() const = 0;
  // Presses a machine button: its pin is asserted for a fixed number of board clocks (SimBoard:
  // kButtonPressClks, well above the input filter) and then released, both timed in board
  // clocks, so the core sees one press whatever the host's speed. Returns the first clock edge
  // that samples the pin pressed. The default (a model without the buttons, the twin board)
  // throws BoardError.
  virtual uint64_t press_button(Button b);
  // Touches (true) or lifts (false) the probe: its pin from the next clock edge, returned. The
  // default (a model without the probe input, the twin board) throws BoardError.
  virtual uint64_t set_probe(bool contact);
  // Nothing in flight and every answer byte already written to the pty: nothing more comes
  // until the host writes (bytes the host wrote that the board has not read yet count as
  // written only once stats().bytes_in counts them).
  virtual bool idle_for_host() const = 0;
  // Blocks until the board is quiet (idle for the host) or `timeout` passes.
  virtual bool wait_quiet(std::chrono::milliseconds timeout) const = 0;
  // Bytes taken from the pty (host -> board) and written to it (board -> host) since the board
  // was made. A host-side link compares them with its own counts: the board is idle for that
  // host only once it has taken every byte the host wrote and the host has read every answer.
  virtual uint64_t bytes_from_host() const = 0;
  virtual uint64_t bytes_to_host() const = 0;
  // Not serving the pty (stopped, or paused): nothing comes at all, whatever the host writes.
  virtual bool frozen() const = 0;
  virtual std::string model() const = 0;  // "rtl" (Verilated cnc_core) or "tlm" (twins)
  // The clock at which the host's next timer fires (a poll, a retransmission, a timeout), set
  // by the host's link before it waits. A board that jumps from event to event stops there and
  // gives the host its grace to act, as a board that runs clock by clock does; -1: none.
  virtual void set_host_deadline(int64_t cycle) = 0;
  // An eventfd (non-blocking) the board signals whenever a wait of the host's may have ended:
  // its clock reached the host's deadline (set_host_deadline), it went quiet (idle_for_host()
  // may have turned true), it froze (paused, stopped). Answer bytes wake the host through the
  // pty itself. A host link polls it together with the pty and clears it (read) before it looks
  // at the board, so that no signal is lost between its look and its next poll.
  int progress_fd() const { return progress_; }

 protected:
  void notify_progress() const;

 private:
  int progress_ = -1;
};

class SimBoard : public Board {
 public:
  // Clock cycles of inactivity after which the board counts as quiet.
  static constexpr uint64_t kQuietCycles = 32;
  // Heater sample tick of the Verilated core (cnc_core SAMPLE_CLKS, see the file comment).
  static constexpr uint64_t kSampleClks = spec::kSimboardSampleClks;
  // cnc_core LIMIT_ENABLE of the Verilated core (bit a min, bit 16 + a max) and the same
  // switches as STATUS numbers them (bit a min, bit 8 + a max).
  static constexpr uint32_t kLimitEnable = static_cast<uint32_t>(spec::kSimboardLimitEnable);
  static constexpr uint16_t kLimitSwitches =
      static_cast<uint16_t>((kLimitEnable & 0xffu) | (((kLimitEnable >> 16) & 0xffu) << 8));
  // cnc_core PROBE_ENABLE of the Verilated core and its probe filter (the default
  // PROBE_FILTER_CLKS): a pin first sampled on edge p is the filtered level from edge p + 1 +
  // kProbeFilterClks.
  static constexpr bool kProbeEnable = spec::kSimboardProbeEnable != 0;
  static constexpr uint64_t kProbeFilterClks = spec::kDefaultProbeFilterClks;

  // Creates the pty and the model, resets the core and writes the step timing. Throws
  // BoardError.
  explicit SimBoard(BoardOptions options = {});
  // Convenience: clock, baud and step timing (all axes) from a machine configuration.
  static BoardOptions options_from_config(const config::MachineConfig& cfg);
  ~SimBoard() override;
  SimBoard(const SimBoard&) = delete;
  SimBoard& operator=(const SimBoard&) = delete;

  // Slave side of the pseudo-terminal, e.g. /dev/pts/7 (raw mode).
  const std::string& path() const override { return path_; }
  const BoardOptions& options() const { return opt_; }

  void start() override;  // own thread; throws if already running
  void stop() override;   // joins the thread (the pty stays open until destruction)
  bool running() const { return thread_.joinable(); }
  // Freeze: no clocks, no bytes read or answered; on return the chunk of clocks in progress has
  // ended and no other runs until resume().
  void pause();
  void resume();
  bool paused() const { return paused_.load(); }

  // Runs the board in the caller's thread until `done(*this)` is true (checked between clock
  // chunks and while blocked, at least every 10 ms) or `wall_timeout` passes. Returns whether
  // `done` became true. Not while start()ed.
  bool run_until(const std::function<bool(const SimBoard&)>& done,
                 std::chrono::milliseconds wall_timeout);
  // Runs until quiet (nothing in flight) in the caller's thread, at most `max_cycles`.
  void run_cycles_until_quiet(uint64_t max_cycles);
  // Blocks until the board thread is quiet (nothing in flight, all output flushed) or timeout.
  bool wait_quiet(std::chrono::milliseconds timeout) const override;
  double clk_hz() const override { return opt_.clk_hz; }
  std::string model() const override { return "rtl"; }

  BoardStats stats() const override;
  // Clocks simulated since reset release, as of the end of the last chunk of clocks; every byte
  // decoded from tx up to that cycle has been written to the pty (or is held because the pty is
  // full). Lock-free.
  uint64_t cycle() const override { return pub_cycle_.load(std::memory_order_acquire); }
  // True when nothing more can reach the host until it writes again: the board is quiet
  // (nothing in flight: see the time policy above) and every byte decoded from tx has been
  // written to the pty; or the board is frozen (paused, or not running its thread), so that
  // nothing can come at all. Bytes the host wrote to the pty that the board has not read yet
  // are not seen here: compare bytes_from_host() with what the host wrote.
  bool idle_for_host() const override;
  // Bytes read from the pty (host -> board, before line faults) and written to it
  // (board -> host, after line faults) since construction. Lock-free; bytes_from_host() counts
  // a byte only once the board has taken it into its line queue (idle_for_host() sees it).
  uint64_t bytes_from_host() const override {
    return pub_from_host_.load(std::memory_order_acquire);
  }
  uint64_t bytes_to_host() const override { return pub_to_host_.load(std::memory_order_acquire); }
  bool frozen() const override { return paused() || !running(); }
  // The Verilated board runs clock by clock and does not stop at the host's deadline; it
  // signals progress_fd() at the end of the chunk of clocks that reaches it.
  void set_host_deadline(int64_t cycle) override;
  std::vector<models::Edge> edges() const override;  // copy
  std::vector<uint64_t> move_done_cycles() const;    // copy
  // Line logs (copies; empty unless line_faults.log): every frame put on the rx line, every
  // byte decoded from tx with what was delivered.
  std::vector<RxFrameRecord> rx_line_log() const;
  std::vector<TxByteRecord> tx_line_log() const;
  std::array<int64_t, models::kBoardAxes> net_steps() const override;
  void write_edges_csv(const std::string& path) const;
  // One-line summary of stats() for reports.
  std::string stats_line() const;

  // ---- Heaters ----
  ThermalStats thermal() const;
  // Plant seconds since reset (sample ticks, fractional).
  double plant_seconds() const;
  void inject_sensor(int channel, SensorFault f);
  void disconnect_heater(int channel, bool disconnected);
  void set_estop(bool pressed) override;

  // ---- Limit switches ----
  uint64_t set_limit(int axis, bool max_side, bool pressed) override;
  uint16_t limit_switches() const override { return kLimitSwitches; }
  std::vector<LimitEvent> limit_events() const;  // copy, in order
  // The operator pulls every carriage that stands on one of its endstops back by hand to one
  // step inside it (the counted carriage position moves, the core's position registers do not:
  // they are not trusted after a trip anyway), so the endstop releases. Returns how many
  // endstops were released.
  int pull_off_endstops();
  // The core's filtered switch levels now (bits as limit_switches()).
  uint16_t limit_state() const;

  // ---- Probe ----
  uint64_t set_probe(bool contact) override;
  std::vector<ProbeEvent> probe_events() const;  // copy, in order
  bool probe_state() const;                      // the core's filtered probe: contact

  // ---- Machine buttons ----
  // The core's input filter (cnc_core LIMIT_FILTER_CLKS, the board's default: buttons and switches
  // alike) and the length of a press: four filter lengths (4 ms of board time), so the filtered
  // level rises about 1 ms after the press starts and falls about 1 ms after its release.
  static constexpr uint64_t kFilterClks = spec::kDefaultLimitFilterClks;
  static constexpr uint64_t kButtonPressClks = 4 * kFilterClks;
  // Asserts the button's pin from the next clock edge for kButtonPressClks edges; the board's
  // clock runs (without host traffic) until the filter has seen the release. A press while the
  // same button is held lengthens the press (no second rise).
  uint64_t press_button(Button b) override;
  BoardPins pins() const;

  // Implementation detail (model, UART driver/monitor, recorder), defined in sim_board.cpp.
  struct Model;

 private:
  void open_pty();
  void reset_and_configure();
  // One pass of the loop: returns after a chunk of clocks or a blocking wait.
  void step_loop(int block_ms);
  uint64_t run_chunk(uint64_t max_cycles);
  void read_pty();
  void admit_inbox();
  void flush_out();
  bool quiet_locked() const;
  void publish_locked();  // cycle and byte counts for the lock-free accessors

  BoardOptions opt_;
  std::string path_;
  int master_ = -1;
  int slave_ = -1;
  int wake_ = -1;  // eventfd: wakes poll() for stop/pause
  std::unique_ptr<Model> model_;

  mutable std::mutex mu_;  // guards the model state and the recorder between chunks
  // Callers from other threads (the host side, tests) waiting for mu_: the board thread lets
  // them in between chunks (std::mutex is not fair; without this a reader could wait seconds
  // while the board thread re-locks chunk after chunk).
  mutable std::atomic<int> waiting_{0};
  class OtherThreadLock;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> paused_{false};
  std::atomic<bool> quiet_{true};
  std::atomic<bool> thread_live_{false};  // start() .. stop() joined
  std::atomic<uint64_t> pub_cycle_{0};
  std::atomic<uint64_t> pub_from_host_{0};
  std::atomic<uint64_t> pub_to_host_{0};
  std::atomic<int64_t> host_deadline_{-1};
  int64_t notified_deadline_ = -1;  // board thread: the deadline last signalled
  bool notified_quiet_ = false;     // board thread: quiet signalled since the last activity
  void notify_host(bool quiet);     // board thread, after publish_locked()
  std::chrono::steady_clock::time_point t_start_{};
  bool started_clock_ = false;
  double sim_wall_s_ = 0.0;
};

}  // namespace fpgacnc::simboard
