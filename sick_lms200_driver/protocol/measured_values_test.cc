#include "sick_lms200_driver/protocol/measured_values.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sick_lms200 {
namespace {

Telegram measuredValuesTelegram(const std::vector<uint16_t>& raw, Units units, uint8_t status = 0) {
  Telegram telegram;
  telegram.address = kSensorAddress;
  telegram.command = cmd::kMeasuredValues;
  telegram.data = buildMeasuredValuesData(raw, units, status);
  return telegram;
}

Telegram partialScanTelegram(const std::vector<uint16_t>& raw, Units units, int offset_quarters) {
  Telegram telegram = measuredValuesTelegram(raw, units);
  telegram.data = buildPartialScanData(raw, units, offset_quarters, 0x10);
  return telegram;
}

TEST(MeasuredValues, ParsesMillimetresAndCentimetres) {
  MeasuredValues values;
  std::string error;
  ASSERT_TRUE(parseMeasuredValues(measuredValuesTelegram({1234, 0, 8182}, Units::kMillimetres),
                                  &values, &error))
      << error;
  ASSERT_EQ(values.ranges.size(), 3u);
  EXPECT_FLOAT_EQ(values.ranges[0], 1.234f);
  EXPECT_FLOAT_EQ(values.ranges[1], 0.0f);
  EXPECT_FLOAT_EQ(values.ranges[2], 8.182f);
  EXPECT_EQ(values.units, Units::kMillimetres);

  ASSERT_TRUE(parseMeasuredValues(measuredValuesTelegram({1234, 8182}, Units::kCentimetres),
                                  &values, &error));
  EXPECT_FLOAT_EQ(values.ranges[0], 12.34f);
  EXPECT_FLOAT_EQ(values.ranges[1], 81.82f);
  EXPECT_EQ(values.units, Units::kCentimetres);
  EXPECT_DOUBLE_EQ(maxRange(Units::kCentimetres), 81.82);
}

TEST(MeasuredValues, MapsEveryReservedCodePerRep117) {
  const float inf = std::numeric_limits<float>::infinity();
  for (Units units : {Units::kMillimetres, Units::kCentimetres}) {
    for (uint16_t code = kFirstReservedCode; code <= 8191; ++code) {
      const float range = rangeFromRaw(code, units);
      if (code == kCodeAboveMaximum || code == kCodeLowSignal) {
        EXPECT_EQ(range, inf) << code;
      } else {
        EXPECT_TRUE(std::isnan(range)) << code;  // dazzle, invalid, overflow, undocumented
      }
    }
    EXPECT_TRUE(std::isfinite(rangeFromRaw(kFirstReservedCode - 1, units)));
  }
}

TEST(MeasuredValues, SeparatesFlagBitsFromRanges) {
  MeasuredValues values;
  std::string error;
  const uint16_t with_flags = static_cast<uint16_t>(1000 | (0x5 << 13));
  ASSERT_TRUE(parseMeasuredValues(measuredValuesTelegram({with_flags}, Units::kMillimetres),
                                  &values, &error));
  EXPECT_EQ(values.raw[0], 1000);
  EXPECT_EQ(values.flags[0], 0x5);
  EXPECT_FLOAT_EQ(values.ranges[0], 1.0f);
}

TEST(MeasuredValues, RoundTripsRangesThroughRawValues) {
  EXPECT_EQ(rawFromRange(2.5, Units::kMillimetres), 2500);
  EXPECT_EQ(rawFromRange(2.5, Units::kCentimetres), 250);
  EXPECT_EQ(rawFromRange(std::numeric_limits<double>::infinity(), Units::kMillimetres),
            kCodeAboveMaximum);
  EXPECT_EQ(rawFromRange(9.0, Units::kMillimetres), kCodeAboveMaximum);
  EXPECT_EQ(rawFromRange(std::nan(""), Units::kMillimetres), kCodeInvalid);
}

TEST(MeasuredValues, RejectsTruncatedOversizedAndInconsistentTelegrams) {
  MeasuredValues values;
  std::string error;
  Telegram telegram = measuredValuesTelegram({1, 2, 3}, Units::kMillimetres);
  Telegram truncated = telegram;
  truncated.data.pop_back();
  EXPECT_FALSE(parseMeasuredValues(truncated, &values, &error));
  EXPECT_NE(error.find("needs"), std::string::npos) << error;
  Telegram oversized = telegram;
  oversized.data.push_back(0);
  EXPECT_FALSE(parseMeasuredValues(oversized, &values, &error));
  Telegram tiny = telegram;
  tiny.data.resize(2);
  EXPECT_FALSE(parseMeasuredValues(tiny, &values, &error));
  Telegram too_many =
      measuredValuesTelegram(std::vector<uint16_t>(kMaxValueCount), Units::kMillimetres);
  too_many.data[0] = 0xFF;  // count 1023
  too_many.data[1] |= 0x03;
  EXPECT_FALSE(parseMeasuredValues(too_many, &values, &error));
  EXPECT_NE(error.find("exceeds"), std::string::npos) << error;
  Telegram bad_units = telegram;
  bad_units.data[1] |= 0xC0;  // units code 3
  EXPECT_FALSE(parseMeasuredValues(bad_units, &values, &error));
  Telegram wrong_command = telegram;
  wrong_command.command = 0xB1;
  EXPECT_FALSE(parseMeasuredValues(wrong_command, &values, &error));
}

TEST(MeasuredValues, ReadsStatusSeverity) {
  MeasuredValues values;
  std::string error;
  ASSERT_TRUE(
      parseMeasuredValues(measuredValuesTelegram({1}, Units::kMillimetres, 0x83), &values, &error));
  EXPECT_EQ(values.status, 0x83);
  EXPECT_EQ(statusSeverity(values.status), StatusSeverity::kError);
  EXPECT_NE(describeStatus(values.status).find("contaminated"), std::string::npos);
  EXPECT_EQ(statusSeverity(0x00), StatusSeverity::kOk);
}

// Bits 3-4 of the status byte name the data source (10 = LMS type 6: 0x10 is
// what an LMS200 sends in normal operation; 00 is reserved). The driver
// reads only the severity (bits 0-2) and contamination (bit 7): both bytes
// are "ok".
TEST(MeasuredValues, ReadsBothTheDevicesStatusByteAndZeroAsOk) {
  for (uint8_t status : {uint8_t{0x10}, uint8_t{0x00}}) {
    EXPECT_EQ(statusSeverity(status), StatusSeverity::kOk) << int{status};
    EXPECT_EQ(describeStatus(status).rfind("ok", 0), 0u) << describeStatus(status);
  }
  EXPECT_EQ(statusSeverity(0x13), StatusSeverity::kError);
}

// Info word of a partial scan (mode 0x2A): bit 13 set, bits 11-12 the
// offset in 0.25° steps (a 0.5° sweep's second partial says 2, not 1).
TEST(MeasuredValues, ReadsThePartialScanFlagAndOffset) {
  const Telegram telegram = partialScanTelegram({100, 200, 300}, Units::kMillimetres, 2);
  const uint16_t info = telegram.data[0] | (telegram.data[1] << 8);
  EXPECT_EQ(info, 3 | (2 << 11) | (1 << 13) | (1 << 14));
  MeasuredValues values;
  std::string error;
  ASSERT_TRUE(parseMeasuredValues(telegram, &values, &error)) << error;
  EXPECT_TRUE(values.partial_scan);
  EXPECT_EQ(values.partial_offset_quarters, 2);
  EXPECT_EQ(values.ranges.size(), 3u);
  ASSERT_TRUE(
      parseMeasuredValues(measuredValuesTelegram({1}, Units::kMillimetres), &values, &error));
  EXPECT_FALSE(values.partial_scan);
  EXPECT_EQ(values.partial_offset_quarters, 0);

  EXPECT_EQ(partialOffsetQuarters(50, 1), 2);
  EXPECT_EQ(partialForOffset(50, 2), 1);
  EXPECT_EQ(partialForOffset(50, 1), -1);  // 0.25° is no multiple of 0.5°
  EXPECT_EQ(partialForOffset(100, 2), -1);
  EXPECT_EQ(partialForOffset(25, 3), 3);
}

TEST(InterlaceAssembler, AssemblesHalfDegreeScanFromTwoPartials) {
  // Beam i of the full 180°/0.5° scan has raw value 1000 + i.
  InterlaceAssembler assembler(180, 50);
  ASSERT_EQ(assembler.partialsPerScan(), 2);
  std::vector<float> full;
  for (int k = 0; k < 2; ++k) {
    std::vector<uint16_t> raw;
    for (int j = 0; j < partialBeamCount(180, 50, k); ++j) raw.push_back(1000 + 2 * j + k);
    MeasuredValues partial;
    std::string error;
    ASSERT_TRUE(parseMeasuredValues(
        partialScanTelegram(raw, Units::kMillimetres, partialOffsetQuarters(50, k)), &partial,
        &error));
    EXPECT_EQ(assembler.add(partial, &full), k == 1);
  }
  ASSERT_EQ(full.size(), 361u);
  for (int i = 0; i < 361; ++i) EXPECT_FLOAT_EQ(full[i], (1000 + i) * 0.001f) << i;
}

TEST(InterlaceAssembler, AssemblesQuarterDegreeAndRestartsOnMissingPartial) {
  InterlaceAssembler assembler(100, 25);
  ASSERT_EQ(assembler.partialsPerScan(), 4);
  auto partial = [](int k) {
    MeasuredValues values;
    values.partial_scan = true;
    values.partial_offset_quarters = k;  // 0.25° steps, here one per resolution step
    for (int j = 0; j < partialBeamCount(100, 25, k); ++j) values.ranges.push_back(j * 4 + k);
    return values;
  };
  std::vector<float> full;
  // 0, 1, (2 lost), 3: the incomplete set is dropped, never published.
  EXPECT_FALSE(assembler.add(partial(0), &full));
  EXPECT_FALSE(assembler.add(partial(1), &full));
  EXPECT_FALSE(assembler.add(partial(3), &full));
  EXPECT_GE(assembler.dropped(), 1u);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(assembler.add(partial(k), &full), k == 3);
  ASSERT_EQ(full.size(), 401u);
  for (int i = 0; i < 401; ++i) EXPECT_FLOAT_EQ(full[i], static_cast<float>(i)) << i;
}

}  // namespace
}  // namespace sick_lms200

namespace sick_lms200 {
namespace {

// Bounded randomised test: random payloads behind a valid 0xB0 header either
// parse into consistent values or are rejected with a message; never crash.
TEST(MeasuredValuesRandomised, RandomPayloadsParseConsistentlyOrFailWithAMessage) {
  std::mt19937 rng(99);
  std::uniform_int_distribution<int> byte(0, 255);
  int parsed = 0, rejected = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    Telegram telegram;
    telegram.command = cmd::kMeasuredValues;
    const int count = byte(rng) % 8;
    telegram.data.resize(trial % 2 ? 2 + 2 * count + 1 : byte(rng) % 24);
    for (auto& b : telegram.data) b = static_cast<uint8_t>(byte(rng));
    if (trial % 2 && telegram.data.size() >= 2) {
      telegram.data[0] = static_cast<uint8_t>(count);
      telegram.data[1] &= 0x7C;  // keep units valid (0/1 chosen below), partial index random
      telegram.data[1] |= static_cast<uint8_t>((trial % 4 == 1) << 6);
    }
    MeasuredValues values;
    std::string error;
    if (parseMeasuredValues(telegram, &values, &error)) {
      parsed++;
      ASSERT_EQ(values.ranges.size(), values.raw.size());
      ASSERT_EQ(telegram.data.size(), 3 + 2 * values.raw.size());
      for (size_t i = 0; i < values.raw.size(); ++i) {
        const float r = values.ranges[i];
        ASSERT_TRUE(std::isnan(r) || r >= 0.0f) << r;
        ASSERT_TRUE(values.raw[i] >= kFirstReservedCode || r <= maxRange(values.units) + 1e-3);
      }
    } else {
      rejected++;
      ASSERT_FALSE(error.empty());
    }
  }
  EXPECT_GT(parsed, 2000);
  EXPECT_GT(rejected, 2000);
}

}  // namespace
}  // namespace sick_lms200
