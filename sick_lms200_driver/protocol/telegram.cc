#include "sick_lms200_driver/protocol/telegram.h"

#include "sick_lms200_driver/protocol/crc.h"

namespace sick_lms200 {

int baudModeByte(int baud) {
  switch (baud) {
    case 9600:
      return mode::kBaud9600;
    case 19200:
      return mode::kBaud19200;
    case 38400:
      return mode::kBaud38400;
    case 500000:
      return mode::kBaud500000;
    default:
      return -1;
  }
}

int baudForModeByte(uint8_t mode_byte) {
  switch (mode_byte) {
    case mode::kBaud9600:
      return 9600;
    case mode::kBaud19200:
      return 19200;
    case mode::kBaud38400:
      return 38400;
    case mode::kBaud500000:
      return 500000;
    default:
      return 0;
  }
}

std::vector<uint8_t> encodeTelegram(uint8_t address, uint8_t command,
                                    const std::vector<uint8_t>& data) {
  const size_t length = data.size() + 1;
  std::vector<uint8_t> bytes;
  bytes.reserve(length + kTelegramOverhead);
  bytes.push_back(kStx);
  bytes.push_back(address);
  bytes.push_back(static_cast<uint8_t>(length & 0xFF));
  bytes.push_back(static_cast<uint8_t>(length >> 8));
  bytes.push_back(command);
  bytes.insert(bytes.end(), data.begin(), data.end());
  const uint16_t crc = lmsCrc16(bytes.data(), bytes.size());
  bytes.push_back(static_cast<uint8_t>(crc & 0xFF));
  bytes.push_back(static_cast<uint8_t>(crc >> 8));
  return bytes;
}

void TelegramDecoder::feed(const uint8_t* data, size_t size) {
  buffer_.insert(buffer_.end(), data, data + size);
  bytes_fed_ += size;
  decode();
}

bool TelegramDecoder::next(DecoderEvent* event) {
  if (events_.empty()) return false;
  *event = std::move(events_.front());
  events_.pop_front();
  return true;
}

void TelegramDecoder::reset() {
  consumed_ += buffer_.size() - start_;
  buffer_.clear();
  start_ = 0;
  events_.clear();
}

void TelegramDecoder::consume(size_t count) {
  start_ += count;
  consumed_ += count;
}

void TelegramDecoder::decode() {
  while (start_ < buffer_.size()) {
    const uint8_t* head = buffer_.data() + start_;
    const size_t available = buffer_.size() - start_;
    if (head[0] != kStx) {
      if (head[0] == kAck || head[0] == kNak) {
        DecoderEvent event;
        event.kind = head[0] == kAck ? DecoderEvent::Kind::kAck : DecoderEvent::Kind::kNak;
        event.end_position = consumed_ + 1;
        (head[0] == kAck ? stats_.acks : stats_.naks)++;
        events_.push_back(std::move(event));
      } else {
        stats_.discarded_bytes++;
      }
      consume(1);
      continue;
    }
    if (available < 2) break;
    if (head[1] != expected_address_) {
      stats_.bad_frames++;
      stats_.discarded_bytes++;
      consume(1);
      continue;
    }
    if (available < 4) break;
    const size_t length = head[2] | (static_cast<size_t>(head[3]) << 8);
    if (length == 0 || length > kMaxTelegramLength) {
      stats_.bad_frames++;
      stats_.discarded_bytes++;
      consume(1);
      continue;
    }
    const size_t total = length + kTelegramOverhead;
    if (available < total) break;  // wait for the rest
    const uint16_t expected = lmsCrc16(head, total - 2);
    const uint16_t received = head[total - 2] | (static_cast<uint16_t>(head[total - 1]) << 8);
    if (expected != received) {
      // Either a corrupted telegram or an STX inside other data: skip only
      // the STX so that a real telegram starting inside is still found.
      stats_.crc_errors++;
      stats_.discarded_bytes++;
      consume(1);
      continue;
    }
    DecoderEvent event;
    event.kind = DecoderEvent::Kind::kTelegram;
    event.telegram.address = head[1];
    event.telegram.command = head[4];
    event.telegram.data.assign(head + 5, head + total - 2);
    event.end_position = consumed_ + total;
    stats_.telegrams++;
    events_.push_back(std::move(event));
    consume(total);
  }
  // Compact so the buffer does not grow without bound.
  if (start_ > 4096 || start_ == buffer_.size()) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
    start_ = 0;
  }
}

}  // namespace sick_lms200
