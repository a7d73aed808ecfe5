#include "serial_io/termios_util.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace serial_io {
namespace {

struct BaudEntry {
  int baud;
  speed_t speed;
};

constexpr BaudEntry kBaudTable[] = {
    {1200, B1200},       {2400, B2400},       {4800, B4800},       {9600, B9600},
    {19200, B19200},     {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400},   {460800, B460800},   {500000, B500000},   {576000, B576000},
    {921600, B921600},   {1000000, B1000000}, {1152000, B1152000}, {1500000, B1500000},
    {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000}, {3500000, B3500000},
    {4000000, B4000000},
};

}  // namespace

speed_t baudToSpeed(int baud) {
  for (const BaudEntry& entry : kBaudTable) {
    if (entry.baud == baud) return entry.speed;
  }
  return 0;
}

int speedToBaud(speed_t speed) {
  for (const BaudEntry& entry : kBaudTable) {
    if (entry.speed == speed) return entry.baud;
  }
  return 0;
}

bool configureRaw(int fd, speed_t speed, std::string* error) {
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    *error = std::string("tcgetattr failed (not a terminal?): ") + std::strerror(errno);
    return false;
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~(CSTOPB | PARENB | CRTSCTS);
  tio.c_iflag &= ~(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (cfsetispeed(&tio, speed) != 0 || cfsetospeed(&tio, speed) != 0) {
    *error = std::string("cannot set line speed: ") + std::strerror(errno);
    return false;
  }
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    *error = std::string("tcsetattr failed: ") + std::strerror(errno);
    return false;
  }
  return true;
}

ReadResult pollRead(int fd, uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) {
  ReadResult result;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    const auto remaining = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd pfd{fd, POLLIN, 0};
    const int ready =
        ::poll(&pfd, 1, remaining.count() > 0 ? static_cast<int>(remaining.count()) : 0);
    if (ready < 0) {
      if (errno == EINTR) continue;
      result.status = IoStatus::kClosed;
      return result;
    }
    if (ready == 0) {
      result.status = IoStatus::kTimeout;
      return result;
    }
    if (pfd.revents & POLLIN) {
      const ssize_t n = ::read(fd, buffer, size);
      if (n > 0) {
        result.status = IoStatus::kOk;
        result.bytes = static_cast<size_t>(n);
        return result;
      }
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      // n == 0 (EOF) or EIO: the device went away.
      result.status = IoStatus::kClosed;
      return result;
    }
    if (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) {
      result.status = IoStatus::kClosed;
      return result;
    }
  }
}

IoStatus writeAll(int fd, const uint8_t* data, size_t size) {
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd pfd{fd, POLLOUT, 0};
      if (::poll(&pfd, 1, 1000) <= 0 || (pfd.revents & (POLLHUP | POLLERR | POLLNVAL))) {
        return IoStatus::kClosed;
      }
      continue;
    }
    return IoStatus::kClosed;
  }
  return IoStatus::kOk;
}

}  // namespace serial_io
