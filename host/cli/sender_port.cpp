#include "sender_port.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace fpgacnc::cli {

namespace {
volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_hangup = 0;
void on_stop_signal(int) {
  g_stop = 1;
}
void on_hangup_signal(int) {
  g_hangup = 1;
}
}  // namespace

void stop_on_signals() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::signal(SIGPIPE, SIG_IGN);
  std::signal(SIGHUP, on_hangup_signal);
}

bool take_hangup() {
  if (!g_hangup) return false;
  g_hangup = 0;
  return true;
}

bool stop_requested() {
  return g_stop != 0;
}

void add_board_options(CLI::App* sub, BoardChoice& choice, const std::string& model_help) {
  sub->add_option("--port", choice.port, "the controller's serial port (default: simulated board)");
  sub->add_option("--model", choice.model, model_help)->check(CLI::IsMember({"tlm", "rtl"}));
  sub->add_option("--endstop", choice.endstops,
                  "rtl: a simulated endstop, AXIS-SIDE=MM (x-max=200): the switch is pressed while "
                  "the axis is at or beyond MM; SIGHUP pulls the carriages off (repeatable)")
      ->type_name("AXIS-SIDE=MM");
  sub->add_option("--probe-plate", choice.probe_plate,
                  "rtl: a simulated probe plate, AXIS-SIDE=MM (z-min=-2: the probe touches while "
                  "Z is at or below -2 mm; x-max=5: at or above 5 mm)")
      ->type_name("AXIS-SIDE=MM");
  sub->add_option("--limit-switches", choice.limit_switches,
                  "--port: the limit switches the board wires (its LIMIT_ENABLE), e.g. "
                  "x-min,x-max,y-min,y-max (M119, $21)")
      ->type_name("LIST");
}

BoardBehind open_board_behind(const config::MachineConfig& cfg, const BoardChoice& choice) {
  BoardBehind b;
  if (choice.realtime && (!choice.port.empty() || choice.model != "tlm"))
    throw std::invalid_argument("--realtime needs the twin board (--model tlm, no --port)");
  if (!(choice.speed > 0.0) || (choice.speed != 1.0 && !choice.realtime))
    throw std::invalid_argument("--speed: a number > 0, with --realtime");
  if (!choice.endstops.empty() && (!choice.port.empty() || choice.model != "rtl"))
    throw std::invalid_argument("--endstop needs the Verilated board (--model rtl, no --port)");
  if (!choice.probe_plate.empty() && (!choice.port.empty() || choice.model != "rtl"))
    throw std::invalid_argument(
        "--probe-plate needs the Verilated board (--model rtl, no --port): the twin board (tlm) "
        "models neither the probe input nor the trigger");
  if (!choice.limit_switches.empty() && choice.port.empty())
    throw std::invalid_argument(
        "--limit-switches is for a real board (--port); the simulated boards report their own");
  if (!choice.port.empty()) {
    b.link = std::make_unique<link::SerialLink>(choice.port, cfg.baud);
    b.description = choice.port;
    b.limit_switches = simboard::parse_limit_switches_option(choice.limit_switches);
    b.probe = true;
  } else if (choice.model == "tlm") {
    twins::TwinBoardOptions o = twins::TwinBoard::options_from_config(cfg);
    o.realtime = choice.realtime;
    o.realtime_speed = choice.speed;
    b.link = simboard::make_board_link(std::make_unique<twins::TwinBoard>(o), cfg.baud, {});
    b.description = "the simulated board (tlm)";
  } else {
    simboard::BoardOptions o = simboard::SimBoard::options_from_config(cfg);
    for (const auto& e : choice.endstops)
      o.endstops.push_back(simboard::parse_endstop_option(e, cfg));
    if (!choice.probe_plate.empty())
      o.probe_plate = simboard::parse_probe_plate_option(choice.probe_plate, cfg);
    b.link = simboard::make_board_link(std::make_unique<simboard::SimBoard>(o), cfg.baud, {});
    b.description = "the simulated board (rtl)";
    b.rtl = true;
    b.probe = simboard::SimBoard::kProbeEnable;
    if (auto* bl = dynamic_cast<simboard::BoardLink*>(b.link.get())) {
      b.estop_press = [bl] { bl->board().set_estop(true); };
      b.estop_release = [bl] { bl->board().set_estop(false); };
      b.pull_off = [bl] {
        const int n = bl->board().pull_off_endstops();
        fmt::print("SIGHUP: {} endstop(s) released by hand\n", n);
        std::fflush(stdout);
      };
    }
  }
  if (const auto* bd = simboard::any_board_of(*b.link)) b.limit_switches = bd->limit_switches();
  return b;
}

void set_nonblocking(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
}

int open_sender_pty(std::string& path) {
  const int m = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (m < 0 || ::grantpt(m) != 0 || ::unlockpt(m) != 0)
    throw std::runtime_error(
        fmt::format("cannot create a pseudo-terminal: {}", std::strerror(errno)));
  path = ::ptsname(m);
  // Raw mode on the pair (open the slave once to set it).
  const int s = ::open(path.c_str(), O_RDWR | O_NOCTTY);
  if (s >= 0) {
    termios t{};
    ::tcgetattr(s, &t);
    ::cfmakeraw(&t);
    ::cfsetispeed(&t, B115200);
    ::cfsetospeed(&t, B115200);
    ::tcsetattr(s, TCSANOW, &t);
    ::close(s);
  }
  set_nonblocking(m);
  return m;
}

void flush_peer(Peer& p) {
  while (p.connected && !p.pending.empty()) {
    const ssize_t n = ::write(p.fd, p.pending.data(), p.pending.size());
    if (n <= 0) break;
    p.pending.erase(0, static_cast<size_t>(n));
  }
}

bool sender_present(int master) {
  pollfd q{master, POLLIN, 0};
  ::poll(&q, 1, 0);
  return !(q.revents & POLLHUP);
}

bool SenderWatch::poll(Peer& pty) {
  if (pty.fd < 0) return false;
  const bool open_now = sender_present(pty.fd);
  const auto now = std::chrono::steady_clock::now();
  if (open_now && !pty.connected) {
    pty.connected = true;
    banner_at_ = now + std::chrono::milliseconds(100);
  } else if (!open_now && pty.connected) {
    pty.connected = false;
    pty.pending.clear();
    banner_at_.reset();
  }
  if (banner_at_ && now >= *banner_at_) {
    banner_at_.reset();
    return true;
  }
  return false;
}

int listen_tcp(const std::string& spec, std::string& where) {
  if (spec.rfind("tcp:", 0) != 0)
    throw std::invalid_argument(fmt::format("--listen {}: expected tcp:HOST:PORT", spec));
  const std::string hp = spec.substr(4);
  const auto colon = hp.rfind(':');
  if (colon == std::string::npos)
    throw std::invalid_argument(fmt::format("--listen {}: expected tcp:HOST:PORT", spec));
  const std::string host = hp.substr(0, colon), port = hp.substr(colon + 1);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* res = nullptr;
  if (int rc = ::getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &res))
    throw std::invalid_argument(fmt::format("--listen {}: {}", spec, ::gai_strerror(rc)));
  int fd = -1;
  for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype, a->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 1) != 0) {
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(res);
  if (fd < 0)
    throw std::runtime_error(
        fmt::format("--listen {}: cannot listen: {}", spec, std::strerror(errno)));
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len);
  char buf[INET6_ADDRSTRLEN] = "?";
  int bound_port = 0;
  if (ss.ss_family == AF_INET) {
    auto* in = reinterpret_cast<sockaddr_in*>(&ss);
    ::inet_ntop(AF_INET, &in->sin_addr, buf, sizeof buf);
    bound_port = ntohs(in->sin_port);
  } else if (ss.ss_family == AF_INET6) {
    auto* in = reinterpret_cast<sockaddr_in6*>(&ss);
    ::inet_ntop(AF_INET6, &in->sin6_addr, buf, sizeof buf);
    bound_port = ntohs(in->sin6_port);
  }
  where = fmt::format("{}:{}", buf, bound_port);
  set_nonblocking(fd);
  return fd;
}

void add_sender_options(CLI::App* sub, SenderChoice& choice) {
  sub->add_option("--listen", choice.listen,
                  "also serve on TCP, tcp:HOST:PORT (PORT 0: any free port, printed)");
  sub->add_flag("--no-pty", choice.no_pty, "serve on TCP only (first line: '-')");
}

void check_sender_choice(const SenderChoice& choice, const std::string& command) {
  if (choice.no_pty && choice.listen.empty())
    throw std::invalid_argument(command + ": --no-pty needs --listen tcp:HOST:PORT");
}

SenderSide::SenderSide(const SenderChoice& choice) {
  if (!choice.no_pty) pty_.fd = open_sender_pty(pty_path_);
  if (!choice.listen.empty()) listen_fd_ = listen_tcp(choice.listen, where_);
}

SenderSide::~SenderSide() {
  if (pty_.fd >= 0) ::close(pty_.fd);
  if (tcp_.connected) ::close(tcp_.fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void SenderSide::poll(int timeout_ms, const std::function<void(Peer&)>& opened,
                      const std::function<void(std::string_view)>& received) {
  if (watch_.poll(pty_)) opened(pty_);
  std::vector<pollfd> fds;
  if (pty_.connected) fds.push_back({pty_.fd, POLLIN, 0});
  if (tcp_.connected) fds.push_back({tcp_.fd, POLLIN, 0});
  if (listen_fd_ >= 0) fds.push_back({listen_fd_, POLLIN, 0});
  if (watch_.banner_pending()) timeout_ms = std::min(timeout_ms, 5);
  ::poll(fds.data(), fds.size(), timeout_ms);
  char buf[4096];
  for (const auto& f : fds) {
    if (!(f.revents & (POLLIN | POLLHUP | POLLERR))) continue;
    if (f.fd == listen_fd_) {
      const int c = ::accept(listen_fd_, nullptr, nullptr);
      if (c >= 0) {
        if (tcp_.connected) ::close(tcp_.fd);
        set_nonblocking(c);
        tcp_ = Peer{c, true, {}};
        opened(tcp_);
      }
      continue;
    }
    Peer& p = f.fd == pty_.fd ? pty_ : tcp_;
    if (!p.connected) continue;
    const ssize_t n = ::read(p.fd, buf, sizeof buf);
    if (n > 0) {
      received(std::string_view(buf, static_cast<size_t>(n)));
    } else if (&p == &tcp_ && (n == 0 || (errno != EAGAIN && errno != EINTR))) {
      ::close(tcp_.fd);
      tcp_ = Peer{};
    }
  }
}

void SenderSide::send(const std::string& out) {
  for (Peer* p : {&pty_, &tcp_}) {
    if (!p->connected) continue;
    p->pending += out;
    flush_peer(*p);
  }
}

}  // namespace fpgacnc::cli
