// A point-landmark world for tests, benchmarks and the demo: a robot drives
// a closed waypoint loop; its odometry is corrupted by the same noise model
// the filter assumes (so consistency can be checked); a range–bearing sensor
// with field of view and range limits reports the landmarks it sees, with
// their true ids (for known-association runs and for scoring association).
#pragma once

#include <random>
#include <vector>

#include "ekf_slam_core/filter/ekf_slam.h"

namespace ekf_slam {
namespace sim {

struct LandmarkSimOptions {
  std::vector<Vector2> landmarks;  // map frame, m; empty: defaultLandmarks()
  std::vector<Vector2> waypoints;  // closed loop, m; empty: defaultWaypoints()
  int laps = 1;
  double max_step_translation = 0.15;  // m per step
  double max_step_rotation = 0.15;     // rad per step
  double dt = 0.2;                     // s per step
  double waypoint_tolerance = 0.2;     // m
  MotionNoiseOptions odometry_noise;   // true noise on each step's control
  double range_sigma = 0.02;           // m
  double bearing_sigma = 0.01;         // rad
  double max_range = 5.0;              // m
  double min_range = 0.1;              // m
  double field_of_view = kPi;          // rad, centred on the laser's x axis
  Pose2 laser_pose{0.1, 0.0, 0.0};     // base_link → laser
  unsigned seed = 1;
};

// Landmarks on both sides of the default loop (a 10 m × 6 m rectangle).
std::vector<Vector2> defaultLandmarks();
std::vector<Vector2> defaultWaypoints();

struct SimStep {
  double stamp = 0.0;                          // s
  Pose2 true_pose;                             // map frame
  Pose2 odometry;                              // the robot's own (drifting) odometry frame
  std::vector<PointObservation> observations;  // laser frame, with the true sensor covariance
  std::vector<int> true_landmark;              // index into landmarks() per observation
};

class LandmarkSimulator {
 public:
  explicit LandmarkSimulator(const LandmarkSimOptions& options);

  // The state before the first motion (step 0: observations from the start pose).
  const SimStep& current() const { return current_; }
  // Advances one step; false when the last lap is complete. The robot
  // steers for the next waypoint from `steer_by` (its estimate of its pose;
  // default the true pose), so that with an estimate its true path strays
  // as the estimate does, and a waypoint counts as reached where the robot
  // believes it is.
  bool next(const Pose2* steer_by = nullptr);

  const std::vector<Vector2>& landmarks() const { return options_.landmarks; }
  const LandmarkSimOptions& options() const { return options_; }
  Matrix2 observationCovariance() const;

 private:
  void observe();

  LandmarkSimOptions options_;
  std::mt19937 rng_;
  SimStep current_;
  size_t next_waypoint_ = 1;
  int lap_ = 0;
};

}  // namespace sim
}  // namespace ekf_slam
