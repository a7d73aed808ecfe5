// Parser for the LMS2xx measured-values telegram (reply 0xB0) and assembly of
// interlaced partial scans.
//
// Data layout (after the 0xB0 command byte):
//   info word u16 LE: bits 0-9 value count (<= 721), bits 11-12 partial-scan
//   index, bits 14-15 units (0 = cm, 1 = mm);
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
  int partial_index = 0;  // 0 for full scans
  Units units = Units::kMillimetres;
  std::vector<uint16_t> raw;   // 13-bit ranges in wire order
  std::vector<uint8_t> flags;  // bits 13-15 of each word, shifted to 0-2
  std::vector<float> ranges;   // metres, REP-117 for reserved codes
  uint8_t status = 0;
};

// Parses an 0xB0 telegram. On malformed data returns false and names the
// problem in *error; *values is then unspecified.
bool parseMeasuredValues(const Telegram& telegram, MeasuredValues* values, std::string* error);

// Builds the data bytes of an 0xB0 telegram (emulator and tests).
std::vector<uint8_t> buildMeasuredValuesData(const std::vector<uint16_t>& raw, Units units,
                                             int partial_index, uint8_t status);

// Partial scans of an interlaced sweep (mode 0x2A): with resolution r and
// n = 1°/r partials, partial k holds the beams at k·r + j·1° (j = 0, 1, ...).
// Number of beams of partial k in a sweep of `angle_deg` degrees.
int partialBeamCount(int angle_deg, int resolution_centideg, int partial_index);

class InterlaceAssembler {
 public:
  // angle_deg 100 or 180, resolution in 0.01° (100, 50, 25).
  InterlaceAssembler(int angle_deg, int resolution_centideg);

  // Adds one partial scan. Returns true and fills *full (beams in angular
  // order) when the last partial of a complete, in-order set arrived. Out of
  // order or wrongly sized partials restart the set (counted in dropped()).
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
