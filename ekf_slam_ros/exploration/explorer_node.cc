// explorer_node: maps an unknown building by itself. It reads the live
// occupancy grid (`map`) and the robot's pose (tf, global_frame ->
// base_frame), drives to the frontier between the known free space and the
// unknown (ekf_slam_core/exploration/frontiers.h: the grid inflated by the
// robot's radius, the robot's own room first where rooms are known, then
// path length against the frontier's size), and replans as the map grows.
// When no reachable frontier is left, or a budget is spent, it drives back
// to where it started, asks the SLAM node to save the map and its whole
// state, and reports on /diagnostics.
//
// It drives through the same pure pursuit and blockage recovery as
// waypoint_driver, publishing on cmd_vel, which sim.launch and robot.launch
// route through the safety gate (cmd_vel_in). A frontier whose goal the
// robot reached without clearing it, or could not reach (blocked,
// max_backoffs back-offs), is tried again up to max_goal_tries times and
// then given up, with the reason in the log.
//
// Whether the robot moves (the recovery's watch, the distance driven) is
// judged on the odometry (odom_frame -> base_frame): the SLAM pose jumps
// with each correction.
//
// The robot stops (a zero cmd_vel, with the reason on /diagnostics) while
// its pose or its odometry is lost, while `map` is older than map_timeout, while paused,
// and for good on abort, when nothing is reachable, and at the end.
//
// Topics: map (nav_msgs/OccupancyGrid) in; cmd_vel (geometry_msgs/Twist),
// ~path (nav_msgs/Path, the planned path), ~frontiers
// (visualization_msgs/MarkerArray: the frontiers and the chosen goal),
// ~done (std_msgs/Bool, latched, true once home) out.
// Services: ~pause, ~resume, ~abort (std_srvs/Trigger).
// Parameters: config/exploration.yaml, docs/simulation.md "Exploration".
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ekf_slam/SaveMap.h"
#include "ekf_slam/StateFile.h"
#include "ekf_slam_core/exploration/frontiers.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"
#include "ekf_slam_ros/waypoints/pure_pursuit.h"
#include "ekf_slam_ros/waypoints/robot_pose.h"
#include "ros_conversions/pose_conversion.h"
#include "ros_params/param_fields.h"

namespace {

using ekf_slam::Pose2;
using ekf_slam::Vector2;
namespace waypoints = ekf_slam::waypoints;

// A back-off shorter than this (m) frees nothing.
constexpr double kMinBackoff = 0.05;
// Odometry poses kept of the floor the robot's body covered (one per 5 cm
// or 0.1 rad): some metres of driving, more than any back-off needs.
constexpr size_t kSweptPoses = 200;
// An odometry step longer than this (m) in one control step is a reset
// (a driver reconnected), not motion: the floor covered is forgotten.
constexpr double kOdometryJump = 1.0;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

struct ExplorerParams {
  std::string global_frame = "map";
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";  // motion (stuck watch, distance) measured here; empty: global
  double rate = 10.0;               // Hz, control loop
  double tf_timeout = 0.5;          // s: an older pose counts as lost
  double map_timeout = 15.0;        // s: an older `map` stops the robot
  double replan_period = 2.0;       // s between checks of the goal and path on the newest map
  double max_time = 0.0;            // s of exploring before it heads home; 0: no limit
  double max_distance = 0.0;        // m driven before it heads home; 0: no limit
  int max_goal_tries = 2;           // arrivals or blockages at one frontier before it is given up
  double goal_radius = 0.6;         // m: goals this close count as the same
  double home_tolerance = 0.3;      // m from the start that counts as home
  bool return_home = true;          // false: stop where exploring ends
  std::string save_path =
      "exploration";                   // saved map and state (relative: in ROS_HOME); empty: none
  std::string slam_node = "ekf_slam";  // whose save_map and write_state are called
  double robot_half_width = 0.25;      // m: half the body's width with a margin, for back-offs
  double robot_rear = 0.35;            // m from the centre to the rear with a margin, for back-offs
  double robot_front = 0.25;  // m from the centre to the front with a margin, for back-offs
  ekf_slam::ExplorationOptions exploration;
  waypoints::PursuitOptions pursuit;
  waypoints::RecoveryOptions recovery;

  template <class Visitor>
  void visitFields(Visitor& v) {
    using ekf_slam::Bounds;
    v.text("global_frame", global_frame);
    v.text("base_frame", base_frame);
    v.text("odom_frame", odom_frame);
    v.number("rate", rate, Bounds::closed(1.0, 100.0, "Hz"));
    v.number("tf_timeout", tf_timeout, Bounds::closed(0.05, 10.0, "s"));
    v.number("map_timeout", map_timeout, Bounds::closed(0.5, 600.0, "s"));
    v.number("replan_period", replan_period, Bounds::closed(0.1, 60.0, "s"));
    v.number("max_time", max_time, Bounds::closed(0.0, 1e6, "s"));
    v.number("max_distance", max_distance, Bounds::closed(0.0, 1e6, "m"));
    v.integer("max_goal_tries", max_goal_tries, Bounds::closed(1, 100, ""));
    v.number("goal_radius", goal_radius, Bounds::closed(0.05, 10.0, "m"));
    v.number("home_tolerance", home_tolerance, Bounds::closed(0.05, 10.0, "m"));
    v.flag("return_home", return_home);
    v.text("save_path", save_path);
    v.text("slam_node", slam_node);
    v.number("robot_half_width", robot_half_width, Bounds::closed(0.0, 5.0, "m"));
    v.number("robot_rear", robot_rear, Bounds::closed(0.0, 5.0, "m"));
    v.number("robot_front", robot_front, Bounds::closed(0.0, 5.0, "m"));
    exploration.visitFields(v);
    v.number("lookahead", pursuit.lookahead, Bounds::closed(0.05, 5.0, "m"));
    v.number("max_linear_speed", pursuit.max_linear_speed, Bounds::closed(0.01, 1.5, "m/s"));
    v.number("max_angular_speed", pursuit.max_angular_speed, Bounds::closed(0.01, 5.0, "rad/s"));
    v.number("goal_tolerance", pursuit.goal_tolerance, Bounds::closed(0.01, 5.0, "m"));
    v.number("stuck_time", recovery.stuck_time, Bounds::closed(0.0, 600.0, "s"));
    v.integer("max_backoffs", recovery.max_backoffs, Bounds::closed(0, 100, ""));
  }
};

bool loadParams(const ros::NodeHandle& private_node, ExplorerParams* params, std::string* error) {
  ekf_slam::PrivateParams read(private_node);
  read.allow("diagnostic_period");
  ekf_slam::PrivateParamFields fields(read);
  params->visitFields(fields);
  if (params->global_frame.empty()) read.fail("global_frame", "must not be empty");
  if (params->base_frame.empty() || params->base_frame == params->global_frame) {
    read.fail("base_frame", "must be set and differ from global_frame");
  }
  if (params->odom_frame == params->base_frame) {
    read.fail("odom_frame", "must differ from base_frame");
  }
  read.rejectUnknown();
  *error = read.errors();
  return read.ok();
}

std::string seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", s);
  return text;
}

// Where the robot is going, and why.
enum class Phase { kStarting, kExploring, kReturning, kFinished, kAborted, kFailed };

const char* toString(Phase phase) {
  switch (phase) {
    case Phase::kStarting:
      return "waiting for the map and the pose";
    case Phase::kExploring:
      return "exploring";
    case Phase::kReturning:
      return "returning to the start";
    case Phase::kFinished:
      return "finished";
    case Phase::kAborted:
      return "aborted";
    case Phase::kFailed:
      return "failed";
  }
  return "?";
}

// A frontier goal the robot went for, and how often it did.
struct GoalRecord {
  Vector2 at;
  int tries = 0;
  bool given_up = false;
};

class Explorer {
 public:
  Explorer(ros::NodeHandle node, ros::NodeHandle private_node, ExplorerParams params)
      : params_(std::move(params)),
        tf_listener_(tf_buffer_),
        recovery_(params_.recovery),
        swept_(params_.robot_front, params_.robot_rear, params_.robot_half_width, kSweptPoses) {
    map_subscriber_ = node.subscribe("map", 1, &Explorer::onMap, this);
    cmd_publisher_ = node.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    path_publisher_ = private_node.advertise<nav_msgs::Path>("path", 1, true);
    marker_publisher_ =
        private_node.advertise<visualization_msgs::MarkerArray>("frontiers", 1, true);
    done_publisher_ = private_node.advertise<std_msgs::Bool>("done", 1, true);
    services_.push_back(private_node.advertiseService("pause", &Explorer::onPause, this));
    services_.push_back(private_node.advertiseService("resume", &Explorer::onResume, this));
    services_.push_back(private_node.advertiseService("abort", &Explorer::onAbort, this));
    save_map_ = node.serviceClient<ekf_slam::SaveMap>(params_.slam_node + "/save_map");
    write_state_ = node.serviceClient<ekf_slam::StateFile>(params_.slam_node + "/write_state");
    std_msgs::Bool done;
    done.data = false;
    done_publisher_.publish(done);
    diagnostics_.setHardwareID("explorer");
    diagnostics_.add("exploration", this, &Explorer::diagnose);
    started_ = ros::Time::now();
  }

  void step() {
    const ros::Time now = ros::Time::now();
    diagnostics_.update();
    if (phase_ == Phase::kFinished || phase_ == Phase::kAborted || phase_ == Phase::kFailed) {
      return;
    }
    // The pose.
    std::string why;
    const std::optional<Pose2> pose = waypoints::lookupRobotPose(
        tf_buffer_, params_.global_frame, params_.base_frame, now, params_.tf_timeout, &why);
    if (!pose) return hold("pose lost: " + why, now);
    // The motion as odometry measures it: a correction of the SLAM pose is
    // neither progress nor distance driven.
    std::optional<Pose2> odometry = pose;
    if (!params_.odom_frame.empty() && params_.odom_frame != params_.global_frame) {
      odometry = waypoints::lookupRobotPose(tf_buffer_, params_.odom_frame, params_.base_frame, now,
                                            params_.tf_timeout, &why);
      if (!odometry) return hold("odometry lost: " + why, now);
    }
    if (!home_) {
      home_ = *pose;
      ROS_INFO("explorer: starting at (%.2f, %.2f) in %s", pose->x, pose->y,
               params_.global_frame.c_str());
    }
    if (last_odometry_) {
      const double step = (odometry->translation() - last_odometry_->translation()).norm();
      if (step > kOdometryJump) {
        ROS_WARN("explorer: the odometry jumped %.2f m in one step (reset?): not counted as driven",
                 step);
        swept_.clear();
      } else {
        driven_ += step;
      }
    }
    last_odometry_ = *odometry;
    last_pose_ = *pose;
    swept_.add(*odometry);
    // The map.
    if (!grid_) {
      if ((now - started_).toSec() > params_.map_timeout) {
        return hold("no map on " + map_subscriber_.getTopic() + " within map_timeout (" +
                        seconds(params_.map_timeout) + ")",
                    now);
      }
      return hold("waiting for the first map", now, false);
    }
    if ((now - map_received_).toSec() > params_.map_timeout) {
      return hold("no new map on " + map_subscriber_.getTopic() + " for longer than map_timeout (" +
                      seconds(params_.map_timeout) + "): the newest map is too old to plan on",
                  now);
    }
    if (paused_) return hold("paused (~resume drives on)", now, false);
    if (!holding_.empty()) ROS_INFO("explorer: driving on after: %s", holding_.c_str());
    holding_.clear();
    if (phase_ == Phase::kStarting) phase_ = Phase::kExploring;

    // The budgets.
    if (phase_ == Phase::kExploring) {
      const double elapsed = (now - started_).toSec();
      if (params_.max_time > 0.0 && elapsed > params_.max_time) {
        endExploring("the time budget is spent (" + std::to_string(static_cast<int>(elapsed)) +
                     " s)");
      } else if (params_.max_distance > 0.0 && driven_ > params_.max_distance) {
        endExploring("the distance budget is spent (" + std::to_string(static_cast<int>(driven_)) +
                     " m)");
      }
    }
    if (phase_ == Phase::kFinished || phase_ == Phase::kFailed) return;

    if (needsPlan(now)) plan(*pose, now);
    if (phase_ == Phase::kFinished || phase_ == Phase::kFailed || !pursuit_) return;
    drive(*pose, *odometry, now);
  }

  void stop() { cmd_publisher_.publish(geometry_msgs::Twist()); }

 private:
  // The robot at rest for `reason`; warned once per reason when `warn`.
  void hold(const std::string& reason, const ros::Time& now, bool warn = true) {
    if (reason != holding_) {
      if (warn) {
        ROS_WARN("explorer: robot stopped: %s", reason.c_str());
      } else {
        ROS_INFO("explorer: %s", reason.c_str());
      }
      stop();
      if (pursuit_) pursuit_->resetCommand();
      recovery_.restartWatch();
    }
    holding_ = reason;
    last_update_ = now;
  }

  void onMap(const nav_msgs::OccupancyGrid::ConstPtr& map) {
    grid_ = ekf_slam::ros_conversions::toGridMapFile(*map);
    map_received_ = ros::Time::now();
    map_changed_ = true;
  }

  bool needsPlan(const ros::Time& now) {
    if (!pursuit_) return plan_now_ || map_changed_;
    if (pathFailed()) return true;
    if (pursuit_->done()) {
      // At a frontier goal the next plan waits for a map made since the
      // arrival: the one it arrived with does not show what it sees there
      // (going elsewhere meanwhile, it came back for the same frontiers).
      return phase_ != Phase::kExploring || (reached_ && map_received_ > *reached_);
    }
    return (now - last_plan_).toSec() >= params_.replan_period && map_changed_;
  }

  // Records a try at the goal, and gives it up after max_goal_tries.
  void countTry(const Vector2& goal, const std::string& why) {
    GoalRecord* record = nullptr;
    for (GoalRecord& r : goals_) {
      if ((r.at - goal).norm() < params_.goal_radius) record = &r;
    }
    if (!record) {
      goals_.push_back({goal, 0, false});
      record = &goals_.back();
    }
    ++record->tries;
    if (record->tries >= params_.max_goal_tries && !record->given_up) {
      record->given_up = true;
      ++given_up_;
      ROS_WARN("explorer: giving up the frontier goal at (%.2f, %.2f) after %d tries: %s", goal.x(),
               goal.y(), record->tries, why.c_str());
    }
  }

  bool givenUp(const Vector2& goal) const {
    for (const GoalRecord& r : goals_) {
      if (r.given_up && (r.at - goal).norm() < params_.goal_radius) return true;
    }
    return false;
  }

  void plan(const Pose2& pose, const ros::Time& now) {
    last_plan_ = now;
    map_changed_ = false;
    plan_now_ = false;
    const Vector2 robot = pose.translation();
    // The laser does not see the floor under the robot: the cells it stands
    // on, and those it started on, are free where the map does not know them.
    ekf_slam::GridMapFile map = *grid_;
    size_t free_cells = 0;
    for (int8_t v : map.cells) free_cells += v >= 0 && v <= params_.exploration.free_max ? 1 : 0;
    if (free_cells == 0) {
      return nothingReachable("the map has no free cell (an empty map)");
    }
    ekf_slam::clearFootprint(&map, robot, params_.exploration.robot_radius);
    ekf_slam::clearFootprint(&map, home_->translation(), params_.exploration.robot_radius);
    grid_view_ = std::make_shared<const ekf_slam::ExplorationGrid>(map, params_.exploration);
    const ekf_slam::ExplorationGrid& grid = *grid_view_;
    // Why the previous path ends, if it does.
    if (pursuit_ && goal_ && phase_ == Phase::kExploring) {
      if (pathFailed()) {
        countTry(*goal_, "blocked on the way (the safety gate or a stall held the robot)");
      } else if (pursuit_->done()) {
        countTry(*goal_, "reached, but the frontier stays (unknown cells the laser does not see)");
      }
    }
    if (phase_ == Phase::kReturning) return planHome(grid, robot, now);

    // The robot's room first (rooms split at doorways; none with door_width 0).
    const std::vector<int> rooms = ekf_slam::segmentRooms(grid, params_.exploration.door_width);
    const ekf_slam::RoomOf room_of = [&](const Vector2& p) {
      const int cell = grid.cellAt(p);
      return cell < 0 ? -1 : rooms[cell];
    };
    // The goal driven to is kept while its frontier lasts (the room it lies
    // in is finished before another is begun); a room left finished is
    // entered again only for a long frontier.
    const ekf_slam::ExplorationPlan plan = ekf_slam::planExploration(
        grid, robot, room_of, [this](const Vector2& g) { return givenUp(g); }, params_.exploration,
        goal_, params_.goal_radius, finished_rooms_);
    frontiers_ = plan.frontiers.size();
    if (plan.finished_room) {
      finished_rooms_.push_back(*plan.finished_room);
      ROS_INFO("explorer: the room around (%.2f, %.2f) is finished (%zu rooms so far)", robot.x(),
               robot.y(), finished_rooms_.size());
    }
    publishFrontiers(grid, plan, now);
    if (!plan.reach.reachable(plan.reach.start)) {
      return nothingReachable("the robot's cell is not free on the map (the robot is off the map)");
    }
    if (!plan.chosen) {
      if (!anything_planned_) {
        return nothingReachable("no frontier can be reached from the start (" +
                                std::to_string(plan.frontiers.size()) +
                                " frontiers, none reachable: the robot is enclosed)");
      }
      return endExploring(plan.frontiers.empty()
                              ? std::string("no frontier is left")
                              : "no reachable frontier is left (" +
                                    std::to_string(plan.frontiers.size()) +
                                    " unreachable, given up or short ones in finished rooms)");
    }
    if (!nothing_reachable_.empty()) ROS_INFO("explorer: a frontier is reachable now");
    nothing_reachable_.clear();
    const ekf_slam::Frontier& chosen = plan.frontiers[*plan.chosen];
    const Vector2 goal = grid.centre(chosen.goal);
    // Keep going to the same goal while its frontier lasts and the path
    // stays open; a new path only when one of them changes.
    const bool same_goal = goal_ && (goal - *goal_).norm() < params_.goal_radius;
    if (same_goal && pursuit_ && !pursuit_->done() && !pathFailed() &&
        ekf_slam::pathClear(grid, path_)) {
      return;
    }
    if (!same_goal) {
      ROS_INFO("explorer: next frontier %.1f m long at (%.2f, %.2f), %.1f m away (%zu frontiers)",
               chosen.length, goal.x(), goal.y(), chosen.distance, plan.frontiers.size());
    }
    goal_ = goal;
    follow(plan.path, now, !same_goal);
  }

  void planHome(const ekf_slam::ExplorationGrid& grid, const Vector2& robot, const ros::Time& now) {
    const Vector2 home = home_->translation();
    if ((robot - home).norm() <= params_.home_tolerance) return finish();
    if (pursuit_ && pursuit_->done()) {
      // The pursuit ended short of home (its tolerance, or the map moved).
      if (++home_tries_ > params_.max_goal_tries) return finish();
    }
    if (pathFailed() && ++home_tries_ > params_.max_goal_tries) {
      return fail("the way back to the start is blocked");
    }
    const ekf_slam::Reach reach = ekf_slam::reachFrom(grid, robot);
    // The start itself, or (when it lies inside the inflation, beside a
    // wall) the reachable cell nearest it within a metre.
    int home_cell = grid.cellAt(home);
    if (!reach.reachable(home_cell)) {
      double nearest = 1.0;
      home_cell = -1;
      for (int c = 0; c < grid.cellCount(); ++c) {
        const double d = (grid.centre(c) - home).norm();
        if (d < nearest && reach.reachable(c)) {
          nearest = d;
          home_cell = c;
        }
      }
    }
    std::vector<Vector2> path = ekf_slam::pathTo(grid, reach, home_cell);
    if (path.empty()) return fail("the start is not reachable on the map");
    if (grid.traversable(grid.cellAt(home))) path.back() = home;
    if (pursuit_ && !pursuit_->done() && !pathFailed() && ekf_slam::pathClear(grid, path_)) {
      return;
    }
    follow(ekf_slam::simplifyPath(path, grid.resolution()), now, !pursuit_);
  }

  // Drives `path` from now on. `new_goal`: the recovery starts afresh; a
  // new path to the same goal keeps its count of back-offs, so a goal the
  // robot cannot get to is given up however often the path is replanned.
  void follow(std::vector<Vector2> path, const ros::Time& now, bool new_goal = true) {
    if (path.size() < 2) path.push_back(path.empty() ? last_pose_->translation() : path.back());
    path_ = path;
    pursuit_ = std::make_unique<waypoints::PurePursuit>(path, params_.pursuit);
    reached_.reset();
    if (new_goal || pathFailed()) {
      recovery_ = waypoints::BlockageRecovery(params_.recovery);
    }
    cornered_ = false;
    last_update_ = now;
    anything_planned_ = true;
    std_msgs::Header header;
    header.stamp = now;
    header.frame_id = params_.global_frame;
    path_publisher_.publish(ekf_slam::ros_conversions::toPathMessage(path, header));
  }

  // The path failed: blocked with back-offs spent, or with no room for one.
  bool pathFailed() const {
    return cornered_ || recovery_.state() == waypoints::RecoveryState::kGaveUp;
  }

  // How far (m, up to backoff_distance) the robot can back off on floor
  // the map shows free, or that its own body covered where the map does not
  // know the floor (it came that way): the strip robot_half_width either
  // side, from its centre to robot_rear behind it and as far again as it
  // backs. `pose` on the map and `odometry` are the robot's at one time.
  double roomBehind(const Pose2& pose, const Pose2& odometry) const {
    if (!grid_view_) return 0.0;
    const Vector2 back(-std::cos(pose.theta), -std::sin(pose.theta));
    const double step = grid_view_->resolution();
    // A point on the map, where the odometry has it.
    const auto swept = [&](const Vector2& p) {
      return swept_.covers(ekf_slam::transformFrom(odometry, ekf_slam::transformTo(pose, p)));
    };
    double room = 0.0;
    while (room + step <= params_.recovery.backoff_distance + 1e-9 &&
           ekf_slam::stripFree(*grid_view_, pose.translation(),
                               pose.translation() + (params_.robot_rear + room + step) * back,
                               params_.robot_half_width, swept)) {
      room += step;
    }
    return room;
  }

  // One control step: the pursuit on the map pose, the recovery watching
  // the odometry.
  void drive(const Pose2& pose, const Pose2& odometry, const ros::Time& now) {
    const double dt = std::max(0.0, (now - last_update_).toSec());
    last_update_ = now;
    const waypoints::VelocityCommand wanted = pursuit_->update(pose, dt);
    if (pursuit_->done() && !reached_) reached_ = now;
    const waypoints::RecoveryState before = recovery_.state();
    const waypoints::VelocityCommand command =
        recovery_.update(odometry, now.toSec(), wanted, pursuit_->remaining());
    if (recovery_.state() != before) {
      switch (recovery_.state()) {
        case waypoints::RecoveryState::kBackingOff: {
          // The laser does not see behind the robot: a back-off into what
          // the map shows occupied or does not know would touch it.
          const double room = roomBehind(pose, odometry);
          if (room < kMinBackoff) {
            ROS_WARN(
                "explorer: blocked at (%.2f, %.2f): held back for %.1f s, and neither the map "
                "nor the way the robot came shows room to back off; this path is given up",
                pose.x, pose.y, params_.recovery.stuck_time);
            cornered_ = true;
            stop();
            return;
          }
          recovery_.limitBackoff(room);
          ROS_WARN(
              "explorer: blocked at (%.2f, %.2f): held back for %.1f s; backing off %.2f m (%d "
              "of %d)",
              pose.x, pose.y, params_.recovery.stuck_time, room, recovery_.backoffs(),
              params_.recovery.max_backoffs);
          break;
        }
        case waypoints::RecoveryState::kTurningAround:
          ROS_WARN(
              "explorer: blocked at (%.2f, %.2f) turning on the spot for %.1f s: turning the "
              "other way round",
              pose.x, pose.y, params_.recovery.stuck_time);
          break;
        case waypoints::RecoveryState::kDriving:
          pursuit_->resetCommand();
          break;
        case waypoints::RecoveryState::kGaveUp:
          break;
      }
    }
    geometry_msgs::Twist twist;
    twist.linear.x = command.linear;
    twist.angular.z = command.angular;
    cmd_publisher_.publish(twist);
  }

  void endExploring(const std::string& why) {
    stop();
    pursuit_.reset();
    goal_.reset();
    explored_in_ = (ros::Time::now() - started_).toSec();
    explored_distance_ = driven_;
    ROS_INFO("explorer: exploring ends after %.0f s and %.1f m: %s", explored_in_, driven_,
             why.c_str());
    end_reason_ = why;
    plan_now_ = true;
    if (params_.return_home) {
      phase_ = Phase::kReturning;
      ROS_INFO("explorer: returning to the start (%.2f, %.2f)", home_->x, home_->y);
    } else {
      finish();
    }
  }

  void finish() {
    stop();
    pursuit_.reset();
    phase_ = Phase::kFinished;
    const double distance_home = (last_pose_->translation() - home_->translation()).norm();
    ROS_INFO("explorer: finished after %.0f s and %.1f m driven, %.2f m from the start; %s",
             (ros::Time::now() - started_).toSec(), driven_, distance_home, end_reason_.c_str());
    save();
    std_msgs::Bool done;
    done.data = true;
    done_publisher_.publish(done);
  }

  // Nothing to drive to on this map: the robot waits at rest, and each new
  // map is tried again (the error stays on /diagnostics meanwhile).
  void nothingReachable(const std::string& why) {
    stop();
    pursuit_.reset();
    if (why != nothing_reachable_) {
      ROS_ERROR(
          "explorer: robot stopped: nothing is reachable: %s; waiting for a map that "
          "shows a way out",
          why.c_str());
    }
    nothing_reachable_ = why;
  }

  void fail(const std::string& why) {
    stop();
    pursuit_.reset();
    phase_ = Phase::kFailed;
    end_reason_ = why;
    ROS_ERROR("explorer: stopped for good: %s", why.c_str());
  }

  void save() {
    if (params_.save_path.empty()) return;
    std::string base = params_.save_path;
    if (base[0] != '/') {
      const char* ros_home = std::getenv("ROS_HOME");
      const char* home = std::getenv("HOME");
      base = (ros_home ? std::string(ros_home) : std::string(home ? home : ".") + "/.ros") + "/" +
             base;
    }
    ekf_slam::SaveMap save_map;
    save_map.request.path = base + ".yaml";
    if (save_map_.waitForExistence(ros::Duration(2.0)) && save_map_.call(save_map)) {
      ROS_INFO("explorer: save_map: %s", save_map.response.message.c_str());
      saved_ = save_map.response.success ? save_map.request.path : "";
    } else {
      ROS_WARN("explorer: %s is not available: the map is not saved",
               save_map_.getService().c_str());
    }
    ekf_slam::StateFile state;
    state.request.path = base + ".state";
    if (write_state_.waitForExistence(ros::Duration(2.0)) && write_state_.call(state)) {
      ROS_INFO("explorer: write_state: %s", state.response.message.c_str());
    } else {
      ROS_WARN("explorer: %s is not available: the SLAM state is not saved",
               write_state_.getService().c_str());
    }
  }

  void publishFrontiers(const ekf_slam::ExplorationGrid& grid,
                        const ekf_slam::ExplorationPlan& plan, const ros::Time& now) {
    visualization_msgs::MarkerArray markers;
    visualization_msgs::Marker cells;
    cells.header.frame_id = params_.global_frame;
    cells.header.stamp = now;
    cells.ns = "frontiers";
    cells.type = visualization_msgs::Marker::POINTS;
    cells.scale.x = cells.scale.y = grid.resolution();
    cells.color.r = 0.2;
    cells.color.g = 0.6;
    cells.color.b = 1.0;
    cells.color.a = 1.0;
    cells.pose.orientation.w = 1.0;
    for (const ekf_slam::Frontier& f : plan.frontiers) {
      for (int c : f.cells) {
        geometry_msgs::Point p;
        p.x = grid.centre(c).x();
        p.y = grid.centre(c).y();
        cells.points.push_back(p);
      }
    }
    markers.markers.push_back(cells);
    visualization_msgs::Marker goal;
    goal.header = cells.header;
    goal.ns = "goal";
    goal.type = visualization_msgs::Marker::SPHERE;
    goal.action =
        plan.chosen ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
    goal.scale.x = goal.scale.y = goal.scale.z = 0.3;
    goal.color.r = 1.0;
    goal.color.g = 0.5;
    goal.color.a = 1.0;
    goal.pose.orientation.w = 1.0;
    if (plan.chosen) {
      const Vector2 g = grid.centre(plan.frontiers[*plan.chosen].goal);
      goal.pose.position.x = g.x();
      goal.pose.position.y = g.y();
    }
    markers.markers.push_back(goal);
    marker_publisher_.publish(markers);
  }

  bool onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    paused_ = true;
    stop();
    response.success = true;
    response.message = "paused; the robot is at rest";
    ROS_INFO("explorer: %s", response.message.c_str());
    return true;
  }

  bool onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    response.success = paused_;
    response.message = paused_ ? "resumed" : "not paused";
    paused_ = false;
    ROS_INFO("explorer: resume: %s", response.message.c_str());
    return true;
  }

  bool onAbort(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    stop();
    pursuit_.reset();
    const bool running =
        phase_ != Phase::kFinished && phase_ != Phase::kFailed && phase_ != Phase::kAborted;
    if (running) {
      phase_ = Phase::kAborted;
      end_reason_ = "aborted by ~abort";
    }
    response.success = running;
    response.message = running ? "aborted; the robot is at rest and stays there"
                               : std::string("already ") + toString(phase_);
    ROS_WARN("explorer: abort: %s", response.message.c_str());
    return true;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (phase_ == Phase::kFailed) {
      status.summaryf(DiagnosticStatus::ERROR, "failed: %s", end_reason_.c_str());
    } else if (!nothing_reachable_.empty() && phase_ == Phase::kExploring) {
      status.summaryf(DiagnosticStatus::ERROR, "robot stopped: nothing is reachable: %s",
                      nothing_reachable_.c_str());
    } else if (!holding_.empty() && phase_ != Phase::kFinished && phase_ != Phase::kAborted) {
      status.summaryf(paused_ ? DiagnosticStatus::OK : DiagnosticStatus::WARN, "robot stopped: %s",
                      holding_.c_str());
    } else if (phase_ == Phase::kFinished) {
      status.summaryf(DiagnosticStatus::OK, "finished: %s", end_reason_.c_str());
    } else {
      status.summary(DiagnosticStatus::OK, toString(phase_));
    }
    status.add("phase", toString(phase_));
    status.add("distance driven (m)", driven_);
    status.add("time (s)", (ros::Time::now() - started_).toSec());
    status.add("frontiers", frontiers_);
    status.add("goals given up", given_up_);
    status.add("rooms finished", finished_rooms_.size());
    if (explored_in_ > 0.0) {
      status.add("exploring took (s)", explored_in_);
      status.add("exploring drove (m)", explored_distance_);
    }
    if (home_ && last_pose_) {
      status.add("distance from the start (m)",
                 (last_pose_->translation() - home_->translation()).norm());
    }
    if (!saved_.empty()) status.add("map saved to", saved_);
  }

  ExplorerParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber map_subscriber_;
  ros::Publisher cmd_publisher_, path_publisher_, marker_publisher_, done_publisher_;
  std::vector<ros::ServiceServer> services_;
  ros::ServiceClient save_map_, write_state_;
  diagnostic_updater::Updater diagnostics_;

  Phase phase_ = Phase::kStarting;
  std::optional<ekf_slam::GridMapFile> grid_;
  std::shared_ptr<const ekf_slam::ExplorationGrid> grid_view_;  // the last plan's, inflated
  ros::Time map_received_, started_, last_plan_, last_update_;
  bool map_changed_ = false;
  bool paused_ = false;
  bool cornered_ = false;  // blocked with no room behind to back off
  bool anything_planned_ = false;
  bool plan_now_ = true;           // plan on the next step, new map or not
  std::string nothing_reachable_;  // why no frontier can be driven to, empty when one can
  std::string holding_;            // why the robot is held at rest, empty while driving
  std::string end_reason_;         // why exploring ended
  std::string saved_;
  std::optional<Pose2> home_, last_pose_, last_odometry_;
  std::optional<Vector2> goal_;
  std::optional<ros::Time> reached_;  // when the pursuit reached the end of its path
  std::vector<Vector2> path_;
  std::unique_ptr<waypoints::PurePursuit> pursuit_;
  waypoints::BlockageRecovery recovery_;
  ekf_slam::SweptFloor swept_;  // odometry frame
  std::vector<GoalRecord> goals_;
  std::vector<Vector2> finished_rooms_;  // a position in each room left finished
  double driven_ = 0.0;
  double explored_in_ = 0.0, explored_distance_ = 0.0;
  size_t frontiers_ = 0;
  int given_up_ = 0;
  int home_tries_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  ros::NodeHandle node, private_node("~");
  ExplorerParams params;
  std::string error;
  if (!loadParams(private_node, &params, &error)) {
    ROS_FATAL("explorer: bad parameters:\n%s", error.c_str());
    return 1;
  }
  Explorer explorer(node, private_node, params);
  ros::Rate rate(params.rate);
  while (!g_stop && ros::ok()) {
    ros::spinOnce();
    explorer.step();
    rate.sleep();
  }
  explorer.stop();
  ROS_INFO("explorer: shutting down, robot stopped");
  ros::Duration(0.1).sleep();
  ros::shutdown();
  return 0;
}
