#include "serial_io/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "serial_io/termios_util.h"

namespace serial_io {

SerialPort::~SerialPort() { close(); }

bool SerialPort::open(const std::string& path, int baud) {
  close();
  path_ = path;
  error_.clear();
  const speed_t speed = baudToSpeed(baud);
  if (speed == 0) {
    error_ = path + ": baud " + std::to_string(baud) +
             " is not a standard rate (a custom divisor is not supported)";
    return false;
  }
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    error_ = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  if (!configureRaw(fd, speed, &error_)) {
    error_ = path + ": " + error_;
    ::close(fd);
    return false;
  }
  fd_ = fd;
  baud_ = baud;
  tcflush(fd_, TCIOFLUSH);
  return true;
}

bool SerialPort::setBaud(int baud) {
  if (fd_ < 0) return false;
  const speed_t speed = baudToSpeed(baud);
  if (speed == 0) {
    error_ = path_ + ": baud " + std::to_string(baud) + " is not a standard rate";
    return false;
  }
  tcdrain(fd_);
  termios tio{};
  if (tcgetattr(fd_, &tio) != 0 || cfsetispeed(&tio, speed) != 0 || cfsetospeed(&tio, speed) != 0 ||
      tcsetattr(fd_, TCSANOW, &tio) != 0) {
    error_ = path_ + ": cannot set baud " + std::to_string(baud) + ": " + std::strerror(errno);
    return false;
  }
  baud_ = baud;
  return true;
}

void SerialPort::flush() {
  if (fd_ >= 0) tcflush(fd_, TCIOFLUSH);
}

ReadResult SerialPort::read(uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) {
  ReadResult result;
  if (fd_ < 0) {
    result.status = IoStatus::kClosed;
    return result;
  }
  result = pollRead(fd_, buffer, size, timeout);
  if (result.status == IoStatus::kClosed) {
    error_ = path_ + ": device closed or unplugged";
  }
  return result;
}

IoStatus SerialPort::write(const uint8_t* data, size_t size) {
  if (fd_ < 0) return IoStatus::kClosed;
  const IoStatus status = writeAll(fd_, data, size);
  if (status == IoStatus::kClosed) error_ = path_ + ": write failed: " + std::strerror(errno);
  return status;
}

void SerialPort::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

bool isStandardBaud(int baud) { return baudToSpeed(baud) != 0; }

}  // namespace serial_io
