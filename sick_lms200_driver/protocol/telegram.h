// LMS2xx telegram framing: STX | ADR | LEN (u16 LE) | CMD | data... | CRC (u16 LE).
// LEN counts CMD + data; in sensor replies the last data byte is the status
// byte. Outside telegrams the sensor sends single ACK (0x06) / NAK (0x15)
// bytes. TelegramDecoder is a streaming decoder that resynchronises after
// garbage, truncation and checksum errors; it never throws and never returns
// a telegram whose checksum failed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace sick_lms200 {

constexpr uint8_t kStx = 0x02;
constexpr uint8_t kAck = 0x06;
constexpr uint8_t kNak = 0x15;
constexpr uint8_t kHostAddress = 0x00;    // host → sensor
constexpr uint8_t kSensorAddress = 0x80;  // sensor → host (0x80 | sensor address 0)
constexpr uint8_t kReplyOffset = 0x80;    // reply CMD = request CMD + 0x80

// Command codes (host → sensor).
namespace cmd {
constexpr uint8_t kModeChange = 0x20;
constexpr uint8_t kRequestValues = 0x30;
constexpr uint8_t kStatus = 0x31;
constexpr uint8_t kErrors = 0x32;  // pending errors (reply: type/number pairs)
constexpr uint8_t kTypeString = 0x3A;
constexpr uint8_t kVariant = 0x3B;
constexpr uint8_t kReadConfig = 0x74;
constexpr uint8_t kWriteConfig = 0x77;
// Sensor → host: measured values (0x30 + 0x80), also streamed unrequested.
constexpr uint8_t kMeasuredValues = 0xB0;
}  // namespace cmd

// Mode-change data bytes (first data byte of a 0x20 telegram).
namespace mode {
constexpr uint8_t kInstallation = 0x00;  // followed by the password "SICK_LMS"
constexpr uint8_t kContinuousAll = 0x24;
constexpr uint8_t kRequestOnly = 0x25;  // stops continuous output
constexpr uint8_t kContinuousPartial = 0x2A;
constexpr uint8_t kBaud38400 = 0x40;
constexpr uint8_t kBaud19200 = 0x41;
constexpr uint8_t kBaud9600 = 0x42;
constexpr uint8_t kBaud500000 = 0x48;
}  // namespace mode

// Mode-change byte selecting `baud`, or -1 when the sensor has no such rate.
int baudModeByte(int baud);
// Inverse: the baud a mode byte selects, or 0 when the byte is not a baud mode.
int baudForModeByte(uint8_t mode_byte);

// Largest LEN accepted (CMD + info word + 721 values + status fits easily).
constexpr size_t kMaxTelegramLength = 1500;
// Bytes around the LEN-counted part: STX, ADR, LEN (2) before, CRC (2) after.
constexpr size_t kTelegramOverhead = 6;

struct Telegram {
  uint8_t address = 0;
  uint8_t command = 0;
  std::vector<uint8_t> data;  // everything after CMD (including a reply's status byte)
};

// Complete wire bytes of a telegram (with checksum).
std::vector<uint8_t> encodeTelegram(uint8_t address, uint8_t command,
                                    const std::vector<uint8_t>& data);

struct DecoderEvent {
  enum class Kind { kTelegram, kAck, kNak };
  Kind kind = Kind::kTelegram;
  Telegram telegram;  // valid for kTelegram
  // Stream position (count of bytes fed before it, +1) just after the event's
  // last byte; the caller compares it with bytesFed() to know how many bytes
  // of its last read arrived after the telegram.
  uint64_t end_position = 0;
};

struct DecoderStats {
  uint64_t telegrams = 0;
  uint64_t crc_errors = 0;       // well-framed telegrams whose checksum failed
  uint64_t bad_frames = 0;       // STX with an impossible address or length
  uint64_t discarded_bytes = 0;  // bytes skipped while resynchronising
  uint64_t acks = 0;
  uint64_t naks = 0;
};

class TelegramDecoder {
 public:
  // `expected_address`: kSensorAddress in a driver, kHostAddress in an emulator.
  explicit TelegramDecoder(uint8_t expected_address) : expected_address_(expected_address) {}

  // Appends received bytes and decodes as far as possible.
  void feed(const uint8_t* data, size_t size);
  // Pops the next decoded event; false when none is pending.
  bool next(DecoderEvent* event);

  // Forgets buffered bytes and pending events (after a baud change or reconnect).
  void reset();

  uint64_t bytesFed() const { return bytes_fed_; }
  size_t bufferedBytes() const { return buffer_.size() - start_; }
  const DecoderStats& stats() const { return stats_; }

 private:
  void decode();
  void consume(size_t count);

  uint8_t expected_address_;
  std::vector<uint8_t> buffer_;
  size_t start_ = 0;        // first unconsumed byte in buffer_
  uint64_t bytes_fed_ = 0;  // total bytes ever fed
  uint64_t consumed_ = 0;   // stream position of buffer_[start_]
  std::deque<DecoderEvent> events_;
  DecoderStats stats_;
};

}  // namespace sick_lms200
