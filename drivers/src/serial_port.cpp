#include "liod/drivers/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace liod::drivers {
namespace {

speed_t speed_of(int baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 2000000: return B2000000;
    case 3000000: return B3000000;
    case 4000000: return B4000000;
    default: throw std::runtime_error("unsupported serial baud rate " + std::to_string(baud));
  }
}

}  // namespace

SerialPort::SerialPort(const std::string& device, int baud) : baud_(baud) {
  const speed_t speed = speed_of(baud);
  fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error("cannot open serial device " + device + ": " + std::strerror(errno));
  termios t{};
  if (::tcgetattr(fd_, &t) == 0) {
    ::cfmakeraw(&t);
    t.c_cflag |= CLOCAL | CREAD;
    t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
    ::cfsetispeed(&t, speed);
    ::cfsetospeed(&t, speed);
    t.c_cc[VMIN] = 0;
    t.c_cc[VTIME] = 0;
    ::tcsetattr(fd_, TCSANOW, &t);  // a pseudo-terminal ignores the speed; that is fine
  }
}

SerialPort::~SerialPort() { ::close(fd_); }

std::size_t SerialPort::read(std::span<std::uint8_t> buffer, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r <= 0) return 0;
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n > 0) return static_cast<std::size_t>(n);
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
  if ((p.revents & (POLLHUP | POLLERR)) != 0 || n < 0) {
    throw std::runtime_error(std::string("serial device lost: ") + (n < 0 ? std::strerror(errno) : "hang-up"));
  }
  return 0;
}

}  // namespace liod::drivers
