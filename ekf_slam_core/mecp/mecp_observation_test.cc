// The MECP observation model: every Jacobian against central differences
// (bearings near ±π, an offset laser mount, a centre close to the laser),
// the noise T R Tᵀ against Monte Carlo, and the refusal of bad input.
#include "ekf_slam_core/mecp/mecp_observation.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <limits>
#include <random>

#include "ekf_slam_core/testing/jacobian_assertions.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::near;
using testing::numericalJacobian;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct MecpCase {
  const char* name;
  Pose2 robot;
  Pose2 laser;
  std::vector<Vector2> members;  // map frame
};

// Members of a square room around the robot, shifted so that the centre sits
// where each case needs it: ahead, just above and just below the ±π bearing
// behind the sensor, a few centimetres from the sensor, a lone member.
std::vector<Vector2> roomAround(const Vector2& centre) {
  return {centre + Vector2(-2.0, -1.5), centre + Vector2(2.0, -1.5), centre + Vector2(2.5, 1.0),
          centre + Vector2(-1.0, 2.0), centre + Vector2(-1.5, 0.0)};
}

const MecpCase kCases[] = {
    {"Ahead", Pose2(0, 0, 0), Pose2(), roomAround(Vector2(3.0, 1.0))},
    {"MountedLaser", Pose2(1, 2, 0.3), Pose2(0.2, -0.05, 0.02), roomAround(Vector2(-1.0, 4.0))},
    {"BehindAbovePi", Pose2(0, 0, 0), Pose2(), roomAround(Vector2(-2.0, 1e-4))},
    {"BehindBelowPi", Pose2(0, 0, 0), Pose2(), roomAround(Vector2(-2.0, -1e-4))},
    {"RobotFacingMinusPi", Pose2(0.5, 0.5, kPi - 1e-4), Pose2(0.16, 0.0, kPi),
     roomAround(Vector2(0.8, 0.52))},
    {"CentreNearTheLaser", Pose2(0, 0, 0.4), Pose2(), roomAround(Vector2(0.05, -0.03))},
    {"OneMember", Pose2(-2, 3, -1.0), Pose2(0.16, 0.0, 0.0), {Vector2(-1.0, 2.0)}},
};

class MecpJacobians : public ::testing::TestWithParam<MecpCase> {};
INSTANTIATE_TEST_SUITE_P(Geometry, MecpJacobians, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

TEST_P(MecpJacobians, PredictedHMatchesCentralDifferences) {
  const MecpCase& c = GetParam();
  const int k = static_cast<int>(c.members.size());
  RangeBearing z;
  Matrix23 H_robot;
  std::vector<Matrix2> H_members;
  ASSERT_TRUE(predictMecpObservation(c.robot, c.laser, c.members, &z, &H_robot, &H_members));
  ASSERT_EQ(static_cast<int>(H_members.size()), k);
  VectorXd v(3 + 2 * k);
  v.head<3>() = c.robot.vector();
  for (int i = 0; i < k; ++i) v.segment<2>(3 + 2 * i) = c.members[i];
  const Pose2 laser = c.laser;
  const auto h = [&laser, k](const VectorXd& s) -> VectorXd {
    std::vector<Vector2> members(k);
    for (int i = 0; i < k; ++i) members[i] = s.segment<2>(3 + 2 * i);
    RangeBearing out;
    predictMecpObservation(Pose2::fromVector(s.head<3>()), laser, members, &out);
    return out.vector();
  };
  const MatrixXd J = numericalJacobian(h, v, {1}, 1e-7);
  EXPECT_TRUE(near(H_robot, J.leftCols<3>(), 1e-5));
  for (int i = 0; i < k; ++i) {
    EXPECT_TRUE(near(H_members[i], J.block(0, 3 + 2 * i, 2, 2), 1e-5)) << "member " << i;
  }
}

// The readings the laser takes of the members from the case's pose.
std::vector<RangeBearing> readingsOf(const MecpCase& c) {
  std::vector<RangeBearing> readings;
  for (const Vector2& m : c.members) {
    RangeBearing z;
    EXPECT_TRUE(predictPointObservation(c.robot, c.laser, m, &z));
    readings.push_back(z);
  }
  return readings;
}

TEST_P(MecpJacobians, ObservedTMatchesCentralDifferencesAndThePrediction) {
  const MecpCase& c = GetParam();
  const std::vector<RangeBearing> readings = readingsOf(c);
  const int k = static_cast<int>(readings.size());
  const std::vector<Matrix2> covariances(k, Matrix2::Identity());
  RangeBearing z;
  Matrix2 covariance;
  Matrix2X T;
  ASSERT_TRUE(observeMecp(readings, covariances, &z, &covariance, &T));
  ASSERT_EQ(T.cols(), 2 * k);
  // The centre of the readings is the reading of the centre: averaging
  // commutes with the rigid map → laser transform.
  RangeBearing predicted;
  ASSERT_TRUE(predictMecpObservation(c.robot, c.laser, c.members, &predicted));
  EXPECT_NEAR(z.range, predicted.range, 1e-9);
  EXPECT_NEAR(wrapAngle(z.bearing - predicted.bearing), 0.0, 1e-7);
  VectorXd v(2 * k);
  for (int i = 0; i < k; ++i) v.segment<2>(2 * i) = readings[i].vector();
  const auto f = [k](const VectorXd& s) -> VectorXd {
    std::vector<RangeBearing> r(k);
    for (int i = 0; i < k; ++i) r[i] = {s(2 * i), s(2 * i + 1)};
    RangeBearing out;
    Matrix2 unused;
    observeMecp(r, std::vector<Matrix2>(k, Matrix2::Identity()), &out, &unused);
    return out.vector();
  };
  EXPECT_TRUE(near(T, numericalJacobian(f, v, {1}, 1e-7), 1e-5));
  // With R = I the covariance is T Tᵀ.
  EXPECT_TRUE(near(covariance, T * T.transpose(), 1e-12));
}

TEST(MecpObservation, LaserAtTheOriginGivesTheClosedForm) {
  // H_r = [−x_c/ρ  −y_c/ρ  0; y_c/ρ²  −x_c/ρ²  −1] and H_m_i = (1/k) of the
  // negated position columns, as the header derives (thesis eq. 4.55 has a
  // factor 2 and the bearing row's entries swapped).
  const Pose2 robot(0.4, -0.3, 0.7);
  const std::vector<Vector2> members{{3, 1}, {-1, 4}, {0.5, -2}};
  const Vector2 d = (members[0] + members[1] + members[2]) / 3.0 - robot.translation();
  const double rho2 = d.squaredNorm(), rho = std::sqrt(rho2);
  Matrix23 expected_robot;
  expected_robot << -d.x() / rho, -d.y() / rho, 0.0,  //
      d.y() / rho2, -d.x() / rho2, -1.0;
  RangeBearing z;
  Matrix23 H_robot;
  std::vector<Matrix2> H_members;
  ASSERT_TRUE(predictMecpObservation(robot, Pose2(), members, &z, &H_robot, &H_members));
  EXPECT_NEAR(z.range, rho, 1e-12);
  EXPECT_NEAR(z.bearing, wrapAngle(std::atan2(d.y(), d.x()) - robot.theta), 1e-12);
  EXPECT_TRUE(near(H_robot, expected_robot, 1e-12));
  for (const Matrix2& H : H_members) {
    EXPECT_TRUE(near(H, -expected_robot.leftCols<2>() / 3.0, 1e-12));
  }
}

// Samples of the observed MECP under small reading noise scatter as T R Tᵀ
// says, with correlated and uncorrelated (r, φ) noise and different k.
TEST(MecpObservation, NoiseMatchesMonteCarlo) {
  struct Setup {
    std::vector<RangeBearing> readings;
    std::vector<Matrix2> covariances;
  };
  Matrix2 correlated;
  correlated << 4e-4, 2e-6,  //
      2e-6, 1e-4;
  const std::vector<Setup> setups{
      {{{3.0, 0.2}, {2.5, 1.9}, {4.0, -2.8}, {2.0, -1.1}},
       std::vector<Matrix2>(4, Matrix2(Eigen::Vector2d(1e-4, 2.5e-5).asDiagonal()))},
      // Bearings either side of ±π and a centre behind the sensor.
      {{{3.0, kPi - 0.01}, {2.0, -kPi + 0.02}, {4.0, 2.5}},
       {correlated, Matrix2(Eigen::Vector2d(1e-4, 1e-6).asDiagonal()), correlated}},
      {{{1.5, 0.3}, {1.0, 2.5}, {2.0, -2.0}, {3.0, -0.5}, {2.2, 1.2}, {1.8, -1.6}},
       std::vector<Matrix2>(6, correlated)},
  };
  std::mt19937 rng(7);
  std::normal_distribution<double> unit;
  constexpr int kSamples = 100000;
  for (std::size_t s = 0; s < setups.size(); ++s) {
    const Setup& setup = setups[s];
    RangeBearing z;
    Matrix2 covariance;
    ASSERT_TRUE(observeMecp(setup.readings, setup.covariances, &z, &covariance));
    std::vector<Matrix2> roots;
    for (const Matrix2& R : setup.covariances) roots.push_back(R.llt().matrixL());
    Vector2 mean = Vector2::Zero();
    Matrix2 second = Matrix2::Zero();
    std::vector<RangeBearing> noisy = setup.readings;
    for (int n = 0; n < kSamples; ++n) {
      for (std::size_t i = 0; i < noisy.size(); ++i) {
        const Vector2 e = roots[i] * Vector2(unit(rng), unit(rng));
        noisy[i] = {setup.readings[i].range + e.x(), setup.readings[i].bearing + e.y()};
      }
      RangeBearing sample;
      Matrix2 unused;
      ASSERT_TRUE(observeMecp(noisy, setup.covariances, &sample, &unused));
      const Vector2 error(sample.range - z.range, wrapAngle(sample.bearing - z.bearing));
      mean += error;
      second += error * error.transpose();
    }
    mean /= kSamples;
    const Matrix2 sample_covariance = second / kSamples - mean * mean.transpose();
    // Each entry within 3 % of the scale sqrt(C_ii C_jj); the sampling error
    // of a variance from 10⁵ draws is about 0.45 %.
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        const double scale = std::sqrt(covariance(i, i) * covariance(j, j));
        EXPECT_NEAR(sample_covariance(i, j), covariance(i, j), 0.03 * scale)
            << "setup " << s << " entry " << i << j;
      }
    }
    // The mean is unbiased to first order.
    EXPECT_LT(std::abs(mean.x()), 0.05 * std::sqrt(covariance(0, 0)));
    EXPECT_LT(std::abs(mean.y()), 0.05 * std::sqrt(covariance(1, 1)));
  }
}

TEST(MecpObservation, AveragingShrinksTheNoise) {
  // Four readings of equal noise around the sensor: the centre's Cartesian
  // covariance is a quarter of one reading's.
  std::vector<RangeBearing> readings{{2.0, 0.0}, {2.0, 0.5 * kPi}, {2.0, kPi}, {2.0, 0.7}};
  const Matrix2 R = Eigen::Vector2d(1e-4, 1e-4 / 4.0).asDiagonal();  // 1 cm, 1 cm at 2 m
  RangeBearing z;
  Matrix2 covariance;
  ASSERT_TRUE(observeMecp(readings, std::vector<Matrix2>(4, R), &z, &covariance));
  // Each reading is isotropic 1e-4 m² in the plane, so the centre is 1e-4/4
  // isotropic: range variance 2.5e-5 m², bearing variance 2.5e-5 / ρ².
  EXPECT_NEAR(covariance(0, 0), 2.5e-5, 1e-12);
  EXPECT_NEAR(covariance(1, 1), 2.5e-5 / (z.range * z.range), 1e-10);
  EXPECT_NEAR(covariance(0, 1), 0.0, 1e-12);
}

TEST(MecpObservation, BadInputIsRefusedWithOutputsUntouched) {
  const std::vector<RangeBearing> good{{2.0, 0.1}, {3.0, 1.5}, {2.5, -1.0}};
  const std::vector<Matrix2> R(3, Matrix2::Identity() * 1e-4);
  const RangeBearing sentinel{-7.0, -7.0};
  const Matrix2 sentinel_covariance = Matrix2::Constant(-7.0);
  const auto refused = [&](const std::vector<RangeBearing>& readings,
                           const std::vector<Matrix2>& covariances) {
    RangeBearing z = sentinel;
    Matrix2 covariance = sentinel_covariance;
    Matrix2X T = Matrix2X::Constant(2, 1, -7.0);
    const bool ok = observeMecp(readings, covariances, &z, &covariance, &T);
    return !ok && z.range == -7.0 && z.bearing == -7.0 && covariance == sentinel_covariance &&
           T.cols() == 1 && T(0, 0) == -7.0;
  };
  RangeBearing z;
  Matrix2 covariance;
  EXPECT_TRUE(observeMecp(good, R, &z, &covariance));
  EXPECT_TRUE(refused({}, {}));
  EXPECT_TRUE(refused(good, {R[0], R[1]}));
  for (int field = 0; field < 2; ++field) {
    for (double bad : {kNaN, std::numeric_limits<double>::infinity()}) {
      std::vector<RangeBearing> readings = good;
      (field == 0 ? readings[1].range : readings[1].bearing) = bad;
      EXPECT_TRUE(refused(readings, R)) << field << " " << bad;
    }
  }
  std::vector<RangeBearing> negative = good;
  negative[0].range = -1.0;
  EXPECT_TRUE(refused(negative, R));
  std::vector<Matrix2> nan_covariance = R;
  nan_covariance[2](1, 1) = kNaN;
  EXPECT_TRUE(refused(good, nan_covariance));
  std::vector<Matrix2> asymmetric = R;
  asymmetric[0](0, 1) = 1e-5;
  EXPECT_TRUE(refused(good, asymmetric));
  // Readings whose centre is the sensor: no bearing.
  EXPECT_TRUE(refused({{1.0, 0.0}, {1.0, kPi}}, {R[0], R[1]}));

  // The prediction refuses the same way.
  const std::vector<Vector2> members{{1, 1}, {3, 0}, {2, 2}};
  Matrix23 H_robot = Matrix23::Constant(-7.0);
  std::vector<Matrix2> H_members;
  const auto predictionRefused = [&](const Pose2& robot, const Pose2& laser,
                                     const std::vector<Vector2>& m) {
    RangeBearing out = sentinel;
    const bool ok = predictMecpObservation(robot, laser, m, &out, &H_robot, &H_members);
    return !ok && out.range == -7.0 && out.bearing == -7.0 && H_robot(0, 0) == -7.0 &&
           H_members.empty();
  };
  EXPECT_TRUE(predictionRefused(Pose2(), Pose2(), {}));
  EXPECT_TRUE(predictionRefused(Pose2(kNaN, 0, 0), Pose2(), members));
  EXPECT_TRUE(predictionRefused(Pose2(), Pose2(0, kNaN, 0), members));
  EXPECT_TRUE(predictionRefused(Pose2(), Pose2(), {{1, 1}, {kNaN, 0}}));
  EXPECT_TRUE(predictionRefused(Pose2(), Pose2(), {{1, 1}, {-1, -1}}));  // centre at the laser
}

}  // namespace
}  // namespace ekf_slam
