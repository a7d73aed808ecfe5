// calibrate_laser_guided: the thesis's calibration of the laser mount
// (§3.4.1) as a guided procedure in a terminal, on the running robot
// (robot.launch or sim.launch):
//
//   rosrun ekf_slam calibrate_laser_guided [_write:=config/calibration.yaml]
//
// 1. pitch and roll: two objects whose tops the beam just grazes, straight
//    ahead and to one side; the rise between them, signed as the mount's
//    pitch and roll (optional; every later scan is levelled with them);
// 2. a box corner placed about 1.5 m ahead, 30° to the left, is averaged over
//    ~n_scans scans;
// 3. the robot drives ~move_distance straight ahead (through cmd_vel_in, so
//    the safety gate watches it; or the operator pushes it), the corner is
//    averaged again: the yaw;
// 4. the robot turns by ~turn_angle to the left, then to the right of its
//    heading: the translation from each turn, averaged.
// The result is printed with its standard deviations and, with ~write,
// written as a calibration file (the frames and z of ~calibration kept).
// The maths: ekf_slam_core/extrinsics/thesis_procedure.h, docs/maths.md.
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2/utils.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <string>
#include <vector>

#include "ekf_slam_core/extrinsics/thesis_procedure.h"
#include "ekf_slam_core/sensors/scan.h"
#include "ekf_slam_ros/calibration/laser_mount.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ros_params/private_params.h"

namespace {

using ekf_slam::kPi;
using ekf_slam::Pose2;
using ekf_slam::Vector2;

struct GuidedParams {
  std::string calibration;  // the mount in use (frames, z, the nominal pose)
  std::string write;        // where to write the result ("" : print only)
  int n_scans = 50;
  double move_distance = 0.5;              // m
  double turn_angle = 30.0 * kPi / 180.0;  // rad
  double speed = 0.1;                      // m/s
  double turn_rate = 0.2;                  // rad/s
  bool drive = true;                       // false: the operator moves the robot
};

class Robot {
 public:
  explicit Robot(ros::NodeHandle node) {
    scan_subscriber_ = node.subscribe("scan", 5, &Robot::onScan, this);
    odom_subscriber_ = node.subscribe("odom", 20, &Robot::onOdom, this);
    command_ = node.advertise<geometry_msgs::Twist>("cmd_vel_in", 1);
  }

  bool odometry(Pose2* pose) {
    std::lock_guard<std::mutex> lock(mutex_);
    *pose = odometry_;
    return have_odometry_;
  }

  // The next `count` scans (waits for them).
  std::vector<ekf_slam::Scan> collect(int count) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      scans_.clear();
      collecting_ = count;
    }
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(count * 0.5 + 5.0);
    while (ros::ok() && ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (static_cast<int>(scans_.size()) >= count) break;
      }
      ros::WallDuration(0.05).sleep();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    collecting_ = 0;
    return scans_;
  }

  // Drives straight (distance, m) or turns on the spot (turn, rad) on the
  // odometry, then waits until it is still. Returns the motion done.
  Pose2 move(double distance, double turn, const GuidedParams& p) {
    Pose2 start;
    odometry(&start);
    geometry_msgs::Twist twist;
    if (distance != 0.0) twist.linear.x = std::copysign(p.speed, distance);
    if (turn != 0.0) twist.angular.z = std::copysign(p.turn_rate, turn);
    const double expected =
        distance != 0.0 ? std::abs(distance) / p.speed : std::abs(turn) / p.turn_rate;
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(2.0 * expected + 3.0);
    ros::WallRate rate(20.0);
    while (ros::ok() && ros::WallTime::now() < deadline) {
      Pose2 now;
      odometry(&now);
      const Pose2 done = ekf_slam::between(start, now);
      if ((distance != 0.0 && std::hypot(done.x, done.y) >= std::abs(distance)) ||
          (turn != 0.0 && std::abs(done.theta) >= std::abs(turn))) {
        break;
      }
      command_.publish(twist);
      rate.sleep();
    }
    command_.publish(geometry_msgs::Twist());
    waitUntilStill();
    Pose2 end;
    odometry(&end);
    return ekf_slam::between(start, end);
  }

  void waitUntilStill() {
    Pose2 last;
    odometry(&last);
    int still = 0;
    for (int i = 0; i < 100 && ros::ok() && still < 8; ++i) {  // 0.4 s still, 5 s at most
      ros::WallDuration(0.05).sleep();
      Pose2 now;
      odometry(&now);
      still = ekf_slam::maxAbsDifference(now, last) < 1e-3 ? still + 1 : 0;
      last = now;
    }
  }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (collecting_ > 0 && static_cast<int>(scans_.size()) < collecting_) {
      scans_.push_back(ekf_slam::ros_conversions::fromLaserScan(*message));
    }
  }
  void onOdom(const nav_msgs::Odometry& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    odometry_ = Pose2(message.pose.pose.position.x, message.pose.pose.position.y,
                      tf2::getYaw(message.pose.pose.orientation));
    have_odometry_ = true;
  }

  std::mutex mutex_;
  ros::Subscriber scan_subscriber_, odom_subscriber_;
  ros::Publisher command_;
  std::vector<ekf_slam::Scan> scans_;
  int collecting_ = 0;
  Pose2 odometry_;
  bool have_odometry_ = false;
};

std::string ask(const std::string& prompt) {
  std::printf("%s", prompt.c_str());
  std::fflush(stdout);
  std::string line;
  if (!std::getline(std::cin, line)) return "q";
  return line;
}

// Step 1 (thesis eq. 3.36): the rise of the beam between two objects whose
// tops it just grazes, h1 at the nearer, h2 at the farther, d apart along
// the beam. Returns false (and leaves `rise`) when the operator skips.
bool askRise(const std::string& where, double* rise) {
  const std::string line =
      ask("  " + where +
          ": heights h1 h2 at which the beam just grazes the nearer and the farther object, "
          "and their distance d along the beam, in m (empty: skip): ");
  double h1, h2, d;
  if (std::sscanf(line.c_str(), "%lf %lf %lf", &h1, &h2, &d) != 3 || !(d > 0.0)) return false;
  *rise = ekf_slam::beamTilt(h1, h2, d);
  return true;
}

// The mount's pitch and roll from step 1, signed as the calibration file
// keeps them (REP-103: a positive pitch tips the front down, a positive roll
// lifts the left side). A beam that rises ahead has its front tipped up; one
// that rises to the left has its left side up, to the right its left side
// down. A step skipped keeps the value in use.
void askTilt(ekf_slam::calibration::LaserMount* mount) {
  std::printf(
      "Step 1, pitch and roll (the SLAM levels every scan with them). An object is seen while\n"
      "the beam meets it and lost once the beam passes over its top: for each object find the\n"
      "height at which the beam just grazes it (raise the object, or a card on it, until the\n"
      "scanner loses it). Pitch in use %.2f deg, roll %.2f deg.\n",
      mount->pitch * 180.0 / kPi, mount->roll * 180.0 / kPi);
  double rise = 0.0;
  if (askRise("pitch, two objects straight ahead", &rise)) {
    mount->pitch = -rise + 0.0;
    std::printf("  the beam %s %.2f deg ahead: the front is tipped %s; pitch %.2f deg\n",
                rise >= 0.0 ? "rises" : "falls", std::abs(rise) * 180.0 / kPi,
                rise >= 0.0 ? "up" : "down", mount->pitch * 180.0 / kPi);
  }
  const std::string side =
      ask("  roll, two objects to one side: l (left) or r (right) (empty: skip): ");
  if ((side == "l" || side == "r") && askRise(side == "l" ? "roll, left" : "roll, right", &rise)) {
    // Rising to the left lifts the left side; rising to the right lowers it.
    mount->roll = (side == "l" ? rise : -rise) + 0.0;  // + 0.0: no "-0.00" for a level beam
    std::printf("  the beam %s %.2f deg to the %s: the left side is %s; roll %.2f deg\n",
                rise >= 0.0 ? "rises" : "falls", std::abs(rise) * 180.0 / kPi,
                side == "l" ? "left" : "right", mount->roll >= 0.0 ? "up" : "down",
                mount->roll * 180.0 / kPi);
  }
}

// The reference corner, averaged over n_scans scans levelled with the
// mount's tilt, near `near` (laser frame).
ekf_slam::FeatureSighting sight(Robot* robot, const GuidedParams& p,
                                const ekf_slam::calibration::LaserMount& mount, const Vector2& near,
                                double gate, const char* when) {
  std::printf("  averaging %d scans %s ...\n", p.n_scans, when);
  std::vector<ekf_slam::Scan> scans = robot->collect(p.n_scans);
  for (ekf_slam::Scan& scan : scans) scan = ekf_slam::levelledScan(scan, mount.roll, mount.pitch);
  const ekf_slam::FeatureSighting s = ekf_slam::sightFeature(scans, near, gate);
  if (s.ok) {
    std::printf("  corner at (%.4f, %.4f) m in the laser frame, from %d scans\n", s.mean.x(),
                s.mean.y(), s.scans);
  } else {
    std::printf("  %s\n", s.message.c_str());
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "calibrate_laser_guided");
  ros::NodeHandle node, private_node("~");
  GuidedParams p;
  ekf_slam::PrivateParams load(private_node);
  load.text("calibration", &p.calibration, false);
  load.text("write", &p.write, false);
  load.integer("n_scans", &p.n_scans, 5, 1000);
  load.number("move_distance", &p.move_distance, 0.2, 2.0);
  load.number("turn_angle", &p.turn_angle, 0.3, 1.2);
  load.number("speed", &p.speed, 0.02, 0.5);
  load.number("turn_rate", &p.turn_rate, 0.05, 1.0);
  load.flag("drive", &p.drive);
  load.rejectUnknown();
  if (!load.ok()) {
    ROS_FATAL("calibrate_laser_guided: bad parameters:\n%s", load.errors().c_str());
    return 1;
  }
  ekf_slam::calibration::LaserMount mount;
  if (!p.calibration.empty()) {
    const std::string error = ekf_slam::calibration::loadLaserMount(p.calibration, &mount);
    if (!error.empty()) {
      ROS_FATAL("calibrate_laser_guided: %s", error.c_str());
      return 1;
    }
  }
  ros::AsyncSpinner spinner(1);
  spinner.start();
  Robot robot(node);

  std::printf(
      "Laser mount calibration (thesis 3.4.1). Mount in use: x %.3f m, y %.3f m, yaw %.2f deg.\n",
      mount.x, mount.y, mount.yaw * 180.0 / kPi);
  askTilt(&mount);

  Pose2 odometry;
  for (int i = 0; i < 100 && !robot.odometry(&odometry); ++i) ros::WallDuration(0.1).sleep();
  if (!robot.odometry(&odometry)) {
    std::printf("no odometry on %s: is the driver running?\n", node.resolveName("odom").c_str());
    return 1;
  }
  char prompt[400];
  std::snprintf(
      prompt, sizeof(prompt),
      "Step 2: place a box about 1.5 m ahead of the scanner so that one of its corners\n"
      "stands about 30 degrees to the left with both its sides in view, and leave %.2f m\n"
      "of free floor ahead. Enter to go on, q to quit: ",
      p.move_distance);
  if (ask(prompt) == "q") return 0;
  const ekf_slam::FeatureSighting first =
      sight(&robot, p, mount, Vector2(1.3, 0.75), 0.8, "before the drive");
  if (!first.ok) return 1;

  if (p.drive) {
    std::printf("Step 3: the robot drives %.2f m straight ahead ...\n", p.move_distance);
  } else {
    ask("Step 3: push the robot about " + std::to_string(p.move_distance) +
        " m straight towards the corner, then press Enter: ");
  }
  const Pose2 drove = p.drive ? robot.move(p.move_distance, 0.0, p) : [&] {
    Pose2 now;
    robot.waitUntilStill();
    robot.odometry(&now);
    return ekf_slam::between(odometry, now);
  }();
  const double distance = std::hypot(drove.x, drove.y);
  std::printf("  moved %.4f m (turned %.2f deg on the way)\n", distance, drove.theta * 180.0 / kPi);
  const Vector2 expected_after =
      first.mean - Pose2(0, 0, mount.yaw).rotation().transpose() * Vector2(distance, 0.0);
  const ekf_slam::FeatureSighting second =
      sight(&robot, p, mount, expected_after, 0.3, "after the drive");
  const ekf_slam::YawCalibration yaw = ekf_slam::yawFromStraightMove(first, second, distance);
  if (!yaw.ok) {
    std::printf("  no yaw: %s\n", yaw.message.c_str());
    return 1;
  }
  std::printf("  yaw %.3f +- %.3f deg\n", yaw.yaw * 180.0 / kPi, yaw.sigma * 180.0 / kPi);

  std::printf("Step 4: the robot turns on the spot by %.0f deg to each side ...\n",
              p.turn_angle * 180.0 / kPi);
  Vector2 sum = Vector2::Zero();
  ekf_slam::Matrix2 information = ekf_slam::Matrix2::Zero();
  double turned_total = 0.0;
  for (double side : {1.0, -2.0}) {  // left by the angle, then right past the start
    const double request = side * p.turn_angle;
    Pose2 turned;
    if (p.drive) {
      turned = robot.move(0.0, request, p);
    } else {
      Pose2 before;
      robot.odometry(&before);
      ask("  turn the robot on the spot by about " + std::to_string(request * 180.0 / kPi) +
          " deg, then press Enter: ");
      robot.waitUntilStill();
      Pose2 now;
      robot.odometry(&now);
      turned = ekf_slam::between(before, now);
    }
    turned_total += turned.theta;
    const Pose2 believed(mount.x, mount.y, yaw.yaw);
    const Vector2 in_robot = ekf_slam::transformFrom(believed, second.mean);
    const Vector2 near =
        ekf_slam::transformTo(believed, ekf_slam::transformTo(Pose2(0, 0, turned_total), in_robot));
    const ekf_slam::FeatureSighting after = sight(&robot, p, mount, near, 0.3, "after the turn");
    const ekf_slam::TranslationCalibration t =
        ekf_slam::translationFromTurn(second, after, turned_total, yaw.yaw, yaw.sigma);
    if (!t.ok) {
      std::printf("  no translation from this turn: %s\n", t.message.c_str());
      continue;
    }
    std::printf("  turned %.2f deg: x %.4f, y %.4f m (+- %.4f, %.4f)\n", turned_total * 180.0 / kPi,
                t.translation.x(), t.translation.y(), std::sqrt(t.covariance(0, 0)),
                std::sqrt(t.covariance(1, 1)));
    const ekf_slam::Matrix2 w = t.covariance.inverse();
    information += w;
    sum += w * t.translation;
  }
  if (p.drive) robot.move(0.0, -turned_total, p);  // back to the start heading
  if (information.determinant() <= 0.0) {
    std::printf("no translation: the corner was lost in both turns\n");
    return 1;
  }
  const ekf_slam::Matrix2 covariance = information.inverse();
  const Vector2 translation = covariance * sum;
  std::printf(
      "Result: x %.4f +- %.4f m, y %.4f +- %.4f m, yaw %.5f +- %.5f rad (%.3f deg), roll %.5f "
      "rad, pitch %.5f rad\n",
      translation.x(), std::sqrt(covariance(0, 0)), translation.y(), std::sqrt(covariance(1, 1)),
      yaw.yaw, yaw.sigma, yaw.yaw * 180.0 / kPi, mount.roll, mount.pitch);
  if (!p.write.empty()) {
    ekf_slam::calibration::LaserMount result = mount;
    result.x = translation.x();
    result.y = translation.y();
    result.yaw = yaw.yaw;
    char heading[320];
    std::snprintf(heading, sizeof(heading),
                  "The laser mount (base_link -> laser) from calibrate_laser_guided (thesis\n"
                  "3.4.1): 1-sigma x %.4f m, y %.4f m, yaw %.5f rad. Roll and pitch from the\n"
                  "heights of step 1 (or as they were); z is carried over.",
                  std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)), yaw.sigma);
    const std::string error = ekf_slam::calibration::saveLaserMount(p.write, result, heading);
    if (!error.empty()) {
      std::printf("not written: %s\n", error.c_str());
      return 1;
    }
    std::printf("written to %s\n", p.write.c_str());
  }
  return 0;
}
