// The emulator on its own, driven through a MemoryStream with framed
// commands: handshake replies, kinematics, limits, watchdog, stall, noise.
#include "p3dx_driver/emulator/p3dx_emulator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "p3dx_driver/protocol/commands.h"
#include "p3dx_driver/protocol/session.h"
#include "serial_io/memory_stream.h"

namespace p3dx {
namespace {

using Bytes = std::vector<uint8_t>;

class EmulatorTest : public ::testing::Test {
 protected:
  void send(const Bytes& payload) { stream_.feed(encodePacket(payload)); }
  // Decodes everything the robot wrote since the last call.
  std::vector<Bytes> replies() {
    std::vector<Bytes> out;
    decoder_.feed(stream_.written().data(), stream_.written().size(), &out);
    stream_.clearWritten();
    return out;
  }
  // Handshake + OPEN + ENABLE 1, at time 0.
  void open(P3dxEmulator* robot) {
    for (int sync = 0; sync < 3; ++sync) {
      send(encodeCommand(static_cast<Command>(sync)));
      robot->step(0.0);
    }
    send(encodeCommand(Command::kOpen));
    send(encodeCommand(Command::kEnable, 1));
    robot->step(0.0);
    replies();
  }
  // Steps the robot every 10 ms from `from` to `to` seconds, pulsing every 0.5 s.
  void run(P3dxEmulator* robot, double from, double to) {
    const int steps = static_cast<int>(std::lround((to - from) / 0.01));
    for (int i = 0; i <= steps; ++i) {
      if (i % 50 == 0) send(encodeCommand(Command::kPulse));
      robot->step(from + 0.01 * i);
    }
  }

  serial_io::MemoryStream stream_;
  PacketDecoder decoder_;
};

TEST_F(EmulatorTest, AnswersTheHandshakeWithItsIdentityThenStreams) {
  EmulatorOptions options;
  options.name = "unit";
  options.subclass = "p3dx-sh";
  P3dxEmulator robot(&stream_, options);
  for (int sync = 0; sync < 3; ++sync) {
    send(encodeCommand(static_cast<Command>(sync)));
    robot.step(0.0);
    const auto reply = replies();
    ASSERT_EQ(reply.size(), 1u);
    EXPECT_EQ(reply[0][0], sync);
    if (sync == 2) {
      const RobotIdentity identity = parseIdentity(reply[0]);
      EXPECT_EQ(identity.name, "unit");
      EXPECT_EQ(identity.robot_class, "Pioneer");
      EXPECT_EQ(identity.subclass, "p3dx-sh");
    }
  }
  EXPECT_FALSE(robot.streaming());
  send(encodeCommand(Command::kOpen));
  robot.step(0.0);
  robot.step(0.35);
  robot.step(0.35);
  EXPECT_TRUE(robot.streaming());
  EXPECT_FALSE(robot.motorsEnabled());  // as the real controller
  EXPECT_GE(replies().size(), 2u);
  send(encodeCommand(Command::kClose));
  robot.step(0.4);
  EXPECT_FALSE(robot.streaming());
}

TEST_F(EmulatorTest, AcceleratesWithinTheLimitAndDrivesStraight) {
  P3dxEmulator robot(&stream_, EmulatorOptions{});
  open(&robot);
  send(encodeCommand(Command::kSetA, 500));
  send(encodeCommand(Command::kVel, 400));
  robot.step(0.0);
  robot.step(0.4);
  EXPECT_NEAR(robot.velocity(), 0.2, 1e-9);  // 0.5 m/s² × 0.4 s, not 0.4 m/s
  run(&robot, 0.41, 3.0);
  EXPECT_NEAR(robot.velocity(), 0.4, 1e-9);
  // 0.8 s ramp (0.16 m) then 2.2 s at 0.4 m/s.
  EXPECT_NEAR(robot.truePose().x, 0.16 + 0.4 * 2.2, 0.01);
  EXPECT_NEAR(robot.truePose().y, 0.0, 1e-9);
  EXPECT_LT(ekf_slam::maxAbsDifference(robot.truePose(), robot.odometryPose()), 1e-9);
}

TEST_F(EmulatorTest, Vel2DrivesTheWheelsAndTurnsOnTheSpot) {
  EmulatorOptions options;
  options.rotational_acceleration = 100.0;  // effectively instant
  P3dxEmulator robot(&stream_, options);
  open(&robot);
  send(encodeVel2(-200, 200));
  run(&robot, 0.0, 1.0);
  const double track = robot.conversions().axleTrackMm() * 1e-3;
  EXPECT_NEAR(robot.rotationalVelocity(), 0.4 / track, 1e-9);
  EXPECT_NEAR(robot.truePose().x, 0.0, 1e-9);
  EXPECT_NEAR(robot.truePose().theta, 0.4 / track * 1.0, 0.02);
}

TEST_F(EmulatorTest, WatchdogStopsTheRobotWhenCommandsStop) {
  EmulatorOptions options;
  options.acceleration = options.deceleration = 10.0;
  P3dxEmulator robot(&stream_, options);
  open(&robot);
  send(encodeCommand(Command::kVel, 300));
  for (double t = 0.0; t <= 1.9; t += 0.01) robot.step(t);  // no PULSE
  EXPECT_NEAR(robot.velocity(), 0.3, 1e-9);
  for (double t = 1.9; t <= 2.3; t += 0.01) robot.step(t);
  EXPECT_EQ(robot.velocity(), 0.0);
  EXPECT_EQ(robot.stats().watchdog_trips, 1u);
}

TEST_F(EmulatorTest, MotionHookBlocksMotionAndReportsAStall) {
  P3dxEmulator robot(&stream_, EmulatorOptions{});
  robot.setMotionHook([](const ekf_slam::Pose2&, const ekf_slam::Pose2& to) { return to.x < 0.1; });
  open(&robot);
  send(encodeCommand(Command::kVel, 300));
  run(&robot, 0.0, 3.0);
  EXPECT_LT(robot.truePose().x, 0.1);
  EXPECT_GT(robot.truePose().x, 0.09);
  StandardSip sip;
  bool found = false;
  for (const Bytes& payload : replies()) {
    if (parseStandardSip(payload.data(), payload.size(), &sip) == SipError::kNone) found = true;
  }
  ASSERT_TRUE(found);
  EXPECT_TRUE(sip.leftStall() && sip.rightStall());
  EXPECT_EQ(sip.frontBumpers(), 0x1F);  // driving forward into it
  EXPECT_EQ(sip.rearBumpers(), 0);
  // Stopped against it: no stall any more, the bumper still pressed.
  send(encodeCommand(Command::kVel, 0));
  run(&robot, 3.0, 5.0);
  replies();
  run(&robot, 5.0, 5.2);
  for (const Bytes& payload : replies()) parseStandardSip(payload.data(), payload.size(), &sip);
  EXPECT_FALSE(sip.leftStall() || sip.rightStall());
  EXPECT_EQ(sip.frontBumpers(), 0x1F);
  // Backing away frees the robot: no stall, no bumper.
  send(encodeCommand(Command::kVel, -100));
  run(&robot, 5.2, 7.0);
  replies();
  run(&robot, 7.0, 7.2);
  found = false;
  for (const Bytes& payload : replies()) {
    if (parseStandardSip(payload.data(), payload.size(), &sip) == SipError::kNone) found = true;
  }
  ASSERT_TRUE(found);
  EXPECT_FALSE(sip.leftStall() || sip.rightStall());
  EXPECT_EQ(sip.frontBumpers(), 0);
  EXPECT_LT(robot.truePose().x, 0.0);
}

TEST_F(EmulatorTest, BackingIntoSomethingPressesTheRearBumper) {
  P3dxEmulator robot(&stream_, EmulatorOptions{});
  robot.setMotionHook(
      [](const ekf_slam::Pose2&, const ekf_slam::Pose2& to) { return to.x > -0.1; });
  open(&robot);
  send(encodeCommand(Command::kVel, -200));
  run(&robot, 0.0, 3.0);
  StandardSip sip;
  bool found = false;
  for (const Bytes& payload : replies()) {
    if (parseStandardSip(payload.data(), payload.size(), &sip) == SipError::kNone) found = true;
  }
  ASSERT_TRUE(found);
  EXPECT_EQ(sip.rearBumpers(), 0x1F);
  EXPECT_EQ(sip.frontBumpers(), 0);
}

TEST_F(EmulatorTest, WheelNoiseMakesOdometryDriftFromTheTruth) {
  EmulatorOptions options;
  options.wheel_noise = 0.05;
  options.seed = 3;
  P3dxEmulator robot(&stream_, options);
  open(&robot);
  send(encodeCommand(Command::kVel, 500));
  send(encodeCommand(Command::kRvel, 20));
  run(&robot, 0.0, 10.0);
  const double drift = ekf_slam::maxAbsDifference(robot.truePose(), robot.odometryPose());
  EXPECT_GT(drift, 1e-4);
  EXPECT_LT(drift, 0.5);
}

TEST_F(EmulatorTest, IgnoresTimeGoingBackwards) {
  P3dxEmulator robot(&stream_, EmulatorOptions{});
  open(&robot);
  send(encodeCommand(Command::kVel, 300));
  run(&robot, 0.0, 1.0);
  const ekf_slam::Pose2 before = robot.truePose();
  robot.step(0.5);
  EXPECT_EQ(robot.truePose().x, before.x);
}

}  // namespace
}  // namespace p3dx
