// The driver's whole life with one robot, without ROS: open the port (probing
// baud rates), handshake, reconnect with back-off after an unplug, chain each
// new session's odometry onto the last pose so odometry never jumps, clamp
// and rate-limit velocity commands, stop the robot when commands stop
// (cmd_vel timeout), keep the watchdog fed with PULSE, STOP + CLOSE on exit.
//
// Single-threaded: the owner calls spinOnce() in a loop and the setters from
// the same thread. Units: m, rad, s (the robot's mm and degrees stay inside).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "p3dx_driver/protocol/session.h"
#include "p3dx_driver/protocol/sip.h"
#include "serial_io/serial_port.h"

namespace p3dx {

struct LinkOptions {
  std::string port = "/dev/ttyUSB0";     // device path (a pty symlink in tests)
  int baud = 9600;                       // tried first, bits/s
  bool probe_baud = true;                // then try 9600..115200 when sync fails
  double reconnect_min_delay = 0.25;     // s, first retry after a failure
  double reconnect_max_delay = 2.0;      // s, back-off cap (doubling)
  bool motors_enabled_at_start = true;   // send ENABLE 1 after OPEN
  bool sonar_enabled = false;            // SONAR 1/0 after OPEN
  double max_linear_velocity = 0.75;     // m/s, cmd_vel clamp and SETV
  double max_angular_velocity = 1.7453;  // rad/s (100 °/s), clamp and SETRV
  double linear_acceleration = 0.3;      // m/s², SETA
  double linear_deceleration = 0.3;      // m/s², SETA (negative argument)
  double angular_acceleration = 1.7453;  // rad/s² (100 °/s²), SETRA
  double cmd_vel_timeout = 0.5;          // s without cmd_vel → stop (≤0: never)
  double pulse_period = 0.5;             // s between keep-alives when idle
  double command_period = 0.2;           // s between repeated velocity commands
  double distance_conversion = 0.0;      // mm/tick; 0 = from the reported subclass
  SessionOptions session;
};

enum class LinkState { kDisconnected, kConnected };

struct OdometrySample {
  std::chrono::steady_clock::time_point arrival;  // when the packet was read
  ekf_slam::Pose2 pose;                           // odom frame, chained over sessions
  double linear_velocity = 0.0;                   // m/s, from the wheel speeds
  double angular_velocity = 0.0;                  // rad/s
  double distance_travelled = 0.0;                // m since the last reset (for covariance)
  double angle_turned = 0.0;                      // rad since the last reset
  StandardSip sip;
};

struct LinkStats {
  uint64_t sips = 0;
  uint64_t checksum_errors = 0;  // all sessions
  uint64_t length_errors = 0;
  uint64_t discarded_bytes = 0;
  uint64_t bad_sips = 0;  // good checksum but unparsable
  uint64_t connects = 0;
  uint64_t disconnects = 0;
  uint64_t rejected_commands = 0;  // non-finite velocities
  uint64_t stale_sessions_closed = 0;
};

class RobotLink {
 public:
  using Clock = std::chrono::steady_clock;

  explicit RobotLink(LinkOptions options);
  ~RobotLink();

  // One bounded slice of work: (re)connect when due (may block for a
  // handshake, at most ~1 s per baud rate), read for up to `wait`, send
  // velocity / PULSE when due. Appends one sample per SIP received.
  void spinOnce(std::chrono::milliseconds wait, std::vector<OdometrySample>* samples);

  // Desired body velocity (m/s, rad/s), clamped to the limits. Returns false
  // (and counts it) for a non-finite value, which is ignored.
  bool setVelocity(double linear, double angular, Clock::time_point now);
  void setMotorsEnabled(bool enabled);
  // Makes the current pose the odometry origin (done in the driver, so
  // packets already in flight cannot undo it).
  void resetOdometry();
  // STOP + CLOSE and release the port.
  void shutdown();

  LinkState state() const { return state_; }
  const std::string& lastError() const { return last_error_; }
  const RobotIdentity& identity() const { return identity_; }
  int connectedBaud() const { return connected_baud_; }
  LinkStats stats() const;
  bool motorsRequested() const { return motors_requested_; }
  const DriveConversions& conversions() const { return conversions_; }
  // Seconds until the next connection attempt (0 when connected).
  double secondsUntilRetry(Clock::time_point now) const;

 private:
  bool tryConnect(Clock::time_point now);
  void disconnect(const std::string& why, Clock::time_point now);
  void handlePacket(const std::vector<uint8_t>& payload, Clock::time_point arrival,
                    std::vector<OdometrySample>* samples);
  void sendCommands(Clock::time_point now);
  bool send(const std::vector<uint8_t>& payload, Clock::time_point now);
  void accumulateDecoderStats();

  LinkOptions options_;
  serial_io::SerialPort port_;
  std::unique_ptr<Session> session_;
  LinkState state_ = LinkState::kDisconnected;
  std::string last_error_;
  RobotIdentity identity_;
  int connected_baud_ = 0;
  DriveConversions conversions_;
  LinkStats stats_;
  DecoderStats finished_sessions_;

  Clock::time_point next_attempt_{};
  double retry_delay_ = 0.0;

  PositionTracker tracker_;
  std::optional<ekf_slam::Pose2> session_origin_;  // robot pose at the session's first SIP
  ekf_slam::Pose2 chain_base_;                     // odom pose at that moment
  ekf_slam::Pose2 last_pose_;
  std::optional<ekf_slam::Pose2> last_robot_pose_;
  double distance_travelled_ = 0.0, angle_turned_ = 0.0;

  double linear_command_ = 0.0, angular_command_ = 0.0;
  Clock::time_point last_cmd_vel_{};
  bool have_cmd_vel_ = false;
  bool timed_out_ = true;
  bool motors_requested_ = true;
  bool motors_dirty_ = false;
  Clock::time_point last_sip_{};
  Clock::time_point last_send_{};
  Clock::time_point last_velocity_send_{};
  bool velocity_dirty_ = false;
};

}  // namespace p3dx
