// Line landmark models: every analytic Jacobian against central differences
// on random poses (headings and line normals near ±π, rotated and offset
// laser mounts), the sign flip of lines through the sensor, lines seen
// end-on, both θ-only association cases, the augmented covariance against
// Monte Carlo, and refusals of bad input.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <limits>
#include <random>

#include "ekf_slam_core/models/line_observation_model.h"
#include "ekf_slam_core/testing/jacobian_assertions.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::near;
using testing::numericalJacobian;

constexpr double kTol = 1e-6;
// Samples whose predicted |p| is below this (m) sit so close to the sign
// flip that a difference step could cross it; they get their own tests.
constexpr double kMinTestOffset = 1e-3;
constexpr int kRandomCases = 400;

// Random geometry; a third of the angles sit within 1 mrad of ±π.
class Geometry {
 public:
  explicit Geometry(unsigned seed) : rng_(seed) {}
  double angle() {
    const int kind = std::uniform_int_distribution<int>(0, 2)(rng_);
    if (kind == 0) return std::uniform_real_distribution<double>(-kPi, kPi)(rng_);
    const double offset = std::uniform_real_distribution<double>(0.0, 1e-3)(rng_);
    return kind == 1 ? kPi - offset : -kPi + offset;
  }
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }
  Pose2 robot() { return Pose2(uniform(-5, 5), uniform(-5, 5), angle()); }
  Pose2 laser() {
    static const double kYaws[] = {0.0, 0.03, kPi};
    return Pose2(uniform(-0.3, 0.3), uniform(-0.2, 0.2),
                 kYaws[std::uniform_int_distribution<int>(0, 2)(rng_)]);
  }
  Vector2 point() { return Vector2(uniform(-6, 6), uniform(-6, 6)); }

 private:
  std::mt19937 rng_;
};

VectorXd stack(const Pose2& robot, const Eigen::VectorXd& rest) {
  VectorXd v(3 + rest.size());
  v << robot.vector(), rest;
  return v;
}

// ---------------------------------------------------------------- (a) (p, θ)

TEST(LineObservationModel, JacobiansMatchCentralDifferencesOnRandomPoses) {
  Geometry g(11);
  int tested = 0, flipped = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const Pose2 robot = g.robot(), laser = g.laser();
    const PolarLine landmark{g.uniform(0, 8), g.angle()};
    PolarLine z;
    Matrix23 H_r;
    Matrix2 H_l;
    ASSERT_TRUE(predictLineObservation(robot, laser, landmark, &z, &H_r, &H_l));
    EXPECT_GE(z.p, 0.0);
    EXPECT_TRUE(z.theta >= -kPi && z.theta < kPi);
    if (z.p < kMinTestOffset) continue;
    ++tested;
    const Vector2 n(std::cos(landmark.theta), std::sin(landmark.theta));
    if (landmark.p - n.dot(compose(robot, laser).translation()) < 0.0) ++flipped;
    const auto h = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineObservation(Pose2::fromVector(s.head<3>()), laser, {s(3), s(4)}, &out);
      return out.vector();
    };
    const MatrixXd J = numericalJacobian(h, stack(robot, landmark.vector()), {1});
    EXPECT_TRUE(near(H_r, J.leftCols<3>(), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_l, J.rightCols<2>(), kTol)) << "case " << i;
  }
  EXPECT_GT(tested, kRandomCases * 9 / 10);
  EXPECT_GT(flipped, kRandomCases / 10);  // the sensor beyond the line is exercised
}

TEST(LineObservationModel, InverseJacobiansMatchAndInverseUndoesForward) {
  Geometry g(12);
  for (int i = 0; i < kRandomCases; ++i) {
    const Pose2 robot = g.robot(), laser = g.laser();
    const PolarLine z{g.uniform(0.05, 8), g.angle()};
    PolarLine landmark;
    Matrix23 G_r;
    Matrix2 G_z;
    ASSERT_TRUE(lineLandmarkFromObservation(robot, laser, z, &landmark, &G_r, &G_z));
    EXPECT_GE(landmark.p, 0.0);
    // forward ∘ inverse = identity on normalised observations.
    PolarLine back;
    ASSERT_TRUE(predictLineObservation(robot, laser, landmark, &back));
    EXPECT_NEAR(back.p, z.p, 1e-9);
    EXPECT_NEAR(wrapAngle(back.theta - z.theta), 0.0, 1e-12);
    // inverse ∘ forward = identity on normalised landmarks.
    PolarLine again;
    ASSERT_TRUE(lineLandmarkFromObservation(robot, laser, back, &again));
    EXPECT_NEAR(again.p, landmark.p, 1e-9);
    EXPECT_NEAR(wrapAngle(again.theta - landmark.theta), 0.0, 1e-12);
    if (landmark.p < kMinTestOffset) continue;
    const auto inv = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      lineLandmarkFromObservation(Pose2::fromVector(s.head<3>()), laser, {s(3), s(4)}, &out);
      return out.vector();
    };
    const MatrixXd J = numericalJacobian(inv, stack(robot, z.vector()), {1});
    EXPECT_TRUE(near(G_r, J.leftCols<3>(), kTol)) << "case " << i;
    EXPECT_TRUE(near(G_z, J.rightCols<2>(), kTol)) << "case " << i;
  }
}

TEST(LineObservationModel, LaserFrameLineOfAKnownGeometry) {
  // The wall y = 3 (map normal +y, p = 3); robot at (1, 1) facing +x, the
  // laser 0.2 m ahead and turned +90°: the wall is 2 m straight ahead.
  PolarLine z;
  ASSERT_TRUE(predictLineObservation(Pose2(1, 1, 0), Pose2(0.2, 0, kPi / 2), {3.0, kPi / 2}, &z));
  EXPECT_NEAR(z.p, 2.0, 1e-12);
  EXPECT_NEAR(z.theta, 0.0, 1e-12);
  // From beyond the wall (y = 4) the normal points back, −y in the map.
  ASSERT_TRUE(predictLineObservation(Pose2(1, 4, 0), Pose2(), {3.0, kPi / 2}, &z));
  EXPECT_NEAR(z.p, 1.0, 1e-12);
  EXPECT_NEAR(z.theta, -kPi / 2, 1e-12);
}

// A map line whose normal is near ±π, with the sensor 0.1 mm either side of
// it: p stays positive, θ turns by π, the Jacobians hold on each side and the
// innovation between the two sightings is their 0.2 mm of signed offset.
TEST(LineObservationModel, LineThroughTheSensorFlipsPAndTurnsThetaByPi) {
  const PolarLine landmark{1.5, kPi - 2e-4};
  const Pose2 laser(0.15, 0.02, 0.01);
  const Vector2 n(std::cos(landmark.theta), std::sin(landmark.theta));
  const Vector2 direction(-n.y(), n.x());
  PolarLine z_side[2];
  for (int side = 0; side < 2; ++side) {
    const double offset = side == 0 ? 1e-4 : -1e-4;  // sensor short of / beyond the line
    // Place the sensor at landmark.p − offset along n, then the robot behind it.
    const Pose2 sensor_pose(n.x() * (landmark.p - offset) + 0.7 * direction.x(),
                            n.y() * (landmark.p - offset) + 0.7 * direction.y(), 2.5);
    const Pose2 robot = compose(sensor_pose, inverse(laser));
    Matrix23 H_r;
    Matrix2 H_l;
    ASSERT_TRUE(predictLineObservation(robot, laser, landmark, &z_side[side], &H_r, &H_l));
    EXPECT_NEAR(z_side[side].p, 1e-4, 1e-9);
    const auto h = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineObservation(Pose2::fromVector(s.head<3>()), laser, {s(3), s(4)}, &out);
      return out.vector();
    };
    const MatrixXd J = numericalJacobian(h, stack(robot, landmark.vector()), {1}, 1e-8);
    EXPECT_TRUE(near(H_r, J.leftCols<3>(), 1e-5)) << "side " << side;
    EXPECT_TRUE(near(H_l, J.rightCols<2>(), 1e-5)) << "side " << side;
  }
  EXPECT_NEAR(std::abs(wrapAngle(z_side[0].theta - z_side[1].theta)), kPi, 1e-9);
  Vector2 nu;
  ASSERT_TRUE(lineInnovation(z_side[0], z_side[1], &nu));
  EXPECT_NEAR(std::abs(nu(0)), 2e-4, 1e-9);
  EXPECT_NEAR(nu(1), 0.0, 1e-9);
}

TEST(LineInnovation, ComparesSignedOffsetsAlongACommonNormal) {
  Vector2 nu;
  Matrix2 J;
  // The same wall with θ either side of ±π.
  ASSERT_TRUE(lineInnovation({2.0, kPi - 1e-3}, {2.0, -kPi + 1e-3}, &nu, &J));
  EXPECT_NEAR(nu(0), 0.0, 1e-12);
  EXPECT_NEAR(nu(1), -2e-3, 1e-12);
  EXPECT_TRUE(J.isApprox(-Matrix2::Identity()));
  // Two lines near the origin on either side: (0.001, 0.1) against
  // (0.002, 0.1 + π) ≡ (−0.002, 0.1).
  ASSERT_TRUE(lineInnovation({0.001, 0.1}, {0.002, wrapAngle(0.1 + kPi)}, &nu, &J));
  EXPECT_NEAR(nu(0), 0.003, 1e-12);
  EXPECT_NEAR(nu(1), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(J(0, 0), 1.0);
  // Parallel walls 2 m either side of the sensor are 4 m apart.
  ASSERT_TRUE(lineInnovation({2.0, 0.0}, {2.0, -kPi}, &nu));
  EXPECT_NEAR(nu(0), 4.0, 1e-12);
  EXPECT_NEAR(nu(1), 0.0, 1e-12);
  // ∂ν/∂ẑ against central differences, on both branches and across ±π.
  const PolarLine cases[][2] = {{{1.0, 3.1}, {1.1, -3.1}},
                                {{1.0, 0.3}, {0.4, 0.3 + kPi - 0.2}},
                                {{0.01, -kPi}, {0.02, 0.05}}};
  for (const auto& c : cases) {
    const PolarLine z = c[0];
    ASSERT_TRUE(lineInnovation(z, c[1], &nu, &J));
    const auto f = [&z](const VectorXd& s) -> VectorXd {
      Vector2 out;
      lineInnovation(z, {s(0), s(1)}, &out);
      return out;
    };
    EXPECT_TRUE(near(J, numericalJacobian(f, c[1].vector(), {1}), kTol));
  }
  EXPECT_NEAR(lineAngleDifference(kPi - 0.1, -0.05), -0.05, 1e-12);  // modulo π
  EXPECT_NEAR(lineAngleDifference(0.2, -kPi + 0.1), 0.1, 1e-12);
}

// ---------------------------------------------------------------- (b) θ-only

TEST(LineAngleOnly, AngleAndAugmentationJacobiansMatchCentralDifferences) {
  Geometry g(13);
  for (int i = 0; i < kRandomCases; ++i) {
    const Pose2 robot = g.robot(), laser = g.laser();
    const double theta_f = g.angle();
    double theta;
    RowVector3 H_r;
    double H_f;
    ASSERT_TRUE(predictLineAngle(robot, laser, theta_f, &theta, &H_r, &H_f));
    const auto h = [&laser](const VectorXd& s) -> VectorXd {
      double out;
      predictLineAngle(Pose2::fromVector(s.head<3>()), laser, s(3), &out);
      return VectorXd::Constant(1, out);
    };
    VectorXd v(4);
    v << robot.vector(), theta_f;
    const MatrixXd J = numericalJacobian(h, v, {0});
    EXPECT_TRUE(near(H_r, J.leftCols<3>(), kTol));
    EXPECT_NEAR(H_f, J(0, 3), kTol);

    // Augmentation from the observation the angle model predicts, and back.
    const PolarLine z{g.uniform(0.1, 6), theta};
    double theta_back;
    RowVector3 G_r;
    RowVector2 G_z;
    ASSERT_TRUE(lineAngleFromObservation(robot, laser, z, &theta_back, &G_r, &G_z));
    EXPECT_NEAR(wrapAngle(theta_back - theta_f), 0.0, 1e-12);
    const auto inv = [&laser](const VectorXd& s) -> VectorXd {
      double out;
      lineAngleFromObservation(Pose2::fromVector(s.head<3>()), laser, {s(3), s(4)}, &out);
      return VectorXd::Constant(1, out);
    };
    const MatrixXd K = numericalJacobian(inv, stack(robot, z.vector()), {0});
    EXPECT_TRUE(near(G_r, K.leftCols<3>(), kTol));
    EXPECT_TRUE(near(G_z, K.rightCols<2>(), kTol));
  }
}

TEST(LineAngleOnly, OneEndpointCaseMatchesCentralDifferencesAndTheFullModel) {
  Geometry g(14);
  int tested = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const Pose2 robot = g.robot(), laser = g.laser();
    const double theta_f = g.angle();
    const Vector2 m1 = g.point();
    PolarLine z;
    Matrix23 H_r;
    Matrix2 H_m;
    Vector2 H_f;
    ASSERT_TRUE(predictLineFromAngleAndPoint(robot, laser, theta_f, m1, &z, &H_r, &H_m, &H_f));
    // The same line as the full model's (ρ, α) = (n(θ_f)·m₁, θ_f).
    PolarLine full;
    const double rho = std::cos(theta_f) * m1.x() + std::sin(theta_f) * m1.y();
    ASSERT_TRUE(predictLineObservation(robot, laser, {rho, theta_f}, &full));
    EXPECT_NEAR(z.p, full.p, 1e-12);
    EXPECT_NEAR(wrapAngle(z.theta - full.theta), 0.0, 1e-12);
    // m₁ lies on the predicted line in the laser frame.
    const Vector2 local = transformTo(compose(robot, laser), m1);
    EXPECT_NEAR(local.x() * std::cos(z.theta) + local.y() * std::sin(z.theta), z.p, 1e-9);
    if (z.p < kMinTestOffset) continue;
    ++tested;
    const auto h = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineFromAngleAndPoint(Pose2::fromVector(s.head<3>()), laser, s(5), s.segment<2>(3),
                                   &out);
      return out.vector();
    };
    VectorXd v(6);
    v << robot.vector(), m1, theta_f;
    const MatrixXd J = numericalJacobian(h, v, {1});
    EXPECT_TRUE(near(H_r, J.leftCols<3>(), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_m, J.middleCols<2>(3), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_f, J.col(5), kTol)) << "case " << i;
  }
  EXPECT_GT(tested, kRandomCases * 9 / 10);
}

// Endpoints on a wall whose direction disagrees with θ_f by up to 0.05 rad.
TEST(LineAngleOnly, BothEndpointsCaseMatchesCentralDifferences) {
  Geometry g(15);
  int tested = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const Pose2 robot = g.robot(), laser = g.laser();
    const double theta_f = g.angle();
    const double wall_normal = theta_f + g.uniform(-0.05, 0.05) + (i % 2 ? kPi : 0.0);
    const Vector2 m1 = g.point();
    const Vector2 m2 =
        m1 + g.uniform(0.3, 4.0) * Vector2(-std::sin(wall_normal), std::cos(wall_normal));
    PolarLine z;
    Matrix23 H_r;
    Matrix2 H_m1, H_m2;
    Vector2 H_f;
    ASSERT_TRUE(predictLineFromAngleAndEndpoints(robot, laser, theta_f, m1, m2, &z, &H_r, &H_m1,
                                                 &H_m2, &H_f));
    // The endpoints' order does not matter.
    PolarLine swapped;
    ASSERT_TRUE(predictLineFromAngleAndEndpoints(robot, laser, theta_f, m2, m1, &swapped));
    EXPECT_NEAR(swapped.p, z.p, 1e-9);
    EXPECT_NEAR(wrapAngle(swapped.theta - z.theta), 0.0, 1e-12);
    if (z.p < kMinTestOffset) continue;
    ++tested;
    const auto h = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineFromAngleAndEndpoints(Pose2::fromVector(s.head<3>()), laser, s(7), s.segment<2>(3),
                                       s.segment<2>(5), &out);
      return out.vector();
    };
    VectorXd v(8);
    v << robot.vector(), m1, m2, theta_f;
    const MatrixXd J = numericalJacobian(h, v, {1});
    EXPECT_TRUE(near(H_r, J.leftCols<3>(), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_m1, J.middleCols<2>(3), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_m2, J.middleCols<2>(5), kTol)) << "case " << i;
    EXPECT_TRUE(near(H_f, J.col(7), kTol)) << "case " << i;
  }
  EXPECT_GT(tested, kRandomCases * 9 / 10);
}

TEST(LineAngleOnly, BothEndpointsAgreesWithOneEndpointWhenTheStateIsConsistent) {
  const Pose2 robot(0.4, -1.0, 2.9), laser(0.2, 0.0, 0.0);
  const double theta_f = -kPi + 3e-4;
  const Vector2 direction(-std::sin(theta_f), std::cos(theta_f));
  const Vector2 m1(-3.0, 0.5), m2 = m1 + 2.5 * direction;
  PolarLine one, both;
  ASSERT_TRUE(predictLineFromAngleAndPoint(robot, laser, theta_f, m1, &one));
  ASSERT_TRUE(predictLineFromAngleAndEndpoints(robot, laser, theta_f, m1, m2, &both));
  EXPECT_NEAR(one.p, both.p, 1e-12);
  EXPECT_NEAR(wrapAngle(one.theta - both.theta), 0.0, 1e-12);
}

// The robot on the wall's extension: the laser sees the wall end-on, p ≈ 0.
// With the sensor 0.1 mm either side of the extension and heading near ±π,
// both cases give p = 0.1 mm, θ turned by π between the sides, Jacobians
// that hold, and an innovation of the 0.2 mm between the sightings.
TEST(LineAngleOnly, EndOnLineSeenFromEitherSide) {
  const Vector2 m1(2.0, 0.0), m2(4.5, 0.0);  // the wall along the map's x axis
  const double theta_f = kPi / 2;
  const Pose2 laser(0.1, 0.02, 0.01);
  PolarLine seen[2][2];  // [side][one endpoint, both endpoints]
  for (int side = 0; side < 2; ++side) {
    const Pose2 sensor(0.0, side == 0 ? 1e-4 : -1e-4, kPi - 1e-4);
    const Pose2 robot = compose(sensor, inverse(laser));
    Matrix23 H_r1, H_r2;
    Matrix2 H_m, H_m1, H_m2;
    Vector2 H_f1, H_f2;
    ASSERT_TRUE(predictLineFromAngleAndPoint(robot, laser, theta_f, m1, &seen[side][0], &H_r1, &H_m,
                                             &H_f1));
    ASSERT_TRUE(predictLineFromAngleAndEndpoints(robot, laser, theta_f, m1, m2, &seen[side][1],
                                                 &H_r2, &H_m1, &H_m2, &H_f2));
    EXPECT_NEAR(seen[side][0].p, 1e-4, 1e-9);
    EXPECT_NEAR(seen[side][1].p, 1e-4, 1e-9);
    const auto h1 = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineFromAngleAndPoint(Pose2::fromVector(s.head<3>()), laser, s(5), s.segment<2>(3),
                                   &out);
      return out.vector();
    };
    const auto h2 = [&laser](const VectorXd& s) -> VectorXd {
      PolarLine out;
      predictLineFromAngleAndEndpoints(Pose2::fromVector(s.head<3>()), laser, s(7), s.segment<2>(3),
                                       s.segment<2>(5), &out);
      return out.vector();
    };
    VectorXd v1(6), v2(8);
    v1 << robot.vector(), m1, theta_f;
    v2 << robot.vector(), m1, m2, theta_f;
    // Steps well below the 0.1 mm offset, so that no step crosses the flip.
    const MatrixXd J1 = numericalJacobian(h1, v1, {1}, 1e-8);
    const MatrixXd J2 = numericalJacobian(h2, v2, {1}, 1e-8);
    EXPECT_TRUE(near(H_r1, J1.leftCols<3>(), 1e-5));
    EXPECT_TRUE(near(H_m, J1.middleCols<2>(3), 1e-5));
    EXPECT_TRUE(near(H_f1, J1.col(5), 1e-5));
    EXPECT_TRUE(near(H_r2, J2.leftCols<3>(), 1e-5));
    EXPECT_TRUE(near(H_m1, J2.middleCols<2>(3), 1e-5));
    EXPECT_TRUE(near(H_m2, J2.middleCols<2>(5), 1e-5));
    EXPECT_TRUE(near(H_f2, J2.col(7), 1e-5));
    // Seen end-on, moving the far endpoint sideways by δ turns the line
    // about m₁ and moves it at the sensor by δ·|m₁ − s|/|m₂ − m₁|.
    EXPECT_NEAR(std::abs(H_m2(0, 1)), 2.0 / 2.5, 1e-9);
    EXPECT_NEAR(std::abs(H_m1(0, 1)), 1.0 + 2.0 / 2.5, 1e-9);
  }
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(std::abs(wrapAngle(seen[0][c].theta - seen[1][c].theta)), kPi, 1e-9);
    Vector2 nu;
    ASSERT_TRUE(lineInnovation(seen[0][c], seen[1][c], &nu));
    EXPECT_NEAR(std::abs(nu(0)), 2e-4, 1e-9);
    EXPECT_NEAR(nu(1), 0.0, 1e-9);
  }
}

TEST(LineAngleOnly, BothEndpointsRefusesCoincidentEndpointsAndADisagreeingAngle) {
  PolarLine z{7.0, 0.5};
  const Vector2 m1(1, 1);
  EXPECT_FALSE(predictLineFromAngleAndEndpoints(Pose2(), Pose2(), 0.0, m1, m1, &z));
  // Endpoints along x: their normal is ±y; θ_f = 0 is 90° off.
  EXPECT_FALSE(predictLineFromAngleAndEndpoints(Pose2(), Pose2(), 0.0, m1, Vector2(3, 1), &z));
  EXPECT_FALSE(
      predictLineFromAngleAndEndpoints(Pose2(), Pose2(), kPi / 4 - 1e-3, m1, Vector2(3, 1), &z));
  EXPECT_EQ(z.p, 7.0);
  EXPECT_EQ(z.theta, 0.5);
  EXPECT_TRUE(
      predictLineFromAngleAndEndpoints(Pose2(), Pose2(), kPi / 4 + 1e-3, m1, Vector2(3, 1), &z));
  EXPECT_NEAR(z.p, 1.0, 1e-12);  // p from the endpoints, θ from θ_f
  EXPECT_NEAR(z.theta, kPi / 4 + 1e-3, 1e-12);
}

// ---------------------------------------------------------- augmentation

struct Gaussian {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

// Draws of the robot pose (if its covariance is not zero) and of the
// observation, pushed through `f`; returns the sample covariance of the
// stacked [f, robot] with f's components differenced through wrapAngle
// where `angle` says so.
template <typename F>
MatrixXd sampleCovariance(const Gaussian& robot, const Gaussian& z, int n, unsigned seed, F f,
                          int f_dim, const std::vector<int>& angles) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const MatrixXd L_r = robot.covariance.llt().matrixL();
  const MatrixXd L_z = z.covariance.llt().matrixL();
  const VectorXd f0 = f(robot.mean, z.mean);
  MatrixXd samples(f_dim + 3, n);
  for (int i = 0; i < n; ++i) {
    VectorXd e_r(3), e_z(2);
    for (int k = 0; k < 3; ++k) e_r(k) = unit(rng);
    for (int k = 0; k < 2; ++k) e_z(k) = unit(rng);
    const VectorXd r = robot.mean + L_r * e_r;
    VectorXd d = f(r, z.mean + L_z * e_z) - f0;
    for (int a : angles) d(a) = wrapAngle(d(a));
    samples.col(i) << d, r - robot.mean;
  }
  const VectorXd mean = samples.rowwise().mean();
  const MatrixXd centred = samples.colwise() - mean;
  return centred * centred.transpose() / (n - 1);
}

// Largest |a − b| in units of √(b_ii b_jj): a few percent of the spread.
double relativeError(const MatrixXd& a, const MatrixXd& b) {
  double worst = 0.0;
  for (int i = 0; i < b.rows(); ++i)
    for (int j = 0; j < b.cols(); ++j)
      worst = std::max(worst, std::abs(a(i, j) - b(i, j)) / std::sqrt(b(i, i) * b(j, j)));
  return worst;
}

constexpr int kMonteCarloSamples = 20000;  // a variance to ~1 % (√(2/n))
constexpr double kMonteCarloTolerance = 0.04;

// θ_f = θ + θ_r + laser yaw near ±π: the first-order variance G_r P_rr G_rᵀ
// + G_z R G_zᵀ and the cross-covariance G_r P_rr against 20,000 draws, first
// with the robot known (G_z R G_zᵀ alone), then uncertain.
TEST(LineAugmentation, AngleLandmarkCovarianceMatchesMonteCarlo) {
  const Pose2 laser(0.2, 0.05, 0.02);
  Gaussian robot{Vector3(1.0, -2.0, 0.08), Matrix3::Zero()};  // θ_f = π
  Gaussian z{Vector2(2.5, kPi - 0.1), Matrix2::Zero()};
  z.covariance << 4e-4, 6e-5, 6e-5, 3e-4;
  const auto f = [&laser](const VectorXd& r, const VectorXd& obs) -> VectorXd {
    double theta_f = 0.0;
    lineAngleFromObservation(Pose2::fromVector(r), laser, {obs(0), obs(1)}, &theta_f);
    return VectorXd::Constant(1, theta_f);
  };
  Matrix3 robot_uncertain;
  robot_uncertain << 4e-3, 1e-3, 5e-4,  //
      1e-3, 2e-3, -4e-4,                //
      5e-4, -4e-4, 1e-3;
  for (const Matrix3& P_rr : {Matrix3(1e-20 * Matrix3::Identity()), robot_uncertain}) {
    robot.covariance = P_rr;
    double theta_f, variance;
    RowVector3 G_r;
    RowVector2 G_z;
    const Pose2 mean_pose = Pose2::fromVector(robot.mean);
    ASSERT_TRUE(
        lineAngleFromObservation(mean_pose, laser, {z.mean(0), z.mean(1)}, &theta_f, &G_r, &G_z));
    EXPECT_LT(std::abs(wrapAngle(theta_f - kPi)), 0.1);  // the draws straddle ±π
    ASSERT_TRUE(newLineAngleVariance(P_rr, z.covariance, G_r, G_z, &variance));
    MatrixXd predicted(4, 4);
    predicted << variance, G_r * P_rr,  //
        (G_r * P_rr).transpose(), P_rr;
    const MatrixXd sampled = sampleCovariance(robot, z, kMonteCarloSamples, 21, f, 1, {0});
    EXPECT_LT(std::abs(sampled(0, 0) / variance - 1.0), kMonteCarloTolerance);
    if (P_rr(0, 0) > 1e-10) {
      EXPECT_LT(relativeError(sampled, predicted), kMonteCarloTolerance)
          << "sampled\n"
          << sampled << "\npredicted\n"
          << predicted;
    }
  }
}

// The same for the full (p, θ) landmark, whose p depends on θ through the
// sensor's position.
TEST(LineAugmentation, FullLineCovarianceMatchesMonteCarlo) {
  const Pose2 laser(0.2, 0.05, 0.02);
  Matrix3 P_rr;
  P_rr << 4e-3, 1e-3, 5e-4,  //
      1e-3, 2e-3, -4e-4,     //
      5e-4, -4e-4, 1e-3;
  const Gaussian robot{Vector3(3.0, -2.0, -3.1), P_rr};
  Gaussian z{Vector2(4.0, 0.3), Matrix2::Zero()};
  z.covariance << 4e-4, 6e-5, 6e-5, 3e-4;
  const auto f = [&laser](const VectorXd& r, const VectorXd& obs) -> VectorXd {
    PolarLine landmark;
    lineLandmarkFromObservation(Pose2::fromVector(r), laser, {obs(0), obs(1)}, &landmark);
    return landmark.vector();
  };
  PolarLine landmark;
  Matrix23 G_r;
  Matrix2 G_z, covariance;
  ASSERT_TRUE(lineLandmarkFromObservation(Pose2::fromVector(robot.mean), laser,
                                          {z.mean(0), z.mean(1)}, &landmark, &G_r, &G_z));
  ASSERT_TRUE(newLineLandmarkCovariance(P_rr, z.covariance, G_r, G_z, &covariance));
  MatrixXd predicted(5, 5);
  predicted << covariance, G_r * P_rr,  //
      (G_r * P_rr).transpose(), P_rr;
  const MatrixXd sampled = sampleCovariance(robot, z, kMonteCarloSamples, 22, f, 2, {1});
  EXPECT_LT(relativeError(sampled, predicted), kMonteCarloTolerance) << "sampled\n"
                                                                     << sampled << "\npredicted\n"
                                                                     << predicted;
  for (int i = 0; i < 2; ++i)
    EXPECT_LT(std::abs(sampled(i, i) / covariance(i, i) - 1.0), kMonteCarloTolerance);
}

// ---------------------------------------------------------- refusals

TEST(LineModels, NonFiniteInputsAndBadCovariancesAreRefusedWithOutputsUntouched) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Pose2 good_pose(1, 2, 0.3);
  const Pose2 bad_poses[] = {Pose2(nan, 0, 0), Pose2(0, inf, 0), Pose2(0, 0, nan)};
  const PolarLine sentinel{-7.0, 9.0};
  for (const Pose2& bad : bad_poses) {
    for (int which = 0; which < 2; ++which) {
      const Pose2& robot = which == 0 ? bad : good_pose;
      const Pose2& laser = which == 0 ? good_pose : bad;
      PolarLine out = sentinel;
      double angle = 9.0;
      EXPECT_FALSE(predictLineObservation(robot, laser, {1, 0}, &out));
      EXPECT_FALSE(lineLandmarkFromObservation(robot, laser, {1, 0}, &out));
      EXPECT_FALSE(predictLineAngle(robot, laser, 0.0, &angle));
      EXPECT_FALSE(predictLineFromAngleAndPoint(robot, laser, 0.0, Vector2(1, 1), &out));
      EXPECT_FALSE(predictLineFromAngleAndEndpoints(robot, laser, kPi / 2, Vector2(1, 1),
                                                    Vector2(3, 1), &out));
      EXPECT_FALSE(lineAngleFromObservation(robot, laser, {1, 0}, &angle));
      EXPECT_EQ(out.p, sentinel.p);
      EXPECT_EQ(out.theta, sentinel.theta);
      EXPECT_EQ(angle, 9.0);
    }
  }
  PolarLine out = sentinel;
  double angle = 9.0;
  Vector2 nu(5, 5);
  for (const double bad : {nan, inf, -inf}) {
    EXPECT_FALSE(predictLineObservation(good_pose, Pose2(), {bad, 0}, &out));
    EXPECT_FALSE(predictLineObservation(good_pose, Pose2(), {1, bad}, &out));
    EXPECT_FALSE(lineLandmarkFromObservation(good_pose, Pose2(), {1, bad}, &out));
    EXPECT_FALSE(lineInnovation({1, bad}, {1, 0}, &nu));
    EXPECT_FALSE(lineInnovation({1, 0}, {bad, 0}, &nu));
    EXPECT_FALSE(predictLineAngle(good_pose, Pose2(), bad, &angle));
    EXPECT_FALSE(predictLineFromAngleAndPoint(good_pose, Pose2(), bad, Vector2(1, 1), &out));
    EXPECT_FALSE(predictLineFromAngleAndPoint(good_pose, Pose2(), 0.0, Vector2(1, bad), &out));
    EXPECT_FALSE(predictLineFromAngleAndEndpoints(good_pose, Pose2(), kPi / 2, Vector2(bad, 1),
                                                  Vector2(3, 1), &out));
    EXPECT_FALSE(predictLineFromAngleAndEndpoints(good_pose, Pose2(), kPi / 2, Vector2(1, 1),
                                                  Vector2(3, bad), &out));
    EXPECT_FALSE(lineAngleFromObservation(good_pose, Pose2(), {bad, 0}, &angle));
  }
  EXPECT_EQ(out.p, sentinel.p);
  EXPECT_EQ(out.theta, sentinel.theta);
  EXPECT_EQ(angle, 9.0);
  EXPECT_TRUE(nu == Vector2(5, 5));

  // Covariances: non-finite, asymmetric, negative eigenvalue.
  const Matrix3 P_rr = 1e-3 * Matrix3::Identity();
  const Matrix2 R = 1e-4 * Matrix2::Identity();
  Matrix23 G_r = Matrix23::Ones();
  const Matrix2 G_z = Matrix2::Identity();
  Matrix3 P_nan = P_rr, P_asym = P_rr, P_neg = P_rr;
  P_nan(1, 1) = nan;
  P_asym(0, 1) = 1e-4;
  P_neg(0, 1) = P_neg(1, 0) = 2e-3;  // |ρ| > 1
  Matrix2 R_inf = R, R_neg = R;
  R_inf(0, 0) = inf;
  R_neg(1, 1) = -1e-6;
  Matrix2 covariance = Matrix2::Constant(3.0);
  double variance = 3.0;
  const RowVector3 g_r(0, 0, 1);
  const RowVector2 g_z(0, 1);
  for (const Matrix3& P : {P_nan, P_asym, P_neg}) {
    EXPECT_FALSE(newLineLandmarkCovariance(P, R, G_r, G_z, &covariance));
    EXPECT_FALSE(newLineAngleVariance(P, R, g_r, g_z, &variance));
  }
  for (const Matrix2& bad_R : {R_inf, R_neg}) {
    EXPECT_FALSE(newLineLandmarkCovariance(P_rr, bad_R, G_r, G_z, &covariance));
    EXPECT_FALSE(newLineAngleVariance(P_rr, bad_R, g_r, g_z, &variance));
  }
  G_r(0, 2) = nan;
  EXPECT_FALSE(newLineLandmarkCovariance(P_rr, R, G_r, G_z, &covariance));
  EXPECT_FALSE(newLineAngleVariance(P_rr, R, RowVector3(0, 0, nan), g_z, &variance));
  EXPECT_TRUE(covariance == Matrix2::Constant(3.0));
  EXPECT_EQ(variance, 3.0);
  // A zero covariance (a perfectly known robot) is a valid one.
  EXPECT_TRUE(newLineAngleVariance(Matrix3::Zero(), R, g_r, g_z, &variance));
  EXPECT_DOUBLE_EQ(variance, 1e-4);
}

// ---------------------------------------------------------- the thesis

// What the printed equations of §4.3.3 say, against their own models.
TEST(ThesisLineEquations, PrintedJacobiansAreNotTheDerivativesOfTheirModels) {
  // Eq. 4.35: n₁ = x_v sin θ − y_v cos θ − x_f sin θ + y_f cos θ.
  const auto n1_435 = [](const VectorXd& s) -> VectorXd {  // (x_v, y_v, x_f, y_f, θ)
    return VectorXd::Constant(1, s(0) * std::sin(s(4)) - s(1) * std::cos(s(4)) -
                                     s(2) * std::sin(s(4)) + s(3) * std::cos(s(4)));
  };
  VectorXd v(5);
  v << 1.0, -2.0, 3.0, 0.5, 0.4;
  const double th = v(4);
  const double printed_dtheta = -v(2) * std::cos(th) - v(3) * std::sin(th);
  const MatrixXd J = numericalJacobian(n1_435, v);
  EXPECT_NEAR(J(0, 2), -std::sin(th), kTol);  // the landmark columns are right
  EXPECT_NEAR(J(0, 3), std::cos(th), kTol);
  // The θ_f column lacks the robot's x_v cos θ + y_v sin θ.
  EXPECT_NEAR(J(0, 4) - printed_dtheta, v(0) * std::cos(th) + v(1) * std::sin(th), kTol);
  EXPECT_GT(std::abs(J(0, 4) - printed_dtheta), 0.1);
  // And with θ the normal, n₁ is the coordinate along the line: the wall
  // x = 2 (θ = 0) through (2, 1) seen from the origin gives 1, not 2.
  VectorXd wall(5);
  wall << 0.0, 0.0, 2.0, 1.0, 0.0;
  EXPECT_NEAR(n1_435(wall)(0), 1.0, 1e-12);
  PolarLine z;
  ASSERT_TRUE(predictLineFromAngleAndPoint(Pose2(), Pose2(), 0.0, Vector2(2, 1), &z));
  EXPECT_NEAR(z.p, 2.0, 1e-12);

  // Eq. 4.38: n₁ = (x_v(y₁ − y₂) + y_v(x₂ − x₁))/d, the distance to the
  // parallel through the map origin: the wall y = 1 seen from the origin gives 0.
  const auto n1_438 = [](const VectorXd& s) -> VectorXd {  // (x_v, y_v, x₁, y₁, x₂, y₂)
    const double dx = s(4) - s(2), dy = s(5) - s(3);
    return VectorXd::Constant(1, (s(0) * -dy + s(1) * dx) / std::hypot(dx, dy));
  };
  VectorXd e(6);
  e << 0.0, 0.0, 0.0, 1.0, 1.0, 1.0;
  EXPECT_NEAR(n1_438(e)(0), 0.0, 1e-12);
  ASSERT_TRUE(predictLineFromAngleAndEndpoints(Pose2(), Pose2(), kPi / 2, Vector2(0, 1),
                                               Vector2(1, 1), &z));
  EXPECT_NEAR(z.p, 1.0, 1e-12);
  // Eqs. 4.40–4.43 as printed: endpoint columns (−y_v n₁, x_v n₂) and
  // (y_v n₁, x_v n₂), n₁ = (d² + 3Δx²)/d³, n₂ = (d² + 3Δy²)/d³.
  VectorXd g(6);
  g << 0.5, -1.5, 2.0, 1.0, 3.0, 3.5;
  const double dx = g(4) - g(2), dy = g(5) - g(3), d = std::hypot(dx, dy);
  const double N1 = (d * d + 3 * dx * dx) / (d * d * d), N2 = (d * d + 3 * dy * dy) / (d * d * d);
  Eigen::RowVectorXd printed(6);
  printed << -dy / d, dx / d, -g(1) * N1, g(0) * N2, g(1) * N1, g(0) * N2;
  const MatrixXd K = numericalJacobian(n1_438, g);
  EXPECT_NEAR(K(0, 0), printed(0), kTol);  // the robot columns are right
  EXPECT_NEAR(K(0, 1), printed(1), kTol);
  EXPECT_GT((K.rightCols<4>() - printed.tail<4>()).cwiseAbs().maxCoeff(), 0.1);
}

}  // namespace
}  // namespace ekf_slam
