#include "fpgacnc/simboard/cli_board.h"

#include <fmt/format.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "fpgacnc/simboard/plot.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/simboard/sim_board.h"

namespace fpgacnc::simboard {
namespace {

void print_sim_extras(const SimBoard& b, const BoardStats& s) {
  if (b.options().line_faults.any()) {
    fmt::print("simulated board: line faults ({}): {}\n", b.options().line_faults.describe(),
               describe(s.line));
  }
  const ThermalStats t = b.thermal();
  if (t.ticks) {
    fmt::print(
        "simulated board heaters: {} sample ticks = {} plant seconds (1 per {} clocks); hot end "
        "{:.1f} degC, bed {:.1f} degC; ADC timing violations {}{}\n",
        t.ticks, t.ticks, SimBoard::kSampleClks, t.plant_c[0], t.plant_c[1], t.adc_violations,
        t.adc_violations ? " (" + t.adc_first_violation + ")" : std::string());
  }
}

constexpr LineFaultOption kLineFaultOptions[] = {
    {"--line-ber", "P[,Q]",
     "bit error rate on the simulated line: P host->board (per UART bit), Q board->host (per "
     "data bit); one value sets both"},
    {"--line-drop", "P", "probability that a host->board byte is dropped"},
    {"--line-dup", "P", "probability that a host->board byte is duplicated"},
    {"--line-lose-frames", "P", "probability that a whole device frame (ACK, ...) is lost"},
    {"--line-stall", "CYCLE:CLOCKS",
     "hold the host->board line from simulated cycle CYCLE for CLOCKS clocks (bN:CLOCKS: before "
     "the N-th byte on the line); repeatable"},
    {"--line-seed", "N", "seed of the line fault generator (default 1)"},
};

[[noreturn]] void bad_value(std::string_view name, std::string_view value, std::string_view why) {
  throw std::invalid_argument(fmt::format("--{}: invalid value '{}': {}", name, value, why));
}

uint64_t parse_u64(std::string_view name, std::string_view v) {
  uint64_t x = 0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size()) {
    bad_value(name, v, "expected a non-negative integer");
  }
  return x;
}

double parse_probability(std::string_view name, std::string_view v) {
  double x = 0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size()) {
    bad_value(name, v, "expected a number");
  }
  if (!(x >= 0.0 && x <= 1.0)) bad_value(name, v, "a probability must be in [0, 1]");
  return x;
}

}  // namespace

void print_board_figures(const Board& b) {
  const BoardStats s = b.stats();
  fmt::print(
      "simulated board ({}): {} cycles ({:.3f} s of machine time), {:.2f} M clocks/s ({:.2f} s "
      "simulating, {:.2f} s wall), {} bytes in, {} bytes out, {} edges, {} moves done\n",
      b.model(), s.cycles, static_cast<double>(s.cycles) / b.clk_hz(), s.clocks_per_s / 1e6,
      s.sim_wall_s, s.wall_s, s.bytes_in, s.bytes_out, s.edges, s.moves_done);
  if (const auto* sim = dynamic_cast<const SimBoard*>(&b)) print_sim_extras(*sim, s);
  if (s.frame_errors || s.timeouts || s.violations) {
    fmt::print(
        "simulated board: {} framing errors, {} packet timeouts, {} step timing violations\n",
        s.frame_errors, s.timeouts, s.violations);
  }
}

std::span<const LineFaultOption> line_fault_options() {
  return kLineFaultOptions;
}

bool parse_line_fault_option(std::string_view name, std::string_view value, LineFaults& f) {
  if (name.starts_with("--")) name.remove_prefix(2);
  if (name == "line-ber") {
    const size_t comma = value.find(',');
    if (comma == std::string_view::npos) {
      f.ber_to_board = f.ber_to_host = parse_probability(name, value);
    } else {
      f.ber_to_board = parse_probability(name, value.substr(0, comma));
      f.ber_to_host = parse_probability(name, value.substr(comma + 1));
    }
  } else if (name == "line-drop") {
    f.drop = parse_probability(name, value);
  } else if (name == "line-dup") {
    f.dup = parse_probability(name, value);
  } else if (name == "line-lose-frames") {
    f.lose_frames = parse_probability(name, value);
  } else if (name == "line-seed") {
    f.seed = parse_u64(name, value);
  } else if (name == "line-stall") {
    const size_t colon = value.find(':');
    if (colon == std::string_view::npos) bad_value(name, value, "expected CYCLE:CLOCKS");
    LineStall s;
    std::string_view at = value.substr(0, colon);
    if (at.starts_with('b')) {
      s.trigger = LineStall::Trigger::kBytes;
      at.remove_prefix(1);
    }
    s.at = parse_u64(name, at);
    s.clocks = parse_u64(name, value.substr(colon + 1));
    if (s.clocks == 0) bad_value(name, value, "a stall must last at least 1 clock");
    f.stalls.push_back(s);
  } else {
    return false;
  }
  return true;
}

Endstop parse_endstop_option(std::string_view v, const config::MachineConfig& cfg) {
  const size_t eq = v.find('=');
  const std::string sw(v.substr(0, eq));
  const std::string axes = "xyz";
  const bool ok_name = sw.size() == 5 && axes.find(sw[0]) != std::string::npos &&
                       (sw.substr(1) == "-min" || sw.substr(1) == "-max");
  const std::string num(eq == std::string_view::npos ? std::string_view() : v.substr(eq + 1));
  char* end = nullptr;
  const double mm = std::strtod(num.c_str(), &end);
  if (!ok_name || num.empty() || *end || !std::isfinite(mm)) {
    throw std::invalid_argument(
        fmt::format("--endstop {}: expected AXIS-SIDE=MM with AXIS x, y or z and SIDE min or max "
                    "(e.g. x-max=200)",
                    v));
  }
  Endstop e;
  e.axis = static_cast<int>(axes.find(sw[0]));
  e.max_side = sw.substr(1) == "-max";
  e.position =
      static_cast<int64_t>(std::llround(mm * cfg.steps_per_mm[static_cast<size_t>(e.axis)]));
  return e;
}

ProbePlate parse_probe_plate_option(std::string_view v, const config::MachineConfig& cfg) {
  Endstop e;
  try {
    e = parse_endstop_option(v, cfg);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(
        fmt::format("--probe-plate {}: expected AXIS-SIDE=MM with AXIS x, y or z and SIDE min (the "
                    "probe touches at or below MM) or max (at or above), e.g. z-min=-2",
                    v));
  }
  return ProbePlate{e.axis, !e.max_side, e.position};
}

uint16_t parse_limit_switches_option(std::string_view value) {
  uint16_t bits = 0;
  size_t b = 0;
  while (b < value.size()) {
    size_t e = value.find(',', b);
    if (e == std::string_view::npos) e = value.size();
    const std::string sw(value.substr(b, e - b));
    const std::string axes = "xyz";
    if (sw.size() != 5 || axes.find(sw[0]) == std::string::npos ||
        (sw.substr(1) != "-min" && sw.substr(1) != "-max")) {
      throw std::invalid_argument(fmt::format(
          "--limit-switches {}: '{}' is not a switch (x-min, x-max, y-min, y-max, z-min, z-max)",
          value, sw));
    }
    bits = static_cast<uint16_t>(bits | (1u << (axes.find(sw[0]) + (sw[2] == 'a' ? 8 : 0))));
    b = e + 1;
  }
  return bits;
}

namespace {

// "x-min,z-max" for switch bits as STATUS numbers them; "none" for 0.
std::string switch_list(uint16_t bits) {
  std::string out;
  for (int side = 0; side < 2; ++side) {
    for (int a = 0; a < models::kBoardAxes; ++a) {
      if (!((bits >> (a + 8 * side)) & 1u)) continue;
      if (!out.empty()) out += ',';
      out += fmt::format("{}-{}", "xyza"[a], side ? "max" : "min");
    }
  }
  return out.empty() ? "none" : out;
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) w.push_back(line.substr(b, i - b));
  }
  return w;
}

constexpr const char* kCommands =
    "hold, start, estop on|off, limit AXIS min|max on|off, probe on|off, state, help";

std::string press(Board& board, Button b) {
  const uint64_t edge = board.press_button(b);
  const uint64_t len = SimBoard::kButtonPressClks;  // the twin board presses as long
  return fmt::format("ok {} pressed from clock edge {} for {} clocks (released at edge {})",
                     button_name(b), edge, len, edge + len);
}

std::string board_state(const Board& board) {
  const auto* sb = dynamic_cast<const SimBoard*>(&board);
  if (!sb) {
    return fmt::format("ok model={} cycle={} (no e-stop or limit switches are modelled)",
                       board.model(), board.cycle());
  }
  const BoardPins p = sb->pins();
  return fmt::format(
      "ok model={} cycle={} estop={} hold={} start={} limit_pins={} limit_filtered={} "
      "limit_wired={} probe_pin={} probe_filtered={} faults=0x{:02x}",
      board.model(), p.cycle, p.estop ? "on" : "off", (p.buttons & 1u) ? "on" : "off",
      (p.buttons & 2u) ? "on" : "off", switch_list(p.limit_pins), switch_list(p.limit_filtered),
      switch_list(p.limit_wired), p.probe_pin ? "on" : "off", p.probe_filtered ? "on" : "off",
      p.faults);
}

// on / off as a bool; nullopt for anything else.
std::optional<bool> on_off(std::string_view w) {
  if (w == "on") return true;
  if (w == "off") return false;
  return std::nullopt;
}

}  // namespace

std::string board_control_command(Board& board, std::string_view line) {
  const auto w = split_words(line);
  if (w.empty()) return "error: empty command (commands: " + std::string(kCommands) + ")";
  const std::string_view cmd = w[0];
  const auto extra = [&](size_t n) -> std::string {
    return w.size() > n ? fmt::format("error: {}: unexpected '{}'", cmd, w[n]) : std::string();
  };
  try {
    if (cmd == "hold" || cmd == "start" || cmd == "state" || cmd == "help") {
      if (auto e = extra(1); !e.empty()) return e;
      if (cmd == "hold") return press(board, Button::kHold);
      if (cmd == "start") return press(board, Button::kStart);
      if (cmd == "state") return board_state(board);
      return "ok commands: " + std::string(kCommands);
    }
    if (cmd == "estop") {
      if (w.size() < 2) return "error: estop: expected on or off";
      const auto on = on_off(w[1]);
      if (!on) return fmt::format("error: estop: '{}' is not on or off", w[1]);
      if (auto e = extra(2); !e.empty()) return e;
      board.set_estop(*on);
      return fmt::format("ok e-stop {} at board cycle {}", *on ? "pressed" : "released",
                         board.cycle());
    }
    if (cmd == "limit") {
      if (w.size() < 4) return "error: limit: expected limit AXIS min|max on|off";
      const std::string_view axes = "xyza";
      const size_t axis = w[1].size() == 1 ? axes.find(w[1][0]) : std::string_view::npos;
      if (axis == std::string_view::npos)
        return fmt::format("error: limit: '{}' is not an axis (x, y, z, a)", w[1]);
      if (w[2] != "min" && w[2] != "max")
        return fmt::format("error: limit: '{}' is not min or max", w[2]);
      const auto on = on_off(w[3]);
      if (!on) return fmt::format("error: limit: '{}' is not on or off", w[3]);
      if (auto e = extra(4); !e.empty()) return e;
      const bool max_side = w[2] == "max";
      const uint64_t edge = board.set_limit(static_cast<int>(axis), max_side, *on);
      return fmt::format("ok {} {} from clock edge {}",
                         limit_switch_name(static_cast<int>(axis), max_side),
                         *on ? "pressed" : "released", edge);
    }
    if (cmd == "probe") {
      if (w.size() < 2) return "error: probe: expected probe on|off";
      const auto on = on_off(w[1]);
      if (!on) return fmt::format("error: probe: '{}' is not on or off", w[1]);
      if (auto e = extra(2); !e.empty()) return e;
      const uint64_t edge = board.set_probe(*on);
      return fmt::format("ok probe {} from clock edge {}", *on ? "touching" : "lifted", edge);
    }
  } catch (const BoardError& e) {
    return fmt::format("error: {}: {}", cmd, e.what());
  }
  return fmt::format("error: unknown command '{}' (commands: {})", cmd, kCommands);
}

namespace {

// The control socket: a listening Unix-domain stream socket and its clients, each with the part
// of a line it has sent so far. Removes the socket file when destroyed.
class ControlSocket {
 public:
  static constexpr size_t kMaxLine = 256;

  explicit ControlSocket(const std::string& path) : path_(path) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (path.empty() || path.size() >= sizeof addr.sun_path) {
      throw std::invalid_argument(fmt::format("--control {}: a socket path must have 1 to {} bytes",
                                              path, sizeof addr.sun_path - 1));
    }
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0) {
      // A socket left behind by a board that did not exit cleanly is replaced; anything else,
      // or a socket some process still answers on, is not touched.
      if (!S_ISSOCK(st.st_mode)) {
        throw std::invalid_argument(
            fmt::format("--control {}: the path exists and is not a socket", path));
      }
      const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
      const bool live =
          probe >= 0 && ::connect(probe, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
      if (probe >= 0) ::close(probe);
      if (live) {
        throw std::invalid_argument(
            fmt::format("--control {}: another process is listening on that socket", path));
      }
      ::unlink(path.c_str());
    }
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (fd_ < 0) fail("socket");
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) fail("bind");
    bound_ = true;
    if (::listen(fd_, 8) != 0) fail("listen");
  }
  ~ControlSocket() {
    for (auto& c : clients_) ::close(c.fd);
    if (fd_ >= 0) ::close(fd_);
    if (bound_) ::unlink(path_.c_str());
  }
  ControlSocket(const ControlSocket&) = delete;
  ControlSocket& operator=(const ControlSocket&) = delete;

  const std::string& path() const { return path_; }
  // The descriptors to poll: the listening socket first, then the clients.
  void add_fds(std::vector<pollfd>& p) const {
    p.push_back({fd_, POLLIN, 0});
    for (const auto& c : clients_) p.push_back({c.fd, POLLIN, 0});
  }
  // Serves what poll() reported for the descriptors add_fds() gave from `first` on.
  void serve(const std::vector<pollfd>& p, size_t first, Board& board) {
    std::vector<int> gone;
    for (size_t i = first + 1; i < p.size() && i - first - 1 < clients_.size(); ++i) {
      if (p[i].revents && !read_client(clients_[i - first - 1], board)) gone.push_back(p[i].fd);
    }
    for (int fd : gone) {
      ::close(fd);
      std::erase_if(clients_, [fd](const Client& c) { return c.fd == fd; });
    }
    if (p[first].revents & POLLIN) {
      for (;;) {
        const int c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
        if (c < 0) break;
        clients_.push_back({c, {}, false});
      }
    }
  }

 private:
  struct Client {
    int fd;
    std::string buf;
    bool overlong;  // the current line passed kMaxLine: dropped up to its newline
  };

  [[noreturn]] void fail(const char* call) {
    const std::string why = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (bound_) ::unlink(path_.c_str());
    bound_ = false;
    throw std::runtime_error(fmt::format("--control {}: {}: {}", path_, call, why));
  }

  // Reads what a client sent and answers each complete line; false when it is gone.
  bool read_client(Client& c, Board& board) {
    char buf[512];
    for (;;) {
      const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
      if (n == 0) return false;
      if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
      for (ssize_t k = 0; k < n; ++k) {
        const char ch = buf[k];
        if (ch != '\n') {
          if (c.buf.size() < kMaxLine)
            c.buf += ch;
          else
            c.overlong = true;
          continue;
        }
        if (!c.buf.empty() && c.buf.back() == '\r') c.buf.pop_back();
        std::string answer;
        if (c.overlong) {
          answer = fmt::format("error: line longer than {} bytes", kMaxLine);
        } else if (split_words(c.buf).empty()) {
          c.buf.clear();
          continue;  // a blank line is no command
        } else {
          answer = board_control_command(board, c.buf);
        }
        // Actions and errors are logged; the answers to queries (state, help) only go back.
        const auto w = split_words(c.buf);
        if (c.overlong || !answer.starts_with("ok ") || (w[0] != "state" && w[0] != "help")) {
          fmt::print("control socket: {} -> {}\n", c.overlong ? "(long line)" : c.buf, answer);
          std::fflush(stdout);
        }
        c.buf.clear();
        c.overlong = false;
        answer += '\n';
        // The answer is short and the client reads it before its next command; one that does
        // not read is dropped rather than blocking the board's command loop.
        if (::send(c.fd, answer.data(), answer.size(), MSG_NOSIGNAL | MSG_DONTWAIT) !=
            static_cast<ssize_t>(answer.size()))
          return false;
      }
    }
  }

  std::string path_;
  int fd_ = -1;
  bool bound_ = false;
  std::vector<Client> clients_;
};

// Keys on the board's terminal: stdin in non-canonical mode without echo (Ctrl-C still sends
// SIGINT); restored when destroyed. Inactive when stdin is not a terminal.
class TerminalKeys {
 public:
  TerminalKeys() {
    if (!::isatty(STDIN_FILENO) || ::tcgetattr(STDIN_FILENO, &saved_) != 0) return;
    termios t = saved_;
    t.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    active_ = ::tcsetattr(STDIN_FILENO, TCSANOW, &t) == 0;
  }
  ~TerminalKeys() {
    if (active_) ::tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }
  TerminalKeys(const TerminalKeys&) = delete;
  TerminalKeys& operator=(const TerminalKeys&) = delete;
  bool active() const { return active_; }

 private:
  termios saved_{};
  bool active_ = false;
};

void key_command(Board& board, char key) {
  std::string answer;
  if (key == 'h') {
    answer = board_control_command(board, "hold");
  } else if (key == 's') {
    answer = board_control_command(board, "start");
  } else if (key == 'e') {
    const auto* sb = dynamic_cast<const SimBoard*>(&board);
    const bool pressed = sb && sb->pins().estop;
    answer = board_control_command(board, pressed ? "estop off" : "estop on");
  } else if (key == 'p') {
    const auto* sb = dynamic_cast<const SimBoard*>(&board);
    const bool touching = sb && sb->pins().probe_pin;
    answer = board_control_command(board, touching ? "probe off" : "probe on");
  } else {
    return;
  }
  fmt::print("key {}: {}\n", key, answer);
  std::fflush(stdout);
}

// The control socket and the keys, served in their own thread until `stop_fd` (an eventfd) is
// signalled. Signals stay with the caller's sigwait(): a process-directed signal goes to the
// main thread only while it waits in sigwait (a thread that blocks it in poll() is passed over,
// and a library thread with nothing blocked would take it with its default action).
void serve_control(Board& board, ControlSocket* control, bool keys, int stop_fd) {
  try {
    for (;;) {
      std::vector<pollfd> p{{stop_fd, POLLIN, 0}};
      if (keys) p.push_back({STDIN_FILENO, POLLIN, 0});
      const size_t ctl_first = p.size();
      if (control) control->add_fds(p);
      if (::poll(p.data(), p.size(), -1) < 0) {
        if (errno == EINTR) continue;
        throw std::runtime_error(fmt::format("poll: {}", std::strerror(errno)));
      }
      if (p[0].revents) return;
      if (keys && p[1].revents) {
        char k = 0;
        if (::read(STDIN_FILENO, &k, 1) == 1) key_command(board, k);
      }
      if (control) control->serve(p, ctl_first, board);
    }
  } catch (const std::exception& e) {
    fmt::print("control socket and keys stopped: {}\n", e.what());
    std::fflush(stdout);
  }
}

}  // namespace

int run_board_command(const BoardCommandArgs& args, Board& board, uint32_t baud) {
  // SIGINT/SIGTERM (stop), SIGUSR1/SIGUSR2 (e-stop) and SIGHUP are taken with sigwait() here;
  // block them before the board thread and the control thread start so that they inherit the
  // mask and the signals always reach this thread.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);
  sigaddset(&set, SIGUSR2);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  struct Unblock {
    sigset_t* s;
    ~Unblock() { pthread_sigmask(SIG_UNBLOCK, s, nullptr); }
  } unblock{&set};
  // The socket exists before the board starts: a bad path stops here with nothing running.
  std::unique_ptr<ControlSocket> control;
  if (!args.control_path.empty()) control = std::make_unique<ControlSocket>(args.control_path);
  const int stop_fd = ::eventfd(0, EFD_CLOEXEC);
  if (stop_fd < 0) throw std::runtime_error(fmt::format("eventfd: {}", std::strerror(errno)));
  struct CloseFd {
    int fd;
    ~CloseFd() { ::close(fd); }
  } close_stop{stop_fd};
  board.start();
  fmt::print("simulated board ({}) on {} ({} baud)\n", board.model(), board.path(), baud);
  if (control) fmt::print("control socket: {}\n", control->path());
  if (!args.fst_path.empty()) fmt::print("FST waveform: {}\n", args.fst_path);
  if (args.line_faults.any()) fmt::print("line faults: {}\n", args.line_faults.describe());
  fmt::print(
      "Ctrl-C (SIGINT) or SIGTERM stops it; SIGUSR1 presses the e-stop, SIGUSR2 releases it "
      "(kill -USR1 {}); SIGHUP pulls the carriages off their endstops\n",
      static_cast<long>(getpid()));
  TerminalKeys keys;
  if (keys.active())
    fmt::print("keys: h feed hold, s cycle start, e e-stop on/off, p probe touch/lift\n");
  std::fflush(stdout);
  std::thread served;
  if (control || keys.active())
    served = std::thread(serve_control, std::ref(board), control.get(), keys.active(), stop_fd);
  int sig = 0;
  for (;;) {
    sigwait(&set, &sig);
    if (sig == SIGHUP) {
      // The operator pulls the carriages off their simulated endstops
      // (SimBoard::pull_off_endstops).
      auto* sb = dynamic_cast<SimBoard*>(&board);
      const int n = sb ? sb->pull_off_endstops() : 0;
      fmt::print("SIGHUP: {} endstop(s) released by hand at board cycle {}\n", n, board.cycle());
      std::fflush(stdout);
      continue;
    }
    if (sig != SIGUSR1 && sig != SIGUSR2) break;
    // The e-stop pin (cnc_core's estop input) follows the signal until the next one; the core
    // synchronizes and latches it on its next clocks (docs/protocol.md "The simulated board").
    const bool pressed = sig == SIGUSR1;
    try {
      board.set_estop(pressed);
      fmt::print("e-stop {} at board cycle {}\n", pressed ? "pressed" : "released", board.cycle());
    } catch (const BoardError& e) {
      fmt::print("e-stop ignored: {}\n", e.what());
    }
    std::fflush(stdout);
  }
  if (served.joinable()) {
    const uint64_t one = 1;
    [[maybe_unused]] ssize_t n = ::write(stop_fd, &one, sizeof one);
    served.join();
  }
  board.stop();
  control.reset();  // the socket file goes before the figures are printed
  fmt::print("\nstopped by {}\n", sig == SIGINT ? "SIGINT" : "SIGTERM");
  print_board_figures(board);
  const auto edges = board.edges();
  const auto n = models::net_steps(edges);
  fmt::print("net steps from the edges: X {} Y {} Z {} E {}\n", n[0], n[1], n[2], n[3]);
  if (!args.edges_csv.empty()) {
    models::write_edges_csv(args.edges_csv, edges, board.clk_hz());
    fmt::print("edges written to {}\n", args.edges_csv);
  }
  return 0;
}

std::unique_ptr<link::Link> make_default_link(const config::MachineConfig& cfg,
                                              const SimOutputs& outputs,
                                              const LineFaults& line_faults) {
  if (!outputs.plot_path.empty()) check_plot_path(outputs.plot_path);
  BoardOptions o = SimBoard::options_from_config(cfg);
  o.fst_path = outputs.fst_path;
  o.line_faults = line_faults;
  if (o.line_faults.any()) fmt::print("line faults: {}\n", o.line_faults.describe());
  return make_board_link(std::make_unique<SimBoard>(o), o.baud, outputs);
}

std::unique_ptr<link::Link> make_board_link(std::unique_ptr<Board> board, uint32_t baud,
                                            const SimOutputs& outputs) {
  if (!outputs.plot_path.empty()) check_plot_path(outputs.plot_path);
  auto lk = std::make_unique<BoardLink>(std::move(board), baud);
  fmt::print("simulated board ({}) on {} ({} baud)\n", lk->any_board().model(),
             lk->any_board().path(), baud);
  std::fflush(stdout);
  return lk;
}

Board* any_board_of(link::Link& lk) {
  auto* bl = dynamic_cast<BoardLink*>(&lk);
  return bl ? &bl->any_board() : nullptr;
}

std::function<double()> plant_clock(link::Link& lk) {
  SimBoard* b = board_of(lk);
  if (!b) return {};
  return [b] { return b->plant_seconds(); };
}

SimBoard* board_of(link::Link& lk) {
  return dynamic_cast<SimBoard*>(any_board_of(lk));
}

bool report_board_run(link::Link& lk, const plan::Plan& plan, const config::MachineConfig& cfg,
                      const SimOutputs& outputs) {
  auto* bl = dynamic_cast<BoardLink*>(&lk);
  if (!bl) return false;
  Board& b = bl->any_board();
  // The last answer has reached the host; the board goes idle within a few clocks after it.
  if (!bl->wait_idle(std::chrono::milliseconds(1000)))
    fmt::print("simulated board: not idle 1 s of board time after the last answer\n");
  b.stop();
  print_board_figures(b);
  const auto edges = b.edges();
  const auto n = models::net_steps(edges);
  // v2 drives all four axes; v1 carries X and Y only, so Z/E that never stepped while the plan
  // moves them are reported as not driven rather than as a mismatch.
  const bool xy_ok = n[0] == plan.final_steps[0] && n[1] == plan.final_steps[1];
  const bool ze_ok = n[2] == plan.final_steps[2] && n[3] == plan.final_steps[3];
  const auto pulses = models::step_pulses(edges);
  const bool ze_idle = pulses[2] == 0 && pulses[3] == 0;
  const char* verdict = !xy_ok    ? "MISMATCH"
                        : ze_ok   ? "match"
                        : ze_idle ? "X/Y match; Z and E not driven (protocol v1)"
                                  : "MISMATCH";
  fmt::print(
      "net steps from the edges: X {} Y {} Z {} E {} (planned final target X {} Y {} Z {} E {}: "
      "{})\n",
      n[0], n[1], n[2], n[3], plan.final_steps[0], plan.final_steps[1], plan.final_steps[2],
      plan.final_steps[3], verdict);
  if (!outputs.plot_path.empty()) {
    PlotOptions po;
    po.steps_per_mm = {cfg.steps_per_mm[0], cfg.steps_per_mm[1]};
    po.title = fmt::format("{} on the simulated board ({})", plan.source, b.model());
    write_plot_svg(outputs.plot_path, edges, commanded_path(plan, cfg), po);
    fmt::print("plot written to {}\n", outputs.plot_path);
  }
  if (!outputs.fst_path.empty()) fmt::print("FST waveform written to {}\n", outputs.fst_path);
  if (!outputs.edges_csv.empty()) {
    models::write_edges_csv(outputs.edges_csv, edges, b.clk_hz());
    fmt::print("edges written to {}\n", outputs.edges_csv);
  }
  return true;
}

}  // namespace fpgacnc::simboard
