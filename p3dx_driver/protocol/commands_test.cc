#include "p3dx_driver/protocol/commands.h"

#include <gtest/gtest.h>

namespace p3dx {
namespace {

using Bytes = std::vector<uint8_t>;

TEST(Commands, IntegerArgumentsAreSignTypedLittleEndian) {
  EXPECT_EQ(encodeCommand(Command::kVel, 300), (Bytes{11, 0x3B, 0x2C, 0x01}));
  EXPECT_EQ(encodeCommand(Command::kRvel, -45), (Bytes{21, 0x1B, 45, 0}));
  EXPECT_EQ(encodeCommand(Command::kSetV, 1000000), (Bytes{6, 0x3B, 0xFF, 0xFF}));  // saturated
  EXPECT_EQ(encodeCommand(Command::kStop), (Bytes{29}));
}

TEST(Commands, DecodeInvertsEncode) {
  for (int value : {0, 1, -1, 255, -256, 2200, -2200, 65535, -65535}) {
    const auto decoded = decodeCommand(encodeCommand(Command::kSetA, value));
    ASSERT_TRUE(decoded);
    EXPECT_EQ(decoded->number, 5);
    EXPECT_TRUE(decoded->has_int);
    EXPECT_EQ(decoded->value, value);
  }
}

TEST(Commands, Vel2PacksLeftHighRightLowInTwentyMillimetreUnits) {
  const Bytes payload = encodeVel2(-200, 400);
  EXPECT_EQ(payload, (Bytes{32, 0x3B, 20, static_cast<uint8_t>(-10)}));
  const auto decoded = decodeCommand(payload);
  ASSERT_TRUE(decoded);
  int left = 0, right = 0;
  decodeVel2(decoded->raw_value, &left, &right);
  EXPECT_EQ(left, -200);
  EXPECT_EQ(right, 400);
  decodeVel2(encodeVel2(100000, -100000)[2] | (encodeVel2(100000, -100000)[3] << 8), &left, &right);
  EXPECT_EQ(left, 127 * kVel2UnitMmPerS);
  EXPECT_EQ(right, -127 * kVel2UnitMmPerS);
}

TEST(Commands, StringArgumentsAndTruncation) {
  const auto decoded = decodeCommand({1, 0x2B, 3, 'a', 'b', 'c'});
  ASSERT_TRUE(decoded);
  EXPECT_TRUE(decoded->has_string);
  EXPECT_EQ(decoded->text, "abc");
  EXPECT_FALSE(decodeCommand({1, 0x2B, 4, 'a'}));
  EXPECT_FALSE(decodeCommand({11, 0x3B, 1}));
  EXPECT_FALSE(decodeCommand({}));
}

TEST(Commands, HostBaudCodes) {
  EXPECT_EQ(hostBaudCode(9600), 0);
  EXPECT_EQ(hostBaudCode(115200), 4);
  EXPECT_EQ(hostBaudCode(4800), -1);
}

}  // namespace
}  // namespace p3dx
