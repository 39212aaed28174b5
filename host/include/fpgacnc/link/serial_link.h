// Serial port link (libserialport): /dev/ttyUSB0, COM3, or a pseudo-terminal such as
// /dev/pts/5. 8N1, no flow control, the configured baud rate.
#pragma once

#include <memory>
#include <string>

#include "fpgacnc/link/link.h"

namespace fpgacnc::link {

class SerialLink : public Link {
 public:
  // Opens and configures the port; throws link::Error naming the port.
  SerialLink(const std::string& port, uint32_t baud);
  ~SerialLink() override;
  SerialLink(const SerialLink&) = delete;
  SerialLink& operator=(const SerialLink&) = delete;

  void write(std::span<const uint8_t> bytes) override;
  std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) override;
  void flush_input() override;
  std::string name() const override { return port_; }
  // True when libserialport refused the device and the POSIX termios fallback is in use.
  bool using_posix_fallback() const;
  // The open port's file descriptor, for poll() beside other descriptors (read through
  // read_byte() only).
  int native_fd() const;

 private:
  struct Impl;
  std::string port_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fpgacnc::link
