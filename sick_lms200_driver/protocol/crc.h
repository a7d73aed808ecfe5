// The LMS2xx telegram checksum (a CRC-16 variant that also mixes in the
// previous byte; it is NOT CRC-16/ARC). See docs/sick_lms200_driver.md.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sick_lms200 {

// Checksum over `size` bytes, from STX through the last data/status byte.
uint16_t lmsCrc16(const uint8_t* data, size_t size);

}  // namespace sick_lms200
