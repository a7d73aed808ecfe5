// A Pioneer P3-DX as seen from its serial port: the robot side of the P2OS
// protocol over any ByteStream, differential-drive kinematics with
// acceleration limits, the ARCOS watchdog, a wheel-odometry error model and
// fault injection. No ROS, no threads, no clock of its own: the owner calls
// step(now) (a simulator next to an LMS200 emulator, or the p3dx_emulator
// executable), so it runs in-process with a shared world.
//
// Frames: truePose() is the robot's pose in the world (m, rad);
// odometryPose() is what the robot believes (its encoders, with the error
// model), reset to zero at OPEN and SETO, as the real controller does.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "p3dx_driver/protocol/packet.h"
#include "p3dx_driver/protocol/sip.h"
#include "serial_io/byte_stream.h"

namespace p3dx {

struct EmulatorFaults {
  double corrupt_rate = 0.0;  // probability a SIP is sent with a wrong checksum
  double garbage_rate = 0.0;  // probability random bytes precede a SIP
  double drop_rate = 0.0;     // probability one byte of a SIP is dropped
  bool stalled = false;       // wheels blocked: no motion, stall bits set
};

struct EmulatorOptions {
  std::string name = "emulated";            // robot name in the SYNC2 reply
  std::string subclass = "p3dx";            // "p3dx" or "p3dx-sh"
  int baud = 9600;                          // answers only at this line speed (0: any)
  double sip_period = 0.1;                  // s between SIPs
  double watchdog = 2.0;                    // s without any command → motors stop
  double max_velocity = 2.2;                // m/s, firmware limit (SETV lowers it)
  double max_rotational_velocity = 8.7266;  // rad/s (500 °/s; SETRV lowers it)
  double acceleration = 0.3;                // m/s² (SETA changes it)
  double deceleration = 0.3;                // m/s²
  double rotational_acceleration = 1.7453;  // rad/s² (100 °/s²; SETRA changes it)
  double wheel_noise = 0.0;    // std of each wheel's distance error, fraction of distance
  uint32_t seed = 1;           // random generator seed (noise and faults)
  bool stale_session = false;  // start streaming as if a previous client left it open
  double battery_volts = 12.6;
  EmulatorFaults faults;
};

struct EmulatorStats {
  uint64_t sips_sent = 0;
  uint64_t sips_corrupted = 0;
  uint64_t commands = 0;
  uint64_t bad_packets = 0;  // checksum / length errors from the client
  uint64_t watchdog_trips = 0;
  uint64_t sessions_opened = 0;
};

class P3dxEmulator {
 public:
  // `stream` is borrowed; it may be a PseudoTerminal (then peerBaud() is
  // checked against options.baud) or any other ByteStream.
  P3dxEmulator(serial_io::ByteStream* stream, EmulatorOptions options);

  // Reads and answers pending commands, integrates motion up to `now`
  // (seconds on any monotonic clock), sends a SIP when one is due.
  void step(double now);

  const ekf_slam::Pose2& truePose() const { return true_pose_; }
  void setTruePose(const ekf_slam::Pose2& pose) { true_pose_ = pose; }
  const ekf_slam::Pose2& odometryPose() const { return odometry_pose_; }
  // Actual body velocities (m/s, rad/s) after acceleration limits.
  double velocity() const { return velocity_; }
  double rotationalVelocity() const { return rotational_velocity_; }
  double targetVelocity() const { return target_velocity_; }
  double targetRotationalVelocity() const { return target_rotational_velocity_; }

  // Called for every motion increment with the current and proposed true
  // pose; returning false blocks the motion (the robot stalls, and the bumper
  // ring on the side it drives to is pressed), as a wall does.
  void setMotionHook(std::function<bool(const ekf_slam::Pose2&, const ekf_slam::Pose2&)> hook) {
    motion_hook_ = std::move(hook);
  }

  EmulatorFaults& faults() { return options_.faults; }
  const EmulatorStats& stats() const { return stats_; }
  bool streaming() const { return state_ == State::kOpen; }
  bool motorsEnabled() const { return motors_enabled_; }
  bool sonarEnabled() const { return sonar_enabled_; }
  const DriveConversions& conversions() const { return conversions_; }

  // Forget the connection (after the link was unplugged): the robot stops
  // streaming and waits for SYNC0 again; its odometry keeps its value.
  void dropConnection();

 private:
  enum class State { kWaitSync0, kWaitSync1, kWaitSync2, kSynced, kOpen };

  void handlePayload(const std::vector<uint8_t>& payload, double now);
  void handleCommand(uint8_t number, bool has_int, int value, uint16_t raw, double now);
  void sendPayload(const std::vector<uint8_t>& payload);
  void writeBytes(std::vector<uint8_t> bytes);
  void sendSip();
  void integrate(double dt);
  void openSession(double now);

  serial_io::ByteStream* stream_;
  EmulatorOptions options_;
  DriveConversions conversions_;
  PacketDecoder decoder_;
  State state_ = State::kWaitSync0;
  std::mt19937 random_;
  EmulatorStats stats_;
  std::function<bool(const ekf_slam::Pose2&, const ekf_slam::Pose2&)> motion_hook_;

  ekf_slam::Pose2 true_pose_;
  ekf_slam::Pose2 odometry_pose_;
  double velocity_ = 0.0, rotational_velocity_ = 0.0;  // m/s, rad/s
  double target_velocity_ = 0.0, target_rotational_velocity_ = 0.0;
  bool wheel_mode_ = false;                        // VEL2 drives the wheels directly
  double target_left_ = 0.0, target_right_ = 0.0;  // m/s (VEL2)
  bool motors_enabled_ = false;
  bool sonar_enabled_ = true;
  bool stalled_now_ = false;  // reported in SIPs
  bool blocked_ = false;      // an increment of the current step was blocked
  bool contact_front_ = false, contact_rear_ = false;             // … driving forward / backward
  double travel_since_contact_ = 0.0, turn_since_contact_ = 0.0;  // m, rad
  bool front_bumped_now_ = false, rear_bumped_now_ = false;       // reported in SIPs
  double last_step_ = -1.0;
  double last_command_ = 0.0;
  double next_sip_ = 0.0;
  bool watchdog_tripped_ = false;
  bool baud_matches_ = true;
};

}  // namespace p3dx
