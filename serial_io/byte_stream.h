// Byte-stream interface shared by the device drivers and their emulators.
//
// Protocol code (packet codecs, session state machines) talks to a
// ByteStream, never to a file descriptor, so the same code runs against a
// real serial port, a pseudo-terminal and an in-memory buffer in a fuzzer.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

namespace serial_io {

enum class IoStatus {
  kOk,       // at least one byte was transferred
  kTimeout,  // nothing arrived within the timeout (the link may still be fine)
  kClosed,   // the device is gone (unplugged, hung up, closed): reopen it
};

struct ReadResult {
  IoStatus status = IoStatus::kTimeout;
  size_t bytes = 0;  // bytes stored into the caller's buffer
};

class ByteStream {
 public:
  virtual ~ByteStream() = default;

  // Reads up to `size` bytes into `buffer`, waiting at most `timeout` for the
  // first byte. Returns as soon as some bytes are available.
  virtual ReadResult read(uint8_t* buffer, size_t size, std::chrono::milliseconds timeout) = 0;

  // Writes all `size` bytes (blocking until the kernel took them, or the
  // device failed). Returns kOk or kClosed.
  virtual IoStatus write(const uint8_t* data, size_t size) = 0;

  virtual bool isOpen() const = 0;
  virtual void close() = 0;

  // Human-readable name for log messages (device path).
  virtual std::string name() const = 0;
};

}  // namespace serial_io
