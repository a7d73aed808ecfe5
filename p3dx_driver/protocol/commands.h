// Client→robot commands of the P2OS/ARCOS protocol: payload encoding (for
// the driver) and decoding (for the emulator). Payloads are framed with
// encodePacket() from packet.h.
//
// An integer argument is a type byte (0x3B positive, 0x1B negative) and the
// absolute value as u16 little-endian; a string argument is 0x2B, a length
// byte and the characters.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace p3dx {

enum class Command : uint8_t {
  kPulse = 0,  // also SYNC0 during the handshake
  kOpen = 1,   // also SYNC1
  kClose = 2,  // also SYNC2
  kEnable = 4,
  kSetA = 5,
  kSetV = 6,
  kSetO = 7,
  kSetRv = 10,
  kVel = 11,
  kConfig = 18,
  kRvel = 21,
  kSetRa = 23,
  kSonar = 28,
  kStop = 29,
  kVel2 = 32,
  kBumpStall = 44,
  kHostBaud = 50,
  kEStop = 55,
};

constexpr uint8_t kArgPositive = 0x3B;
constexpr uint8_t kArgNegative = 0x1B;
constexpr uint8_t kArgString = 0x2B;

// Command without an argument (SYNC0/1/2, PULSE, OPEN, CLOSE, STOP, SETO).
std::vector<uint8_t> encodeCommand(Command command);
// Command with a signed integer argument, saturated to ±65535.
std::vector<uint8_t> encodeCommand(Command command, int argument);
// VEL2: left and right wheel speeds in mm/s, sent as signed bytes in units
// of kVel2UnitMmPerS (high byte left, low byte right), saturated to ±127.
constexpr int kVel2UnitMmPerS = 20;
std::vector<uint8_t> encodeVel2(int left_mm_per_s, int right_mm_per_s);

// HOSTBAUD argument for a baud rate, or -1 when the robot does not know it.
int hostBaudCode(int baud);

struct DecodedCommand {
  uint8_t number = 0;
  bool has_int = false;
  int value = 0;           // signed integer argument
  uint16_t raw_value = 0;  // the two argument bytes as u16 LE (VEL2)
  bool has_string = false;
  std::string text;
};

// Parses a command payload; nullopt when it is empty or its argument is
// truncated. Unknown command numbers are returned as they are.
std::optional<DecodedCommand> decodeCommand(const std::vector<uint8_t>& payload);

// VEL2 raw argument → wheel speeds in mm/s.
void decodeVel2(uint16_t raw_value, int* left_mm_per_s, int* right_mm_per_s);

}  // namespace p3dx
