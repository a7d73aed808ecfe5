#include "sick_lms200_driver/protocol/crc.h"

namespace sick_lms200 {

uint16_t lmsCrc16(const uint8_t* data, size_t size) {
  constexpr uint16_t kPolynomial = 0x8005;
  uint16_t crc = 0;
  uint8_t previous = 0;
  for (size_t i = 0; i < size; ++i) {
    const uint8_t current = data[i];
    if (crc & 0x8000) {
      crc = static_cast<uint16_t>(((crc & 0x7FFF) << 1) ^ kPolynomial);
    } else {
      crc = static_cast<uint16_t>(crc << 1);
    }
    crc ^= static_cast<uint16_t>(current | (previous << 8));
    previous = current;
  }
  return crc;
}

}  // namespace sick_lms200
