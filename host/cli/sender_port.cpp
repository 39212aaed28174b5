#include "sender_port.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "fpgacnc/link/serial_link.h"
#include "fpgacnc/simboard/cli_board.h"
#include "fpgacnc/simboard/runner.h"
#include "fpgacnc/twins/twin_board.h"

namespace fpgacnc::cli {

void add_board_options(CLI::App* sub, BoardChoice& choice, const std::string& model_help) {
  sub->add_option("--port", choice.port, "the controller's serial port (default: simulated board)");
  sub->add_option("--model", choice.model, model_help)->check(CLI::IsMember({"tlm", "rtl"}));
}

BoardBehind open_board_behind(const config::MachineConfig& cfg, const BoardChoice& choice) {
  BoardBehind b;
  if (choice.realtime && (!choice.port.empty() || choice.model != "tlm"))
    throw std::invalid_argument("--realtime needs the twin board (--model tlm, no --port)");
  if (!choice.port.empty()) {
    b.link = std::make_unique<link::SerialLink>(choice.port, cfg.baud);
    b.description = choice.port;
  } else if (choice.model == "tlm") {
    twins::TwinBoardOptions o = twins::TwinBoard::options_from_config(cfg);
    o.realtime = choice.realtime;
    b.link = simboard::make_board_link(std::make_unique<twins::TwinBoard>(o), cfg.baud, {});
    b.description = "the simulated board (tlm)";
  } else {
    b.link = simboard::make_default_link(cfg, {});
    b.description = "the simulated board (rtl)";
    b.rtl = true;
    if (auto* bl = dynamic_cast<simboard::BoardLink*>(b.link.get())) {
      b.estop_press = [bl] { bl->board().set_estop(true); };
      b.estop_release = [bl] { bl->board().set_estop(false); };
    }
  }
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

}  // namespace fpgacnc::cli
