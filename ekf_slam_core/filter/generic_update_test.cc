#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ekf_slam_core/filter/ekf_slam.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

PointObservation reading(double range, double bearing) {
  PointObservation obs;
  obs.z = {range, bearing};
  obs.covariance << 0.02 * 0.02, 0.0, 0.0, 0.01 * 0.01;
  return obs;
}

// Four point landmarks and a θ-only line, correlated through the pose by a
// prediction and an update between the augmentations.
EkfSlam correlatedFilter() {
  FilterOptions options;
  options.laser_pose = Pose2(0.1, 0.0, 0.0);
  options.tentative_max_age = 0;
  EkfSlam filter(options, Pose2(1.0, -0.5, 0.2), Matrix3::Identity() * 0.02);
  EXPECT_EQ(filter.augment(reading(2.0, 0.4)), FilterStatus::kOk);
  EXPECT_EQ(filter.augment(reading(3.0, -0.7)), FilterStatus::kOk);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.3, 0.05, 0.1), 0.2), FilterStatus::kOk);
  EXPECT_EQ(filter.augment(reading(1.5, 1.2)), FilterStatus::kOk);
  LineObservation wall;
  wall.z = {2.5, 0.3};
  wall.covariance << 0.02 * 0.02, 0.0, 0.0, 0.01 * 0.01;
  EXPECT_EQ(filter.augmentLine(wall, LandmarkKind::kLineAngle), FilterStatus::kOk);
  EXPECT_EQ(filter.augment(reading(4.0, 0.1)), FilterStatus::kOk);
  EXPECT_EQ(filter.update({reading(1.95, 0.37)}, {{0, 0}}), FilterStatus::kOk);
  return filter;
}

// A two-row observation of the pose, landmarks 0 and 2 and the line
// (id 3), with arbitrary but fixed Jacobians and a correlated noise.
GenericObservation someObservation() {
  GenericObservation obs;
  obs.innovation = Eigen::Vector2d(0.04, -0.02);
  obs.J_z_pose = MatrixXd(2, 3);
  obs.J_z_pose << -0.6, -0.8, 0.0, 0.3, -0.2, -1.0;
  obs.landmark_ids = {0, 2, 3};
  MatrixXd a(2, 2), b(2, 2), c(2, 1);
  a << 0.3, 0.4, -0.1, 0.15;
  b << 0.25, 0.1, 0.05, -0.2;
  c << 0.7, -0.4;
  obs.J_z_landmarks = {a, b, c};
  obs.noise = MatrixXd(2, 2);
  obs.noise << 4e-4, 1e-4, 1e-4, 2e-4;
  return obs;
}

TEST(GenericUpdate, EqualsTheTextbookEkfUpdateOnTheWholeState) {
  EkfSlam filter = correlatedFilter();
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();
  const GenericObservation obs = someObservation();

  // Dense reference: H over the whole state, K = P Hᵀ S⁻¹,
  // x' = x + K ν, P' = (I − K H) P.
  const int n = static_cast<int>(x0.size());
  MatrixXd H = MatrixXd::Zero(2, n);
  H.leftCols(3) = obs.J_z_pose;
  for (size_t i = 0; i < obs.landmark_ids.size(); ++i) {
    const int slot = filter.slotOf(obs.landmark_ids[i]);
    H.middleCols(filter.landmarkIndex(slot), obs.J_z_landmarks[i].cols()) = obs.J_z_landmarks[i];
  }
  const MatrixXd S = H * P0 * H.transpose() + obs.noise;
  const MatrixXd K = P0 * H.transpose() * S.inverse();
  VectorXd expected_x = x0 + K * obs.innovation;
  expected_x(2) = wrapAngle(expected_x(2));
  const MatrixXd expected_P = (MatrixXd::Identity(n, n) - K * H) * P0;

  double nis = -1.0;
  ASSERT_EQ(filter.updateGeneric(obs, &nis), FilterStatus::kOk);
  EXPECT_LT((filter.state() - expected_x).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((filter.covariance() - expected_P).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(nis, obs.innovation.dot(S.ldlt().solve(obs.innovation)), 1e-9);
  // The blocks the filter's own predictions read stay current.
  EXPECT_LT((filter.poseCovariance() - expected_P.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(),
            1e-12);
  const int j = filter.landmarkIndex(filter.slotOf(4));
  EXPECT_LT((filter.landmarkCovariance(filter.slotOf(4)) - expected_P.block<2, 2>(j, j))
                .cwiseAbs()
                .maxCoeff(),
            1e-12);
}

TEST(GenericUpdate, WithAPointsModelEqualsThePointUpdate) {
  EkfSlam points = correlatedFilter();
  EkfSlam generic = points;
  const PointObservation z = reading(2.9, -0.66);
  EkfSlam::Prediction prediction;
  ASSERT_TRUE(points.predictObservation(points.slotOf(1), &prediction));
  ASSERT_EQ(points.update({z}, {{0, 1}}), FilterStatus::kOk);

  GenericObservation obs;
  obs.innovation = Eigen::Vector2d(z.z.range - prediction.z.range,
                                   wrapAngle(z.z.bearing - prediction.z.bearing));
  obs.J_z_pose = prediction.H_robot;
  obs.landmark_ids = {1};
  obs.J_z_landmarks = {MatrixXd(prediction.H_landmark)};
  obs.noise = z.covariance;
  ASSERT_EQ(generic.updateGeneric(obs), FilterStatus::kOk);
  EXPECT_LT((generic.state() - points.state()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((generic.covariance() - points.covariance()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(GenericUpdate, RefusesBadInputAndLeavesTheStateUnchanged) {
  EkfSlam filter = correlatedFilter();
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();

  GenericObservation unknown = someObservation();
  unknown.landmark_ids[1] = 99;
  EXPECT_EQ(filter.updateGeneric(unknown), FilterStatus::kUnknownLandmark);

  GenericObservation repeated = someObservation();
  repeated.landmark_ids[1] = 0;
  EXPECT_EQ(filter.updateGeneric(repeated), FilterStatus::kBadObservation);

  GenericObservation wrong_width = someObservation();
  wrong_width.J_z_landmarks[2] = MatrixXd::Ones(2, 2);  // the line has one component
  EXPECT_EQ(filter.updateGeneric(wrong_width), FilterStatus::kBadObservation);

  GenericObservation not_finite = someObservation();
  not_finite.innovation(1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(filter.updateGeneric(not_finite), FilterStatus::kNonFiniteInput);

  GenericObservation singular = someObservation();
  singular.J_z_pose.setZero();
  for (MatrixXd& J : singular.J_z_landmarks) J.setZero();
  singular.noise.setZero();
  EXPECT_EQ(filter.updateGeneric(singular), FilterStatus::kSingularInnovation);

  EXPECT_EQ(filter.state(), x0);
  EXPECT_EQ(filter.covariance(), P0);
}

}  // namespace
}  // namespace ekf_slam
