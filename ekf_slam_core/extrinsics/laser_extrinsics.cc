#include "ekf_slam_core/extrinsics/laser_extrinsics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace ekf_slam {
namespace {

constexpr double kMinMeanTravel = 0.05;  // m per pair: less is turning on the spot

// The sums the cost needs, over the pairs used. With P_k = I − R(θ_o,k),
// b_k = t_o,k, u_k(φ) = R(φ) t_s,k = c t_s,k + s J t_s,k (J: +90° rotation):
//     y(φ) = (Σ PᵀP)⁻¹ Σ Pᵀ(b − u(φ)),   cost(φ) = Σ |P y + u − b|².
struct Sums {
  Matrix2 PtP = Matrix2::Zero();
  Vector2 Ptb = Vector2::Zero(), Ptt = Vector2::Zero(), PtJt = Vector2::Zero();
  double bb = 0.0, tt = 0.0, bt = 0.0, bJt = 0.0;
};

Matrix2 rot90() {
  Matrix2 J;
  J << 0.0, -1.0, 1.0, 0.0;
  return J;
}

Sums sumsOf(const std::vector<MotionPair>& pairs, const std::vector<char>& use) {
  Sums s;
  const Matrix2 J = rot90();
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!use[k]) continue;
    const Matrix2 P = Matrix2::Identity() - pairs[k].robot.rotation();
    const Vector2 b = pairs[k].robot.translation(), t = pairs[k].laser.translation();
    s.PtP += P.transpose() * P;
    s.Ptb += P.transpose() * b;
    s.Ptt += P.transpose() * t;
    s.PtJt += P.transpose() * (J * t);
    s.bb += b.squaredNorm();
    s.tt += t.squaredNorm();
    s.bt += b.dot(t);
    s.bJt += b.dot(J * t);
  }
  return s;
}

// Translation of the mount for yaw φ, and the cost there.
Vector2 translationAt(const Sums& s, double phi, double* cost) {
  const double c = std::cos(phi), sn = std::sin(phi);
  const Vector2 rhs = s.Ptb - c * s.Ptt - sn * s.PtJt;  // Σ Pᵀ(b − u)
  const Vector2 y = s.PtP.ldlt().solve(rhs);
  // Σ|b − u|² = Σ|b|² + Σ|t|² − 2 (c Σ b·t + s Σ b·Jt); minus yᵀ Σ Pᵀ(b − u).
  if (cost) *cost = s.bb + s.tt - 2.0 * (c * s.bt + sn * s.bJt) - y.dot(rhs);
  return y;
}

double minimiseYaw(const Sums& s) {
  // Every 0.5° around the circle, then golden-section search on the best
  // bracket: the cost is smooth in φ and may have a second local minimum.
  constexpr int kSamples = 720;
  double best_phi = 0.0, best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kSamples; ++i) {
    const double phi = -kPi + 2.0 * kPi * i / kSamples;
    double cost;
    translationAt(s, phi, &cost);
    if (cost < best) best = cost, best_phi = phi;
  }
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = best_phi - 2.0 * kPi / kSamples, b = best_phi + 2.0 * kPi / kSamples;
  for (int i = 0; i < 60; ++i) {
    const double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a);
    double f1, f2;
    translationAt(s, x1, &f1);
    translationAt(s, x2, &f2);
    if (f1 < f2) {
      b = x2;
    } else {
      a = x1;
    }
  }
  return wrapAngle(0.5 * (a + b));
}

Vector2 residual(const MotionPair& pair, const Vector2& t, double phi) {
  const Matrix2 P = Matrix2::Identity() - pair.robot.rotation();
  return P * t + Pose2(0.0, 0.0, phi).rotation() * pair.laser.translation() -
         pair.robot.translation();
}

std::string degrees(double rad) {
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(2);
  text << rad * 180.0 / kPi << " deg";
  return text.str();
}

}  // namespace

ExtrinsicsResult estimateLaserPose(const std::vector<MotionPair>& pairs,
                                   const ExtrinsicsOptions& options) {
  ExtrinsicsResult out;
  std::vector<char> use(pairs.size(), 1);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const MotionPair& p = pairs[k];
    if (!p.robot.allFinite() || !p.laser.allFinite() ||
        std::abs(wrapAngle(p.laser.theta - p.robot.theta)) > options.max_rotation_disagreement) {
      use[k] = 0;
      ++out.pairs_dropped;
    }
  }
  auto used = [&]() { return static_cast<int>(std::count(use.begin(), use.end(), 1)); };
  auto describeMotion = [&]() {
    out.total_turn = out.total_travel = 0.0;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (!use[k]) continue;
      out.total_turn += std::abs(pairs[k].robot.theta);
      out.total_travel += pairs[k].robot.translation().norm();
    }
  };
  describeMotion();
  if (used() < options.min_pairs) {
    out.message = "only " + std::to_string(used()) + " usable scan pairs (min_pairs " +
                  std::to_string(options.min_pairs) + "): record a longer drive";
    return out;
  }
  const Sums first = sumsOf(pairs, use);
  // Without turns I − R(θ_o) vanishes: the translation is not observable.
  const double turn_information = first.PtP.eigenvalues().real().minCoeff();
  if (turn_information < 1e-3) {
    out.message = "the drive has (almost) no turns (" + degrees(out.total_turn) +
                  " in all): the laser's x and y are not observable; drive curves or turn on "
                  "the spot as well";
    return out;
  }

  double phi = 0.0;
  Vector2 t = Vector2::Zero();
  for (int round = 0; round < 3; ++round) {
    const Sums s = sumsOf(pairs, use);
    phi = minimiseYaw(s);
    t = translationAt(s, phi, nullptr);
    // Robust scale of the residuals (median absolute norm) and the outliers.
    std::vector<double> norms;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (use[k]) norms.push_back(residual(pairs[k], t, phi).norm());
    }
    std::nth_element(norms.begin(), norms.begin() + norms.size() / 2, norms.end());
    const double gate = std::max(options.min_outlier_residual,
                                 options.outlier_sigmas * 1.4826 * norms[norms.size() / 2]);
    int dropped = 0;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (use[k] && residual(pairs[k], t, phi).norm() > gate) {
        use[k] = 0;
        ++dropped;
      }
    }
    out.pairs_dropped += dropped;
    if (dropped == 0 || used() < options.min_pairs) break;
  }
  describeMotion();
  out.pairs_used = used();
  out.laser_pose = Pose2(t.x(), t.y(), phi);

  // Covariance: Gauss-Newton at the solution, with the residuals' own scale.
  Matrix3 information = Matrix3::Zero();
  double squared = 0.0;
  const Matrix2 dR = Pose2(0.0, 0.0, phi).rotation() * rot90();  // d R(φ) / dφ
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!use[k]) continue;
    Eigen::Matrix<double, 2, 3> J;
    J.leftCols<2>() = Matrix2::Identity() - pairs[k].robot.rotation();
    J.col(2) = dR * pairs[k].laser.translation();
    information += J.transpose() * J;
    squared += residual(pairs[k], t, phi).squaredNorm();
  }
  const int dof = std::max(1, 2 * out.pairs_used - 3);
  out.residual_rms = std::sqrt(squared / std::max(1, out.pairs_used));
  const double variance = squared / dof;
  const Eigen::FullPivLU<Matrix3> lu(information);
  if (!lu.isInvertible()) {
    out.message = "the drive does not determine the mount (singular information)";
    return out;
  }
  out.covariance = variance * lu.inverse();
  const double sigma_t = std::sqrt(std::max(out.covariance(0, 0), out.covariance(1, 1)));
  const double sigma_yaw = std::sqrt(out.covariance(2, 2));
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(4);
  if (sigma_yaw > options.max_sigma_yaw || sigma_t > options.max_sigma_translation) {
    if (out.total_travel < kMinMeanTravel * out.pairs_used) {
      text << "the drive turns on the spot but hardly travels (" << out.total_travel
           << " m in all): the laser's yaw and the direction of its offset cannot be told "
              "apart; drive straight stretches as well";
    } else if (sigma_yaw > options.max_sigma_yaw) {
      text << "the laser's yaw is not determined (1-sigma " << degrees(sigma_yaw) << ", max "
           << degrees(options.max_sigma_yaw) << "): drive longer straight stretches";
    } else {
      text << "the laser's x and y are not determined (1-sigma " << sigma_t << " m, max "
           << options.max_sigma_translation << " m): turn more, in both directions";
    }
    out.message = text.str();
    return out;
  }
  out.ok = true;
  text << "x " << t.x() << " m, y " << t.y() << " m, yaw " << phi << " rad from " << out.pairs_used
       << " scan pairs (" << out.pairs_dropped << " dropped)";
  out.message = text.str();
  return out;
}

std::vector<MotionPair> motionPairs(const std::vector<Scan>& scans,
                                    const std::vector<Pose2>& odometry, const Pose2& nominal_laser,
                                    const ExtrinsicsOptions& options, int* refused) {
  std::vector<MotionPair> pairs;
  if (refused) *refused = 0;
  const size_t n = std::min(scans.size(), odometry.size());
  const Pose2 identity;
  int anchor = -1;
  std::unique_ptr<PointCloudReference> reference;
  for (size_t i = 0; i < n; ++i) {
    if (!odometry[i].allFinite() || !validateScan(scans[i]).empty()) continue;
    if (anchor < 0) {
      const std::vector<Vector2> points =
          scanPointsInRobotFrame(scans[i], identity, options.matcher);
      reference = std::make_unique<PointCloudReference>(
          points, options.matcher.normal_radius, options.matcher.initial_correspondence_distance);
      anchor = static_cast<int>(i);
      continue;
    }
    const Pose2 robot = between(odometry[anchor], odometry[i]);
    if (robot.translation().norm() < options.pair_distance &&
        std::abs(robot.theta) < options.pair_angle) {
      continue;
    }
    // The laser's motion, guessed through the believed mount, then matched.
    const Pose2 guess = compose(compose(inverse(nominal_laser), robot), nominal_laser);
    const std::vector<Vector2> points = scanPointsInRobotFrame(scans[i], identity, options.matcher);
    const MatchResult match = matchPoints(points, *reference, guess, options.matcher);
    if (match.ok) {
      pairs.push_back({robot, match.pose});
    } else if (refused) {
      ++*refused;
    }
    reference = std::make_unique<PointCloudReference>(
        points, options.matcher.normal_radius, options.matcher.initial_correspondence_distance);
    anchor = static_cast<int>(i);
  }
  return pairs;
}

}  // namespace ekf_slam
