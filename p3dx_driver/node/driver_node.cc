#include "p3dx_driver/node/driver_node.h"

#include <cmath>

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/BatteryState.h>
#include <sensor_msgs/Range.h>
#include <std_msgs/Bool.h>
#include <std_msgs/UInt16.h>

#include "ros_conversions/pose_conversion.h"

namespace p3dx {
namespace {

constexpr double kLargeVariance = 1e6;  // for the unused 3D axes (z, roll, pitch)
constexpr int kSonarCount = 16;

// ROS time of a packet that arrived at `arrival` on the steady clock.
ros::Time arrivalStamp(RobotLink::Clock::time_point arrival) {
  const double age = std::chrono::duration<double>(RobotLink::Clock::now() - arrival).count();
  return ros::Time::now() - ros::Duration(std::max(0.0, age));
}

}  // namespace

DriverNode::DriverNode(ros::NodeHandle node, ros::NodeHandle private_node, DriverParams params)
    : node_(node), private_node_(private_node), params_(std::move(params)), link_(params_.link) {
  cmd_vel_subscriber_ = node_.subscribe("cmd_vel", 10, &DriverNode::onCmdVel, this);
  odom_publisher_ = node_.advertise<nav_msgs::Odometry>("odom", 50);
  battery_publisher_ = node_.advertise<sensor_msgs::BatteryState>("battery", 5);
  motors_publisher_ = node_.advertise<std_msgs::Bool>("motors_enabled", 1, true);
  bumpers_publisher_ = node_.advertise<std_msgs::UInt16>("bumpers", 5, true);
  stall_publisher_ = node_.advertise<std_msgs::Bool>("stall", 5, true);
  if (params_.link.sonar_enabled) {
    for (int i = 0; i < kSonarCount; ++i) {
      sonar_publishers_.push_back(
          node_.advertise<sensor_msgs::Range>("sonar/" + std::to_string(i), 5));
    }
  }
  enable_service_ =
      private_node_.advertiseService("enable_motors", &DriverNode::onEnableMotors, this);
  reset_service_ =
      private_node_.advertiseService("reset_odometry", &DriverNode::onResetOdometry, this);
  updater_.setHardwareID("p3dx " + params_.link.port);
  updater_.add("P3-DX link", this, &DriverNode::diagnose);
  last_diagnosis_ = ros::WallTime::now();
}

void DriverNode::onCmdVel(const geometry_msgs::Twist& twist) {
  if (!link_.setVelocity(twist.linear.x, twist.angular.z, RobotLink::Clock::now())) {
    ROS_WARN_THROTTLE(5.0, "p3dx: ignored a cmd_vel with a non-finite value (%g, %g); %lu so far",
                      twist.linear.x, twist.angular.z,
                      static_cast<unsigned long>(link_.stats().rejected_commands));
  }
}

bool DriverNode::onEnableMotors(std_srvs::SetBool::Request& request,
                                std_srvs::SetBool::Response& response) {
  link_.setMotorsEnabled(request.data);
  response.success = true;
  response.message =
      std::string(request.data ? "enabling" : "disabling") + " motors" +
      (link_.state() == LinkState::kConnected ? "" : " (applied when the robot connects)");
  ROS_INFO("p3dx: %s", response.message.c_str());
  return true;
}

bool DriverNode::onResetOdometry(std_srvs::Trigger::Request&,
                                 std_srvs::Trigger::Response& response) {
  link_.resetOdometry();
  response.success = true;
  response.message = "odometry reset to the origin of " + params_.odom_frame;
  ROS_INFO("p3dx: %s", response.message.c_str());
  return true;
}

void DriverNode::run() {
  std::vector<OdometrySample> samples;
  while (ros::ok()) {
    samples.clear();
    link_.spinOnce(std::chrono::milliseconds(10), &samples);
    for (const OdometrySample& sample : samples) publish(sample);
    reportLinkChanges();
    ros::spinOnce();
    updater_.update();
  }
  link_.shutdown();
  ROS_INFO("p3dx: stopped the robot and closed the session");
}

void DriverNode::reportLinkChanges() {
  const LinkState state = link_.state();
  if (state != reported_state_) {
    if (state == LinkState::kConnected) {
      const RobotIdentity& robot = link_.identity();
      ROS_INFO("p3dx: connected to %s '%s' (%s) on %s at %d baud; motors %s",
               robot.robot_class.c_str(), robot.name.c_str(), robot.subclass.c_str(),
               params_.link.port.c_str(), link_.connectedBaud(),
               link_.motorsRequested() ? "enabled" : "disabled (call ~enable_motors)");
      if (!link_.lastError().empty()) ROS_WARN("p3dx: %s", link_.lastError().c_str());
    } else {
      ROS_ERROR(
          "p3dx: lost the robot: %s. Reconnecting with back-off; odometry will continue "
          "from the last pose.",
          link_.lastError().c_str());
      published_motors_.reset();
    }
    reported_state_ = state;
    reported_error_ = link_.lastError();
  } else if (state == LinkState::kDisconnected && link_.lastError() != reported_error_) {
    reported_error_ = link_.lastError();
    ROS_WARN_THROTTLE(10.0, "p3dx: cannot connect: %s (retrying)", reported_error_.c_str());
  }
}

void DriverNode::publish(const OdometrySample& sample) {
  const ros::Time stamp = arrivalStamp(sample.arrival);

  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = params_.odom_frame;
  odom.child_frame_id = params_.base_frame;
  odom.pose.pose.position.x = sample.pose.x;
  odom.pose.pose.position.y = sample.pose.y;
  odom.pose.pose.orientation = ekf_slam::ros_conversions::quaternionOfYaw(sample.pose.theta);
  const double position_variance = params_.position_variance_per_metre * sample.distance_travelled;
  odom.pose.covariance[0] = odom.pose.covariance[7] = position_variance;
  odom.pose.covariance[14] = odom.pose.covariance[21] = odom.pose.covariance[28] = kLargeVariance;
  odom.pose.covariance[35] = params_.yaw_variance_per_radian * sample.angle_turned +
                             params_.yaw_variance_per_metre * sample.distance_travelled;
  odom.twist.twist.linear.x = sample.linear_velocity;
  odom.twist.twist.angular.z = sample.angular_velocity;
  odom.twist.covariance[0] = odom.twist.covariance[7] = params_.linear_velocity_variance;
  odom.twist.covariance[14] = odom.twist.covariance[21] = odom.twist.covariance[28] =
      kLargeVariance;
  odom.twist.covariance[35] = params_.angular_velocity_variance;
  odom_publisher_.publish(odom);

  if (params_.publish_tf) {
    geometry_msgs::TransformStamped transform;
    transform.header = odom.header;
    transform.child_frame_id = params_.base_frame;
    transform.transform.translation.x = sample.pose.x;
    transform.transform.translation.y = sample.pose.y;
    transform.transform.rotation = odom.pose.pose.orientation;
    tf_broadcaster_.sendTransform(transform);
  }

  const StandardSip& sip = sample.sip;
  sensor_msgs::BatteryState battery;
  battery.header.stamp = stamp;
  battery.voltage = static_cast<float>(sip.batteryVolts());
  battery.current = battery.charge = battery.capacity = battery.design_capacity =
      battery.percentage = std::nanf("");
  battery.power_supply_status = sensor_msgs::BatteryState::POWER_SUPPLY_STATUS_UNKNOWN;
  battery.power_supply_health = sensor_msgs::BatteryState::POWER_SUPPLY_HEALTH_UNKNOWN;
  battery.power_supply_technology = sensor_msgs::BatteryState::POWER_SUPPLY_TECHNOLOGY_UNKNOWN;
  battery.present = true;
  battery_publisher_.publish(battery);

  if (published_motors_ != sip.motorsEnabled()) {
    std_msgs::Bool message;
    message.data = sip.motorsEnabled();
    motors_publisher_.publish(message);
    published_motors_ = sip.motorsEnabled();
  }
  const uint16_t bumpers = static_cast<uint16_t>(sip.stall_bump & 0xFEFE);
  if (published_bumpers_ != bumpers) {
    std_msgs::UInt16 message;
    message.data = bumpers;
    bumpers_publisher_.publish(message);
    published_bumpers_ = bumpers;
  }
  const bool stalled = sip.leftStall() || sip.rightStall();
  if (published_stall_ != stalled) {
    std_msgs::Bool message;
    message.data = stalled;
    stall_publisher_.publish(message);
    published_stall_ = stalled;
    if (stalled)
      ROS_WARN("p3dx: wheel stall (left %d, right %d)", sip.leftStall(), sip.rightStall());
  }
  if (!sonar_publishers_.empty()) publishSonar(sip, stamp);
  last_sip_ = sip;
}

void DriverNode::publishSonar(const StandardSip& sip, const ros::Time& stamp) {
  for (const SonarReading& reading : sip.sonars) {
    if (reading.index >= sonar_publishers_.size()) continue;
    sensor_msgs::Range range;
    range.header.stamp = stamp;
    range.header.frame_id = params_.sonar_frame_prefix + std::to_string(reading.index);
    range.radiation_type = sensor_msgs::Range::ULTRASOUND;
    range.field_of_view = 0.2618f;  // about 15°
    range.min_range = 0.1f;
    range.max_range = 5.0f;
    range.range = reading.range_mm * 1e-3f;
    if (range.range >= range.max_range) range.range = std::numeric_limits<float>::infinity();
    sonar_publishers_[reading.index].publish(range);
  }
}

void DriverNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const LinkStats stats = link_.stats();
  const ros::WallTime now = ros::WallTime::now();
  const double elapsed = (now - last_diagnosis_).toSec();
  const double rate = elapsed > 0.0 ? (stats.sips - sips_at_last_diagnosis_) / elapsed : 0.0;
  sips_at_last_diagnosis_ = stats.sips;
  last_diagnosis_ = now;

  const bool connected = link_.state() == LinkState::kConnected;
  if (!connected) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "disconnected: %s",
                    link_.lastError().c_str());
  } else if (last_sip_ && last_sip_->batteryVolts() < params_.battery_error_voltage) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "battery critical: %.1f V",
                    last_sip_->batteryVolts());
  } else if (last_sip_ && last_sip_->batteryVolts() < params_.battery_warn_voltage) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "battery low: %.1f V",
                    last_sip_->batteryVolts());
  } else if (last_sip_ && (last_sip_->leftStall() || last_sip_->rightStall())) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "wheel stall");
  } else if (last_sip_ && !last_sip_->motorsEnabled()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "motors disabled (call ~enable_motors)");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "connected");
  }
  status.add("link state", connected ? "connected" : "disconnected");
  status.add("port", params_.link.port);
  status.add("baud", link_.connectedBaud());
  status.add("robot", link_.identity().name + " (" + link_.identity().subclass + ")");
  status.addf("packet rate (Hz)", "%.1f", rate);
  status.add("packets", stats.sips);
  status.add("checksum errors", stats.checksum_errors);
  status.add("length errors", stats.length_errors);
  status.add("discarded bytes", stats.discarded_bytes);
  status.add("unparsable SIPs", stats.bad_sips);
  status.add("connects", stats.connects);
  status.add("disconnects", stats.disconnects);
  status.add("rejected cmd_vel", stats.rejected_commands);
  status.add("stale sessions closed", stats.stale_sessions_closed);
  if (!connected)
    status.addf("next attempt in (s)", "%.2f", link_.secondsUntilRetry(RobotLink::Clock::now()));
  if (last_sip_) {
    status.addf("battery (V)", "%.2f", last_sip_->batteryVolts());
    status.add("motors enabled", last_sip_->motorsEnabled());
    status.add("stalled", last_sip_->leftStall() || last_sip_->rightStall());
  }
  if (!link_.lastError().empty()) status.add("last error", link_.lastError());
}

}  // namespace p3dx
