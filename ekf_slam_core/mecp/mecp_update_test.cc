// The MECP update against a dense EKF update whose Jacobian is a central
// difference of "range and bearing of the members' mean" over the whole
// state, and its skip conditions.
#include "ekf_slam_core/mecp/mecp_update.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>

#include "ekf_slam_core/mecp/mecp_observation.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

const Pose2 kLaser(0.1, 0.0, 0.0);

Matrix2 readingCovariance() {
  Matrix2 c;
  c << 0.02 * 0.02, 0.0, 0.0, 0.01 * 0.01;
  return c;
}

PointObservation readingOf(const Pose2& robot, const Vector2& landmark, double dr = 0.0,
                           double dphi = 0.0) {
  PointObservation obs;
  EXPECT_TRUE(predictPointObservation(robot, kLaser, landmark, &obs.z));
  obs.z.range += dr;
  obs.z.bearing = wrapAngle(obs.z.bearing + dphi);
  obs.covariance = readingCovariance();
  return obs;
}

// Four landmarks around the robot (ids 0–3, the polygon) and one (id 4)
// behind landmark 0 as seen from the robot, so that any polygon through it
// holds 0 (ids 0–4), mapped from an uncertain pose and then driven a
// little, so that the pose and the landmarks are correlated.
struct Scene {
  EkfSlam filter;
  std::vector<Vector2> truth = {{3.0, 2.0}, {-2.0, 2.5}, {-2.5, -2.0}, {2.5, -3.0}, {5.8, 3.95}};
  explicit Scene(const Pose2& start = Pose2(0.0, 0.0, 0.1))
      : filter(options(), start, Matrix3::Identity() * 0.01) {
    for (const Vector2& m : truth) {
      EXPECT_EQ(filter.augment(readingOf(start, m, 0.01, -0.004)), FilterStatus::kOk);
    }
    EXPECT_EQ(filter.predict(Pose2(), Pose2(0.2, 0.02, 0.05), 0.2), FilterStatus::kOk);
  }
  static FilterOptions options() {
    FilterOptions o;
    o.laser_pose = kLaser;
    o.tentative_max_age = 0;
    return o;
  }
  // Readings of every landmark from `robot`, a little off the truth.
  std::vector<PointObservation> scan(const Pose2& robot) const {
    std::vector<PointObservation> out;
    for (const Vector2& m : truth) out.push_back(readingOf(robot, m, -0.015, 0.006));
    return out;
  }
};

TEST(MecpUpdate, EqualsTheDenseEkfUpdateOfTheMembersMean) {
  Scene scene;
  EkfSlam& filter = scene.filter;
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();
  const Pose2 robot(0.2, 0.05, 0.13);
  const std::vector<PointObservation> scan = scene.scan(robot);

  const MecpUpdateResult result = updateWithMecp(&filter, scan, {0, 1, 2, 3, 4});
  ASSERT_EQ(result.outcome, MecpOutcome::kApplied);
  std::vector<int> members = result.member_ids;
  std::sort(members.begin(), members.end());
  ASSERT_EQ(members, (std::vector<int>{0, 1, 2, 3}));

  // h(x): range and bearing from the laser of the mean of the members.
  auto h = [&](const VectorXd& x) {
    Vector2 centre = Vector2::Zero();
    for (int id : members) centre += x.segment<2>(3 + 2 * id);
    centre /= static_cast<double>(members.size());
    RangeBearing z;
    EXPECT_TRUE(predictMecpObservation(Pose2(x(0), x(1), x(2)), kLaser, {centre}, &z));
    return VectorXd(Vector2(z.range, z.bearing));
  };
  const MatrixXd H = testing::numericalJacobian(h, x0, {1});
  std::vector<RangeBearing> readings;
  std::vector<Matrix2> covariances;
  for (int id : result.member_ids) {
    readings.push_back(scan[id].z);
    covariances.push_back(scan[id].covariance);
  }
  RangeBearing observed;
  Matrix2 R;
  ASSERT_TRUE(observeMecp(readings, covariances, &observed, &R));
  const VectorXd predicted = h(x0);
  const Vector2 nu(observed.range - predicted(0), wrapAngle(observed.bearing - predicted(1)));
  const MatrixXd S = H * P0 * H.transpose() + MatrixXd(R);
  const MatrixXd K = P0 * H.transpose() * S.inverse();
  const VectorXd expected_x = x0 + K * nu;
  const MatrixXd expected_P = P0 - K * S * K.transpose();

  EXPECT_LT((filter.state() - expected_x).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_LT((filter.covariance() - expected_P).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_NEAR(result.nis, nu.dot(S.ldlt().solve(nu)), 1e-5);
  // The update informs the state: the pose's covariance shrinks.
  EXPECT_LT(filter.poseCovariance().trace(), P0.topLeftCorner(3, 3).trace());
}

TEST(MecpUpdate, UnmatchedReadingsTakeNoPartAndTooFewLeaveTheFilterAlone) {
  Scene scene;
  EkfSlam& filter = scene.filter;
  const VectorXd x0 = filter.state();
  const std::vector<PointObservation> scan = scene.scan(Pose2(0.2, 0.05, 0.13));

  // With landmark 0's reading unmatched, 4 takes its place.
  EkfSlam copy = filter;
  const MecpUpdateResult without_zero = updateWithMecp(&copy, scan, {-1, 1, 2, 3, 4});
  ASSERT_EQ(without_zero.outcome, MecpOutcome::kApplied);
  std::vector<int> members = without_zero.member_ids;
  std::sort(members.begin(), members.end());
  EXPECT_EQ(members, (std::vector<int>{1, 2, 3, 4}));

  const MecpUpdateResult two = updateWithMecp(&filter, scan, {0, -1, 2, -1, -1});
  EXPECT_EQ(two.outcome, MecpOutcome::kNoPolygon);
  EXPECT_EQ(filter.state(), x0);
  // Ids the filter does not hold count as unmatched.
  EXPECT_EQ(updateWithMecp(&filter, scan, {0, 17, 2, 18, -1}).outcome, MecpOutcome::kNoPolygon);
  EXPECT_EQ(filter.state(), x0);
}

TEST(MecpUpdate, ACentreAtTheLaserIsSkipped) {
  // Four landmarks symmetric about a point 3 cm from the laser: the centre's
  // bearing is meaningless there.
  FilterOptions options = Scene::options();
  const Pose2 robot(0.0, 0.0, 0.0);
  EkfSlam filter(options, robot, Matrix3::Identity() * 1e-4);
  const Vector2 near_laser(0.13, 0.0);
  std::vector<PointObservation> scan;
  for (const Vector2& offset :
       {Vector2(2.0, 2.0), Vector2(-2.0, 2.0), Vector2(-2.0, -2.0), Vector2(2.0, -2.0)}) {
    scan.push_back(readingOf(robot, near_laser + offset));
    ASSERT_EQ(filter.augment(scan.back()), FilterStatus::kOk);
  }
  const VectorXd x0 = filter.state();
  const MecpUpdateResult result = updateWithMecp(&filter, scan, {0, 1, 2, 3});
  EXPECT_EQ(result.outcome, MecpOutcome::kNearCentre);
  EXPECT_EQ(result.member_ids.size(), 4u);
  EXPECT_EQ(filter.state(), x0);
}

TEST(MecpUpdateOptions, ANonPositiveBearingLimitIsRefusedByName) {
  EXPECT_EQ(MecpUpdateOptions().validate(), "");
  MecpUpdateOptions options;
  options.max_bearing_sigma = 0.0;
  EXPECT_NE(options.validate().find("max_bearing_sigma"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
