// gtest assertion for the Jacobian tests of the core: an analytic Jacobian
// against its central-difference estimate (numerical_jacobian.h). Header
// only, test use only.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>

namespace ekf_slam {
namespace testing {

// Success when every entry agrees within `tol`, relative to the largest
// numeric entry (absolute below 1); the failure prints both matrices.
inline ::testing::AssertionResult near(const Eigen::MatrixXd& analytic,
                                       const Eigen::MatrixXd& numeric, double tol) {
  const double err = (analytic - numeric).cwiseAbs().maxCoeff();
  if (err <= tol * std::max(1.0, numeric.cwiseAbs().maxCoeff())) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "max error " << err << "\nanalytic\n"
                                       << analytic << "\nnumeric\n"
                                       << numeric;
}

}  // namespace testing
}  // namespace ekf_slam
