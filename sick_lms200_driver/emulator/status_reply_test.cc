#include "sick_lms200_driver/emulator/status_reply.h"

#include <gtest/gtest.h>

#include <string>

namespace sick_lms200 {
namespace {

uint16_t wordAt(const std::vector<uint8_t>& data, size_t offset) {
  return static_cast<uint16_t>(data[offset] | (data[offset + 1] << 8));
}

TEST(StatusReply, Holds152BytesWithTheFieldsAtTheListingsOffsets) {
  StatusReport report;
  report.software_version = "V02.10";
  report.boot_prom_version = "S01.31 extra";
  report.operating_mode = 0x2A;
  report.measuring_mode = 0x06;
  report.angle_deg = 100;
  report.resolution_centideg = 25;
  report.restart_mode = 0x02;
  report.restart_time = 7;
  report.baud = 38400;
  report.units = Units::kCentimetres;
  const std::vector<uint8_t> data = buildStatusData(report);
  ASSERT_EQ(data.size(), 152u);
  EXPECT_EQ(std::string(data.begin(), data.begin() + 7), "V02.10 ") << "padded to 7";
  EXPECT_EQ(data[7], 0x2A);
  EXPECT_EQ(data[8], 0x00);
  EXPECT_EQ(data[17], 0x00);
  EXPECT_EQ(data[101], 0x06);
  EXPECT_EQ(wordAt(data, 106), 100);
  EXPECT_EQ(wordAt(data, 108), 25);
  EXPECT_EQ(data[110], 0x02);
  EXPECT_EQ(wordAt(data, 111), 7);
  EXPECT_EQ(wordAt(data, 115), 0x8019);
  EXPECT_EQ(data[121], 0x00) << "cm";
  EXPECT_EQ(std::string(data.begin() + 123, data.begin() + 130), "S01.31 ") << "cut to 7";

  report.error_pending = true;
  report.units = Units::kMillimetres;
  const std::vector<uint8_t> with_error = buildStatusData(report);
  EXPECT_EQ(with_error[8], 0x01);
  EXPECT_EQ(with_error[121], 0x01);
}

TEST(StatusReply, EncodesTheFourBaudRates) {
  EXPECT_EQ(statusBaudCode(9600), 0x8067);
  EXPECT_EQ(statusBaudCode(19200), 0x8033);
  EXPECT_EQ(statusBaudCode(38400), 0x8019);
  EXPECT_EQ(statusBaudCode(500000), 0x8001);
  EXPECT_EQ(statusBaudCode(57600), 0);
}

TEST(StatusReply, SplitsTheTypeString) {
  const std::string type = "LMS200;30106;V02.10 ;S01.31 ";
  EXPECT_EQ(typeStringField(type, 0), "LMS200");
  EXPECT_EQ(typeStringField(type, 2), "V02.10 ");
  EXPECT_EQ(typeStringField(type, 3), "S01.31 ");
  EXPECT_EQ(typeStringField(type, 4), "");
  EXPECT_EQ(typeStringField(type, 5), "");
  EXPECT_EQ(typeStringField("LMS200", 1), "");
}

}  // namespace
}  // namespace sick_lms200
