#include "fpgacnc/twins/twin_board.h"

#include <fmt/format.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <limits>
#include <thread>

#include "fpgacnc/twins/input_filter.h"
#include "fpgacnc/twins/virtual_board.h"

namespace fpgacnc::twins {
namespace {

using simboard::BoardError;
using wall_clock = std::chrono::steady_clock;

// The process's SystemC kernel: elaborated once (one VirtualBoard), in a thread of its own; runs
// the queued sessions one after the other until the process exits.
class Kernel {
 public:
  static Kernel& get() {
    static Kernel k;
    return k;
  }
  void submit(const CoreParams& p, std::function<void(VirtualBoard&)> fn) {
    std::lock_guard<std::mutex> l(mu_);
    if (!started_) {
      p_ = p;
      started_ = true;
      th_ = std::thread([this] { run(); });
    } else if (p.clk_hz != p_.clk_hz || p.baud != p_.baud || p.watchdog_clks != p_.watchdog_clks) {
      throw BoardError(fmt::format(
          "twin board: clock {} Hz / {} baud differ from the first twin board's ({} Hz / {} "
          "baud): SystemC elaborates once per process",
          p.clk_hz, p.baud, p_.clk_hz, p_.baud));
    }
    q_.push_back(std::move(fn));
    cv_.notify_all();
  }
  ~Kernel() {
    {
      std::lock_guard<std::mutex> l(mu_);
      exit_ = true;
      cv_.notify_all();
    }
    if (th_.joinable()) th_.join();
  }

 private:
  void run() {
    VirtualBoard vb("twin_board", p_, true);
    vb.live = [this](VirtualBoard& b) {
      for (;;) {
        std::function<void(VirtualBoard&)> fn;
        {
          std::unique_lock<std::mutex> l(mu_);
          cv_.wait(l, [this] { return exit_ || !q_.empty(); });
          if (q_.empty()) return;
          fn = std::move(q_.front());
          q_.pop_front();
        }
        fn(b);
      }
    };
    sc_core::sc_start();
  }
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::function<void(VirtualBoard&)>> q_;
  bool started_ = false, exit_ = false;
  CoreParams p_;
  std::thread th_;
};

std::array<AxisTiming, kAxes> axis_timing(const TwinBoardOptions& o) {
  std::array<AxisTiming, kAxes> t{};
  if (o.step_timing) {
    for (int a = 0; a < kAxes; ++a) {
      const auto& s = (*o.step_timing)[static_cast<size_t>(a)];
      t[static_cast<size_t>(a)] = AxisTiming{s.step_high, s.step_low, s.dir_setup, s.dir_hold};
    }
  }
  return t;
}

CoreParams core_params(const TwinBoardOptions& o) {
  CoreParams p;
  p.clk_hz = o.clk_hz;
  p.baud = o.baud;
  p.watchdog_clks = o.clk_hz / 10;  // cnc_core WATCHDOG_CLKS: 100 ms
  p.timing = axis_timing(o);
  return p;
}

}  // namespace

TwinBoardOptions TwinBoard::options_from_config(const config::MachineConfig& cfg) {
  TwinBoardOptions o;
  o.clk_hz = cfg.clk_hz;
  o.baud = cfg.baud;
  std::array<config::StepTiming, models::kBoardAxes> t;
  t.fill(cfg.step_timing);
  o.step_timing = t;
  return o;
}

TwinBoard::TwinBoard(TwinBoardOptions options) : opt_(std::move(options)) {
  if (opt_.clk_hz == 0 || 1'000'000'000'000ull % opt_.clk_hz != 0) {
    throw BoardError(fmt::format(
        "twin board: clk_hz {} not supported: the clock period must be a whole number of ps",
        opt_.clk_hz));
  }
  if (opt_.baud == 0 || opt_.baud * 4 > opt_.clk_hz) {
    throw BoardError(
        fmt::format("twin board: baud {} not supported at {} Hz", opt_.baud, opt_.clk_hz));
  }
  if (opt_.step_timing) {
    for (const auto& t : *opt_.step_timing) {
      for (uint32_t v : {t.step_high, t.step_low, t.dir_setup, t.dir_hold}) {
        if (v < 1 || v > 65535) {
          throw BoardError(
              fmt::format("twin board: step timing value {} out of range [1, 65535] clocks", v));
        }
      }
    }
  }
  open_pty();
}

TwinBoard::~TwinBoard() {
  stop();
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
  if (wake_ >= 0) ::close(wake_);
}

void TwinBoard::open_pty() {
  const simboard::BoardPty p = simboard::open_board_pty();
  master_ = p.master;
  slave_ = p.slave;
  wake_ = p.wake;
  path_ = p.path;
}

void TwinBoard::wake() const {
  const uint64_t one = 1;
  [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
}

void TwinBoard::start() {
  std::lock_guard<std::mutex> l(mu_);
  if (running_) throw BoardError("twin board: already running");
  if (!session_done_.load()) throw BoardError("twin board: the previous session has not ended");
  running_ = true;
  stop_ = false;
  session_done_ = false;
  quiet_ = false;
  st_ = simboard::BoardStats{};
  replays_ = 0;
  press_req_.clear();
  press_asked_ = press_taken_ = 0;
  edges_.clear();
  error_.clear();
  t_start_ = wall_clock::now();
  Kernel::get().submit(core_params(opt_), [this](VirtualBoard& vb) {
    try {
      session(vb);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> g(mu_);
      error_ = fmt::format("twin board: session ended by an error: {}", e.what());
    }
    quiet_ = true;
    {
      std::lock_guard<std::mutex> g(mu_);
      session_done_ = true;
    }
    press_cv_.notify_all();
  });
}

void TwinBoard::stop() {
  {
    std::lock_guard<std::mutex> l(mu_);
    if (!running_) return;
    running_ = false;
  }
  stop_ = true;
  wake();
  while (!session_done_.load()) std::this_thread::sleep_for(std::chrono::microseconds(200));
  notify_progress();
}

uint64_t TwinBoard::cycle() const {
  std::lock_guard<std::mutex> l(mu_);
  return st_.cycles;
}

simboard::BoardStats TwinBoard::stats() const {
  std::lock_guard<std::mutex> l(mu_);
  simboard::BoardStats s = st_;
  s.wall_s = running_ || s.cycles
                 ? std::chrono::duration<double>(wall_clock::now() - t_start_).count()
                 : 0.0;
  if (!running_) s.wall_s = st_.wall_s;
  return s;
}

std::vector<models::Edge> TwinBoard::edges() const {
  std::vector<models::Edge> e;
  uint64_t now;
  {
    std::lock_guard<std::mutex> l(mu_);
    e = edges_;
    now = st_.cycles;
  }
  sort_edges(e);
  // Edges of moves already accepted lie ahead of the board's time: report those up to now.
  while (!e.empty() && e.back().cycle > now) e.pop_back();
  return e;
}

std::array<int64_t, models::kBoardAxes> TwinBoard::net_steps() const {
  return models::net_steps(edges());
}

uint64_t TwinBoard::press_button(simboard::Button b) {
  std::unique_lock<std::mutex> l(mu_);
  if (!running_ || session_done_.load())
    throw BoardError("twin board: press_button while no session runs");
  press_req_.push_back(static_cast<int>(b));
  const uint64_t mine = ++press_asked_;
  l.unlock();
  wake();
  l.lock();
  press_cv_.wait(l, [&] { return press_taken_ >= mine || session_done_.load(); });
  if (press_taken_ < mine) throw BoardError("twin board: the session ended before the press");
  return press_edge_;
}

void TwinBoard::set_estop(bool) {
  throw BoardError("twin board (--model tlm): no e-stop input is modelled; use --model rtl");
}

uint64_t TwinBoard::set_limit(int, bool, bool) {
  throw BoardError("the twin board has no limit switches; use --model rtl");
}

void TwinBoard::set_host_deadline(int64_t cycle) {
  host_deadline_.store(cycle);
  if (cycle >= 0) {
    const uint64_t one = 1;
    [[maybe_unused]] ssize_t n = ::write(wake_, &one, sizeof one);
    // Already reached (the board may have looked before the store): signal it here.
    if (static_cast<int64_t>(this->cycle()) >= cycle) notify_progress();
  }
}

bool TwinBoard::idle_for_host() const {
  if (!quiet_.load()) return false;
  // Bytes the host wrote that the board has not read yet: not idle.
  pollfd p{master_, POLLIN, 0};
  return ::poll(&p, 1, 0) == 0;
}

uint64_t TwinBoard::bytes_from_host() const {
  std::lock_guard<std::mutex> l(mu_);
  return st_.bytes_in;
}

uint64_t TwinBoard::bytes_to_host() const {
  std::lock_guard<std::mutex> l(mu_);
  return st_.bytes_out;
}

bool TwinBoard::frozen() const {
  std::lock_guard<std::mutex> l(mu_);
  return !running_ || session_done_.load();
}

bool TwinBoard::wait_quiet(std::chrono::milliseconds timeout) const {
  const auto deadline = wall_clock::now() + timeout;
  for (;;) {
    if (idle_for_host() || session_done_.load()) return true;
    if (wall_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

std::string TwinBoard::error() const {
  std::lock_guard<std::mutex> l(mu_);
  return error_;
}

// The board's loop (docs in twin_board.h), in the SystemC thread.
void TwinBoard::session(VirtualBoard& vb) {
  const auto t0 = wall_clock::now();
  // Cycle 0 of this session: the next whole clock of SystemC time.
  const uint64_t per = vb.clk_.period_ps();
  const uint64_t now_ps = sc_core::sc_time_stamp().value();
  vb.clk_.set_base(sc_core::sc_time::from_value((now_ps + per - 1) / per * per));
  // MOTION frames: a frame not known up front makes the session run again from its reset with
  // the requests known (replay below, docs/systemc.md "The twin board")
  vb.known_motion_.clear();
  vb.known_flush_.clear();
  vb.dec_.accept_motion = true;
  vb.reset(axis_timing(opt_));
  vb.pins_.record_tx = true;
  vb.host_ = nullptr;

  const double cpb = static_cast<double>(opt_.clk_hz) / opt_.baud;
  const SenderTiming sender{opt_.clk_hz, opt_.baud};
  const Cycle frame = sender.frame();
  // SimBoard's UART monitor decodes a byte on the first clock >= 9.5 bits after its start edge,
  // and counts tx as active until the end of that stop bit (ceil(bit / 2) + 1 clocks later).
  const auto dec_off = static_cast<Cycle>(std::ceil(9.5 * cpb));
  const Cycle stop_tail = static_cast<Cycle>(std::ceil(cpb / 2.0)) + 1;
  constexpr Cycle kQuiet = static_cast<Cycle>(simboard::SimBoard::kQuietCycles);
  constexpr Cycle kNone = std::numeric_limits<Cycle>::max();
  const auto grace = std::chrono::duration_cast<wall_clock::duration>(opt_.host_grace);

  Cycle now = 0;
  bool never_active = true;
  Cycle act = 0;        // last clock with something in flight
  Cycle line_next = 0;  // host bytes on the line: the next frame starts here (back to back)
  std::deque<std::pair<Cycle, uint8_t>> pending;  // decided tx bytes (start edge, byte)
  std::vector<uint8_t> out;                       // decoded, not yet written to the pty
  Cycle hold_at = -1;                             // clock of the answer hold
  wall_clock::time_point last_write{};
  bool had_write = false;
  uint64_t bytes_in = 0, bytes_out = 0;
  Cycle c_ref = 0;  // realtime: clock c_ref at wall time t_ref
  wall_clock::time_point t_ref = t0;
  double waited_s = 0.0;
  std::vector<uint8_t> in;
  std::vector<models::Edge> batch_out;
  // For a replay: every host byte given to the twins (start edge, byte), every tx byte taken
  // from them, and the activity of each.
  std::vector<std::pair<Cycle, uint8_t>> rx_log, tx_log;
  Cycle act_host = 0, act_tx = 0, act_buttons = 0;
  std::vector<ButtonPress> presses;  // the buttons pressed so far
  constexpr Cycle kPress = static_cast<Cycle>(simboard::SimBoard::kButtonPressClks);
  constexpr Cycle kFilter = static_cast<Cycle>(simboard::SimBoard::kFilterClks);
  // The presses' requests to the rate (after a reset: the twins know them up front).
  auto press_requests = [&] {
    for (Cycle t : button_requests(presses, 0, vb.p_.button_filter_clks)) vb.rate_.hold_input(t);
    for (Cycle t : button_requests(presses, 1, vb.p_.button_filter_clks)) vb.rate_.start_input(t);
  };

  auto read_input = [&] {
    uint8_t buf[4096];
    for (;;) {
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n > 0) {
        quiet_.store(false);  // before the bytes count in stats(): idle_for_host() stays exact
        in.insert(in.end(), buf, buf + n);
        last_write = wall_clock::now();
        had_write = true;
        if (static_cast<size_t>(n) < sizeof buf) return;
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      return;
    }
  };
  auto flush_out = [&] {
    size_t done = 0;
    while (done < out.size()) {
      const ssize_t n = ::write(master_, out.data() + done, out.size() - done);
      if (n > 0) {
        done += static_cast<size_t>(n);
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else {
        break;  // the client is not reading: keep the rest
      }
    }
    out.erase(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(done));
  };
  // Waits (wall) for host input, a wake-up or `until`; true when input is readable.
  auto wait_input = [&](wall_clock::time_point until) {
    const auto w0 = wall_clock::now();
    pollfd p[2] = {{master_, POLLIN, 0}, {wake_, POLLIN, 0}};
    if (!out.empty()) p[0].events |= POLLOUT;
    const auto left = until > w0 ? until - w0 : wall_clock::duration::zero();
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
    timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
    const int r = ::ppoll(p, 2, &ts, nullptr);
    if (r > 0 && (p[1].revents & POLLIN)) {
      uint64_t v;
      [[maybe_unused]] ssize_t n = ::read(wake_, &v, sizeof v);
    }
    if (!out.empty()) flush_out();
    waited_s += std::chrono::duration<double>(wall_clock::now() - w0).count();
    return r > 0 && (p[0].revents & POLLIN);
  };
  // Host bytes read while the board is at `now` (time policy in twin_board.h).
  auto admit = [&] {
    if (in.empty()) return;
    Cycle start;
    if (line_next > now + 1) {
      start = line_next;
    } else if (!never_active && now > act && now <= act + kQuiet) {
      now = act + kQuiet + 1;  // the quiet tail runs out first
      start = now + 1;
    } else {
      start = now + 1;
    }
    if (opt_.realtime && never_active) {
      c_ref = now;
      t_ref = wall_clock::now();
    }
    for (uint8_t b : in) {
      RxFrame f{b};
      transport(vb.host_pin_, vb.gp_, vb.clk_, f, start);
      rx_log.emplace_back(start, b);
      start += frame;
    }
    bytes_in += in.size();
    in.clear();
    line_next = start;
    act_host = start - 2;  // the last frame's stop bit ends on start - 1
    act = std::max(act, act_host);
    never_active = false;
  };
  Cycle notified_deadline = -1;
  bool notified_quiet = false;
  auto publish = [&](bool quiet) {
    // The host's waits end on these (Board::progress_fd): quiet, or its deadline reached.
    struct Notify {
      const TwinBoard& b;
      bool signal = false;
      ~Notify() {
        if (signal) b.notify_progress();
      }
    } notify{*this};
    const bool now_quiet = quiet && out.empty();
    if (now_quiet && !notified_quiet) notify.signal = true;
    notified_quiet = now_quiet;
    const Cycle d = host_deadline_.load();
    if (d >= 0 && d != notified_deadline && now >= d) {
      notified_deadline = d;
      notify.signal = true;
    }
    std::lock_guard<std::mutex> l(mu_);
    st_.cycles = static_cast<uint64_t>(now);
    st_.bytes_in = bytes_in;
    st_.bytes_out = bytes_out;
    if (!batch_out.empty()) {
      edges_.insert(edges_.end(), batch_out.begin(), batch_out.end());
      batch_out.clear();
    }
    st_.edges = edges_.size();
    st_.moves_done = vb.enc_.moves_done;
    st_.frame_errors = static_cast<uint16_t>(vb.rx_.frame_errors);
    st_.timeouts = vb.dec_.current().timeouts;
    for (int a = 0; a < kAxes; ++a)
      st_.position[static_cast<size_t>(a)] =
          static_cast<int32_t>(vb.pulse_[static_cast<size_t>(a)]->position_after(now));
    const double wall = std::chrono::duration<double>(wall_clock::now() - t0).count();
    st_.wall_s = wall;
    st_.sim_wall_s = std::max(0.0, wall - waited_s);
    st_.clocks_per_s = st_.sim_wall_s > 0 ? static_cast<double>(now) / st_.sim_wall_s : 0.0;
    quiet_.store(quiet && out.empty());
  };

  // Pin activity (act) of an edge.
  auto pin_act = [&](const models::Edge& e) {
    if (e.signal < models::kDir0) {
      act = std::max(act, static_cast<Cycle>(e.cycle) - (e.value ? 0 : 1));
      never_active = false;
    }
  };
  // A MOTION frame the twins did not know (VirtualBoard::on_motion): run again from the reset
  // with every host byte at its clock and the requests of every MOTION frame so far known up
  // front, up to `now`. What was released is the same again (checked): the answers decided (tx
  // bytes taken) and the edges up to the published cycle; the edges after it are replaced.
  auto replay = [&](bool force) {
    for (int runs = 0;; ++runs) {
      if (!vb.settle_motion()) force = true;
      if (!force) break;
      force = false;
      if (runs > 64) throw std::logic_error("twin board: the MOTION requests do not settle");
      vb.reset(axis_timing(opt_));
      press_requests();
      vb.pins_.record_tx = true;
      for (const auto& [c, b] : rx_log) {
        RxFrame f{b};
        transport(vb.host_pin_, vb.gp_, vb.clk_, f, c);
      }
      vb.dec_.advance(now + 1);
      while (vb.enc_.step(now + 1)) {
      }
    }
    ++replays_;
    if (vb.tx_bytes_.size() < tx_log.size() ||
        !std::equal(tx_log.begin(), tx_log.end(), vb.tx_bytes_.begin()))
      throw std::logic_error("twin board: the answers before a MOTION frame changed in its replay");
    vb.tx_bytes_.erase(vb.tx_bytes_.begin(),
                       vb.tx_bytes_.begin() + static_cast<std::ptrdiff_t>(tx_log.size()));
    std::vector<models::Edge> all = vb.pins_.take_sorted();
    {
      std::lock_guard<std::mutex> l(mu_);
      std::vector<models::Edge> old = edges_;
      old.insert(old.end(), batch_out.begin(), batch_out.end());
      sort_edges(old);
      const auto released = [&](const std::vector<models::Edge>& v) {
        return std::upper_bound(v.begin(), v.end(), st_.cycles,
                                [](uint64_t c, const models::Edge& e) { return c < e.cycle; }) -
               v.begin();
      };
      std::vector<models::Edge> mine;
      for (const models::Edge& e : all)
        if (e.signal != models::kTx || opt_.record_tx) mine.push_back(e);
      sort_edges(mine);
      const auto n = released(old);
      if (released(mine) != n || !std::equal(old.begin(), old.begin() + n, mine.begin(),
                                             [](const models::Edge& a, const models::Edge& b) {
                                               return a.cycle == b.cycle && a.signal == b.signal &&
                                                      a.value == b.value;
                                             }))
        throw std::logic_error("twin board: the edges before a MOTION frame changed in its replay");
      edges_ = std::move(mine);
      batch_out.clear();
    }
    // The activity again: the host's bytes and the answers as before, the pins and the entries
    // as they are now (a hold delays them, a resume brings them forward).
    act = std::max({act_host, act_tx, act_buttons});
    for (const models::Edge& e : all) pin_act(e);
    if (!vb.entry_ends_.empty()) act = std::max(act, vb.entry_ends_.back() - 1);
  };

  // Buttons pressed by the host: pressed from the next edge (SimBoard::press_button).
  auto take_presses = [&] {
    std::vector<int> req;
    {
      std::lock_guard<std::mutex> l(mu_);
      req.swap(press_req_);
      if (!req.empty()) {
        press_taken_ += req.size();
        press_edge_ = static_cast<uint64_t>(now + 1);
      }
    }
    if (req.empty()) return false;
    press_cv_.notify_all();
    for (int b : req) {
      presses.push_back(ButtonPress{b, now + 1, kPress});
      act_buttons = std::max(act_buttons, now + 1 + kPress + kFilter + 8 - 1);
    }
    act = std::max(act, act_buttons);
    never_active = false;
    return true;
  };

  // Held at the host's timer until the host writes, presses a button or waits for a later clock
  // (at most 5 s of wall time: a host that went away does not stop the board). A press keeps the
  // timer (the board takes it at this clock and holds here again).
  auto hold_at_timer = [&](Cycle host_at) {
    publish(false);
    const auto give_up = wall_clock::now() + std::chrono::seconds(5);
    bool input = false, press = false;
    auto press_pending = [&] {
      std::lock_guard<std::mutex> l(mu_);
      return !press_req_.empty();
    };
    while (!input && host_deadline_.load() == host_at && wall_clock::now() < give_up &&
           !stop_.load() && !(press = press_pending()))
      input = wait_input(std::min(give_up, wall_clock::now() + std::chrono::milliseconds(10)));
    if (host_deadline_.load() == host_at && !press) host_deadline_.store(-1);
  };

  while (!stop_.load(std::memory_order_relaxed)) {
    read_input();
    const bool pressed = take_presses();
    admit();
    // Answers that start by `now` are final: no host byte can start before now + 1.
    vb.dec_.advance(now + 1);
    while (vb.enc_.step(now + 1)) {
    }
    if (vb.motion_mismatch_ || pressed) replay(pressed);
    if (pressed && !opt_.realtime && host_deadline_.load() == now) {
      hold_at_timer(now);  // pressed at the host's timer: held there again
      continue;
    }
    for (const auto& b : vb.tx_bytes_) {
      pending.push_back(b);
      tx_log.push_back(b);
      act_tx = std::max(act_tx, b.first + dec_off + stop_tail - 1);
      act = std::max(act, act_tx);
      never_active = false;
      hold_at = -1;
    }
    vb.tx_bytes_.clear();
    for (const models::Edge& e : vb.pins_.take_sorted()) {
      pin_act(e);
      if (e.signal != models::kTx || opt_.record_tx) batch_out.push_back(e);
    }
    if (!vb.entry_ends_.empty()) {
      act = std::max(act, vb.entry_ends_.back() - 1);
      never_active = false;
    }
    const Cycle wd = vb.dec_.watchdog_edge();
    if (wd >= 0) act = std::max(act, wd + 1);
    while (!pending.empty() && pending.front().first + dec_off <= now) {
      const Cycle d = pending.front().first + dec_off;
      out.push_back(pending.front().second);
      pending.pop_front();
      ++bytes_out;
      if (pending.empty() && !opt_.realtime) {
        // SimBoard writes an answer on the first inactive clock (at most a poll interval later).
        hold_at =
            std::max(now, std::min(act + 1, d + static_cast<Cycle>(opt_.poll_interval_cycles)));
      }
    }
    flush_out();

    if (hold_at >= 0 && hold_at <= now) {
      hold_at = -1;
      publish(false);
      // The client reads the answer, then has host_grace to write.
      const auto limit = wall_clock::now() + std::chrono::milliseconds(50);
      bool input = false;
      for (;;) {
        int unread = 0;
        if (::ioctl(slave_, FIONREAD, &unread) != 0 || unread == 0) break;
        if (wall_clock::now() >= limit || stop_.load()) break;
        if (wait_input(wall_clock::now() + std::chrono::microseconds(20))) {
          input = true;
          break;
        }
      }
      if (input || wait_input(wall_clock::now() + grace)) continue;
    }

    // The next event.
    Cycle e = kNone;
    if (!pending.empty()) e = std::min(e, pending.front().first + dec_off);
    const Cycle dn = vb.enc_.next_decision();
    if (dn >= 0) e = std::min(e, std::max(dn, now + 1));
    if (!never_active && act + kQuiet + 1 > now) e = std::min(e, act + kQuiet + 1);
    if (wd >= 0) e = std::min(e, std::max(wd + 1, now + 1));
    if (hold_at > now) e = std::min(e, hold_at);
    // The host's next timer: stop there (not past it) so that it can poll during a long move.
    const Cycle host_at = host_deadline_.load();
    const bool to_host = !opt_.realtime && host_at > now && e != kNone && host_at <= e;
    if (to_host) e = host_at;
    if (!opt_.realtime && !to_host && e != kNone && e >= kHeldForever / 2) {
      // Held for good (the motion rate at 0 with nothing to end it): the clock does not run on
      // its own to the end of a hold that never ends; it moves on to the host's deadlines.
      publish(false);
      wait_input(wall_clock::now() + std::chrono::milliseconds(100));
      continue;
    }
    if (e == kNone) {
      // Quiet: time stands still until the host writes.
      publish(true);
      wait_input(wall_clock::now() + std::chrono::milliseconds(100));
      if (opt_.realtime) {
        c_ref = now;
        t_ref = wall_clock::now();
      }
      continue;
    }
    publish(false);
    if (opt_.realtime) {
      const double rate = static_cast<double>(opt_.clk_hz) * opt_.realtime_speed;  // clocks/s
      const auto at =
          t_ref + std::chrono::duration_cast<wall_clock::duration>(
                      std::chrono::duration<double>(static_cast<double>(e - c_ref) / rate));
      if (wall_clock::now() < at) {
        wait_input(std::min(at, wall_clock::now() + std::chrono::milliseconds(10)));
        const double el = std::chrono::duration<double>(wall_clock::now() - t_ref).count();
        const auto wall_cycle = c_ref + static_cast<Cycle>(el * rate);
        now = std::max(now, std::min(e, wall_cycle));
        continue;
      }
    } else if (line_next > now + 1 && e >= line_next - 1 && had_write &&
               wall_clock::now() - last_write < grace) {
      // The host may still be writing the rest of what is on the line.
      if (wait_input(last_write + grace)) continue;
    }
    now = e;
    if (to_host) hold_at_timer(host_at);
  }
  // Final figures: violations as cnc_core counts them (clocks with a `violation` strobe).
  std::vector<Cycle> strobes = vb.exec_.arc_violation_cycles;
  for (int a = 0; a < kAxes; ++a) {
    const auto& v = vb.pulse_[static_cast<size_t>(a)]->violation_strobes;
    strobes.insert(strobes.end(), v.begin(), v.end());
  }
  std::sort(strobes.begin(), strobes.end());
  const auto viol = std::unique(strobes.begin(), strobes.end()) - strobes.begin();
  publish(true);
  std::lock_guard<std::mutex> l(mu_);
  st_.violations = static_cast<uint16_t>(viol);
  // The edges in order, laser pairs of back-to-back cutting segments dropped across the batches
  // they were drained in: the count is that of edges(), whatever the batches were.
  sort_edges(edges_);
  st_.edges = static_cast<uint64_t>(
      std::upper_bound(edges_.begin(), edges_.end(), static_cast<uint64_t>(now),
                       [](uint64_t c, const models::Edge& e) { return c < e.cycle; }) -
      edges_.begin());
}

}  // namespace fpgacnc::twins
