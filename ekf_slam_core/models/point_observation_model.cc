#include "ekf_slam_core/models/point_observation_model.h"

#include <cmath>

namespace ekf_slam {
namespace {

// Closer than this (m) the bearing is numerically meaningless.
constexpr double kMinRange = 1e-6;

}  // namespace

bool predictPointObservation(const Pose2& robot, const Pose2& laser, const Vector2& m,
                             RangeBearing* z, Matrix23* H_robot, Matrix2* H_landmark) {
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  Matrix23 J_local_sensor;
  Matrix2 J_local_m;
  const Vector2 local = transformTo(sensor, m, &J_local_sensor, &J_local_m);
  const double r2 = local.squaredNorm();
  const double r = std::sqrt(r2);
  if (!(r >= kMinRange)) return false;
  z->range = r;
  z->bearing = std::atan2(local.y(), local.x());
  if (H_robot || H_landmark) {
    Matrix2 J_z_local;
    J_z_local << local.x() / r, local.y() / r,  //
        -local.y() / r2, local.x() / r2;
    if (H_robot) *H_robot = J_z_local * J_local_sensor * J_sensor_robot;
    if (H_landmark) *H_landmark = J_z_local * J_local_m;
  }
  return true;
}

Vector2 landmarkFromObservation(const Pose2& robot, const Pose2& laser, const RangeBearing& z,
                                Matrix23* G_robot, Matrix2* G_z) {
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  const double c = std::cos(z.bearing), s = std::sin(z.bearing);
  const Vector2 local(z.range * c, z.range * s);
  Matrix23 J_m_sensor;
  Matrix2 J_m_local;
  const Vector2 m = transformFrom(sensor, local, &J_m_sensor, &J_m_local);
  if (G_robot) *G_robot = J_m_sensor * J_sensor_robot;
  if (G_z) {
    Matrix2 J_local_z;
    J_local_z << c, -z.range * s,  //
        s, z.range * c;
    *G_z = J_m_local * J_local_z;
  }
  return m;
}

}  // namespace ekf_slam
