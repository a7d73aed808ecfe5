#include "p3dx_driver/protocol/commands.h"

#include <algorithm>
#include <cstdlib>

namespace p3dx {

std::vector<uint8_t> encodeCommand(Command command) { return {static_cast<uint8_t>(command)}; }

std::vector<uint8_t> encodeCommand(Command command, int argument) {
  const int magnitude = std::min(std::abs(argument), 0xFFFF);
  return {static_cast<uint8_t>(command), argument < 0 ? kArgNegative : kArgPositive,
          static_cast<uint8_t>(magnitude & 0xFF), static_cast<uint8_t>(magnitude >> 8)};
}

std::vector<uint8_t> encodeVel2(int left_mm_per_s, int right_mm_per_s) {
  auto to_byte = [](int speed) {
    const int units = std::clamp(speed / kVel2UnitMmPerS, -127, 127);
    return static_cast<uint8_t>(static_cast<int8_t>(units));
  };
  return {static_cast<uint8_t>(Command::kVel2), kArgPositive, to_byte(right_mm_per_s),
          to_byte(left_mm_per_s)};
}

int hostBaudCode(int baud) {
  switch (baud) {
    case 9600:
      return 0;
    case 19200:
      return 1;
    case 38400:
      return 2;
    case 57600:
      return 3;
    case 115200:
      return 4;
    default:
      return -1;
  }
}

std::optional<DecodedCommand> decodeCommand(const std::vector<uint8_t>& payload) {
  if (payload.empty()) return std::nullopt;
  DecodedCommand command;
  command.number = payload[0];
  if (payload.size() == 1) return command;
  const uint8_t type = payload[1];
  if (type == kArgPositive || type == kArgNegative) {
    if (payload.size() < 4) return std::nullopt;
    command.has_int = true;
    command.raw_value = static_cast<uint16_t>(payload[2] | (payload[3] << 8));
    command.value = type == kArgNegative ? -static_cast<int>(command.raw_value)
                                         : static_cast<int>(command.raw_value);
  } else if (type == kArgString) {
    if (payload.size() < 3 || payload.size() < 3u + payload[2]) return std::nullopt;
    command.has_string = true;
    command.text.assign(payload.begin() + 3, payload.begin() + 3 + payload[2]);
  }
  // Any other byte after the command number is ignored, as the robot does.
  return command;
}

void decodeVel2(uint16_t raw_value, int* left_mm_per_s, int* right_mm_per_s) {
  *right_mm_per_s = static_cast<int8_t>(raw_value & 0xFF) * kVel2UnitMmPerS;
  *left_mm_per_s = static_cast<int8_t>(raw_value >> 8) * kVel2UnitMmPerS;
}

}  // namespace p3dx
