#include "ekf_slam_core/extrinsics/thesis_procedure.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

namespace ekf_slam {
namespace {

constexpr double kMinTurn = 0.17;  // rad (10°): below, (I − R(φ)ᵀ) is too close to singular
constexpr double kMaxScatter = 0.03;  // m, 1-sigma of one scan's corner estimate

Vector2 solveTranslation(const Vector2& z, const Vector2& z_after, double turn, double yaw,
                         Vector2* feature) {
  const Matrix2 R = Pose2(0.0, 0.0, yaw).rotation();
  const Vector2 q = R * z, q_after = R * z_after;
  const Matrix2 A = Matrix2::Identity() - Pose2(0.0, 0.0, turn).rotation().transpose();
  const Vector2 p = A.inverse() * (q - q_after);
  if (feature) *feature = p;
  return p - q;
}

}  // namespace

double beamTilt(double h1, double h2, double d) { return std::atan2(h2 - h1, d); }

FeatureSighting sightFeature(const std::vector<Scan>& scans, const Vector2& near, double gate,
                             const FeatureOptions& options) {
  FeatureSighting out;
  std::vector<Vector2> found;
  for (const Scan& scan : scans) {
    const FeatureSet features = extractFeatures(scan, options);
    const PointFeature* best = nullptr;
    double best_distance = gate;
    for (const PointFeature& point : features.points_of_interest) {
      // A corner between two fitted lines: where they meet does not depend
      // on where the beams fall, unlike a segment's end.
      if (point.kind != PointKind::kCorner) continue;
      const double distance = (point.position - near).norm();
      if (distance <= best_distance) best_distance = distance, best = &point;
    }
    if (best) found.push_back(best->position);
  }
  out.scans = static_cast<int>(found.size());
  if (found.size() < 2 || 2 * found.size() < scans.size()) {
    std::ostringstream text;
    text << "the reference corner was found in " << found.size() << " of " << scans.size()
         << " scans within " << gate << " m of (" << near.x() << ", " << near.y()
         << "): place a box corner there, facing the scanner";
    out.message = text.str();
    return out;
  }
  for (const Vector2& p : found) out.mean += p;
  out.mean /= static_cast<double>(found.size());
  Matrix2 spread = Matrix2::Zero();
  for (const Vector2& p : found) spread += (p - out.mean) * (p - out.mean).transpose();
  spread /= static_cast<double>(found.size() - 1);
  out.covariance = spread / static_cast<double>(found.size());
  // Sightings of one corner scatter by the range noise; a wider spread is
  // two corners taken in turn, or one the extractor places unsteadily.
  const double scatter = std::sqrt(spread.eigenvalues().real().maxCoeff());
  if (scatter > kMaxScatter) {
    std::ostringstream text;
    text << "the corner's sightings scatter by " << scatter << " m (more than " << kMaxScatter
         << " m): not one clear corner; face a box corner so that both its sides are seen";
    out.message = text.str();
    return out;
  }
  out.ok = true;
  return out;
}

YawCalibration yawFromStraightMove(const FeatureSighting& before, const FeatureSighting& after,
                                   double distance, double distance_tolerance) {
  YawCalibration out;
  if (!before.ok || !after.ok) {
    out.message = "the reference corner is missing before or after the move";
    return out;
  }
  const Vector2 seen = before.mean - after.mean;  // d (cos ψ, −sin ψ)
  out.distance = seen.norm();
  if (std::abs(out.distance - distance) > distance_tolerance) {
    std::ostringstream text;
    text << "the laser saw the corner move " << out.distance << " m, the odometry says " << distance
         << " m: the robot turned or slipped, or another corner was taken";
    out.message = text.str();
    return out;
  }
  out.yaw = std::atan2(-seen.y(), seen.x());
  // σ of the direction of `seen`: its covariance across the direction, over |seen|.
  const Vector2 across(std::sin(out.yaw), std::cos(out.yaw));  // ⟂ (cos ψ, −sin ψ)
  const Matrix2 covariance = before.covariance + after.covariance;
  out.sigma = std::sqrt(across.dot(covariance * across)) / out.distance;
  out.ok = true;
  return out;
}

TranslationCalibration translationFromTurn(const FeatureSighting& before,
                                           const FeatureSighting& after, double turn, double yaw,
                                           double yaw_sigma) {
  TranslationCalibration out;
  if (!before.ok || !after.ok) {
    out.message = "the reference corner is missing before or after the turn";
    return out;
  }
  if (std::abs(std::sin(turn / 2.0)) < std::sin(kMinTurn / 2.0)) {
    out.message = "the turn is too small to give the translation: turn by 30 degrees or more";
    return out;
  }
  out.translation = solveTranslation(before.mean, after.mean, turn, yaw, &out.feature);
  // Covariance by first-order propagation over (z, z', ψ), numerically.
  Eigen::Matrix<double, 2, 5> J;
  const double h = 1e-6;
  for (int i = 0; i < 5; ++i) {
    Vector2 z = before.mean, z_after = after.mean;
    double psi = yaw;
    auto shift = [&](double step) {
      Vector2 a = z, b = z_after;
      double y = psi;
      if (i < 2)
        a[i] += step;
      else if (i < 4)
        b[i - 2] += step;
      else
        y += step;
      return solveTranslation(a, b, turn, y, nullptr);
    };
    J.col(i) = (shift(h) - shift(-h)) / (2.0 * h);
  }
  Eigen::Matrix<double, 5, 5> input = Eigen::Matrix<double, 5, 5>::Zero();
  input.block<2, 2>(0, 0) = before.covariance;
  input.block<2, 2>(2, 2) = after.covariance;
  input(4, 4) = yaw_sigma * yaw_sigma;
  out.covariance = J * input * J.transpose();
  out.ok = true;
  return out;
}

}  // namespace ekf_slam
