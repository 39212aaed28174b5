#include "fpgacnc/link/serial_link.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <libserialport.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace fpgacnc::link {
namespace {

std::string sp_message() {
  char* m = sp_last_error_message();
  std::string s = m ? m : "unknown error";
  if (m) sp_free_error_message(m);
  return s;
}

speed_t termios_speed(uint32_t baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    case 1000000:
      return B1000000;
    case 2000000:
      return B2000000;
    case 3000000:
      return B3000000;
    default:
      return B0;
  }
}

}  // namespace

// Two back ends: libserialport (the normal path, all platforms), and a POSIX termios fallback
// used ONLY when libserialport refuses a pseudo-terminal (a path resolving to /dev/pts/N):
// libserialport 0.1.1 (Debian 12) fails sp_get_port_by_name() on every pty with "No such file or
// directory" because it looks the device up in sysfs, where ptys have no entry. Real ports never
// take the fallback; their libserialport error is reported as is.
struct SerialLink::Impl {
  sp_port* sp = nullptr;
  int fd = -1;  // termios fallback

  ~Impl() {
    if (sp) {
      sp_close(sp);
      sp_free_port(sp);
    }
    if (fd >= 0) ::close(fd);
  }
};

SerialLink::SerialLink(const std::string& port, uint32_t baud)
    : port_(port), impl_(std::make_unique<Impl>()) {
  if (port.empty()) throw Error("serial port: no port name given");
  std::string sp_error;
  sp_port* p = nullptr;
  if (sp_get_port_by_name(port.c_str(), &p) != SP_OK) {
    sp_error = sp_message();
  } else if (sp_open(p, SP_MODE_READ_WRITE) != SP_OK) {
    sp_error = sp_message();
    sp_free_port(p);
  } else {
    impl_->sp = p;
    if (sp_set_baudrate(p, static_cast<int>(baud)) != SP_OK || sp_set_bits(p, 8) != SP_OK ||
        sp_set_parity(p, SP_PARITY_NONE) != SP_OK || sp_set_stopbits(p, 1) != SP_OK ||
        sp_set_flowcontrol(p, SP_FLOWCONTROL_NONE) != SP_OK) {
      sp_error = sp_message();
      sp_close(p);
      sp_free_port(p);
      impl_->sp = nullptr;
    }
  }
  if (impl_->sp) return;

  // Pseudo-terminal: the resolved path is a /dev/pts/N slave (symlinks such as a simulated
  // board's stable name are followed).
  bool is_pty = false;
  if (char* real = ::realpath(port.c_str(), nullptr)) {
    is_pty = std::strncmp(real, "/dev/pts/", 9) == 0;
    std::free(real);
  }
  if (!is_pty) {
    throw Error(fmt::format("serial port {}: cannot open: {}", port, sp_error));
  }
  const int fd = ::open(port.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    throw Error(fmt::format("serial port {}: cannot open: {} (libserialport: {})", port,
                            std::strerror(errno), sp_error));
  }
  impl_->fd = fd;
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    throw Error(fmt::format("serial port {}: not a terminal: {} (libserialport: {})", port,
                            std::strerror(errno), sp_error));
  }
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS);
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (const speed_t s = termios_speed(baud); s != B0) {
    ::cfsetispeed(&t, s);
    ::cfsetospeed(&t, s);
  }
  if (::tcsetattr(fd, TCSANOW, &t) != 0) {
    throw Error(fmt::format("serial port {}: cannot configure 8N1 at {} baud: {}", port, baud,
                            std::strerror(errno)));
  }
}

SerialLink::~SerialLink() = default;

bool SerialLink::using_posix_fallback() const {
  return impl_->fd >= 0;
}

int SerialLink::native_fd() const {
  if (impl_->fd >= 0) return impl_->fd;
  int fd = -1;
  if (sp_get_port_handle(impl_->sp, &fd) != SP_OK) {
    throw Error(fmt::format("serial port {}: no descriptor: {}", port_, sp_message()));
  }
  return fd;
}

void SerialLink::write(std::span<const uint8_t> bytes) {
  if (impl_->sp) {
    const auto r = sp_blocking_write(impl_->sp, bytes.data(), bytes.size(), 0);
    if (r < 0 || static_cast<size_t>(r) != bytes.size()) {
      throw Error(fmt::format("serial port {}: write failed: {}", port_, sp_message()));
    }
    return;
  }
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t r = ::write(impl_->fd, bytes.data() + done, bytes.size() - done);
    if (r < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      throw Error(fmt::format("serial port {}: write failed: {}", port_, std::strerror(errno)));
    }
    done += static_cast<size_t>(r);
  }
  ::tcdrain(impl_->fd);
}

std::optional<uint8_t> SerialLink::read_byte(std::chrono::milliseconds timeout) {
  uint8_t b = 0;
  if (impl_->sp) {
    // libserialport: a timeout of 0 means "wait forever", so poll without blocking instead.
    const auto r = timeout.count() <= 0
                       ? sp_nonblocking_read(impl_->sp, &b, 1)
                       : sp_blocking_read(impl_->sp, &b, 1, static_cast<unsigned>(timeout.count()));
    if (r < 0) throw Error(fmt::format("serial port {}: read failed: {}", port_, sp_message()));
    if (r == 0) return std::nullopt;
    return b;
  }
  pollfd pfd{impl_->fd, POLLIN, 0};
  const int pr = ::poll(&pfd, 1, static_cast<int>(std::max<int64_t>(timeout.count(), 0)));
  if (pr < 0) {
    if (errno == EINTR) return std::nullopt;
    throw Error(fmt::format("serial port {}: poll failed: {}", port_, std::strerror(errno)));
  }
  if (pr == 0) return std::nullopt;
  const ssize_t r = ::read(impl_->fd, &b, 1);
  if (r == 1) return b;
  if (r < 0 && errno != EAGAIN && errno != EINTR) {
    throw Error(fmt::format("serial port {}: read failed: {}", port_, std::strerror(errno)));
  }
  return std::nullopt;
}

void SerialLink::flush_input() {
  if (impl_->sp) {
    sp_flush(impl_->sp, SP_BUF_INPUT);
  } else {
    ::tcflush(impl_->fd, TCIFLUSH);
  }
}

}  // namespace fpgacnc::link
