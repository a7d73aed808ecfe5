#include "ekf_slam_core/geometry/pose2.h"

#include <gtest/gtest.h>

#include <random>

#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::VectorXd;
using testing::numericalJacobian;

constexpr double kJacobianTol = 1e-6;

VectorXd stack(const Pose2& a, const Pose2& b) {
  VectorXd v(6);
  v << a.vector(), b.vector();
  return v;
}

TEST(Angle, WrapsIntoHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapAngle(0.0), 0.0);
  EXPECT_NEAR(wrapAngle(kPi), -kPi, 1e-15);
  EXPECT_NEAR(wrapAngle(-kPi), -kPi, 1e-15);
  EXPECT_NEAR(wrapAngle(3.0 * kPi / 2.0), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(wrapAngle(-7.0 * kPi / 2.0), kPi / 2.0, 1e-12);
  EXPECT_NEAR(wrapAngle(1e6), std::remainder(1e6, 2 * kPi), 1e-9);
  EXPECT_TRUE(std::isnan(wrapAngle(std::nan(""))));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> any(-100.0, 100.0);
  for (int i = 0; i < 1000; ++i) {
    const double a = any(rng);
    const double w = wrapAngle(a);
    EXPECT_GE(w, -kPi);
    EXPECT_LT(w, kPi);
    EXPECT_NEAR(std::sin(w), std::sin(a), 1e-9);
    EXPECT_NEAR(std::cos(w), std::cos(a), 1e-9);
  }
}

TEST(Pose2, ComposeInverseIsIdentityAndBetweenUndoesCompose) {
  const Pose2 a(1.0, -2.0, 2.5), b(-0.3, 0.7, 3.0);
  const Pose2 identity = compose(a, inverse(a));
  EXPECT_LT(maxAbsDifference(identity, Pose2()), 1e-12);
  EXPECT_LT(maxAbsDifference(between(a, compose(a, b)), b), 1e-12);
  const Vector2 p(0.4, -1.1);
  EXPECT_LT((transformTo(a, transformFrom(a, p)) - p).norm(), 1e-12);
}

class Pose2Jacobians : public ::testing::TestWithParam<double> {};

// Headings around ±pi are where wrapping bugs live.
INSTANTIATE_TEST_SUITE_P(Headings, Pose2Jacobians,
                         ::testing::Values(0.0, 0.7, -2.0, kPi - 1e-4, -kPi + 1e-4, 3.1));

TEST_P(Pose2Jacobians, MatchCentralDifferences) {
  const Pose2 a(0.5, -1.5, GetParam()), b(2.0, 0.3, -GetParam() + 0.4);
  const VectorXd ab = stack(a, b);

  Matrix3 J_a, J_b;
  compose(a, b, &J_a, &J_b);
  const auto f_compose = [](const VectorXd& v) -> VectorXd {
    return compose(Pose2::fromVector(v.head<3>()), Pose2::fromVector(v.tail<3>())).vector();
  };
  const Eigen::MatrixXd Jn = numericalJacobian(f_compose, ab, {2});
  EXPECT_TRUE(J_a.isApprox(Jn.leftCols<3>(), kJacobianTol)) << J_a << "\n" << Jn;
  EXPECT_TRUE(J_b.isApprox(Jn.rightCols<3>(), kJacobianTol)) << J_b << "\n" << Jn;

  Matrix3 J_inv;
  inverse(a, &J_inv);
  const auto f_inverse = [](const VectorXd& v) -> VectorXd {
    return inverse(Pose2::fromVector(v)).vector();
  };
  EXPECT_TRUE(J_inv.isApprox(numericalJacobian(f_inverse, a.vector(), {2}), kJacobianTol));

  between(a, b, &J_a, &J_b);
  const auto f_between = [](const VectorXd& v) -> VectorXd {
    return between(Pose2::fromVector(v.head<3>()), Pose2::fromVector(v.tail<3>())).vector();
  };
  const Eigen::MatrixXd Jb = numericalJacobian(f_between, ab, {2});
  EXPECT_TRUE(J_a.isApprox(Jb.leftCols<3>(), kJacobianTol)) << J_a << "\n" << Jb;
  EXPECT_TRUE(J_b.isApprox(Jb.rightCols<3>(), kJacobianTol)) << J_b << "\n" << Jb;

  const Vector2 p(-0.8, 1.7);
  VectorXd ap(5);
  ap << a.vector(), p;
  Matrix23 J_pose;
  Matrix2 J_point;
  transformFrom(a, p, &J_pose, &J_point);
  const auto f_from = [](const VectorXd& v) -> VectorXd {
    return transformFrom(Pose2::fromVector(v.head<3>()), v.tail<2>());
  };
  Eigen::MatrixXd Jf = numericalJacobian(f_from, ap);
  EXPECT_TRUE(J_pose.isApprox(Jf.leftCols<3>(), kJacobianTol));
  EXPECT_TRUE(J_point.isApprox(Jf.rightCols<2>(), kJacobianTol));

  transformTo(a, p, &J_pose, &J_point);
  const auto f_to = [](const VectorXd& v) -> VectorXd {
    return transformTo(Pose2::fromVector(v.head<3>()), v.tail<2>());
  };
  Jf = numericalJacobian(f_to, ap);
  EXPECT_TRUE(J_pose.isApprox(Jf.leftCols<3>(), kJacobianTol));
  EXPECT_TRUE(J_point.isApprox(Jf.rightCols<2>(), kJacobianTol));
}

}  // namespace
}  // namespace ekf_slam
