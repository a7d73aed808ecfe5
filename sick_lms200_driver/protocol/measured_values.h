// Parser for the LMS2xx measured-values telegram (reply 0xB0) and assembly of
// interlaced partial scans.
//
// Data layout (after the 0xB0 command byte):
//   info word u16 LE: bits 0-9 value count (<= 721), bits 11-12 where a
//   partial scan starts (0.25° steps), bit 13 set for a partial scan, bits
//   14-15 units (0 = cm, 1 = mm);
//   count words u16 LE: bits 0-12 the range, bits 13-15 flags;
//   one status byte.
// Ranges are converted to metres following REP-117: codes meaning "no return"
// become +inf, codes meaning an erroneous value (dazzle, invalid, overflow,
// undocumented reserved codes) become NaN.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "sick_lms200_driver/protocol/telegram.h"

namespace sick_lms200 {

enum class Units { kCentimetres = 0, kMillimetres = 1 };

constexpr int kMaxValueCount = 721;
constexpr uint16_t kRangeMask = 0x1FFF;
// Reserved range codes (raw 13-bit values, the same in mm and cm mode).
constexpr uint16_t kCodeAboveMaximum = 8183;  // no return within range → +inf
constexpr uint16_t kCodeLowSignal = 8187;     // signal-to-noise too low → +inf
constexpr uint16_t kCodeOverflow = 8189;      // operation overflow → NaN
constexpr uint16_t kCodeDazzle = 8190;        // dazzled → NaN
constexpr uint16_t kCodeInvalid = 8191;       // measured value not valid → NaN
// Raw values below this are ranges; 8183..8191 are all reserved.
constexpr uint16_t kFirstReservedCode = 8183;

// Metres per raw unit.
inline double unitScale(Units units) { return units == Units::kMillimetres ? 0.001 : 0.01; }
// Largest measurable range (m): 8.182 m in mm mode, 81.82 m in cm mode.
inline double maxRange(Units units) { return (kFirstReservedCode - 1) * unitScale(units); }

// One raw 13-bit value → metres (REP-117 for reserved codes).
float rangeFromRaw(uint16_t raw13, Units units);
// Inverse for emulators: metres → raw value (+inf/out of range → 8183, NaN → 8191).
uint16_t rawFromRange(double range_m, Units units);

// Severity in the status byte, bits 0-2 (LMS2xx telegram listing).
enum class StatusSeverity { kOk = 0, kInfo = 1, kWarning = 2, kError = 3, kFatal = 4 };
StatusSeverity statusSeverity(uint8_t status);
constexpr uint8_t kStatusContaminationBit = 0x80;  // optics dirty (warning)
std::string describeStatus(uint8_t status);

struct MeasuredValues {
  // Bit 13 of the info word: the telegram holds one partial scan of an
  // interlaced sweep (mode 0x2A); false for complete scans.
  bool partial_scan = false;
  // Bits 11-12: where a partial scan starts, in 0.25° steps after the first
  // beam of a complete scan (0 = 0°, 1 = 0.25°, 2 = 0.5°, 3 = 0.75°).
  int partial_offset_quarters = 0;
  Units units = Units::kMillimetres;
  std::vector<uint16_t> raw;   // 13-bit ranges in wire order
  std::vector<uint8_t> flags;  // bits 13-15 of each word, shifted to 0-2
  std::vector<float> ranges;   // metres, REP-117 for reserved codes
  uint8_t status = 0;
};

// Parses an 0xB0 telegram. On malformed data returns false and names the
// problem in *error; *values is then unspecified.
bool parseMeasuredValues(const Telegram& telegram, MeasuredValues* values, std::string* error);

// Data bytes of an 0xB0 telegram holding a complete scan (emulator and tests).
std::vector<uint8_t> buildMeasuredValuesData(const std::vector<uint16_t>& raw, Units units,
                                             uint8_t status);
// Data bytes of an 0xB0 telegram holding one partial scan that starts
// `offset_quarters` × 0.25° after the first beam of a complete scan.
std::vector<uint8_t> buildPartialScanData(const std::vector<uint16_t>& raw, Units units,
                                          int offset_quarters, uint8_t status);

// Partial scans of an interlaced sweep (mode 0x2A): with resolution r and
// n = 1°/r partials, partial k (0 <= k < n) holds the beams at k·r + j·1°
// (j = 0, 1, ...), measured in one mirror turn.
// Number of beams of partial k in a sweep of `angle_deg` degrees.
int partialBeamCount(int angle_deg, int resolution_centideg, int k);
// The telegram's offset field (0.25° steps) of partial k.
inline int partialOffsetQuarters(int resolution_centideg, int k) {
  return k * resolution_centideg / 25;
}
// Inverse: k, or -1 when the offset is not a whole number of resolution
// steps below 1°.
int partialForOffset(int resolution_centideg, int offset_quarters);

class InterlaceAssembler {
 public:
  // angle_deg 100 or 180, resolution in 0.01° (100, 50, 25).
  InterlaceAssembler(int angle_deg, int resolution_centideg);

  // Adds one partial scan. Returns true and fills *full (beams in angular
  // order) when the last partial of a complete, in-order set arrived. Out of
  // order or wrongly sized partials, and offsets that are no multiple of the
  // resolution, restart the set (counted in dropped()).
  bool add(const MeasuredValues& partial, std::vector<float>* full);

  int partialsPerScan() const { return partials_; }
  uint64_t dropped() const { return dropped_; }

 private:
  int angle_deg_;
  int resolution_centideg_;
  int partials_;
  int expected_next_ = 0;
  std::vector<float> assembling_;
  uint64_t dropped_ = 0;
};

}  // namespace sick_lms200
