// Byte link to a controller: a serial port, later the simulated board.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

namespace fpgacnc::link {

// Link failures (open, configure, I/O, ACK timeout). what() names the port or the move.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Link {
 public:
  virtual ~Link() = default;
  // Writes all bytes (blocking until handed to the OS / device).
  virtual void write(std::span<const uint8_t> bytes) = 0;
  // One byte, or nullopt when none arrived within `timeout`.
  virtual std::optional<uint8_t> read_byte(std::chrono::milliseconds timeout) = 0;
  // Discards bytes received but not yet read.
  virtual void flush_input() = 0;
  // Human-readable name (port path) for messages.
  virtual std::string name() const = 0;
};

}  // namespace fpgacnc::link
