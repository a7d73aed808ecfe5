#include "ekf_slam_core/extrinsics/motion_noise_fit.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

namespace ekf_slam {
namespace {

// Least squares y ≈ X c with c ≥ 0: columns whose coefficient comes out
// negative are dropped (fixed at 0) and the rest solved again.
Eigen::VectorXd nonNegativeFit(const Eigen::MatrixXd& X, const Eigen::VectorXd& y) {
  const int n = static_cast<int>(X.cols());
  std::vector<bool> active(n, true);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
  for (int round = 0; round < n; ++round) {
    std::vector<int> columns;
    for (int j = 0; j < n; ++j) {
      if (active[j]) columns.push_back(j);
    }
    if (columns.empty()) break;
    Eigen::MatrixXd A(X.rows(), columns.size());
    for (size_t k = 0; k < columns.size(); ++k) A.col(k) = X.col(columns[k]);
    const Eigen::VectorXd solution = A.colPivHouseholderQr().solve(y);
    c.setZero();
    bool negative = false;
    for (size_t k = 0; k < columns.size(); ++k) {
      if (solution[k] < 0.0) {
        active[columns[k]] = false;
        negative = true;
      } else {
        c[columns[k]] = solution[k];
      }
    }
    if (!negative) break;
  }
  return c;
}

}  // namespace

MotionNoiseFit fitMotionNoise(const std::vector<MotionPair>& pairs, const Pose2& laser,
                              int min_pairs) {
  MotionNoiseFit out;
  const int n = static_cast<int>(pairs.size());
  out.pairs = n;
  if (n < min_pairs) {
    out.message = "only " + std::to_string(n) + " scan pairs (at least " +
                  std::to_string(min_pairs) + "): record a longer drive";
    return out;
  }
  // Rows: the whole turn's squared error on [rot1² + rot2², 2 trans², 1];
  // the translation's on [trans², rot1² + rot2², 1].
  Eigen::MatrixXd X_rot(n, 3), X_trans(n, 3);
  Eigen::VectorXd y_rot(n), y_trans(n);
  double sum_rot = 0.0, sum_trans = 0.0, turn_squares = 0.0, travel_squares = 0.0;
  for (int k = 0; k < n; ++k) {
    const Pose2 reference = compose(compose(laser, pairs[k].laser), inverse(laser));
    const OdometryControl u = controlFromOdometry(Pose2(), pairs[k].robot);
    const OdometryControl r = controlFromOdometry(Pose2(), reference);
    const double turn = wrapAngle(pairs[k].robot.theta - reference.theta);
    const double along = u.trans - r.trans;
    const double rot_squares = u.rot1 * u.rot1 + u.rot2 * u.rot2;
    X_rot.row(k) << rot_squares, 2.0 * u.trans * u.trans, 1.0;
    X_trans.row(k) << u.trans * u.trans, rot_squares, 1.0;
    y_rot[k] = turn * turn;
    y_trans[k] = along * along;
    sum_rot += turn * turn;
    sum_trans += along * along;
    turn_squares += rot_squares;
    travel_squares += u.trans * u.trans;
  }
  out.rotation_rms = std::sqrt(sum_rot / n);
  out.translation_rms = std::sqrt(sum_trans / n);
  if (turn_squares < 1e-3 * n || travel_squares < 1e-3 * n) {
    out.message = turn_squares < 1e-3 * n
                      ? "the drive hardly turns: drive a square (or curves) so that the noise of "
                        "turning can be told from that of driving"
                      : "the drive hardly travels: drive a square so that the noise of driving can "
                        "be told from that of turning";
    return out;
  }
  const Eigen::VectorXd c_rot = nonNegativeFit(X_rot, y_rot);
  const Eigen::VectorXd c_trans = nonNegativeFit(X_trans, y_trans);
  out.noise = MotionNoiseOptions{};
  out.noise.rot_per_rot = c_rot[0];
  out.noise.rot_per_trans = c_rot[1];
  out.noise.trans_per_trans = c_trans[0];
  out.noise.trans_per_rot = c_trans[1];
  out.noise.min_rot_sigma = out.noise.min_trans_sigma = 0.0;
  out.matcher_rotation_sigma = std::sqrt(c_rot[2] / 2.0);  // the pair's two matches
  out.matcher_translation_sigma = std::sqrt(c_trans[2]);
  out.ok = true;
  std::ostringstream text;
  text << "fitted from " << n << " scan pairs";
  out.message = text.str();
  return out;
}

}  // namespace ekf_slam
