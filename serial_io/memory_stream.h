// An in-memory ByteStream for unit tests and fuzzers: reads come from a
// buffer the test fills, writes are collected for inspection.
#pragma once

#include <deque>
#include <vector>

#include "serial_io/byte_stream.h"

namespace serial_io {

class MemoryStream : public ByteStream {
 public:
  void feed(const std::vector<uint8_t>& bytes) {
    input_.insert(input_.end(), bytes.begin(), bytes.end());
  }
  const std::vector<uint8_t>& written() const { return written_; }
  void clearWritten() { written_.clear(); }

  ReadResult read(uint8_t* buffer, size_t size, std::chrono::milliseconds) override {
    ReadResult result;
    if (!open_) {
      result.status = IoStatus::kClosed;
      return result;
    }
    while (result.bytes < size && !input_.empty()) {
      buffer[result.bytes++] = input_.front();
      input_.pop_front();
    }
    result.status = result.bytes > 0 ? IoStatus::kOk : IoStatus::kTimeout;
    return result;
  }
  IoStatus write(const uint8_t* data, size_t size) override {
    if (!open_) return IoStatus::kClosed;
    written_.insert(written_.end(), data, data + size);
    return IoStatus::kOk;
  }
  bool isOpen() const override { return open_; }
  void close() override { open_ = false; }
  std::string name() const override { return "memory"; }

 private:
  std::deque<uint8_t> input_;
  std::vector<uint8_t> written_;
  bool open_ = true;
};

}  // namespace serial_io
