#pragma once
// A raw serial port (termios, 8N1, no flow control) with bounded reads. Boost.Asio's
// serial_port wraps the same termios calls; using them directly keeps every wait a bounded
// poll() (the driver thread must notice a stop request and feed the watchdog) and works on
// pseudo-terminals, which the tests use.

#include <cstdint>
#include <span>
#include <string>

namespace liod::drivers {

class SerialPort {
 public:
  /// Opens `device` raw at `baud` (standard rates up to 4 Mbaud). Throws std::runtime_error.
  SerialPort(const std::string& device, int baud);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  /// Waits up to `timeout_ms`, then reads what is there (0 on timeout). Throws when the device
  /// is gone (unplugged USB adapter).
  std::size_t read(std::span<std::uint8_t> buffer, int timeout_ms);
  int baud() const noexcept { return baud_; }

 private:
  int fd_ = -1;
  int baud_;
};

}  // namespace liod::drivers
