// p3dx_driver_node: the ROS shell around RobotLink. Converts cmd_vel into
// link commands and SIPs into odom / tf / battery / bumpers / stall / sonar
// messages, offers the motor and odometry services and reports the link on
// /diagnostics. All protocol and connection logic lives in RobotLink.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include "p3dx_driver/node/driver_params.h"
#include "p3dx_driver/protocol/robot_link.h"

namespace p3dx {

class DriverNode {
 public:
  DriverNode(ros::NodeHandle node, ros::NodeHandle private_node, DriverParams params);

  // Runs until ROS shuts down, then stops the robot and closes the session.
  void run();

 private:
  void onCmdVel(const geometry_msgs::Twist& twist);
  bool onEnableMotors(std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response);
  bool onResetOdometry(std_srvs::Trigger::Request& request, std_srvs::Trigger::Response& response);
  void publish(const OdometrySample& sample);
  void publishSonar(const StandardSip& sip, const ros::Time& stamp);
  void reportLinkChanges();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle node_, private_node_;
  DriverParams params_;
  RobotLink link_;

  ros::Subscriber cmd_vel_subscriber_;
  ros::Publisher odom_publisher_, battery_publisher_, motors_publisher_, bumpers_publisher_,
      stall_publisher_;
  std::vector<ros::Publisher> sonar_publishers_;
  ros::ServiceServer enable_service_, reset_service_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  diagnostic_updater::Updater updater_;

  LinkState reported_state_ = LinkState::kDisconnected;
  std::string reported_error_;
  std::optional<StandardSip> last_sip_;
  std::optional<bool> published_motors_;
  std::optional<uint16_t> published_bumpers_;
  std::optional<bool> published_stall_;
  uint64_t sips_at_last_diagnosis_ = 0;
  ros::WallTime last_diagnosis_;
};

}  // namespace p3dx
