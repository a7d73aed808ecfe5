// safety_gate_node: passes velocity commands from cmd_vel_in to cmd_vel
// (the P3-DX driver) through SafetyGate: it slows or stops the robot before
// the laser's readings enter its footprint, on a pressed bumper and on a
// wheel stall, and reports every stop on /diagnostics and in the log.
//
// Topics: cmd_vel_in (geometry_msgs/Twist, from teleop, step mode or the
// waypoint driver), scan (sensor_msgs/LaserScan, its stamp on this
// computer's clock), odom (nav_msgs/Odometry: the robot's velocity),
// bumpers (std_msgs/UInt16, the SIP's stall/bump word as p3dx_driver
// publishes it), stall (std_msgs/Bool) in; cmd_vel (geometry_msgs/Twist)
// out.
//
// The last command is re-checked and re-sent at `rate` while it is fresher
// than input_timeout, so an obstacle that appears stops a robot that keeps
// its command; once the input falls silent the gate sends one zero command
// and then nothing, leaving the driver's own cmd_vel watchdog in charge.
// Parameters: docs/bringup.md, "Safety".
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/Bool.h>
#include <std_msgs/UInt16.h>
#include <tf2/exceptions.h>
#include <tf2/utils.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <csignal>
#include <map>
#include <string>
#include <vector>

#include "ekf_slam_ros/safety/safety_gate.h"
#include "ros_params/private_params.h"

namespace {

using ekf_slam::Pose2;
using ekf_slam::Vector2;
namespace safety = ekf_slam::safety;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

struct GateParams {
  safety::SafetyOptions gate;
  std::string base_frame = "base_link";
  double input_timeout = 0.5;  // s: an older command is not re-sent
  double rate = 20.0;          // Hz, re-check of the last command
};

bool loadParams(const ros::NodeHandle& private_node, GateParams* params, std::string* error) {
  ekf_slam::PrivateParams load(private_node);
  safety::SafetyOptions& g = params->gate;
  load.number("footprint_front", &g.footprint_front, 0.0, 3.0);
  load.number("footprint_rear", &g.footprint_rear, 0.0, 3.0);
  load.number("footprint_half_width", &g.footprint_half_width, 0.01, 3.0);
  load.number("clearance", &g.clearance, 0.0, 2.0);
  load.number("deceleration", &g.deceleration, 0.01, 10.0);
  load.number("angular_deceleration", &g.angular_deceleration, 0.01, 50.0);
  load.number("reaction_time", &g.reaction_time, 0.0, 5.0);
  load.number("min_range", &g.min_range, 0.0, 1.0);
  load.number("scan_timeout", &g.scan_timeout, 0.05, 10.0);
  load.number("stall_hold", &g.stall_hold, 0.0, 60.0);
  load.flag("use_laser", &g.use_laser);
  load.text("base_frame", &params->base_frame);
  load.number("input_timeout", &params->input_timeout, 0.05, 10.0);
  load.number("rate", &params->rate, 1.0, 200.0);
  load.allow("diagnostic_period");
  load.rejectUnknown();
  *error = load.errors();
  return load.ok();
}

class SafetyGateNode {
 public:
  SafetyGateNode(ros::NodeHandle node, const GateParams& params)
      : params_(params), gate_(params.gate), tf_listener_(tf_buffer_) {
    cmd_publisher_ = node.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    cmd_subscriber_ = node.subscribe("cmd_vel_in", 1, &SafetyGateNode::onCommand, this);
    scan_subscriber_ = node.subscribe("scan", 1, &SafetyGateNode::onScan, this);
    odom_subscriber_ = node.subscribe("odom", 5, &SafetyGateNode::onOdometry, this);
    bumper_subscriber_ = node.subscribe("bumpers", 5, &SafetyGateNode::onBumpers, this);
    stall_subscriber_ = node.subscribe("stall", 5, &SafetyGateNode::onStall, this);
    timer_ = node.createTimer(ros::Duration(1.0 / params.rate), &SafetyGateNode::onTimer, this);
    diagnostics_.setHardwareID("safety_gate");
    diagnostics_.add("safety gate", this, &SafetyGateNode::diagnose);
  }

  void stop() { cmd_publisher_.publish(geometry_msgs::Twist()); }

 private:
  void onCommand(const geometry_msgs::Twist& message) {
    if (!std::isfinite(message.linear.x) || !std::isfinite(message.angular.z)) {
      ROS_WARN_THROTTLE(2.0,
                        "safety_gate: a command that is not finite (%g m/s, %g rad/s) "
                        "refused; the robot is stopped",
                        message.linear.x, message.angular.z);
      request_ = safety::Command{};
    } else {
      request_ = {message.linear.x, message.angular.z};
    }
    request_time_ = ros::Time::now();
    have_request_ = true;
    sendDecision();
  }

  void onScan(const sensor_msgs::LaserScan& scan) {
    Pose2 mount;
    try {
      const geometry_msgs::TransformStamped t =
          tf_buffer_.lookupTransform(params_.base_frame, scan.header.frame_id, ros::Time(0));
      mount = Pose2(t.transform.translation.x, t.transform.translation.y,
                    tf2::getYaw(t.transform.rotation));
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5.0,
                        "safety_gate: scan ignored, no transform %s -> %s: %s (forward "
                        "motion stays refused until it arrives)",
                        params_.base_frame.c_str(), scan.header.frame_id.c_str(), e.what());
      return;
    }
    std::vector<Vector2> points;
    points.reserve(scan.ranges.size());
    for (size_t i = 0; i < scan.ranges.size(); ++i) {
      const double r = scan.ranges[i];
      if (!std::isfinite(r) || r < scan.range_min || r > scan.range_max) continue;
      const double bearing = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
      points.push_back(
          ekf_slam::transformFrom(mount, Vector2(r * std::cos(bearing), r * std::sin(bearing))));
    }
    // Judged by when the scan was measured, not when it arrived: a scan
    // held up on a loaded computer shows the obstacles as they were.
    const double age = (ros::Time::now() - scan.header.stamp).toSec();
    if (age > params_.gate.scan_timeout) {
      ROS_WARN_THROTTLE(5.0,
                        "safety_gate: a scan measured %.2f s ago arrived (scan_timeout %.2f s): "
                        "forward motion refused until a fresh one; a loaded computer, or the "
                        "laser's clock apart from this one's",
                        age, params_.gate.scan_timeout);
    }
    gate_.setObstacles(std::move(points), scan.header.stamp.toSec());
    if (live()) sendDecision();
  }

  void onOdometry(const nav_msgs::Odometry& message) {
    const geometry_msgs::Twist& t = message.twist.twist;
    if (std::isfinite(t.linear.x) && std::isfinite(t.angular.z)) {
      gate_.setMotion({t.linear.x, t.angular.z});
    }
  }

  void onBumpers(const std_msgs::UInt16& message) {
    gate_.setBumpers((message.data >> 9) & 0x7F, (message.data >> 1) & 0x7F);
    if (live()) sendDecision();
  }

  void onStall(const std_msgs::Bool& message) {
    gate_.setStall(message.data, ros::Time::now().toSec());
    if (live() || message.data) sendDecision();
  }

  void onTimer(const ros::TimerEvent&) {
    if (have_request_) {
      if (live()) {
        sendDecision();
      } else {
        stop();  // the input fell silent: one zero, then the driver's watchdog
        have_request_ = false;
      }
    }
    diagnostics_.update();
  }

  bool live() const {
    return have_request_ && (ros::Time::now() - request_time_).toSec() <= params_.input_timeout;
  }

  void sendDecision() {
    const safety::GateDecision decision = gate_.filter(request_, ros::Time::now().toSec());
    if (decision.reason != last_reason_) {
      if (decision.reason != safety::StopReason::kNone) {
        ++stops_[decision.reason];
        ROS_WARN(
            "safety_gate: %s: commanded (%.2f m/s, %.2f rad/s), allowed (%.2f m/s, "
            "%.2f rad/s)",
            safety::toString(decision.reason), request_.linear, request_.angular,
            decision.command.linear, decision.command.angular);
      } else {
        ROS_INFO("safety_gate: clear again (%s is over)", safety::toString(last_reason_));
      }
      last_reason_ = decision.reason;
    }
    last_decision_ = decision;
    geometry_msgs::Twist out;
    out.linear.x = decision.command.linear;
    out.angular.z = decision.command.angular;
    cmd_publisher_.publish(out);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    if (last_reason_ == safety::StopReason::kNone) {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "clear");
    } else {
      status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "limiting the robot: %s",
                      safety::toString(last_reason_));
    }
    status.add("active reason", safety::toString(last_reason_));
    status.add("closest reading along the stopping path (m)", last_decision_.closest);
    for (safety::StopReason reason : safety::kAllStopReasons) {
      status.add(std::string("stops: ") + safety::toString(reason), stops_[reason]);
    }
  }

  GateParams params_;
  safety::SafetyGate gate_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Publisher cmd_publisher_;
  ros::Subscriber cmd_subscriber_, scan_subscriber_, odom_subscriber_, bumper_subscriber_,
      stall_subscriber_;
  ros::Timer timer_;
  diagnostic_updater::Updater diagnostics_;
  safety::Command request_;
  ros::Time request_time_;
  bool have_request_ = false;
  safety::StopReason last_reason_ = safety::StopReason::kNone;
  safety::GateDecision last_decision_;
  std::map<safety::StopReason, long> stops_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "safety_gate", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  ros::NodeHandle node, private_node("~");
  GateParams params;
  std::string error;
  if (!loadParams(private_node, &params, &error)) {
    ROS_FATAL("safety_gate: bad parameters:\n%s", error.c_str());
    return 1;
  }
  SafetyGateNode gate(node, params);
  ROS_INFO(
      "safety_gate: cmd_vel_in -> cmd_vel; footprint %.3f m ahead, %.3f m behind, %.3f m "
      "to each side, clearance %.2f m%s",
      params.gate.footprint_front, params.gate.footprint_rear, params.gate.footprint_half_width,
      params.gate.clearance,
      params.gate.use_laser ? "" : " (laser check off: bumpers and stall only)");
  while (!g_stop && ros::ok()) {
    ros::spinOnce();
    ros::WallDuration(0.002).sleep();
  }
  // Leave the robot at rest (the driver's cmd_vel watchdog would stop it
  // too, later).
  gate.stop();
  ros::WallDuration(0.1).sleep();
  ros::shutdown();
  return 0;
}
