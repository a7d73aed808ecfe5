#include "serial_io/pseudo_terminal.h"

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "serial_io/termios_util.h"

namespace serial_io {

PseudoTerminal::~PseudoTerminal() { close(); }

bool PseudoTerminal::open(const std::string& link_path) {
  close();
  link_path_ = link_path;
  error_.clear();

  const int master = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (master < 0) {
    error_ = std::string("posix_openpt failed: ") + std::strerror(errno);
    return false;
  }
  if (::grantpt(master) != 0 || ::unlockpt(master) != 0) {
    error_ = std::string("grantpt/unlockpt failed: ") + std::strerror(errno);
    ::close(master);
    return false;
  }
  char name[128];
  if (::ptsname_r(master, name, sizeof(name)) != 0) {
    error_ = std::string("ptsname failed: ") + std::strerror(errno);
    ::close(master);
    return false;
  }
  const int slave = ::open(name, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (slave < 0) {
    error_ = std::string(name) + ": cannot open pty slave: " + std::strerror(errno);
    ::close(master);
    return false;
  }
  // Raw mode on the slave so that no line discipline rewrites binary data
  // (CR/LF mapping, echo, ^C) before the driver sets its own mode.
  if (!configureRaw(slave, B9600, &error_)) {
    ::close(slave);
    ::close(master);
    return false;
  }

  if (!link_path_.empty()) {
    struct stat st {};
    if (::lstat(link_path_.c_str(), &st) == 0) {
      if (!S_ISLNK(st.st_mode)) {
        error_ = link_path_ + " exists and is not a symlink; refusing to replace it";
        ::close(slave);
        ::close(master);
        return false;
      }
      ::unlink(link_path_.c_str());
    }
    if (::symlink(name, link_path_.c_str()) != 0) {
      error_ = link_path_ + ": cannot create symlink: " + std::strerror(errno);
      ::close(slave);
      ::close(master);
      return false;
    }
  }
  master_fd_ = master;
  slave_keepalive_fd_ = slave;
  slave_path_ = name;
  return true;
}

std::string PseudoTerminal::devicePath() const {
  return link_path_.empty() ? slave_path_ : link_path_;
}

int PseudoTerminal::peerBaud() const {
  if (slave_keepalive_fd_ < 0) return 0;
  termios tio{};
  if (tcgetattr(slave_keepalive_fd_, &tio) != 0) return 0;
  return speedToBaud(cfgetospeed(&tio));
}

void PseudoTerminal::unplug() {
  const std::string link = link_path_;
  close();
  link_path_ = link;  // remembered for replug()
}

bool PseudoTerminal::replug() { return open(link_path_); }

ReadResult PseudoTerminal::read(uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) {
  ReadResult result;
  if (master_fd_ < 0) {
    result.status = IoStatus::kClosed;
    return result;
  }
  return pollRead(master_fd_, buffer, size, timeout);
}

IoStatus PseudoTerminal::write(const uint8_t* data, size_t size) {
  if (master_fd_ < 0) return IoStatus::kClosed;
  // Like a real wire, bytes that nobody reads are lost rather than blocking
  // the device: wait briefly for room, then drop what does not fit.
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(master_fd_, data + done, size - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd pfd{master_fd_, POLLOUT, 0};
      if (::poll(&pfd, 1, 50) <= 0) return IoStatus::kOk;  // overrun: rest dropped
      continue;
    }
    return IoStatus::kClosed;
  }
  return IoStatus::kOk;
}

void PseudoTerminal::close() {
  if (slave_keepalive_fd_ >= 0) {
    ::close(slave_keepalive_fd_);
    slave_keepalive_fd_ = -1;
  }
  if (master_fd_ >= 0) {
    ::close(master_fd_);
    master_fd_ = -1;
  }
  removeLink();
  slave_path_.clear();
}

void PseudoTerminal::removeLink() {
  if (link_path_.empty()) return;
  struct stat st {};
  if (::lstat(link_path_.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    ::unlink(link_path_.c_str());
  }
}

}  // namespace serial_io
