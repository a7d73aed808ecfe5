#include "p3dx_driver/protocol/robot_link.h"

#include <algorithm>
#include <cmath>
#include <thread>

#include "p3dx_driver/protocol/commands.h"

namespace p3dx {
namespace {

constexpr double kRadToDeg = 180.0 / ekf_slam::kPi;
constexpr int kProbeBauds[] = {9600, 19200, 38400, 57600, 115200};
// A session that delivers no SIP for this long is treated as lost.
constexpr std::chrono::milliseconds kLinkSilence{1000};

double seconds(RobotLink::Clock::duration duration) {
  return std::chrono::duration<double>(duration).count();
}

RobotLink::Clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<RobotLink::Clock::duration>(
      std::chrono::duration<double>(seconds));
}

}  // namespace

RobotLink::RobotLink(LinkOptions options)
    : options_(std::move(options)), motors_requested_(options_.motors_enabled_at_start) {
  retry_delay_ = options_.reconnect_min_delay;
}

RobotLink::~RobotLink() { shutdown(); }

LinkStats RobotLink::stats() const {
  LinkStats stats = stats_;
  DecoderStats decoder = finished_sessions_;
  if (session_) {
    decoder.checksum_errors += session_->decoderStats().checksum_errors;
    decoder.length_errors += session_->decoderStats().length_errors;
    decoder.discarded_bytes += session_->decoderStats().discarded_bytes;
  }
  stats.checksum_errors = decoder.checksum_errors;
  stats.length_errors = decoder.length_errors;
  stats.discarded_bytes = decoder.discarded_bytes;
  return stats;
}

double RobotLink::secondsUntilRetry(Clock::time_point now) const {
  if (state_ == LinkState::kConnected) return 0.0;
  return std::max(0.0, seconds(next_attempt_ - now));
}

void RobotLink::accumulateDecoderStats() {
  if (!session_) return;
  finished_sessions_.checksum_errors += session_->decoderStats().checksum_errors;
  finished_sessions_.length_errors += session_->decoderStats().length_errors;
  finished_sessions_.discarded_bytes += session_->decoderStats().discarded_bytes;
  stats_.stale_sessions_closed += session_->staleSessionsClosed();
}

bool RobotLink::tryConnect(Clock::time_point now) {
  std::vector<int> bauds = {options_.baud};
  if (options_.probe_baud) {
    for (int baud : kProbeBauds) {
      if (baud != options_.baud) bauds.push_back(baud);
    }
  }
  bool connected = false;
  if (!port_.open(options_.port, options_.baud)) {
    last_error_ = port_.error();
  } else {
    session_ = std::make_unique<Session>(&port_, options_.session);
    for (int baud : bauds) {
      if (!port_.setBaud(baud)) {
        last_error_ = port_.error();
        continue;
      }
      if (session_->handshake()) {
        connected = true;
        connected_baud_ = baud;
        break;
      }
      last_error_ = session_->error();
      if (!port_.isOpen()) break;
    }
  }
  if (!connected) {
    accumulateDecoderStats();
    session_.reset();
    port_.close();
    next_attempt_ = now + toDuration(retry_delay_);
    retry_delay_ = std::min(retry_delay_ * 2.0, options_.reconnect_max_delay);
    return false;
  }

  state_ = LinkState::kConnected;
  ++stats_.connects;
  retry_delay_ = options_.reconnect_min_delay;
  identity_ = session_->identity();
  last_error_.clear();
  const std::optional<DriveConversions> table = conversionsForSubclass(identity_.subclass);
  conversions_ = table.value_or(DriveConversions{});
  if (!table) {
    last_error_ = "robot reports unknown subclass '" + identity_.subclass +
                  "': using p3dx conversion factors (set distance_conversion to override)";
  }
  if (options_.distance_conversion > 0.0) {
    conversions_.distance_mm_per_tick = options_.distance_conversion;
  }
  // Chain the new session's odometry onto the last published pose.
  tracker_.reset();
  session_origin_.reset();
  last_robot_pose_.reset();

  const Clock::time_point sent = Clock::now();
  send(encodeCommand(Command::kSetV,
                     static_cast<int>(std::lround(options_.max_linear_velocity * 1e3))),
       sent);
  send(encodeCommand(Command::kSetRv,
                     static_cast<int>(std::lround(options_.max_angular_velocity * kRadToDeg))),
       sent);
  send(encodeCommand(Command::kSetA,
                     static_cast<int>(std::lround(options_.linear_acceleration * 1e3))),
       sent);
  send(encodeCommand(Command::kSetA,
                     -static_cast<int>(std::lround(options_.linear_deceleration * 1e3))),
       sent);
  send(encodeCommand(Command::kSetRa,
                     static_cast<int>(std::lround(options_.angular_acceleration * kRadToDeg))),
       sent);
  send(encodeCommand(Command::kSonar, options_.sonar_enabled ? 1 : 0), sent);
  motors_dirty_ = true;
  velocity_dirty_ = true;
  return state_ == LinkState::kConnected;
}

void RobotLink::disconnect(const std::string& why, Clock::time_point now) {
  if (state_ != LinkState::kConnected) return;
  state_ = LinkState::kDisconnected;
  ++stats_.disconnects;
  last_error_ = why;
  accumulateDecoderStats();
  session_.reset();
  port_.close();
  retry_delay_ = options_.reconnect_min_delay;
  next_attempt_ = now + toDuration(retry_delay_);
}

bool RobotLink::send(const std::vector<uint8_t>& payload, Clock::time_point now) {
  if (!session_) return false;
  if (!session_->send(payload)) {
    disconnect(session_->error(), now);
    return false;
  }
  last_send_ = now;
  return true;
}

void RobotLink::spinOnce(std::chrono::milliseconds wait, std::vector<OdometrySample>* samples) {
  Clock::time_point now = Clock::now();
  if (state_ == LinkState::kDisconnected) {
    if (now < next_attempt_) {
      std::this_thread::sleep_for(std::min<Clock::duration>(wait, next_attempt_ - now));
      return;
    }
    if (!tryConnect(now)) return;
    for (const auto& payload : session_->pending()) handlePacket(payload, Clock::now(), samples);
    session_->pending().clear();
    last_sip_ = Clock::now();
  }

  std::vector<std::vector<uint8_t>> payloads;
  const serial_io::IoStatus status = session_->receive(wait, &payloads);
  now = Clock::now();
  if (status == serial_io::IoStatus::kClosed) {
    disconnect(session_->error(), now);
    return;
  }
  for (const auto& payload : payloads) handlePacket(payload, now, samples);
  if (now - last_sip_ > kLinkSilence) {
    disconnect(port_.name() + ": no data from the robot for " +
                   std::to_string(kLinkSilence.count()) + " ms (robot off or cable loose?)",
               now);
    return;
  }
  sendCommands(now);
}

void RobotLink::handlePacket(const std::vector<uint8_t>& payload, Clock::time_point arrival,
                             std::vector<OdometrySample>* samples) {
  if (payload.empty() || !isStandardSip(payload[0])) return;  // config, echoes: not odometry
  StandardSip sip;
  if (parseStandardSip(payload.data(), payload.size(), &sip) != SipError::kNone) {
    ++stats_.bad_sips;
    return;
  }
  ++stats_.sips;
  last_sip_ = arrival;
  const ekf_slam::Pose2 robot_pose = tracker_.update(sip, conversions_);
  if (!session_origin_) {
    session_origin_ = robot_pose;
    chain_base_ = last_pose_;
  }
  if (last_robot_pose_) {
    const ekf_slam::Pose2 step = ekf_slam::between(*last_robot_pose_, robot_pose);
    distance_travelled_ += std::hypot(step.x, step.y);
    angle_turned_ += std::abs(step.theta);
  }
  last_robot_pose_ = robot_pose;
  last_pose_ = ekf_slam::compose(chain_base_, ekf_slam::between(*session_origin_, robot_pose));

  OdometrySample sample;
  sample.arrival = arrival;
  sample.pose = last_pose_;
  const double left = sip.left_velocity * conversions_.velocity_mm_s_per_unit;
  const double right = sip.right_velocity * conversions_.velocity_mm_s_per_unit;
  sample.linear_velocity = (left + right) / 2.0 * 1e-3;
  sample.angular_velocity = (right - left) / 2.0 * conversions_.diff_conv;
  sample.distance_travelled = distance_travelled_;
  sample.angle_turned = angle_turned_;
  sample.sip = std::move(sip);
  samples->push_back(std::move(sample));
}

bool RobotLink::setVelocity(double linear, double angular, Clock::time_point now) {
  if (!std::isfinite(linear) || !std::isfinite(angular)) {
    ++stats_.rejected_commands;
    return false;
  }
  linear = std::clamp(linear, -options_.max_linear_velocity, options_.max_linear_velocity);
  angular = std::clamp(angular, -options_.max_angular_velocity, options_.max_angular_velocity);
  if (linear != linear_command_ || angular != angular_command_ || timed_out_) {
    velocity_dirty_ = true;
  }
  linear_command_ = linear;
  angular_command_ = angular;
  last_cmd_vel_ = now;
  have_cmd_vel_ = true;
  timed_out_ = false;
  return true;
}

void RobotLink::setMotorsEnabled(bool enabled) {
  motors_requested_ = enabled;
  motors_dirty_ = true;
}

void RobotLink::resetOdometry() {
  chain_base_ = ekf_slam::Pose2();
  last_pose_ = ekf_slam::Pose2();
  if (last_robot_pose_) {
    session_origin_ = last_robot_pose_;
  } else {
    session_origin_.reset();
  }
  distance_travelled_ = angle_turned_ = 0.0;
}

void RobotLink::sendCommands(Clock::time_point now) {
  if (options_.cmd_vel_timeout > 0.0 && have_cmd_vel_ && !timed_out_ &&
      now - last_cmd_vel_ > toDuration(options_.cmd_vel_timeout)) {
    timed_out_ = true;
    linear_command_ = angular_command_ = 0.0;
    velocity_dirty_ = true;
  }
  if (motors_dirty_) {
    if (!send(encodeCommand(Command::kEnable, motors_requested_ ? 1 : 0), now)) return;
    motors_dirty_ = false;
  }
  const bool repeat =
      !timed_out_ && now - last_velocity_send_ >= toDuration(options_.command_period);
  if (velocity_dirty_ || (have_cmd_vel_ && repeat)) {
    const int vel = static_cast<int>(std::lround(linear_command_ * 1e3));
    const int rvel = static_cast<int>(std::lround(angular_command_ * kRadToDeg));
    if (!send(encodeCommand(Command::kVel, vel), now)) return;
    if (!send(encodeCommand(Command::kRvel, rvel), now)) return;
    velocity_dirty_ = false;
    last_velocity_send_ = now;
  }
  if (now - last_send_ >= toDuration(options_.pulse_period)) {
    send(encodeCommand(Command::kPulse), now);
  }
}

void RobotLink::shutdown() {
  if (state_ == LinkState::kConnected && session_) session_->close();
  accumulateDecoderStats();
  session_.reset();
  port_.close();
  state_ = LinkState::kDisconnected;
}

}  // namespace p3dx
