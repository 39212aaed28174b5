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
#include "sender_port.h"

namespace fpgacnc::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
  g_stop = 1;
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

struct Args {
  CommonOptions common;
  BoardChoice board;
  std::string listen;
  std::string settings;
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

  BoardBehind board = open_board_behind(cfg, args.board);
  grbl::EngineOptions eo;
  eo.v2 = link::stream_v2_options(cfg);
  eo.settings_path = settings_path;
  eo.estop_press = board.estop_press;
  eo.estop_release = board.estop_release;
  const std::string& behind = board.description;
  fmt::print("grbl 1.1 front end for {}; settings {}\n", behind, settings_path);
  std::fflush(stdout);

  grbl::Engine engine(*board.link, cfg, settings, eo);
  engine.connect();
  engine.take_output();  // the banner goes to each sender when it connects

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);
  char buf[4096];
  SenderWatch watch;
  while (!g_stop) {
    if (watch.poll(pty)) engine.opened();
    std::vector<pollfd> fds;
    if (pty.connected) fds.push_back({pty.fd, POLLIN, 0});
    if (tcp.connected) fds.push_back({tcp.fd, POLLIN, 0});
    if (listen_fd >= 0) fds.push_back({listen_fd, POLLIN, 0});
    ::poll(fds.data(), fds.size(), engine.busy() ? 0 : watch.banner_pending() ? 5 : 20);
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
  add_board_options(sub, args->board,
                    "simulated board: tlm (the SystemC twins, default) or rtl (the Verilated "
                    "cnc_core: soft reset mid-job presses its e-stop)");
  sub->add_option("--listen", args->listen,
                  "also serve on TCP, tcp:HOST:PORT (PORT 0: any free port, printed)");
  sub->add_option("--settings", args->settings,
                  "grbl $ settings file (default $XDG_CONFIG_HOME/fpgacnc/grbl-settings.txt or "
                  "~/.config/fpgacnc/grbl-settings.txt)");
  sub->add_flag("--realtime", args->board.realtime,
                "tlm: simulated time follows the wall clock while the board is busy");
  sub->add_flag("--no-pty", args->no_pty, "serve on TCP only (first line: '-')");
  sub->callback([args] {
    if (args->no_pty && args->listen.empty())
      throw std::invalid_argument("grbl: --no-pty needs --listen tcp:HOST:PORT");
    run(*args);
  });
}

}  // namespace fpgacnc::cli
