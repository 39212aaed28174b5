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

namespace fpgacnc::cli {

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

}  // namespace fpgacnc::cli
