#include "ekf_slam_core/models/line_observation_model.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace ekf_slam {
namespace {

constexpr double kHalfPi = 0.5 * kPi;
// A covariance whose asymmetry exceeds this fraction of its largest entry is
// not a covariance but a bug upstream.
constexpr double kSymmetryTolerance = 1e-9;
// Eigenvalues down to −this fraction of the largest entry are rounding of a
// PSD matrix (a zero variance computed as −1e-18, say).
constexpr double kPsdTolerance = 1e-12;

Vector2 normal(double angle) { return Vector2(std::cos(angle), std::sin(angle)); }
// The vector turned by +90°: n⊥(α) = perpendicular(n(α)).
Vector2 perpendicular(const Vector2& v) { return Vector2(-v.y(), v.x()); }

// Writes (p, θ) with p >= 0 into `out` using (p, θ) ≡ (−p, θ + π); returns
// the sign applied to p (+1 at p = 0).
double normalise(double p, double theta, PolarLine* out) {
  const double sign = p < 0.0 ? -1.0 : 1.0;
  out->p = sign * p;
  out->theta = wrapAngle(sign < 0.0 ? theta + kPi : theta);
  return sign;
}

template <int N>
bool isCovariance(const Eigen::Matrix<double, N, N>& c) {
  if (!c.allFinite()) return false;
  const double scale = c.cwiseAbs().maxCoeff();
  if ((c - c.transpose()).cwiseAbs().maxCoeff() > kSymmetryTolerance * scale) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(c, Eigen::EigenvaluesOnly);
  return eigen.eigenvalues().minCoeff() >= -kPsdTolerance * scale;
}

// H_robot = ∂z/∂s · ∂s/∂x_r, the second factor from compose.
void chainRobot(const Matrix23& J_z_sensor, const Matrix3& J_sensor_robot, Matrix23* H_robot) {
  if (H_robot) *H_robot = J_z_sensor * J_sensor_robot;
}

// ∂(p, θ)/∂s for z = normalised(p', θ_f − s_θ) with ∂p'/∂s_t = −sign·normal_row
// (the line's normal as the laser sees it) and ∂p'/∂s_θ = 0.
Matrix23 observationWrtSensor(const Vector2& normal_row, double sign) {
  Matrix23 J;
  J << -sign * normal_row.x(), -sign * normal_row.y(), 0.0,  //
      0.0, 0.0, -1.0;
  return J;
}

}  // namespace

double lineAngleDifference(double a, double b) {
  double d = wrapAngle(a - b);
  if (d >= kHalfPi) d -= kPi;
  if (d < -kHalfPi) d += kPi;
  return d;
}

bool predictLineObservation(const Pose2& robot, const Pose2& laser, const PolarLine& landmark,
                            PolarLine* z, Matrix23* H_robot, Matrix2* H_landmark) {
  if (!robot.allFinite() || !laser.allFinite() || !landmark.allFinite()) return false;
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  const Vector2 n = normal(landmark.theta);
  const double sign =
      normalise(landmark.p - n.dot(sensor.translation()), landmark.theta - sensor.theta, z);
  chainRobot(observationWrtSensor(n, sign), J_sensor_robot, H_robot);
  if (H_landmark) {
    *H_landmark << sign, -sign * perpendicular(n).dot(sensor.translation()),  //
        0.0, 1.0;
  }
  return true;
}

bool lineLandmarkFromObservation(const Pose2& robot, const Pose2& laser, const PolarLine& z,
                                 PolarLine* landmark, Matrix23* G_robot, Matrix2* G_z) {
  if (!robot.allFinite() || !laser.allFinite() || !z.allFinite()) return false;
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  const double alpha = z.theta + sensor.theta;
  const Vector2 n = normal(alpha);
  const double dp_dalpha = perpendicular(n).dot(sensor.translation());
  const double sign = normalise(z.p + n.dot(sensor.translation()), alpha, landmark);
  if (G_robot) {
    Matrix23 J_landmark_sensor;
    J_landmark_sensor << sign * n.x(), sign * n.y(), sign * dp_dalpha,  //
        0.0, 0.0, 1.0;
    *G_robot = J_landmark_sensor * J_sensor_robot;
  }
  if (G_z) {
    *G_z << sign, sign * dp_dalpha,  //
        0.0, 1.0;
  }
  return true;
}

bool lineInnovation(const PolarLine& z, const PolarLine& z_hat, Vector2* innovation,
                    Matrix2* J_innovation_prediction) {
  if (!z.allFinite() || !z_hat.allFinite()) return false;
  const double dtheta = wrapAngle(z.theta - z_hat.theta);
  // ẑ's normal more than a right angle from z's: compare with (−p̂, θ̂ + π).
  const double sign = (dtheta >= kHalfPi || dtheta < -kHalfPi) ? -1.0 : 1.0;
  *innovation = Vector2(z.p - sign * z_hat.p, lineAngleDifference(z.theta, z_hat.theta));
  if (J_innovation_prediction) *J_innovation_prediction << -sign, 0.0, 0.0, -1.0;
  return true;
}

bool predictLineAngle(const Pose2& robot, const Pose2& laser, double theta_f, double* theta,
                      RowVector3* H_robot, double* H_angle) {
  if (!robot.allFinite() || !laser.allFinite() || !std::isfinite(theta_f)) return false;
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  *theta = wrapAngle(theta_f - sensor.theta);
  if (H_robot) *H_robot = RowVector3(0.0, 0.0, -1.0) * J_sensor_robot;
  if (H_angle) *H_angle = 1.0;
  return true;
}

bool predictLineFromAngleAndPoint(const Pose2& robot, const Pose2& laser, double theta_f,
                                  const Vector2& m1, PolarLine* z, Matrix23* H_robot,
                                  Matrix2* H_point, Vector2* H_angle) {
  if (!robot.allFinite() || !laser.allFinite() || !std::isfinite(theta_f) || !m1.allFinite())
    return false;
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  const Vector2 n = normal(theta_f);
  const Vector2 w = m1 - sensor.translation();
  const double sign = normalise(n.dot(w), theta_f - sensor.theta, z);
  chainRobot(observationWrtSensor(n, sign), J_sensor_robot, H_robot);
  if (H_point) {
    *H_point << sign * n.x(), sign * n.y(),  //
        0.0, 0.0;
  }
  if (H_angle) *H_angle = Vector2(sign * perpendicular(n).dot(w), 1.0);
  return true;
}

bool predictLineFromAngleAndEndpoints(const Pose2& robot, const Pose2& laser, double theta_f,
                                      const Vector2& m1, const Vector2& m2, PolarLine* z,
                                      Matrix23* H_robot, Matrix2* H_m1, Matrix2* H_m2,
                                      Vector2* H_angle) {
  if (!robot.allFinite() || !laser.allFinite() || !std::isfinite(theta_f) || !m1.allFinite() ||
      !m2.allFinite())
    return false;
  const Vector2 u = m2 - m1;
  const double d = u.norm();
  if (!(d >= kMinEndpointSeparation)) return false;
  const Vector2 e = u / d;
  const Vector2 k = perpendicular(e);
  const double agreement = k.dot(normal(theta_f));
  if (std::abs(agreement) < std::cos(kMaxEndpointDisagreement)) return false;
  const Vector2 k_oriented = agreement < 0.0 ? Vector2(-k) : k;  // κ k

  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  const Vector2 w = m1 - sensor.translation();
  const double sign = normalise(k_oriented.dot(w), theta_f - sensor.theta, z);
  chainRobot(observationWrtSensor(k_oriented, sign), J_sensor_robot, H_robot);
  const double lever = e.dot(w) / d;  // a/d
  if (H_m1) {
    H_m1->row(0) = sign * (1.0 + lever) * k_oriented.transpose();
    H_m1->row(1).setZero();
  }
  if (H_m2) {
    H_m2->row(0) = -sign * lever * k_oriented.transpose();
    H_m2->row(1).setZero();
  }
  if (H_angle) *H_angle = Vector2(0.0, 1.0);
  return true;
}

bool lineAngleFromObservation(const Pose2& robot, const Pose2& laser, const PolarLine& z,
                              double* theta_f, RowVector3* G_robot, RowVector2* G_z) {
  if (!robot.allFinite() || !laser.allFinite() || !z.allFinite()) return false;
  Matrix3 J_sensor_robot;
  const Pose2 sensor = compose(robot, laser, &J_sensor_robot);
  *theta_f = wrapAngle(z.theta + sensor.theta);
  if (G_robot) *G_robot = RowVector3(0.0, 0.0, 1.0) * J_sensor_robot;
  if (G_z) *G_z = RowVector2(0.0, 1.0);
  return true;
}

bool newLineLandmarkCovariance(const Matrix3& robot_covariance, const Matrix2& z_covariance,
                               const Matrix23& G_robot, const Matrix2& G_z, Matrix2* covariance) {
  if (!isCovariance(robot_covariance) || !isCovariance(z_covariance) || !G_robot.allFinite() ||
      !G_z.allFinite())
    return false;
  const Matrix2 c =
      G_robot * robot_covariance * G_robot.transpose() + G_z * z_covariance * G_z.transpose();
  *covariance = 0.5 * (c + c.transpose());
  return true;
}

bool newLineAngleVariance(const Matrix3& robot_covariance, const Matrix2& z_covariance,
                          const RowVector3& G_robot, const RowVector2& G_z, double* variance) {
  if (!isCovariance(robot_covariance) || !isCovariance(z_covariance) || !G_robot.allFinite() ||
      !G_z.allFinite())
    return false;
  *variance = (G_robot * robot_covariance * G_robot.transpose() +
               G_z * z_covariance * G_z.transpose())(0, 0);
  return true;
}

}  // namespace ekf_slam
