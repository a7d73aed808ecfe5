#include "p3dx_driver/protocol/packet.h"

#include <algorithm>
#include <cassert>

namespace p3dx {

uint16_t checksum(const uint8_t* payload, size_t size) {
  uint16_t sum = 0;
  size_t i = 0;
  for (; i + 1 < size; i += 2) {
    sum = static_cast<uint16_t>(sum + ((payload[i] << 8) | payload[i + 1]));
  }
  if (i < size) sum ^= payload[i];
  return sum;
}

std::vector<uint8_t> encodePacket(const std::vector<uint8_t>& payload) {
  assert(!payload.empty() && payload.size() <= kMaxPayloadBytes);
  std::vector<uint8_t> packet;
  packet.reserve(payload.size() + 5);
  packet.push_back(kHeader0);
  packet.push_back(kHeader1);
  packet.push_back(static_cast<uint8_t>(payload.size() + 2));
  packet.insert(packet.end(), payload.begin(), payload.end());
  const uint16_t sum = checksum(payload.data(), payload.size());
  packet.push_back(static_cast<uint8_t>(sum >> 8));
  packet.push_back(static_cast<uint8_t>(sum & 0xFF));
  return packet;
}

void PacketDecoder::discard(size_t count) {
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(count));
}

size_t PacketDecoder::feed(const uint8_t* data, size_t size,
                           std::vector<std::vector<uint8_t>>* payloads) {
  buffer_.insert(buffer_.end(), data, data + size);
  size_t delivered = 0;
  while (!buffer_.empty()) {
    // Skip to the next 0xFA 0xFB (a lone trailing 0xFA may start a header).
    size_t start = 0;
    while (start < buffer_.size()) {
      if (buffer_[start] == kHeader0 &&
          (start + 1 == buffer_.size() || buffer_[start + 1] == kHeader1)) {
        break;
      }
      ++start;
    }
    if (start > 0) {
      stats_.discarded_bytes += start;
      discard(start);
    }
    if (buffer_.size() < 3) break;
    const size_t length = buffer_[2];
    if (length < kMinLength || length > kMaxLength) {
      ++stats_.length_errors;
      stats_.discarded_bytes += 2;
      discard(2);
      continue;
    }
    if (buffer_.size() < 3 + length) break;  // wait for the rest
    const uint8_t* payload = buffer_.data() + 3;
    const size_t payload_size = length - 2;
    const uint16_t received =
        static_cast<uint16_t>((payload[payload_size] << 8) | payload[payload_size + 1]);
    if (received != checksum(payload, payload_size)) {
      // The header may have been garbage that looked like one: resync from
      // the byte after it, so a real packet inside is not lost.
      ++stats_.checksum_errors;
      stats_.discarded_bytes += 2;
      discard(2);
      continue;
    }
    payloads->emplace_back(payload, payload + payload_size);
    ++stats_.packets;
    ++delivered;
    discard(3 + length);
  }
  return delivered;
}

}  // namespace p3dx
