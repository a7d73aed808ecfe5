// SE(2) pose (x, y, theta) with compose / inverse / between / point transforms.
//
// Jacobian convention (whole library): J_<output>_<input> = d output / d input,
// with poses parametrised additively as the vector (x, y, theta) and points as
// (x, y). This is the parametrisation the EKF state uses, so these Jacobians
// drop straight into F, G, H. Every Jacobian is checked against central
// differences in pose2_test.cc.
#pragma once

#include <Eigen/Core>

#include "ekf_slam_core/geometry/angle.h"

namespace ekf_slam {

using Matrix2 = Eigen::Matrix2d;
using Matrix3 = Eigen::Matrix3d;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using Vector2 = Eigen::Vector2d;
using Vector3 = Eigen::Vector3d;

struct Pose2 {
  double x = 0.0;      // m
  double y = 0.0;      // m
  double theta = 0.0;  // rad, kept in [-pi, pi)

  Pose2() = default;
  Pose2(double x_in, double y_in, double theta_in) : x(x_in), y(y_in), theta(wrapAngle(theta_in)) {}
  static Pose2 fromVector(const Vector3& v) { return Pose2(v.x(), v.y(), v.z()); }

  Vector3 vector() const { return Vector3(x, y, theta); }
  Vector2 translation() const { return Vector2(x, y); }
  Matrix2 rotation() const;
  bool allFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(theta); }
};

// a ⊕ b: the pose b, given in a's frame, expressed in a's parent frame.
Pose2 compose(const Pose2& a, const Pose2& b, Matrix3* J_out_a = nullptr,
              Matrix3* J_out_b = nullptr);

// ⊖a: the parent frame seen from a.
Pose2 inverse(const Pose2& a, Matrix3* J_out_a = nullptr);

// ⊖a ⊕ b: pose b expressed in the frame of pose a (the relative motion).
Pose2 between(const Pose2& a, const Pose2& b, Matrix3* J_out_a = nullptr,
              Matrix3* J_out_b = nullptr);

// Point given in the pose's frame → parent frame: t + R p.
Vector2 transformFrom(const Pose2& pose, const Vector2& point, Matrix23* J_out_pose = nullptr,
                      Matrix2* J_out_point = nullptr);

// Point given in the parent frame → the pose's frame: Rᵀ (p − t).
Vector2 transformTo(const Pose2& pose, const Vector2& point, Matrix23* J_out_pose = nullptr,
                    Matrix2* J_out_point = nullptr);

// Largest of |dx|, |dy|, |wrap(dθ)|: for tests and tolerances.
double maxAbsDifference(const Pose2& a, const Pose2& b);

}  // namespace ekf_slam
