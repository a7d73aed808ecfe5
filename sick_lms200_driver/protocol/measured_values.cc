#include "sick_lms200_driver/protocol/measured_values.h"

#include <cmath>
#include <cstdio>

namespace sick_lms200 {

float rangeFromRaw(uint16_t raw13, Units units) {
  const uint16_t value = raw13 & kRangeMask;
  if (value < kFirstReservedCode) return static_cast<float>(value * unitScale(units));
  switch (value) {
    case kCodeAboveMaximum:
    case kCodeLowSignal:
      return std::numeric_limits<float>::infinity();
    default:  // dazzle, invalid, overflow and undocumented reserved codes
      return std::numeric_limits<float>::quiet_NaN();
  }
}

uint16_t rawFromRange(double range_m, Units units) {
  if (std::isnan(range_m)) return kCodeInvalid;
  if (!std::isfinite(range_m) || range_m > maxRange(units)) return kCodeAboveMaximum;
  if (range_m <= 0.0) return 0;
  const long raw = std::lround(range_m / unitScale(units));
  return static_cast<uint16_t>(raw >= kFirstReservedCode ? kFirstReservedCode - 1 : raw);
}

StatusSeverity statusSeverity(uint8_t status) {
  const int severity = status & 0x07;
  return severity > 4 ? StatusSeverity::kFatal : static_cast<StatusSeverity>(severity);
}

std::string describeStatus(uint8_t status) {
  static const char* const kNames[] = {"ok", "info", "warning", "error", "fatal error"};
  const int severity = static_cast<int>(statusSeverity(status));
  std::string text = kNames[severity];
  if (status & kStatusContaminationBit) text += ", optics contaminated";
  char hex[8];
  std::snprintf(hex, sizeof(hex), "0x%02X", status);
  return text + " (status byte " + hex + ")";
}

bool parseMeasuredValues(const Telegram& telegram, MeasuredValues* values, std::string* error) {
  if (telegram.command != cmd::kMeasuredValues) {
    *error = "not a measured-values telegram (command 0x" +
             std::to_string(static_cast<int>(telegram.command)) + ")";
    return false;
  }
  const std::vector<uint8_t>& data = telegram.data;
  if (data.size() < 3) {
    *error = "measured-values telegram too short (" + std::to_string(data.size()) + " bytes)";
    return false;
  }
  const uint16_t info = data[0] | (static_cast<uint16_t>(data[1]) << 8);
  const int count = info & 0x03FF;
  const int unit_bits = (info >> 14) & 0x03;
  if (count > kMaxValueCount) {
    *error = "value count " + std::to_string(count) + " exceeds " + std::to_string(kMaxValueCount);
    return false;
  }
  if (unit_bits > 1) {
    *error = "reserved units code " + std::to_string(unit_bits) + " in the info word";
    return false;
  }
  const size_t expected_size = 2 + 2 * static_cast<size_t>(count) + 1;
  if (data.size() != expected_size) {
    *error = "value count " + std::to_string(count) + " needs " + std::to_string(expected_size) +
             " data bytes, telegram has " + std::to_string(data.size());
    return false;
  }
  values->partial_offset_quarters = (info >> 11) & 0x03;
  values->partial_scan = ((info >> 13) & 0x01) != 0;
  values->units = unit_bits == 1 ? Units::kMillimetres : Units::kCentimetres;
  values->raw.resize(count);
  values->flags.resize(count);
  values->ranges.resize(count);
  for (int i = 0; i < count; ++i) {
    const uint16_t word = data[2 + 2 * i] | (static_cast<uint16_t>(data[3 + 2 * i]) << 8);
    values->raw[i] = word & kRangeMask;
    values->flags[i] = static_cast<uint8_t>(word >> 13);
    values->ranges[i] = rangeFromRaw(values->raw[i], values->units);
  }
  values->status = data.back();
  return true;
}

namespace {

std::vector<uint8_t> measuredValuesData(const std::vector<uint16_t>& raw, Units units,
                                        uint16_t partial_bits, uint8_t status) {
  std::vector<uint8_t> data;
  data.reserve(3 + 2 * raw.size());
  const uint16_t info =
      static_cast<uint16_t>((raw.size() & 0x03FF) | partial_bits | (static_cast<int>(units) << 14));
  data.push_back(static_cast<uint8_t>(info & 0xFF));
  data.push_back(static_cast<uint8_t>(info >> 8));
  for (uint16_t value : raw) {
    data.push_back(static_cast<uint8_t>(value & 0xFF));
    data.push_back(static_cast<uint8_t>(value >> 8));
  }
  data.push_back(status);
  return data;
}

}  // namespace

std::vector<uint8_t> buildMeasuredValuesData(const std::vector<uint16_t>& raw, Units units,
                                             uint8_t status) {
  return measuredValuesData(raw, units, 0, status);
}

std::vector<uint8_t> buildPartialScanData(const std::vector<uint16_t>& raw, Units units,
                                          int offset_quarters, uint8_t status) {
  const uint16_t bits = static_cast<uint16_t>(((offset_quarters & 0x03) << 11) | (1 << 13));
  return measuredValuesData(raw, units, bits, status);
}

int partialBeamCount(int angle_deg, int resolution_centideg, int k) {
  const int offset = k * resolution_centideg;  // 0.01°
  if (offset > angle_deg * 100) return 0;
  return (angle_deg * 100 - offset) / 100 + 1;
}

int partialForOffset(int resolution_centideg, int offset_quarters) {
  const int offset = offset_quarters * 25;  // 0.01°
  if (offset < 0 || offset >= 100 || offset % resolution_centideg != 0) return -1;
  return offset / resolution_centideg;
}

InterlaceAssembler::InterlaceAssembler(int angle_deg, int resolution_centideg)
    : angle_deg_(angle_deg),
      resolution_centideg_(resolution_centideg),
      partials_(100 / resolution_centideg) {}

bool InterlaceAssembler::add(const MeasuredValues& partial, std::vector<float>* full) {
  const int k = partialForOffset(resolution_centideg_, partial.partial_offset_quarters);
  const int expected_count = k < 0 ? -1 : partialBeamCount(angle_deg_, resolution_centideg_, k);
  if (k < 0 || static_cast<int>(partial.ranges.size()) != expected_count) {
    if (expected_next_ != 0) dropped_++;
    expected_next_ = 0;
    dropped_++;
    return false;
  }
  if (k != expected_next_) {
    if (expected_next_ != 0) dropped_++;  // an incomplete set is abandoned
    expected_next_ = 0;
    if (k != 0) {
      dropped_++;
      return false;
    }
  }
  if (k == 0) {
    assembling_.assign(angle_deg_ * 100 / resolution_centideg_ + 1,
                       std::numeric_limits<float>::quiet_NaN());
  }
  for (int j = 0; j < expected_count; ++j) {
    assembling_[static_cast<size_t>(j * partials_ + k)] = partial.ranges[j];
  }
  expected_next_ = k + 1;
  if (expected_next_ < partials_) return false;
  expected_next_ = 0;
  *full = assembling_;
  return true;
}

}  // namespace sick_lms200
