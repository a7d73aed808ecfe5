#include "sick_lms200_driver/emulator/status_reply.h"

#include <algorithm>

namespace sick_lms200 {
namespace {

void putWord(std::vector<uint8_t>* data, size_t offset, uint16_t value) {
  (*data)[offset] = static_cast<uint8_t>(value & 0xFF);
  (*data)[offset + 1] = static_cast<uint8_t>(value >> 8);
}

// Seven ASCII bytes: the text, padded with spaces or cut.
void putVersion(std::vector<uint8_t>* data, size_t offset, const std::string& text) {
  for (size_t i = 0; i < 7; ++i) (*data)[offset + i] = i < text.size() ? text[i] : ' ';
}

}  // namespace

uint16_t statusBaudCode(int baud) {
  switch (baud) {
    case 9600:
      return 0x8067;
    case 19200:
      return 0x8033;
    case 38400:
      return 0x8019;
    case 500000:
      return 0x8001;
    default:
      return 0;
  }
}

std::vector<uint8_t> buildStatusData(const StatusReport& report) {
  namespace f = status_field;
  std::vector<uint8_t> data(f::kSize, 0);
  putVersion(&data, f::kSoftwareVersion, report.software_version);
  data[f::kOperatingMode] = report.operating_mode;
  data[f::kStatus] = report.error_pending ? 1 : 0;
  data[f::kVariantType] = 0;
  data[f::kMeasuringMode] = report.measuring_mode;
  putWord(&data, f::kScanAngle, static_cast<uint16_t>(report.angle_deg));
  putWord(&data, f::kResolution, static_cast<uint16_t>(report.resolution_centideg));
  data[f::kRestartMode] = report.restart_mode;
  putWord(&data, f::kRestartTime, report.restart_time);
  putWord(&data, f::kBaudRate, statusBaudCode(report.baud));
  data[f::kPermanentBaud] = 0;
  data[f::kAddress] = 0;
  data[f::kUnits] = report.units == Units::kMillimetres ? 1 : 0;
  data[f::kLaserOff] = 0;
  putVersion(&data, f::kBootPromVersion, report.boot_prom_version);
  return data;
}

std::string typeStringField(const std::string& type_string, int index) {
  size_t start = 0;
  for (int i = 0; i < index; ++i) {
    start = type_string.find(';', start);
    if (start == std::string::npos) return "";
    ++start;
  }
  const size_t end = std::min(type_string.find(';', start), type_string.size());
  return type_string.substr(start, end - start);
}

}  // namespace sick_lms200
