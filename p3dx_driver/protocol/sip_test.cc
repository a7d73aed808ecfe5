#include "p3dx_driver/protocol/sip.h"

#include <gtest/gtest.h>

namespace p3dx {
namespace {

StandardSip exampleSip() {
  StandardSip sip;
  sip.type = kSipMoving;
  sip.x_ticks = 0x7FF0;
  sip.y_ticks = 12;
  sip.theta_units = -1024;
  sip.left_velocity = -120;
  sip.right_velocity = 250;
  sip.battery_decivolts = 125;
  sip.stall_bump = 0x0301;  // left stall, right stall, front bumper 0
  sip.control = 77;
  sip.flags = 0x0003;
  sip.compass = 90;
  sip.sonars = {{0, 1500}, {7, 4999}};
  return sip;
}

TEST(Sip, RoundTripsEveryFieldWithoutOptionalGroups) {
  const StandardSip in = exampleSip();
  const std::vector<uint8_t> payload = encodeStandardSip(in);
  StandardSip out;
  ASSERT_EQ(parseStandardSip(payload.data(), payload.size(), &out), SipError::kNone);
  EXPECT_EQ(out.type, kSipMoving);
  EXPECT_EQ(out.x_ticks, 0x7FF0);
  EXPECT_EQ(out.y_ticks, 12);
  EXPECT_EQ(out.theta_units, -1024);
  EXPECT_EQ(out.left_velocity, -120);
  EXPECT_EQ(out.right_velocity, 250);
  EXPECT_DOUBLE_EQ(out.batteryVolts(), 12.5);
  EXPECT_TRUE(out.leftStall());
  EXPECT_TRUE(out.rightStall());
  EXPECT_EQ(out.frontBumpers(), 1);
  EXPECT_EQ(out.rearBumpers(), 0);
  EXPECT_TRUE(out.motorsEnabled());
  ASSERT_EQ(out.sonars.size(), 2u);
  EXPECT_EQ(out.sonars[1].index, 7);
  EXPECT_EQ(out.sonars[1].range_mm, 4999);
  EXPECT_FALSE(out.has_io);
  EXPECT_FALSE(out.has_battery_x10);
}

TEST(Sip, ParsesOptionalTrailingFieldsAndToleratesExtraBytes) {
  StandardSip in = exampleSip();
  in.has_io = in.has_battery_x10 = in.has_extended = true;
  in.battery_x10 = 1262;
  in.rotational_velocity = -305;
  in.fault_flags = 4;
  std::vector<uint8_t> payload = encodeStandardSip(in);
  payload.insert(payload.end(), {1, 2, 3, 4, 5, 6, 7});  // newer firmware fields
  StandardSip out;
  ASSERT_EQ(parseStandardSip(payload.data(), payload.size(), &out), SipError::kNone);
  EXPECT_TRUE(out.has_extended);
  EXPECT_DOUBLE_EQ(out.batteryVolts(), 12.62);
  EXPECT_EQ(out.rotational_velocity, -305);
  EXPECT_EQ(out.fault_flags, 4);
}

TEST(Sip, RejectsTruncatedPacketsAtEveryLength) {
  const std::vector<uint8_t> payload = encodeStandardSip(exampleSip());
  for (size_t size = 1; size < payload.size(); ++size) {
    StandardSip out;
    EXPECT_EQ(parseStandardSip(payload.data(), size, &out), SipError::kTruncated) << size;
  }
  const uint8_t config[] = {kConfigPacket, 1, 2};
  StandardSip out;
  EXPECT_EQ(parseStandardSip(config, sizeof(config), &out), SipError::kNotStandardSip);
}

TEST(Sip, PositionDeltaHandlesTheFifteenBitWrap) {
  EXPECT_EQ(positionDelta(0x7FFE, 0x0003), 5);
  EXPECT_EQ(positionDelta(0x0003, 0x7FFE), -5);
  EXPECT_EQ(positionDelta(100, 600), 500);
  EXPECT_EQ(wrapPositionTicks(-1), 0x7FFF);
  EXPECT_EQ(wrapPositionTicks(0x8000 + 4), 4);
}

TEST(Sip, TrackerUnwrapsAcrossManyWrapsInBothDirections) {
  const DriveConversions p3dx = *conversionsForSubclass("p3dx");
  PositionTracker tracker;
  StandardSip sip;
  long ticks = 0x7F00;  // start just below the wrap
  sip.x_ticks = wrapPositionTicks(ticks);
  const double start = tracker.update(sip, p3dx).x;
  double x = start;
  // 200 steps of 400 ticks forward (several wraps), then 100 back.
  for (int i = 0; i < 300; ++i) {
    ticks += (i < 200) ? 400 : -400;
    sip.x_ticks = wrapPositionTicks(ticks);
    x = tracker.update(sip, p3dx).x;
  }
  EXPECT_NEAR(x - start, 100 * 400 * 0.485e-3, 1e-9);
}

TEST(Sip, SubclassSelectsDistanceFactor) {
  ASSERT_TRUE(conversionsForSubclass("p3dx"));
  EXPECT_DOUBLE_EQ(conversionsForSubclass("p3dx")->distance_mm_per_tick, 0.485);
  EXPECT_DOUBLE_EQ(conversionsForSubclass("P3DX-SH")->distance_mm_per_tick, 1.0);
  EXPECT_FALSE(conversionsForSubclass("p3at"));
  // The same counters mean different distances on the two subclasses.
  StandardSip sip;
  PositionTracker a, b;
  a.update(sip, *conversionsForSubclass("p3dx"));
  b.update(sip, *conversionsForSubclass("p3dx-sh"));
  sip.x_ticks = 1000;
  sip.theta_units = 1024;  // a quarter turn
  const auto pose_a = a.update(sip, *conversionsForSubclass("p3dx"));
  const auto pose_b = b.update(sip, *conversionsForSubclass("p3dx-sh"));
  EXPECT_NEAR(pose_a.x, 0.485, 1e-12);
  EXPECT_NEAR(pose_b.x, 1.0, 1e-12);
  EXPECT_NEAR(pose_a.theta, 1024 * 0.001534, 1e-12);
}

}  // namespace
}  // namespace p3dx
