#include "ekf_slam_core/sim/landmark_simulator.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace sim {

std::vector<Vector2> defaultWaypoints() { return {{0, 0}, {10, 0}, {10, 6}, {0, 6}}; }

std::vector<Vector2> defaultLandmarks() {
  // Two rows of posts along every side of the loop, 2 m apart, 1.5 m off
  // the path on each side, slightly staggered so they are not collinear.
  std::vector<Vector2> out;
  for (double x = 0.0; x <= 10.0; x += 2.0) {
    out.push_back({x + 0.3, -1.5});
    out.push_back({x - 0.4, 1.4});
    out.push_back({x + 0.2, 7.5});
    out.push_back({x - 0.3, 4.6});
  }
  for (double y = 2.0; y <= 4.0; y += 2.0) {
    out.push_back({-1.5, y + 0.2});
    out.push_back({1.4, y - 0.3});
    out.push_back({11.5, y - 0.2});
    out.push_back({8.6, y + 0.3});
  }
  return out;
}

LandmarkSimulator::LandmarkSimulator(const LandmarkSimOptions& options)
    : options_(options), rng_(options.seed) {
  if (options_.landmarks.empty()) options_.landmarks = defaultLandmarks();
  if (options_.waypoints.empty()) options_.waypoints = defaultWaypoints();
  const Vector2 start = options_.waypoints[0];
  const Vector2 toward = options_.waypoints[1 % options_.waypoints.size()] - start;
  current_.true_pose = Pose2(start.x(), start.y(), std::atan2(toward.y(), toward.x()));
  current_.odometry = Pose2();  // the robot's odometry frame starts at its own origin
  observe();
}

Matrix2 LandmarkSimulator::observationCovariance() const {
  Matrix2 r = Matrix2::Zero();
  r(0, 0) = options_.range_sigma * options_.range_sigma;
  r(1, 1) = options_.bearing_sigma * options_.bearing_sigma;
  return r;
}

bool LandmarkSimulator::next(const Pose2* steer_by) {
  if (lap_ >= options_.laps) return false;
  const Vector2 target = options_.waypoints[next_waypoint_];
  const Pose2 believed = steer_by ? *steer_by : current_.true_pose;
  const Vector2 delta = target - believed.translation();
  const double heading_error = wrapAngle(std::atan2(delta.y(), delta.x()) - believed.theta);

  // Turn toward the waypoint, then drive; both limited per step.
  OdometryControl u;
  u.rot1 = std::clamp(heading_error, -options_.max_step_rotation, options_.max_step_rotation);
  if (std::abs(heading_error) < 0.3) {
    u.trans = std::min(delta.norm(), options_.max_step_translation);
  }
  current_.true_pose = applyControl(current_.true_pose, u);

  // The odometry measures the control with noise of covariance Q(u).
  const Matrix3 q = controlCovariance(u, options_.odometry_noise);
  std::normal_distribution<double> unit(0.0, 1.0);
  OdometryControl measured = u;
  measured.rot1 += std::sqrt(q(0, 0)) * unit(rng_);
  measured.trans += std::sqrt(q(1, 1)) * unit(rng_);
  measured.rot2 += std::sqrt(q(2, 2)) * unit(rng_);
  current_.odometry = applyControl(current_.odometry, measured);
  current_.stamp += options_.dt;

  const Pose2 after = steer_by ? applyControl(believed, u) : current_.true_pose;
  if ((target - after.translation()).norm() < options_.waypoint_tolerance) {
    next_waypoint_ = (next_waypoint_ + 1) % options_.waypoints.size();
    if (next_waypoint_ == 1) ++lap_;
  }
  observe();
  return true;
}

void LandmarkSimulator::observe() {
  current_.observations.clear();
  current_.true_landmark.clear();
  const Matrix2 R = observationCovariance();
  std::normal_distribution<double> unit(0.0, 1.0);
  for (size_t i = 0; i < options_.landmarks.size(); ++i) {
    RangeBearing z;
    if (!predictPointObservation(current_.true_pose, options_.laser_pose, options_.landmarks[i],
                                 &z)) {
      continue;
    }
    if (z.range > options_.max_range || z.range < options_.min_range ||
        std::abs(z.bearing) > options_.field_of_view / 2.0) {
      continue;
    }
    PointObservation obs;
    obs.z.range = z.range + options_.range_sigma * unit(rng_);
    obs.z.bearing = wrapAngle(z.bearing + options_.bearing_sigma * unit(rng_));
    obs.covariance = R;
    current_.observations.push_back(obs);
    current_.true_landmark.push_back(static_cast<int>(i));
  }
}

}  // namespace sim
}  // namespace ekf_slam
