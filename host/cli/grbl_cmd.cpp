// fpgacnc grbl [--config F] [--port DEV | --model tlm|rtl] [--listen tcp:HOST:PORT]
//              [--settings FILE] [--realtime] [--no-pty]: grbl 1.1's protocol (docs/grbl.md)
// on a new pseudo-terminal (its path is the first line on stdout) and on TCP, with the FPGA
// behind it: a real port, or the simulated board (default: the twins). Serves until SIGINT or
// SIGTERM.
#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "fpgacnc/grbl/engine.h"
#include "fpgacnc/grbl/settings.h"
#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace fpgacnc::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
}

// A sender's end: the pty master or a TCP connection, with what is still to be written.
struct Peer {
  int fd = -1;
  bool connected = false;
  std::string pending;
};

void set_nonblocking(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
}

// The pty the sender opens: raw, 8-bit clean; no slave kept open by us, so POLLHUP on the
// master tells whether a sender has it open.
int open_sender_pty(std::string& path) {
  const int m = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (m < 0 || ::grantpt(m) != 0 || ::unlockpt(m) != 0)
    throw std::runtime_error(
        fmt::format("grbl: cannot create a pseudo-terminal: {}", std::strerror(errno)));
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

// "tcp:HOST:PORT" -> a listening socket.
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

void flush_peer(Peer& p) {
  while (p.connected && !p.pending.empty()) {
    const ssize_t n = ::write(p.fd, p.pending.data(), p.pending.size());
    if (n <= 0) break;
    p.pending.erase(0, static_cast<size_t>(n));
  }
}

struct Args {
  CommonOptions common;
  std::string port;
  std::string model = "tlm";
  std::string listen;
  std::string settings;
  bool realtime = false;
  bool no_pty = false;
};

void run(const Args& args) {
  const config::MachineConfig cfg = load_config(args.common);
  const std::string settings_path =
      args.settings.empty() ? grbl::default_settings_path() : args.settings;
  const grbl::Settings defaults = grbl::settings_from_config(cfg);
  const grbl::Settings settings = grbl::load_settings(settings_path, defaults).value_or(defaults);

  Peer pty, tcp;
  int listen_fd = -1;
  std::string pty_path, where;
  if (!args.no_pty) pty.fd = open_sender_pty(pty_path);
  if (!args.listen.empty()) listen_fd = listen_tcp(args.listen, where);
  // First line: the pty path (scripts read it), before the board prints its own line.
  fmt::print("{}\n", args.no_pty ? std::string("-") : pty_path);
  if (listen_fd >= 0) fmt::print("grbl on tcp {}\n", where);

  std::unique_ptr<link::Link> lk;
  grbl::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  eo.settings_path = settings_path;
  std::string behind;
  if (!args.port.empty()) {
    lk = std::make_unique<link::SerialLink>(args.port, cfg.baud);
    behind = args.port;
  } else if (args.model == "tlm") {
    twins::TwinBoardOptions o = twins::TwinBoard::options_from_config(cfg);
    o.realtime = args.realtime;
    lk = simboard::make_board_link(std::make_unique<twins::TwinBoard>(o), cfg.baud, {});
    behind = "the simulated board (tlm)";
  } else {
    if (args.realtime) throw std::invalid_argument("grbl: --realtime needs --model tlm");
    lk = simboard::make_default_link(cfg, {});
    behind = "the simulated board (rtl)";
    auto* bl = dynamic_cast<simboard::BoardLink*>(lk.get());
    if (bl) {
      eo.estop_press = [bl] { bl->board().set_estop(true); };
      eo.estop_release = [bl] { bl->board().set_estop(false); };
    }
  }

  fmt::print("grbl 1.1 front end for {}; settings {}\n", behind, settings_path);
  std::fflush(stdout);

  grbl::Engine engine(*lk, cfg, settings, eo);
  engine.connect();
  engine.take_output();  // the banner goes to each sender when it connects

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);
  char buf[4096];
  std::optional<std::chrono::steady_clock::time_point> banner_at;
  while (!g_stop) {
    // Is a sender on the pty? (POLLHUP on the master while no one has the slave open.)
    if (pty.fd >= 0) {
      pollfd q{pty.fd, POLLIN, 0};
      ::poll(&q, 1, 0);
      const bool open_now = !(q.revents & POLLHUP);
      if (open_now && !pty.connected) {
        pty.connected = true;
        // A sender sets up its port (termios, flushes) right after opening it: the banner
        // comes 100 ms later, as a grbl board's comes after its boot.
        banner_at = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      } else if (!open_now && pty.connected) {
        pty.connected = false;
        pty.pending.clear();
        banner_at.reset();
      }
      if (banner_at && std::chrono::steady_clock::now() >= *banner_at) {
        banner_at.reset();
        engine.opened();
      }
    }
    std::vector<pollfd> fds;
    if (pty.connected) fds.push_back({pty.fd, POLLIN, 0});
    if (tcp.connected) fds.push_back({tcp.fd, POLLIN, 0});
    if (listen_fd >= 0) fds.push_back({listen_fd, POLLIN, 0});
    ::poll(fds.data(), fds.size(), engine.busy() ? 0 : banner_at ? 5 : 20);
    for (const auto& f : fds) {
      if (!(f.revents & (POLLIN | POLLHUP | POLLERR))) continue;
      if (f.fd == listen_fd) {
        const int c = ::accept(listen_fd, nullptr, nullptr);
        if (c >= 0) {
          if (tcp.connected) ::close(tcp.fd);
          set_nonblocking(c);
          tcp = Peer{c, true, {}};
          engine.opened();
        }
        continue;
      }
      Peer& p = f.fd == pty.fd ? pty : tcp;
      const ssize_t n = ::read(p.fd, buf, sizeof buf);
      if (n > 0) {
        engine.receive(std::string_view(buf, static_cast<size_t>(n)));
      } else if (&p == &tcp && (n == 0 || (errno != EAGAIN && errno != EINTR))) {
        ::close(tcp.fd);
        tcp = Peer{};
      }
    }
    engine.step(std::chrono::milliseconds(engine.busy() ? 5 : 0));
    const std::string out = engine.take_output();
    for (Peer* p : {&pty, &tcp}) {
      if (!p->connected) continue;
      p->pending += out;
      flush_peer(*p);
    }
  }
  const auto& s = engine.stats();
  fmt::print(
      "grbl: {} lines ({} ok, {} errors), {} status reports, {} frames, {} flushes, {} "
      "soft resets\n",
      s.lines, s.oks, s.errors, s.reports, s.frames, s.flushes, s.resets);
  if (pty.fd >= 0) ::close(pty.fd);
  if (tcp.connected) ::close(tcp.fd);
  if (listen_fd >= 0) ::close(listen_fd);
}

}  // namespace

void register_grbl(CLI::App& app) {
  auto args = std::make_shared<Args>();
  auto* sub = app.add_subcommand(
      "grbl",
      "Serve grbl 1.1's protocol on a new pty (its path is the first line on stdout) and on TCP, "
      "with the FPGA behind it (a real --port, or the simulated board)");
  sub->add_option("--config", args->common.config_path, "machine configuration (TOML)");
  sub->add_option("--port", args->port, "the controller's serial port (default: simulated board)");
  sub->add_option("--model", args->model,
                  "simulated board: tlm (the SystemC twins, default) or rtl (the Verilated "
                  "cnc_core: soft reset mid-job presses its e-stop)")
      ->check(CLI::IsMember({"tlm", "rtl"}));
  sub->add_option("--listen", args->listen,
                  "also serve on TCP, tcp:HOST:PORT (PORT 0: any free port, printed)");
  sub->add_option("--settings", args->settings,
                  "grbl $ settings file (default $XDG_CONFIG_HOME/fpgacnc/grbl-settings.txt or "
                  "~/.config/fpgacnc/grbl-settings.txt)");
  sub->add_flag("--realtime", args->realtime,
                "tlm: simulated time follows the wall clock while the board is busy");
  sub->add_flag("--no-pty", args->no_pty, "serve on TCP only (first line: '-')");
  sub->callback([args] {
    if (args->no_pty && args->listen.empty())
      throw std::invalid_argument("grbl: --no-pty needs --listen tcp:HOST:PORT");
    run(*args);
  });
}

}  // namespace fpgacnc::cli
