// A serial device (real tty, USB adapter or the slave side of a pty) opened
// in raw 8N1 mode with non-blocking, poll()-timed reads.
#pragma once

#include <string>

#include "serial_io/byte_stream.h"

namespace serial_io {

// Returns true when `baud` is a rate termios can set without a custom
// divisor (9600 ... 4000000 standard rates).
bool isStandardBaud(int baud);

class SerialPort : public ByteStream {
 public:
  SerialPort() = default;
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  // Opens `path` raw 8N1, no flow control, at `baud`. On failure returns false
  // and error() names the path and the system error.
  bool open(const std::string& path, int baud);

  // Changes the line speed of an open port (draining pending output first).
  bool setBaud(int baud);
  int baud() const { return baud_; }

  // Discards bytes received but not read, and bytes written but not sent.
  void flush();

  ReadResult read(uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) override;
  IoStatus write(const uint8_t* data, size_t size) override;
  bool isOpen() const override { return fd_ >= 0; }
  void close() override;
  std::string name() const override { return path_; }

  const std::string& error() const { return error_; }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  int baud_ = 0;
  std::string path_;
  std::string error_;
};

}  // namespace serial_io
