// simulator_node: a simulated P3-DX with an LMS200 in a world image, behind
// two pseudo-terminals, so that the real driver nodes run unchanged: the
// same graph as on the robot, only the serial ports differ. Optionally a
// second, rear LMS200 on a third pseudo-terminal (~rear_lms200_link).
//
// One process, one world, one true pose: the P3-DX emulator drives the true
// pose (blocked by the walls through a motion hook with the robot radius);
// the LMS200 emulator ray-casts from the laser pose = true pose ∘ mount,
// the mount read from config/calibration.yaml (the file the SLAM side's tf
// comes from); the rear one likewise from its own mount
// (~rear_calibration_file, config/calibration_rear.yaml in sim.launch). All
// are stepped on one monotonic clock; the loop sleeps to the next deadline.
//
// Publishes the ground truth (docs/simulation.md):
//   ground_truth/odom   nav_msgs/Odometry, frame ground_truth (world), child
//                       base_link_truth, and the same as tf (a separate tree)
//   ground_truth/path   nav_msgs/Path in the SLAM map frame
//   ground_truth/world  nav_msgs/OccupancyGrid in the SLAM map frame, latched
// The SLAM map frame is the start pose: pose_in_map = start⁻¹ ∘ pose_in_world.
//
// Subscribes to ~teleport (geometry_msgs/Pose2D, in the SLAM map frame):
// the robot is carried there at once, its wheels turning nothing (a
// kidnapped robot); refused with a warning where the robot would touch a
// wall.
#include <geometry_msgs/Pose2D.h>
#include <ros/ros.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "ekf_slam_core/sim/grid_world.h"
#include "ekf_slam_ros/calibration/laser_mount.h"
#include "ekf_slam_ros/simulator/footprint.h"
#include "ekf_slam_ros/simulator/ground_truth.h"
#include "ekf_slam_ros/simulator/pose_history.h"
#include "ekf_slam_ros/simulator/simulator_params.h"
#include "p3dx_driver/emulator/p3dx_emulator.h"
#include "serial_io/pseudo_terminal.h"
#include "sick_lms200_driver/emulator/lms200_emulator.h"

namespace {

using ekf_slam::Pose2;

// A pseudo-terminal whose symlink's folder exists (created when missing).
bool openPty(serial_io::PseudoTerminal* pty, const std::string& link, std::string* error) {
  std::error_code ignored;
  const std::filesystem::path folder = std::filesystem::path(link).parent_path();
  if (!folder.empty()) std::filesystem::create_directories(folder, ignored);
  if (pty->open(link)) return true;
  *error = "cannot create the pseudo-terminal " + link + ": " + pty->error();
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulator");
  ros::NodeHandle node, private_node("~");

  ekf_slam::sim::SimulatorParams params;
  std::string error;
  if (!ekf_slam::sim::loadSimulatorParams(private_node, &params, &error)) {
    ROS_FATAL("simulator: bad parameters:\n%s", error.c_str());
    return 1;
  }
  ekf_slam::sim::GridWorld world;
  error = ekf_slam::sim::GridWorld::load(params.world_file, &world);
  if (!error.empty()) {
    ROS_FATAL("simulator: cannot load the world (parameter ~world_file): %s", error.c_str());
    return 1;
  }
  if (!world.hasStartPose()) {
    ROS_FATAL("simulator: %s has no start_pose: [x, y, yaw] (where the robot is put)",
              params.world_file.c_str());
    return 1;
  }
  const Pose2 start = world.startPose();
  if (!ekf_slam::sim::footprintFree(world, start.translation(), params.robot_radius)) {
    ROS_FATAL("simulator: start_pose (%.2f, %.2f) of %s is within robot_radius %.2f m of a wall",
              start.x, start.y, params.world_file.c_str(), params.robot_radius);
    return 1;
  }
  ekf_slam::calibration::LaserMount mount;
  error = ekf_slam::calibration::loadLaserMount(params.calibration_file, &mount);
  if (!error.empty()) {
    ROS_FATAL("simulator: parameter ~calibration_file: %s", error.c_str());
    return 1;
  }

  const bool rear = !params.rear_lms200_link.empty();
  ekf_slam::calibration::LaserMount rear_mount;
  if (rear) {
    error = ekf_slam::calibration::loadLaserMount(params.rear_calibration_file, &rear_mount);
    if (!error.empty()) {
      ROS_FATAL("simulator: parameter ~rear_calibration_file: %s", error.c_str());
      return 1;
    }
    if (rear_mount.child_frame == mount.child_frame) {
      ROS_FATAL(
          "simulator: ~rear_calibration_file %s names the child_frame '%s' of "
          "~calibration_file %s: the two lasers need frames of their own",
          params.rear_calibration_file.c_str(), rear_mount.child_frame.c_str(),
          params.calibration_file.c_str());
      return 1;
    }
  }

  serial_io::PseudoTerminal p3dx_pty, lms200_pty;
  if (!openPty(&p3dx_pty, params.p3dx_link, &error) ||
      !openPty(&lms200_pty, params.lms200_link, &error)) {
    ROS_FATAL("simulator: %s", error.c_str());
    return 1;
  }
  std::unique_ptr<serial_io::PseudoTerminal> rear_pty;
  if (rear) {
    rear_pty = std::make_unique<serial_io::PseudoTerminal>();
    if (!openPty(rear_pty.get(), params.rear_lms200_link, &error)) {
      ROS_FATAL("simulator: %s", error.c_str());
      return 1;
    }
  }

  // The robot. Its odometry starts at zero at the driver's OPEN, as on the
  // real controller; its true pose starts at the world's start pose.
  p3dx::EmulatorOptions robot_options;
  robot_options.name = "simulated";
  robot_options.wheel_noise = params.wheel_noise;
  robot_options.seed = static_cast<uint32_t>(params.seed);
  p3dx::P3dxEmulator robot(&p3dx_pty, robot_options);
  robot.setTruePose(start);
  uint64_t blocked_steps = 0;
  robot.setMotionHook([&](const Pose2& current, const Pose2& proposed) {
    if (ekf_slam::sim::footprintFree(world, proposed.translation(), params.robot_radius)) {
      return true;
    }
    ++blocked_steps;
    ROS_WARN_THROTTLE(2.0, "simulator: the robot touches a wall at (%.2f, %.2f); it stalls",
                      current.x, current.y);
    return false;
  });

  // The scanner, looking from the true pose at each mirror turn's start.
  ekf_slam::sim::PoseHistory history(1.0);
  sick_lms200::EmulatorOptions laser_options;
  laser_options.range_noise_sigma = params.range_noise;
  laser_options.seed = static_cast<uint32_t>(params.seed) + 1;
  laser_options.roll = mount.roll;
  laser_options.pitch = mount.pitch;
  const Pose2 laser_in_base = mount.pose();
  sick_lms200::Lms200Emulator laser(
      lms200_pty, world, [&](double t) { return ekf_slam::compose(history.at(t), laser_in_base); },
      laser_options);
  laser.setPeerBaudSource([&lms200_pty] { return lms200_pty.peerBaud(); });
  uint64_t scans = 0;
  laser.setScanObserver([&](const sick_lms200::TrueScan&) { ++scans; });

  // The rear scanner: its own mount, pty and noise stream, the same world
  // and true pose.
  std::unique_ptr<sick_lms200::Lms200Emulator> rear_laser;
  uint64_t rear_scans = 0;
  if (rear) {
    sick_lms200::EmulatorOptions rear_options = laser_options;
    rear_options.seed = static_cast<uint32_t>(params.seed) + 2;
    rear_options.roll = rear_mount.roll;
    rear_options.pitch = rear_mount.pitch;
    const Pose2 rear_in_base = rear_mount.pose();
    serial_io::PseudoTerminal* pty = rear_pty.get();
    rear_laser = std::make_unique<sick_lms200::Lms200Emulator>(
        *pty, world,
        [&history, rear_in_base](double t) {
          return ekf_slam::compose(history.at(t), rear_in_base);
        },
        rear_options);
    rear_laser->setPeerBaudSource([pty] { return pty->peerBaud(); });
    rear_laser->setScanObserver([&](const sick_lms200::TrueScan&) { ++rear_scans; });
  }

  ekf_slam::sim::GroundTruthPublisher::Frames frames;
  frames.truth = params.truth_frame;
  frames.truth_child = params.truth_child_frame;
  frames.map = params.map_frame;
  ekf_slam::sim::GroundTruthPublisher truth_publisher(node, world, start, frames,
                                                      params.path_spacing);

  ROS_INFO(
      "simulator: world %s (%d x %d cells), start (%.2f, %.2f, %.3f); P3-DX on %s, "
      "LMS200 on %s; laser mount (%.3f, %.3f, %.3f), roll %.4f, pitch %.4f rad from %s",
      params.world_file.c_str(), world.width(), world.height(), start.x, start.y, start.theta,
      params.p3dx_link.c_str(), params.lms200_link.c_str(), mount.x, mount.y, mount.yaw, mount.roll,
      mount.pitch, params.calibration_file.c_str());
  if (rear) {
    ROS_INFO("simulator: rear LMS200 on %s; laser mount (%.3f, %.3f, %.3f) from %s",
             params.rear_lms200_link.c_str(), rear_mount.x, rear_mount.y, rear_mount.yaw,
             params.rear_calibration_file.c_str());
  }

  using Clock = std::chrono::steady_clock;
  const Clock::time_point epoch = Clock::now();
  auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - epoch).count(); };

  // Callbacks run in the loop below (ros::spinOnce), between its steps.
  const ros::Subscriber teleport = private_node.subscribe<geometry_msgs::Pose2D>(
      "teleport", 1, [&](const geometry_msgs::Pose2D::ConstPtr& message) {
        const Pose2 in_world =
            ekf_slam::compose(start, Pose2(message->x, message->y, message->theta));
        if (!in_world.allFinite() ||
            !ekf_slam::sim::footprintFree(world, in_world.translation(), params.robot_radius)) {
          ROS_WARN(
              "simulator: teleport to (%.2f, %.2f) refused: not finite, or within "
              "robot_radius %.2f m of a wall",
              message->x, message->y, params.robot_radius);
          return;
        }
        robot.setTruePose(in_world);
        history.jump(seconds(), in_world);
        ROS_INFO("simulator: the robot is carried to (%.2f, %.2f, %.2f) in the map frame",
                 message->x, message->y, message->theta);
      });
  const double truth_period = 1.0 / params.ground_truth_rate;
  double next_robot_step = 0.0, next_truth = 0.0;
  history.add(0.0, start);
  // The true pose is that of the last robot step; the truth is stamped with
  // that step's time, not with the (up to one step later) publishing time,
  // which at 0.5 rad/s would put 2.5 mrad of error into the truth.
  ros::Time true_pose_stamp = ros::Time::now(), last_truth_stamp;
  while (ros::ok()) {
    ros::spinOnce();
    const double now = seconds();
    if (now >= next_robot_step) {
      robot.step(now);
      true_pose_stamp = ros::Time::now();
      history.add(now, robot.truePose());
      next_robot_step = std::max(next_robot_step + params.robot_step, now);
    }
    laser.spinOnce(now);
    if (rear_laser) rear_laser->spinOnce(now);
    if (now >= next_truth) {
      next_truth = std::max(next_truth + truth_period, now);
      if (true_pose_stamp > last_truth_stamp) {  // each pose once (tf refuses repeats)
        last_truth_stamp = true_pose_stamp;
        truth_publisher.publish(robot.truePose(), robot.velocity(), robot.rotationalVelocity(),
                                true_pose_stamp);
      }
    }
    // Sleep to the earliest deadline; at most 5 ms so that commands from
    // the drivers are answered promptly (a real device answers within ms).
    double wake =
        std::min({next_robot_step, next_truth, laser.nextDeadline(now), seconds() + 0.005});
    if (rear_laser) wake = std::min(wake, rear_laser->nextDeadline(now));
    const double sleep = wake - seconds();
    if (sleep > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(sleep));
  }
  // rosconsole is already shut down here (SIGINT): plain stdout.
  if (rear_laser) {
    std::printf("simulator: %lu rear scans\n", static_cast<unsigned long>(rear_scans));
  }
  std::printf("simulator: stopping after %lu scans, %lu P3-DX SIPs, %lu blocked motion steps\n",
              static_cast<unsigned long>(scans),
              static_cast<unsigned long>(robot.stats().sips_sent),
              static_cast<unsigned long>(blocked_steps));
  std::fflush(stdout);
  return 0;
}
