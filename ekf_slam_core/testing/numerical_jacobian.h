// Central-difference Jacobians for the tests that prove every analytic
// Jacobian of the core. Header-only, test use only.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "ekf_slam_core/geometry/angle.h"

namespace ekf_slam {
namespace testing {

using VectorFunction = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

// d f / d x at x by central differences with step h. Output components whose
// index is listed in `angle_outputs` are differenced through wrapAngle so that
// a bearing crossing ±pi does not produce a 2π/h spike.
inline Eigen::MatrixXd numericalJacobian(const VectorFunction& f, const Eigen::VectorXd& x,
                                         const std::vector<int>& angle_outputs = {},
                                         double h = 1e-6) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd jacobian(f0.size(), x.size());
  for (int j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    Eigen::VectorXd diff = f(plus) - f(minus);
    for (int i : angle_outputs) diff(i) = wrapAngle(diff(i));
    jacobian.col(j) = diff / (2.0 * h);
  }
  return jacobian;
}

}  // namespace testing
}  // namespace ekf_slam
