// waypoint_driver: drives the robot through the waypoints of a YAML file by
// pure pursuit on its pose from tf (global_frame -> base_frame), e.g. the
// SLAM pose (map) or the odometry (odom). Publishes cmd_vel; publishes the
// latched std_msgs/Bool ~done (false at start, true once the last waypoint
// is reached) and the latched ~path (the waypoints, nav_msgs/Path).
//
// It stops the robot (a zero cmd_vel, logged with the reason) when it is
// done, when it shuts down, and whenever the pose is lost (no transform, or
// one older than tf_timeout); it resumes when the pose returns. A robot that
// does not move while it is told to (the safety gate holding it at an
// obstacle; judged on the odometry, odom_frame -> base_frame) backs off and tries again, and gives
// up after max_backoffs tries (BlockageRecovery in pure_pursuit.h); ~done then stays false.
// Parameters: docs/simulation.md, "`waypoint_driver`".
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "ekf_slam_ros/waypoints/pure_pursuit.h"
#include "ekf_slam_ros/waypoints/robot_pose.h"
#include "ekf_slam_ros/waypoints/waypoint_file.h"
#include "ros_conversions/pose_conversion.h"
#include "ros_params/private_params.h"

namespace {

using ekf_slam::Pose2;
using ekf_slam::Vector2;
namespace waypoints = ekf_slam::waypoints;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

struct DriverParams {
  std::string waypoints_file;
  std::string global_frame = "map";
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";  // the recovery watches the motion here; empty: global_frame
  int laps = 1;                     // times a closed loop is driven
  double rate = 20.0;               // Hz, control loop
  double tf_timeout = 0.5;          // s, an older pose counts as lost
  waypoints::PursuitOptions pursuit;
  waypoints::RecoveryOptions recovery;
};

bool loadParams(const ros::NodeHandle& private_node, DriverParams* params, std::string* error) {
  ekf_slam::PrivateParams load(private_node);
  load.text("waypoints_file", &params->waypoints_file);
  load.text("global_frame", &params->global_frame);
  load.text("base_frame", &params->base_frame);
  load.text("odom_frame", &params->odom_frame, /*required=*/false);
  load.integer("laps", &params->laps, 1, 1000);
  load.number("rate", &params->rate, 1.0, 200.0);
  load.number("tf_timeout", &params->tf_timeout, 0.05, 10.0);
  waypoints::PursuitOptions& p = params->pursuit;
  load.number("lookahead", &p.lookahead, 0.05, 10.0);
  load.number("max_linear_speed", &p.max_linear_speed, 0.01, 2.0);
  load.number("max_angular_speed", &p.max_angular_speed, 0.01, 5.0);
  load.number("max_linear_acceleration", &p.max_linear_acceleration, 0.01, 5.0);
  load.number("max_angular_acceleration", &p.max_angular_acceleration, 0.01, 20.0);
  load.number("goal_tolerance", &p.goal_tolerance, 0.01, 5.0);
  load.number("rotate_in_place_angle", &p.rotate_in_place_angle, 0.1, 3.1416);
  waypoints::RecoveryOptions& r = params->recovery;
  load.number("stuck_time", &r.stuck_time, 0.0, 600.0);
  load.number("stuck_distance", &r.stuck_distance, 0.001, 1.0);
  load.number("stuck_angle", &r.stuck_angle, 0.001, 1.0);
  load.number("stuck_fraction", &r.stuck_fraction, 0.0, 1.0);
  load.number("backoff_distance", &r.backoff_distance, 0.0, 2.0);
  load.number("backoff_speed", &r.backoff_speed, 0.01, 0.5);
  load.number("turn_speed", &r.turn_speed, 0.01, 3.0);
  load.integer("max_backoffs", &r.max_backoffs, 0, 100);
  load.number("progress_distance", &r.progress_distance, 0.0, 100.0);
  if (params->global_frame == params->base_frame) {
    load.fail("base_frame", "must differ from global_frame (" + params->global_frame + ")");
  }
  if (params->odom_frame == params->base_frame) {
    load.fail("odom_frame", "must differ from base_frame (" + params->base_frame + ")");
  }
  load.rejectUnknown();
  *error = load.errors();
  return load.ok();
}

geometry_msgs::Twist toTwist(const waypoints::VelocityCommand& command) {
  geometry_msgs::Twist twist;
  twist.linear.x = command.linear;
  twist.angular.z = command.angular;
  return twist;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "waypoint_driver", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  ros::NodeHandle node, private_node("~");

  DriverParams params;
  std::string error;
  if (!loadParams(private_node, &params, &error)) {
    ROS_FATAL("waypoint_driver: bad parameters:\n%s", error.c_str());
    return 1;
  }
  waypoints::WaypointFile file;
  error = waypoints::loadWaypointFile(params.waypoints_file, &file);
  if (!error.empty()) {
    ROS_FATAL("waypoint_driver: parameter ~waypoints_file: %s", error.c_str());
    return 1;
  }
  if (!file.closed && params.laps > 1) {
    ROS_WARN("waypoint_driver: %s is not a closed loop; laps = %d ignored, driven once",
             params.waypoints_file.c_str(), params.laps);
  }

  ros::Publisher cmd_publisher = node.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  ros::Publisher done_publisher = private_node.advertise<std_msgs::Bool>("done", 1, true);
  ros::Publisher path_publisher = private_node.advertise<nav_msgs::Path>("path", 1, true);
  std_msgs::Bool done;
  done.data = false;
  done_publisher.publish(done);

  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  std::unique_ptr<waypoints::PurePursuit> pursuit;
  waypoints::BlockageRecovery recovery(params.recovery);
  const std::vector<Vector2> laps = waypoints::expandLaps(file.waypoints, params.laps, file.closed);
  ROS_INFO("waypoint_driver: %zu waypoints from %s, %d lap(s), following %s -> %s",
           file.waypoints.size(), params.waypoints_file.c_str(), file.closed ? params.laps : 1,
           params.global_frame.c_str(), params.base_frame.c_str());

  bool pose_lost = true;  // until the first transform arrives
  bool finished = false;
  ros::Time last_update;
  ros::Rate rate(params.rate);
  const ros::Time started = ros::Time::now();
  while (!g_stop && ros::ok()) {
    ros::spinOnce();
    const ros::Time now = ros::Time::now();
    // The robot pose: the newest transform, refused when too old; and the
    // odometry's, on which the recovery watches whether the robot moves (a
    // correction of the SLAM pose is no motion).
    std::string why_lost;
    std::optional<Pose2> pose = waypoints::lookupRobotPose(
        tf_buffer, params.global_frame, params.base_frame, now, params.tf_timeout, &why_lost);
    std::optional<Pose2> odometry = pose;
    if (pose && !params.odom_frame.empty() && params.odom_frame != params.global_frame) {
      odometry = waypoints::lookupRobotPose(tf_buffer, params.odom_frame, params.base_frame, now,
                                            params.tf_timeout, &why_lost);
    }
    if (!pose || !odometry) {
      if (!pose_lost && pursuit) {
        ROS_WARN("waypoint_driver: robot stopped, pose lost: %s", why_lost.c_str());
        cmd_publisher.publish(geometry_msgs::Twist());
        pursuit->resetCommand();
        recovery.restartWatch();
      } else if (!pursuit && (now - started).toSec() > 5.0) {
        ROS_WARN_THROTTLE(10.0, "waypoint_driver: waiting for the robot pose: %s",
                          why_lost.c_str());
      }
      pose_lost = true;
      rate.sleep();
      continue;
    }
    if (pose_lost && pursuit) ROS_INFO("waypoint_driver: pose back, driving on");
    pose_lost = false;

    if (!pursuit) {
      // The path starts where the robot is.
      std::vector<Vector2> path{pose->translation()};
      path.insert(path.end(), laps.begin(), laps.end());
      pursuit = std::make_unique<waypoints::PurePursuit>(path, params.pursuit);
      std_msgs::Header header;
      header.stamp = now;
      header.frame_id = params.global_frame;
      path_publisher.publish(ekf_slam::ros_conversions::toPathMessage(path, header));
      ROS_INFO("waypoint_driver: starting at (%.2f, %.2f) in %s, %.1f m to drive", pose->x, pose->y,
               params.global_frame.c_str(), pursuit->remaining());
      last_update = now;
    }
    const double dt = std::max(0.0, (now - last_update).toSec());
    last_update = now;
    const waypoints::VelocityCommand wanted = pursuit->update(*pose, dt);
    const waypoints::RecoveryState before = recovery.state();
    const waypoints::VelocityCommand command =
        recovery.update(*odometry, now.toSec(), wanted, pursuit->remaining());
    if (recovery.state() != before) {
      switch (recovery.state()) {
        case waypoints::RecoveryState::kTurningAround:
          ROS_WARN(
              "waypoint_driver: blocked at (%.2f, %.2f) in %s turning on the spot for %.1f s: "
              "turning the other way round",
              pose->x, pose->y, params.global_frame.c_str(), params.recovery.stuck_time);
          break;
        case waypoints::RecoveryState::kBackingOff:
          ROS_WARN(
              "waypoint_driver: blocked at (%.2f, %.2f) in %s: no progress for %.1f s although "
              "motion was commanded (the safety gate holding the robot at an obstacle, or a "
              "stall); backing off %.2f m and trying again (%d of %d)",
              pose->x, pose->y, params.global_frame.c_str(), params.recovery.stuck_time,
              params.recovery.backoff_distance, recovery.backoffs(), params.recovery.max_backoffs);
          break;
        case waypoints::RecoveryState::kDriving:
          ROS_INFO("waypoint_driver: backed off to (%.2f, %.2f), driving on", pose->x, pose->y);
          pursuit->resetCommand();
          break;
        case waypoints::RecoveryState::kGaveUp:
          ROS_ERROR(
              "waypoint_driver: blocked at (%.2f, %.2f) in %s after %d back-offs; giving up with "
              "%.1f m of the path left. The robot stays at rest and ~done stays false; check "
              "the path's clearance from obstacles (safety gate log) and the pose",
              pose->x, pose->y, params.global_frame.c_str(), recovery.backoffs(),
              pursuit->remaining());
          break;
      }
    }
    if (!finished) cmd_publisher.publish(toTwist(command));
    if (pursuit->done() && !finished && wanted.linear == 0.0 && wanted.angular == 0.0) {
      finished = true;
      done.data = true;
      done_publisher.publish(done);
      ROS_INFO("waypoint_driver: done: last waypoint reached at (%.2f, %.2f) in %s", pose->x,
               pose->y, params.global_frame.c_str());
    }
    rate.sleep();
  }
  // Leave the robot at rest (the P3-DX driver would also stop it after its
  // cmd_vel_timeout, but an explicit zero is immediate).
  cmd_publisher.publish(geometry_msgs::Twist());
  ROS_INFO("waypoint_driver: shutting down, robot stopped%s", finished ? " (run complete)" : "");
  ros::Duration(0.1).sleep();
  ros::shutdown();
  return 0;
}
