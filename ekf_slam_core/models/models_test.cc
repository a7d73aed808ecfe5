// Every analytic Jacobian of the models against central differences,
// including bearings near ±π and landmarks close to the robot.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ekf_slam_core/models/odometry_motion_model.h"
#include "ekf_slam_core/models/point_observation_model.h"
#include "ekf_slam_core/testing/jacobian_assertions.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::near;
using testing::numericalJacobian;

constexpr double kTol = 1e-6;

TEST(OdometryMotionModel, ControlReproducesTheOdometryIncrement) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-5, 5), ang(-kPi, kPi), step(-0.4, 0.4);
  for (int i = 0; i < 500; ++i) {
    const Pose2 o1(pos(rng), pos(rng), ang(rng));
    const Pose2 o2 = compose(o1, Pose2(step(rng), step(rng), step(rng)));
    if (between(o1, o2).translation().norm() < 0.01) continue;  // see SmallTranslation below
    const OdometryControl u = controlFromOdometry(o1, o2);
    // Applying u to the first odometry pose lands on the second: the model
    // loses nothing of a general motion.
    EXPECT_LT(maxAbsDifference(applyControl(o1, u), o2), 1e-12);
    // And the same u moves any other starting pose by the same relative motion.
    const Pose2 slam(1.0, 2.0, 0.3);
    EXPECT_LT(maxAbsDifference(between(slam, applyControl(slam, u)), between(o1, o2)), 1e-12);
  }
}

TEST(OdometryMotionModel, BackingUpIsANegativeTranslationNotAHalfTurn) {
  const Pose2 o1(0, 0, 0.2);
  const Pose2 o2 = compose(o1, Pose2(-0.3, 0.01, 0.0));
  const OdometryControl u = controlFromOdometry(o1, o2);
  EXPECT_LT(u.trans, 0.0);
  EXPECT_LT(std::abs(u.rot1), 0.1);
  EXPECT_LT(std::abs(u.rot2), 0.1);
}

TEST(OdometryMotionModel, SmallTranslationIsATurnNotTwoHalfTurns) {
  // A turn on the spot with 3 mm of lateral wheel jitter.
  const Pose2 o1(1, 1, 0.5);
  const Pose2 o2 = compose(o1, Pose2(0.0005, 0.003, 0.2));
  const OdometryControl u = controlFromOdometry(o1, o2);
  EXPECT_DOUBLE_EQ(u.rot1, 0.0);
  EXPECT_NEAR(u.rot2, 0.2, 1e-12);
  EXPECT_NEAR(u.trans, 0.0005, 1e-12);
  // The pose is reproduced but for the dropped lateral jitter.
  const Pose2 reached = applyControl(o1, u);
  EXPECT_NEAR(reached.theta, o2.theta, 1e-12);
  EXPECT_LT((reached.translation() - o2.translation()).norm(), 0.0031);
  // And the motion noise is that of a 0.2 rad turn, not of two ±90° turns.
  const Matrix3 q = controlCovariance(u, MotionNoiseOptions());
  EXPECT_LT(q(0, 0) + q(2, 2), 0.01 * 0.2 * 0.2 + 1e-6);
}

TEST(OdometryMotionModel, PureRotationHasNoTranslation) {
  const OdometryControl u = controlFromOdometry(Pose2(1, 1, 0.5), Pose2(1, 1, 1.2));
  EXPECT_DOUBLE_EQ(u.trans, 0.0);
  EXPECT_NEAR(u.rot1 + u.rot2, 0.7, 1e-12);
}

class MotionJacobians : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Headings, MotionJacobians,
                         ::testing::Values(0.0, 1.2, -2.5, kPi - 1e-3, -kPi + 1e-3));

TEST_P(MotionJacobians, FAndGMatchCentralDifferences) {
  const Pose2 pose(0.3, -0.2, GetParam());
  const OdometryControl u{0.2, 0.45, -0.1};
  Matrix3 F, G;
  applyControl(pose, u, &F, &G);
  VectorXd v(6);
  v << pose.vector(), u.vector();
  const auto f = [](const VectorXd& s) -> VectorXd {
    return applyControl(Pose2::fromVector(s.head<3>()), OdometryControl{s(3), s(4), s(5)}).vector();
  };
  const MatrixXd J = numericalJacobian(f, v, {2});
  EXPECT_TRUE(near(F, J.leftCols<3>(), kTol));
  EXPECT_TRUE(near(G, J.rightCols<3>(), kTol));
}

TEST(OdometryMotionModel, NoiseGrowsWithMotionAndValidates) {
  MotionNoiseOptions noise;
  EXPECT_EQ(noise.validate(), "");
  const Matrix3 q_small = controlCovariance({0.01, 0.05, 0.0}, noise);
  const Matrix3 q_large = controlCovariance({0.2, 0.5, 0.1}, noise);
  for (int i = 0; i < 3; ++i) EXPECT_GT(q_large(i, i), q_small(i, i));
  EXPECT_TRUE(controlCovariance({}, noise).isZero());
  noise.trans_per_trans = -1.0;
  EXPECT_NE(noise.validate().find("trans_per_trans"), std::string::npos);
}

// The random-walk terms give a drive the same variance however many filter
// steps it is cut into (the quadratic terms do not), and split the heading
// diffusion evenly over the two rotations.
TEST(OdometryMotionModel, RandomWalkNoiseDoesNotDependOnTheStepCount) {
  MotionNoiseOptions noise{0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  noise.rot_per_metre = 4e-4;
  noise.trans_per_metre = 1e-4;
  noise.rot_per_radian = 2e-3;
  EXPECT_EQ(noise.validate(), "");
  // A straight 1 m drive in 1 step and in 25 steps of 4 cm.
  const Matrix3 one = controlCovariance({0.0, 1.0, 0.0}, noise);
  Matrix3 many = Matrix3::Zero();
  for (int k = 0; k < 25; ++k) many += controlCovariance({0.0, 0.04, 0.0}, noise);
  EXPECT_TRUE(one.isApprox(many, 1e-12));
  EXPECT_NEAR(one(0, 0) + one(2, 2), 4e-4, 1e-15);
  EXPECT_NEAR(one(1, 1), 1e-4, 1e-15);
  // Driving backwards diffuses as much as driving forwards; a turn on the spot
  // by its angle.
  EXPECT_TRUE(controlCovariance({0.0, -1.0, 0.0}, noise).isApprox(one, 1e-12));
  EXPECT_NEAR(controlCovariance({0.0, 0.0, -0.5}, noise)(2, 2), 1e-3, 1e-15);
  // The thesis's quadratic terms do depend on the step count.
  MotionNoiseOptions quadratic;
  Matrix3 quadratic_many = Matrix3::Zero();
  for (int k = 0; k < 25; ++k) quadratic_many += controlCovariance({0.0, 0.04, 0.0}, quadratic);
  EXPECT_LT(quadratic_many(1, 1), 0.1 * controlCovariance({0.0, 1.0, 0.0}, quadratic)(1, 1));
  noise.rot_per_metre = -1.0;
  EXPECT_NE(noise.validate().find("rot_per_metre"), std::string::npos);
}

struct ObservationCase {
  Pose2 robot;
  Pose2 laser;
  Vector2 landmark;
};

class ObservationJacobians : public ::testing::TestWithParam<ObservationCase> {};

// Bearings just either side of ±π (landmark behind the sensor), landmarks a
// few centimetres from the sensor, an offset and rotated laser mount.
INSTANTIATE_TEST_SUITE_P(
    Geometry, ObservationJacobians,
    ::testing::Values(
        ObservationCase{Pose2(0, 0, 0), Pose2(), Vector2(3, 1)},
        ObservationCase{Pose2(1, 2, 0.3), Pose2(0.2, 0.0, 0.0), Vector2(-4, 2.001)},
        ObservationCase{Pose2(0, 0, 0), Pose2(), Vector2(-3, 1e-4)},
        ObservationCase{Pose2(0, 0, 0), Pose2(), Vector2(-3, -1e-4)},
        ObservationCase{Pose2(0.5, 0.5, kPi - 1e-4), Pose2(0.1, -0.05, 0.02), Vector2(0.55, 0.52)},
        ObservationCase{Pose2(-2, 3, -1.0), Pose2(0.16, 0.0, kPi), Vector2(-1.0, 2.0)}));

TEST_P(ObservationJacobians, HAndInverseMatchCentralDifferences) {
  const ObservationCase& c = GetParam();
  RangeBearing z;
  Matrix23 H_r;
  Matrix2 H_m;
  ASSERT_TRUE(predictPointObservation(c.robot, c.laser, c.landmark, &z, &H_r, &H_m));
  VectorXd v(5);
  v << c.robot.vector(), c.landmark;
  const Pose2 laser = c.laser;
  const auto h = [&laser](const VectorXd& s) -> VectorXd {
    RangeBearing out;
    predictPointObservation(Pose2::fromVector(s.head<3>()), laser, s.tail<2>(), &out);
    return out.vector();
  };
  // A small step: near-sensor landmarks have large second derivatives.
  const MatrixXd J = numericalJacobian(h, v, {1}, 1e-7);
  EXPECT_TRUE(near(H_r, J.leftCols<3>(), 1e-5));
  EXPECT_TRUE(near(H_m, J.rightCols<2>(), 1e-5));

  // The inverse model returns the landmark and its Jacobians are right.
  Matrix23 G_r;
  Matrix2 G_z;
  const Vector2 m = landmarkFromObservation(c.robot, c.laser, z, &G_r, &G_z);
  EXPECT_LT((m - c.landmark).norm(), 1e-9);
  VectorXd w(5);
  w << c.robot.vector(), z.vector();
  const auto g = [&laser](const VectorXd& s) -> VectorXd {
    return landmarkFromObservation(Pose2::fromVector(s.head<3>()), laser, {s(3), s(4)});
  };
  const MatrixXd K = numericalJacobian(g, w, {}, 1e-7);
  EXPECT_TRUE(near(G_r, K.leftCols<3>(), 1e-5));
  EXPECT_TRUE(near(G_z, K.rightCols<2>(), 1e-5));
}

TEST(PointObservationModel, BearingIsMeasuredInTheLaserFrame) {
  // Robot at origin facing +y, laser mounted 0.2 m ahead: a landmark 1 m
  // ahead of the laser is at range 1, bearing 0.
  RangeBearing z;
  ASSERT_TRUE(predictPointObservation(Pose2(0, 0, kPi / 2), Pose2(0.2, 0, 0), Vector2(0, 1.2), &z));
  EXPECT_NEAR(z.range, 1.0, 1e-12);
  EXPECT_NEAR(z.bearing, 0.0, 1e-12);
  // A landmark at the sensor origin has no bearing: refused, not NaN.
  EXPECT_FALSE(predictPointObservation(Pose2(), Pose2(), Vector2(0, 0), &z));
}

// The thesis's augmentation Jacobians (eqs. 4.14-4.15) write sin θᵢ and
// cos θᵢ, θᵢ the measured bearing, where its own inverse model (eq. 4.9)
// has the absolute bearing θ_v + θᵢ: they are the derivatives of eq. 4.9
// only for a robot heading along the map's x axis. (The laser on the
// robot's origin, as in the thesis.)
TEST(PointObservationModel, PrintedAugmentationJacobiansHoldOnlyAtZeroHeading) {
  const RangeBearing z{2.0, 0.4};
  const auto printed = [&z](Matrix23* A_v, Matrix2* A_f) {
    const double s = std::sin(z.bearing), c = std::cos(z.bearing);
    *A_v << 1, 0, -z.range * s, 0, 1, z.range * c;
    *A_f << c, -z.range * s, s, z.range * c;
  };
  Matrix23 A_v, G_r;
  Matrix2 A_f, G_z;
  printed(&A_v, &A_f);
  landmarkFromObservation(Pose2(1.0, -2.0, 0.0), Pose2(), z, &G_r, &G_z);
  EXPECT_TRUE(near(A_v, G_r, 1e-12));
  EXPECT_TRUE(near(A_f, G_z, 1e-12));
  landmarkFromObservation(Pose2(1.0, -2.0, 0.7), Pose2(), z, &G_r, &G_z);
  EXPECT_GT((A_v - G_r).norm(), 0.5);
  EXPECT_GT((A_f - G_z).norm(), 0.5);
}

}  // namespace
}  // namespace ekf_slam
