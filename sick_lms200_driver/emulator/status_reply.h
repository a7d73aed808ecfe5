// The data of the LMS2xx status reply (0xB1, the answer to request 0x31) as
// the telegram listing lays it out: 152 bytes, then the status byte. Offsets
// below count from the first byte after the command byte; words are u16
// little-endian. The emulator fills the fields it models (versions, modes,
// variant, units, baud) from its state; the measurement-internal values it
// does not model (pollution, reference, calibration, thresholds) are 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sick_lms200_driver/protocol/measured_values.h"

namespace sick_lms200 {

namespace status_field {
constexpr size_t kSoftwareVersion = 0;        // 7 ASCII bytes
constexpr size_t kOperatingMode = 7;          // the mode byte of the last 0x20 accepted
constexpr size_t kStatus = 8;                 // 0 = ok, otherwise an error is pending
constexpr size_t kManufacturer = 9;           // 8 bytes
constexpr size_t kVariantType = 17;           // 0 = standard LMS2xx type 6
constexpr size_t kPollution = 18;             // 8 words
constexpr size_t kReferencePollution = 34;    // 4 words
constexpr size_t kCalibPollution = 42;        // 8 words
constexpr size_t kCalibRefPollution = 58;     // 4 words
constexpr size_t kMotorRevolutions = 66;      // word
constexpr size_t kMeasuringMode = 101;        // as configuration byte 5
constexpr size_t kScanAngle = 106;            // word, degrees
constexpr size_t kResolution = 108;           // word, 0.01°
constexpr size_t kRestartMode = 110;          // as configuration byte 10
constexpr size_t kRestartTime = 111;          // word, as configuration byte 11
constexpr size_t kBaudRate = 115;             // word, statusBaudCode()
constexpr size_t kPermanentBaud = 118;        // 0: 9600 at power-on
constexpr size_t kAddress = 119;              // the sensor's address
constexpr size_t kUnits = 121;                // 0 = cm, 1 = mm
constexpr size_t kLaserOff = 122;             // 0 = laser on
constexpr size_t kBootPromVersion = 123;      // 7 ASCII bytes
constexpr size_t kCalibrationInterval = 150;  // word, the last field
constexpr size_t kSize = 152;
}  // namespace status_field

// What the emulator reports in its status reply.
struct StatusReport {
  std::string software_version;   // padded or cut to 7 bytes
  std::string boot_prom_version;  // padded or cut to 7 bytes
  uint8_t operating_mode = 0x25;  // request mode at power-on
  bool error_pending = false;
  uint8_t measuring_mode = 0;  // configuration byte 5
  int angle_deg = 180;
  int resolution_centideg = 100;
  uint8_t restart_mode = 0;  // configuration byte 10
  uint8_t restart_time = 0;  // configuration byte 11
  int baud = 9600;
  Units units = Units::kMillimetres;
};

// The baud-rate word of the status reply: 0x8067 (9600), 0x8033 (19200),
// 0x8019 (38400), 0x8001 (500000); 0 for any other rate.
uint16_t statusBaudCode(int baud);

// The 152 data bytes (without the status byte that follows them).
std::vector<uint8_t> buildStatusData(const StatusReport& report);

// Field `index` (0-based) of a ';'-separated type string such as
// "LMS200;30106;V02.10 ;S01.31 ", or "" when there is none.
std::string typeStringField(const std::string& type_string, int index);

}  // namespace sick_lms200
