#include "ekf_slam_core/mecp/mecp_observation.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace {

// Closer than this (m) the centre's bearing is meaningless (the same bound
// as the point model's).
constexpr double kMinRange = 1e-6;

// Covariance entries may differ from their transpose by this much relative
// to the matrix's largest entry (rounding of whoever built them).
constexpr double kSymmetryTolerance = 1e-9;

bool isSymmetricFinite(const Matrix2& m) {
  return m.allFinite() &&
         std::abs(m(0, 1) - m(1, 0)) <= kSymmetryTolerance * std::max(1.0, m.cwiseAbs().maxCoeff());
}

}  // namespace

bool predictMecpObservation(const Pose2& robot, const Pose2& laser,
                            const std::vector<Vector2>& members, RangeBearing* z, Matrix23* H_robot,
                            std::vector<Matrix2>* H_members) {
  if (members.empty() || !robot.allFinite() || !laser.allFinite()) return false;
  Vector2 centre = Vector2::Zero();
  for (const Vector2& m : members) {
    if (!m.allFinite()) return false;
    centre += m;
  }
  const double k = static_cast<double>(members.size());
  centre /= k;
  RangeBearing predicted;
  Matrix23 J_z_robot;
  Matrix2 J_z_centre;
  if (!predictPointObservation(robot, laser, centre, &predicted, &J_z_robot, &J_z_centre)) {
    return false;
  }
  *z = predicted;
  if (H_robot) *H_robot = J_z_robot;
  // ∂c/∂m_i = I/k for every member.
  if (H_members) H_members->assign(members.size(), J_z_centre / k);
  return true;
}

bool observeMecp(const std::vector<RangeBearing>& readings,
                 const std::vector<Matrix2>& reading_covariances, RangeBearing* z,
                 Matrix2* covariance, Matrix2X* J_z_readings) {
  const int count = static_cast<int>(readings.size());
  if (count == 0 || reading_covariances.size() != readings.size()) return false;
  for (int i = 0; i < count; ++i) {
    const RangeBearing& reading = readings[i];
    if (!std::isfinite(reading.range) || !std::isfinite(reading.bearing) || reading.range < 0.0 ||
        !isSymmetricFinite(reading_covariances[i])) {
      return false;
    }
  }
  const double k = static_cast<double>(count);
  // J_centre_reading[i] = A_i / k: how reading i moves the centre (laser frame).
  std::vector<Matrix2> J_centre_reading(count);
  Vector2 centre = Vector2::Zero();
  for (int i = 0; i < count; ++i) {
    const double c = std::cos(readings[i].bearing), s = std::sin(readings[i].bearing);
    const double r = readings[i].range;
    centre += Vector2(r * c, r * s);
    J_centre_reading[i] << c, -r * s,  //
        s, r * c;
    J_centre_reading[i] /= k;
  }
  centre /= k;
  const double rho2 = centre.squaredNorm();
  const double rho = std::sqrt(rho2);
  if (!(rho >= kMinRange) || !std::isfinite(rho)) return false;
  Matrix2 J_z_centre;                                // P(ĉ)
  J_z_centre << centre.x() / rho, centre.y() / rho,  //
      -centre.y() / rho2, centre.x() / rho2;
  Matrix2 sum = Matrix2::Zero();
  Matrix2X T(2, 2 * count);
  for (int i = 0; i < count; ++i) {
    const Matrix2 T_i = J_z_centre * J_centre_reading[i];
    T.block<2, 2>(0, 2 * i) = T_i;
    sum += T_i * reading_covariances[i] * T_i.transpose();
  }
  z->range = rho;
  z->bearing = std::atan2(centre.y(), centre.x());
  *covariance = 0.5 * (sum + sum.transpose());
  if (J_z_readings) *J_z_readings = T;
  return true;
}

}  // namespace ekf_slam
