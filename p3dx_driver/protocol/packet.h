// P2OS/ARCOS packet framing: 0xFA 0xFB | LEN | payload | CHK_hi CHK_lo.
//
// LEN counts the bytes after it (payload plus the two checksum bytes). The
// checksum sums the payload as big-endian byte pairs into 16 bits and XORs a
// left-over odd byte into the low byte (see ../shared/docs/PROTOCOLS.md §1).
// The decoder verifies every checksum, resynchronises on the header after
// garbage, and counts what it throws away: bad data never reaches the caller.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace p3dx {

constexpr uint8_t kHeader0 = 0xFA;
constexpr uint8_t kHeader1 = 0xFB;
// Largest whole packet (header, LEN, payload, checksum) a robot sends.
constexpr size_t kMaxPacketBytes = 200;
// Smallest LEN: one payload byte (the command / packet type) plus checksum.
constexpr size_t kMinLength = 3;
constexpr size_t kMaxLength = kMaxPacketBytes - 3;
constexpr size_t kMaxPayloadBytes = kMaxLength - 2;

// The P2OS checksum of `size` payload bytes.
uint16_t checksum(const uint8_t* payload, size_t size);

// Frames `payload` (1..kMaxPayloadBytes bytes) into a complete packet.
// An empty or oversized payload is a programming error (asserts).
std::vector<uint8_t> encodePacket(const std::vector<uint8_t>& payload);

struct DecoderStats {
  uint64_t packets = 0;          // packets with a good checksum, delivered
  uint64_t checksum_errors = 0;  // framed packets whose checksum did not match
  uint64_t length_errors = 0;    // headers with an impossible LEN byte
  uint64_t discarded_bytes = 0;  // bytes skipped while looking for a header
};

// Incremental decoder: feed it whatever the link delivered, in any chunks.
class PacketDecoder {
 public:
  // Appends the payload of every complete, checksum-valid packet to
  // `payloads`. Returns the number of payloads appended.
  size_t feed(const uint8_t* data, size_t size, std::vector<std::vector<uint8_t>>* payloads);

  // Forgets buffered partial data (e.g. after a reconnect). Keeps stats.
  void clear() { buffer_.clear(); }
  const DecoderStats& stats() const { return stats_; }
  size_t buffered() const { return buffer_.size(); }

 private:
  // Drops `count` leading bytes of the buffer.
  void discard(size_t count);

  std::vector<uint8_t> buffer_;
  DecoderStats stats_;
};

}  // namespace p3dx
