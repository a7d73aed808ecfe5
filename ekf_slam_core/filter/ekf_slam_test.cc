#include "ekf_slam_core/filter/ekf_slam.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <random>

#include "ekf_slam_core/sim/landmark_simulator.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

FilterOptions testOptions() {
  FilterOptions options;
  options.laser_pose = Pose2(0.1, 0.02, 0.05);
  options.tentative_max_age = 0;
  return options;
}

PointObservation observation(double range, double bearing) {
  PointObservation obs;
  obs.z = {range, bearing};
  obs.covariance << 0.01 * 0.01, 0.0, 0.0, 0.01 * 0.01;
  return obs;
}

// A filter with a few landmarks and correlated covariance, built by running
// real iterations (predict / augment / update) so that P has structure.
EkfSlam builtFilter() {
  EkfSlam filter(testOptions(), Pose2(0.5, -0.2, 0.3), Matrix3::Identity() * 0.01);
  EXPECT_EQ(filter.augment(observation(2.0, 0.4)), FilterStatus::kOk);
  EXPECT_EQ(filter.augment(observation(3.0, -0.7)), FilterStatus::kOk);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.3, 0.05, 0.1), 0.2), FilterStatus::kOk);
  EXPECT_EQ(filter.augment(observation(1.5, 1.2)), FilterStatus::kOk);
  EXPECT_EQ(filter.update({observation(1.75, 0.33)}, {{0, 0}}), FilterStatus::kOk);
  return filter;
}

MatrixXd denseCovariance(const EkfSlam& f) { return f.covariance(); }

TEST(EkfSlam, PredictEqualsTheFullJacobianProduct) {
  EkfSlam filter = builtFilter();
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = denseCovariance(filter);
  const Pose2 o1(1.0, 1.0, 0.2), o2 = compose(o1, Pose2(0.25, -0.03, 0.12));
  ASSERT_EQ(filter.predict(o1, o2, 0.1), FilterStatus::kOk);

  // Textbook eq. 2.62: P' = F_x P F_xᵀ + G Q Gᵀ with F_x = diag(F, I).
  const OdometryControl u = controlFromOdometry(o1, o2);
  Matrix3 F, G;
  applyControl(Pose2::fromVector(x0.head<3>()), u, &F, &G);
  MatrixXd Fx = MatrixXd::Identity(x0.size(), x0.size());
  Fx.topLeftCorner<3, 3>() = F;
  MatrixXd expected = Fx * P0 * Fx.transpose();
  expected.topLeftCorner<3, 3>() +=
      G * controlCovariance(u, testOptions().motion_noise) * G.transpose();
  EXPECT_LT((denseCovariance(filter) - expected).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(filter.state().tail(x0.size() - 3), x0.tail(x0.size() - 3));
}

TEST(EkfSlam, BatchUpdateEqualsTheTextbookUpdate) {
  EkfSlam filter = builtFilter();
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = denseCovariance(filter);
  const std::vector<PointObservation> obs = {observation(2.1, 0.35), observation(2.9, -0.68)};
  const std::vector<PointMatch> matches = {{0, 0}, {1, 1}};

  // Dense reference: stacked H, S = H P Hᵀ + R, K = P Hᵀ S⁻¹, P' = (I − K H) P.
  const int n = x0.size();
  MatrixXd H = MatrixXd::Zero(4, n);
  MatrixXd R = MatrixXd::Zero(4, 4);
  VectorXd nu(4);
  for (int i = 0; i < 2; ++i) {
    EkfSlam::Prediction p;
    ASSERT_TRUE(filter.predictObservation(i, &p));
    H.block<2, 3>(2 * i, 0) = p.H_robot;
    H.block<2, 2>(2 * i, filter.landmarkIndex(i)) = p.H_landmark;
    R.block<2, 2>(2 * i, 2 * i) = obs[i].covariance;
    nu(2 * i) = obs[i].z.range - p.z.range;
    nu(2 * i + 1) = wrapAngle(obs[i].z.bearing - p.z.bearing);
  }
  const MatrixXd S = H * P0 * H.transpose() + R;
  const MatrixXd K = P0 * H.transpose() * S.inverse();
  VectorXd x_expected = x0 + K * nu;
  const MatrixXd P_expected = (MatrixXd::Identity(n, n) - K * H) * P0;

  std::vector<double> nis;
  ASSERT_EQ(filter.update(obs, matches, &nis), FilterStatus::kOk);
  VectorXd dx = filter.state() - x_expected;
  dx(2) = wrapAngle(dx(2));
  EXPECT_LT(dx.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((denseCovariance(filter) - P_expected).cwiseAbs().maxCoeff(), 1e-12);
  const MatrixXd P1 = denseCovariance(filter);
  EXPECT_EQ(P1, P1.transpose()) << "P must be exactly symmetric";
  ASSERT_EQ(nis.size(), 2u);
  const Eigen::Vector2d nu0 = nu.head<2>();
  EXPECT_NEAR(nis[0], nu0.dot(S.topLeftCorner<2, 2>().inverse() * nu0), 1e-9);
}

TEST(EkfSlam, AugmentEqualsTheFullJacobianProduct) {
  EkfSlam filter = builtFilter();
  const MatrixXd P0 = denseCovariance(filter);
  const int n = P0.rows();
  const PointObservation obs = observation(2.5, -0.2);
  Matrix23 G_r;
  Matrix2 G_z;
  landmarkFromObservation(filter.pose(), testOptions().laser_pose, obs.z, &G_r, &G_z);
  int id = -1;
  ASSERT_EQ(filter.augment(obs, &id), FilterStatus::kOk);
  EXPECT_EQ(id, 3);

  // P_aug = J P Jᵀ + N R Nᵀ, J = [I; G_r 0], N = [0; G_z]  (eq. 2.82–2.83).
  MatrixXd J = MatrixXd::Zero(n + 2, n);
  J.topRows(n) = MatrixXd::Identity(n, n);
  J.block<2, 3>(n, 0) = G_r;
  MatrixXd N = MatrixXd::Zero(n + 2, 2);
  N.bottomRows<2>() = G_z;
  const MatrixXd expected = J * P0 * J.transpose() + N * obs.covariance * N.transpose();
  EXPECT_LT((denseCovariance(filter) - expected).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(filter.landmarkCount(), 4);
  EXPECT_EQ(filter.slotOf(id), 3);
}

TEST(EkfSlam, CovarianceStaysSymmetricPsdOverTenThousandSteps) {
  sim::LandmarkSimOptions sim_options;
  sim_options.laps = 1000;  // ends by the step limit below
  sim::LandmarkSimulator sim(sim_options);
  FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.tentative_max_age = 0;
  EkfSlam filter(options, sim.current().true_pose);
  std::vector<int> id_of_true(sim.landmarks().size(), -1);
  Pose2 odom = sim.current().odometry;
  double worst = 0.0;
  for (int step = 0; step < 10000; ++step) {
    ASSERT_TRUE(sim.next());
    const sim::SimStep& s = sim.current();
    ASSERT_EQ(filter.predict(odom, s.odometry, sim_options.dt), FilterStatus::kOk) << step;
    odom = s.odometry;
    std::vector<PointMatch> matches;
    std::vector<int> fresh;
    for (size_t i = 0; i < s.observations.size(); ++i) {
      const int id = id_of_true[s.true_landmark[i]];
      if (id >= 0) {
        matches.push_back({static_cast<int>(i), id});
      } else {
        fresh.push_back(static_cast<int>(i));
      }
    }
    ASSERT_EQ(filter.update(s.observations, matches), FilterStatus::kOk) << step;
    for (int i : fresh) {
      ASSERT_EQ(filter.augment(s.observations[i], &id_of_true[s.true_landmark[i]]),
                FilterStatus::kOk);
    }
    const MatrixXd P = filter.covariance();
    ASSERT_TRUE(P.isApprox(P.transpose(), 0.0)) << "asymmetric at step " << step;
    const Eigen::LDLT<MatrixXd> ldlt(P);
    const double scale = P.diagonal().maxCoeff();
    const double min_d = ldlt.vectorD().minCoeff();
    worst = std::min(worst, min_d / scale);
    ASSERT_GT(min_d, -1e-9 * scale) << "P lost positive semi-definiteness at step " << step;
  }
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(filter.covariance());
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-12);
  RecordProperty("worst_relative_ldlt_pivot", std::to_string(worst));
}

void expectUnchanged(const EkfSlam& filter, const VectorXd& x, const MatrixXd& P) {
  EXPECT_EQ(filter.state(), x);
  EXPECT_EQ(filter.covariance(), P);
}

TEST(EkfSlam, BadInputIsRejectedAndLeavesTheStateUnchanged) {
  EkfSlam filter = builtFilter();
  const VectorXd x = filter.state();
  const MatrixXd P = filter.covariance();
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  const long step = filter.step();

  EXPECT_EQ(filter.predict(Pose2(), Pose2(nan, 0, 0), 0.1), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(inf, 0, 0), 0.1), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.1, 0, 0), 0.0), FilterStatus::kBadTimeStep);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.1, 0, 0), -0.5), FilterStatus::kBadTimeStep);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.1, 0, 0), nan), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(5.0, 0, 0), 0.1), FilterStatus::kOdometryJump);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0, 0, 3.0), 0.1), FilterStatus::kOdometryJump);
  EXPECT_EQ(filter.step(), step);

  EXPECT_EQ(filter.update({observation(nan, 0.1)}, {{0, 0}}), FilterStatus::kNonFiniteInput);
  PointObservation singular = observation(2.0, 0.4);
  singular.covariance.setZero();
  EXPECT_EQ(filter.update({singular}, {{0, 0}}), FilterStatus::kSingularInnovation);
  singular.covariance << 1.0, 2.0, 2.0, 1.0;  // indefinite
  EXPECT_EQ(filter.update({singular}, {{0, 0}}), FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.update({observation(2.0, 0.4)}, {{0, 42}}), FilterStatus::kUnknownLandmark);
  EXPECT_EQ(filter.update({observation(2.0, 0.4)}, {{3, 0}}), FilterStatus::kBadObservation);
  EXPECT_EQ(filter.update({observation(2.0, 0.4), observation(2.0, 0.4)}, {{0, 0}, {1, 0}}),
            FilterStatus::kBadObservation)
      << "a landmark may be matched once per batch";
  EXPECT_EQ(filter.augment(observation(inf, 0.0)), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.augment(singular), FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.augment(observation(0.0, 0.0)), FilterStatus::kBadObservation);
  expectUnchanged(filter, x, P);
  EXPECT_EQ(filter.landmarkCount(), 3);
}

TEST(EkfSlam, TentativeLandmarksSeenOnceArePrunedOthersKept) {
  FilterOptions options = testOptions();
  options.tentative_max_age = 3;
  EkfSlam filter(options, Pose2(), Matrix3::Identity() * 1e-4);
  int clutter = -1, post = -1;
  ASSERT_EQ(filter.augment(observation(2.0, 0.5), &clutter), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(observation(3.0, -0.5), &post), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(observation(4.0, 0.0)), FilterStatus::kOk);
  for (int step = 0; step < 3; ++step) {
    ASSERT_EQ(filter.predict(Pose2(), Pose2(1e-3, 0, 0), 0.1), FilterStatus::kOk);
    if (step == 0) {
      EkfSlam::Prediction p;
      ASSERT_TRUE(filter.predictObservation(filter.slotOf(post), &p));
      PointObservation again = observation(p.z.range, p.z.bearing);
      ASSERT_EQ(filter.update({again}, {{0, post}}), FilterStatus::kOk);
    }
    if (step < 2) EXPECT_EQ(filter.pruneTentative(), 0);
  }
  EXPECT_EQ(filter.pruneTentative(), 2);  // the clutter and the third, each seen once
  EXPECT_EQ(filter.landmarkCount(), 1);
  EXPECT_EQ(filter.slotOf(clutter), -1);
  EXPECT_EQ(filter.slotOf(post), 0);
  EXPECT_EQ(filter.stateDim(), 5);
}

// Re-anchoring moves the robot and some landmarks rigidly; the covariance
// is the first-order image J P Jᵀ, with J the numerical Jacobian of the
// whole state map (landmark 2 is not listed and stays).
TEST(EkfSlam, ReanchorIsTheRigidMoveOfEachPieceWithItsJacobian) {
  EkfSlam filter = builtFilter();
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = denseCovariance(filter);
  const Pose2 robot_c(0.4, -0.3, 0.2), first_c(-1.0, 0.5, -0.6), second_c(0.2, 0.1, 3.0);
  const int first = filter.landmarks()[0].id, second = filter.landmarks()[1].id;
  const auto map = [&](const VectorXd& x) {
    VectorXd y = x;
    const Pose2 r = compose(robot_c, Pose2(x(0), x(1), x(2)));
    y.head<3>() = r.vector();
    y.segment<2>(3) = transformFrom(first_c, Vector2(x.segment<2>(3)));
    y.segment<2>(5) = transformFrom(second_c, Vector2(x.segment<2>(5)));
    return y;
  };
  filter.reanchor(robot_c, {{first, first_c}, {second, second_c}, {12345, Pose2(9, 9, 1)}});
  const VectorXd expected_x = map(x0);
  EXPECT_LT((filter.state().head<2>() - expected_x.head<2>()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(wrapAngle(filter.state()(2) - expected_x(2)), 0.0, 1e-12);
  EXPECT_LT(
      (filter.state().tail(x0.size() - 3) - expected_x.tail(x0.size() - 3)).cwiseAbs().maxCoeff(),
      1e-12);
  EXPECT_EQ(filter.state().segment<2>(7), x0.segment<2>(7));  // not listed: stays
  const MatrixXd J = testing::numericalJacobian(map, x0);
  const MatrixXd expected_P = J * P0 * J.transpose();
  EXPECT_LT((denseCovariance(filter) - expected_P).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(denseCovariance(filter), denseCovariance(filter).transpose());
}

TEST(EkfSlam, RemovingALandmarkKeepsTheOthersJointCovariance) {
  EkfSlam filter = builtFilter();
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  const int removed = filter.landmarks()[1].id;
  ASSERT_TRUE(filter.removeLandmark(removed));
  const std::vector<int> keep = {0, 1, 2, 3, 4, 7, 8};
  EXPECT_EQ(filter.covariance(), P(keep, keep));
  EXPECT_EQ(filter.state(), x(keep));
  EXPECT_FALSE(filter.removeLandmark(removed));
  EXPECT_EQ(filter.slotOf(filter.landmarks()[1].id), 1);
}

TEST(EkfSlam, RemovingTheNewestLandmarkNeedsNoCopyAndKeepsTheRest) {
  EkfSlam filter = builtFilter();
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  int id = -1;
  ASSERT_EQ(filter.augment(observation(2.5, -0.2), &id), FilterStatus::kOk);
  ASSERT_TRUE(filter.removeLandmark(id));
  EXPECT_EQ(filter.covariance(), P);
  EXPECT_EQ(filter.state(), x);
  EXPECT_EQ(filter.slotOf(id), -1);
  // And the state grows again from there.
  ASSERT_EQ(filter.augment(observation(2.5, -0.2), &id), FilterStatus::kOk);
  EXPECT_EQ(filter.slotOf(id), 3);
  EXPECT_EQ(filter.stateDim(), 11);
}

// The block accessors (what the predictions and data association read) agree
// with the whole covariance, in both orders of a pair.
void expectBlocksOfTheCovariance(const EkfSlam& filter) {
  const MatrixXd P = filter.covariance();
  EXPECT_EQ(filter.poseCovariance(), Matrix3(P.topLeftCorner<3, 3>()));
  for (int a = 0; a < filter.landmarkCount(); ++a) {
    const int ja = filter.landmarkIndex(a);
    EXPECT_EQ(filter.landmarkCovariance(a), Matrix2(P.block<2, 2>(ja, ja))) << a;
    EXPECT_EQ(filter.poseLandmarkCovariance(a), (Eigen::Matrix<double, 3, 2>(P.block<3, 2>(0, ja))))
        << a;
    for (int b = 0; b < filter.landmarkCount(); ++b) {
      const int jb = filter.landmarkIndex(b);
      EXPECT_EQ(filter.landmarkCrossCovariance(a, b), Matrix2(P.block<2, 2>(ja, jb)))
          << a << ", " << b;
    }
  }
}

// Updates `filter` with an observation of each landmark in `slots`, a little
// off its prediction, and checks the result against the dense textbook update
// (stacked H, K = P Hᵀ S⁻¹, P' = (I − K H) P) of the state it had before.
void expectTextbookUpdate(EkfSlam& filter, const std::vector<int>& slots) {
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();
  const int n = x0.size(), k = slots.size();
  MatrixXd H = MatrixXd::Zero(2 * k, n);
  MatrixXd R = MatrixXd::Zero(2 * k, 2 * k);
  VectorXd nu(2 * k);
  std::vector<PointObservation> obs;
  std::vector<PointMatch> matches;
  for (int i = 0; i < k; ++i) {
    EkfSlam::Prediction p;
    ASSERT_TRUE(filter.predictObservation(slots[i], &p));
    obs.push_back(observation(p.z.range + 0.01 * (i + 1), p.z.bearing - 0.004 * (i + 1)));
    matches.push_back({i, filter.landmarks()[slots[i]].id});
    H.block<2, 3>(2 * i, 0) = p.H_robot;
    H.block<2, 2>(2 * i, filter.landmarkIndex(slots[i])) = p.H_landmark;
    R.block<2, 2>(2 * i, 2 * i) = obs.back().covariance;
    nu(2 * i) = obs.back().z.range - p.z.range;
    nu(2 * i + 1) = wrapAngle(obs.back().z.bearing - p.z.bearing);
  }
  const MatrixXd K = P0 * H.transpose() * (H * P0 * H.transpose() + R).inverse();
  const VectorXd x_expected = x0 + K * nu;
  const MatrixXd P_expected = (MatrixXd::Identity(n, n) - K * H) * P0;
  ASSERT_EQ(filter.update(obs, matches), FilterStatus::kOk);
  VectorXd dx = filter.state() - x_expected;
  dx(2) = wrapAngle(dx(2));
  EXPECT_LT(dx.cwiseAbs().maxCoeff(), 1e-12);
  const MatrixXd P1 = filter.covariance();
  EXPECT_LT((P1 - P_expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(P1, P1.transpose()) << "P must be exactly symmetric";
  expectBlocksOfTheCovariance(filter);
}

// Pruning several landmarks at once (the first, two adjacent pairs, the
// newest) moves the remaining rows and columns down within the storage; the
// result must be exactly the rows and columns of the kept landmarks, and the
// filter must go on from there.
TEST(EkfSlam, PruningFromTheMiddleKeepsExactlyTheOtherRowsAndColumns) {
  FilterOptions options = testOptions();
  options.tentative_max_age = 2;
  EkfSlam filter(options, Pose2(0.5, -0.2, 0.3), Matrix3::Identity() * 0.01);
  for (int i = 0; i < 10; ++i) {
    ASSERT_EQ(filter.augment(observation(1.5 + 0.4 * i, -1.2 + 0.27 * i)), FilterStatus::kOk);
  }
  ASSERT_EQ(filter.predict(Pose2(), Pose2(0.2, 0.05, 0.1), 0.2), FilterStatus::kOk);
  const std::vector<int> seen = {1, 2, 5, 8};  // the others stay seen once
  std::vector<int> seen_ids;
  for (int slot : seen) seen_ids.push_back(filter.landmarks()[slot].id);
  expectTextbookUpdate(filter, seen);
  ASSERT_EQ(filter.predict(Pose2(), Pose2(0.2, 0.0, 0.05), 0.2), FilterStatus::kOk);
  const VectorXd x = filter.state();
  const MatrixXd P = filter.covariance();
  // Where the seen landmarks sit in the state before the pruning.
  std::vector<int> seen_index;
  for (int slot : seen) seen_index.push_back(filter.landmarkIndex(slot));

  EXPECT_EQ(filter.pruneTentative(), 6);  // slots 0, 3, 4, 6, 7, 9
  std::vector<int> keep = {0, 1, 2};
  for (int index : seen_index) {
    keep.push_back(index);
    keep.push_back(index + 1);
  }
  ASSERT_EQ(filter.stateDim(), static_cast<int>(keep.size()));
  EXPECT_EQ(filter.state(), x(keep));
  EXPECT_EQ(filter.covariance(), P(keep, keep));
  ASSERT_EQ(filter.landmarkCount(), 4);
  for (int s = 0; s < 4; ++s) {
    EXPECT_EQ(filter.landmarks()[s].id, seen_ids[s]);
    EXPECT_EQ(filter.slotOf(seen_ids[s]), s);
    const int j = seen_index[s];
    EXPECT_EQ(filter.landmarkCovariance(s), Matrix2(P.block<2, 2>(j, j)));
  }
  expectBlocksOfTheCovariance(filter);
  expectTextbookUpdate(filter, {1, 3});
  int id = -1;
  ASSERT_EQ(filter.augment(observation(2.2, 0.1), &id), FilterStatus::kOk);
  EXPECT_EQ(filter.slotOf(id), 4);
  expectTextbookUpdate(filter, {0, 2, 4});
}

// A corner seen a second time outside the new-landmark gate becomes a twin.
// Merging conditions the state on "the two are one point" — the textbook
// constrained update x − P Hᵀ(H P Hᵀ)⁻¹ H x, P − P Hᵀ(H P Hᵀ)⁻¹ H P with
// H = [.. I .. −I ..] — and then drops the twin's rows and columns.
TEST(EkfSlam, MergingTwinLandmarksIsTheConstrainedUpdate) {
  EkfSlam filter = builtFilter();
  int twin = -1;
  // Landmark 0 re-observed from the same pose: the twin sits next to it.
  ASSERT_EQ(filter.augment(observation(1.76, 0.335), &twin), FilterStatus::kOk);
  const int original = filter.landmarks()[0].id;
  const int observations = filter.landmarks()[0].observations;
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  const int n = filter.stateDim();
  MatrixXd H = MatrixXd::Zero(2, n);
  H.block<2, 2>(0, filter.landmarkIndex(0)).setIdentity();
  H.block<2, 2>(0, filter.landmarkIndex(filter.slotOf(twin))) = -Matrix2::Identity();
  const MatrixXd K = P * H.transpose() * (H * P * H.transpose()).inverse();
  VectorXd x_expected = x - K * (H * x);
  MatrixXd P_expected = P - K * H * P;

  ASSERT_EQ(filter.mergeLandmarks(original, twin, 9.21), FilterStatus::kOk);
  EXPECT_EQ(filter.slotOf(twin), -1);
  EXPECT_EQ(filter.stateDim(), n - 2);
  EXPECT_EQ(filter.landmarks()[0].observations, observations + 1);
  std::vector<int> keep;
  for (int i = 0; i < n - 2; ++i) keep.push_back(i);  // the twin was the newest
  EXPECT_LT((filter.state() - x_expected(keep)).norm(), 1e-12);
  EXPECT_LT((filter.covariance() - P_expected(keep, keep)).norm(), 1e-12);
  // The merged landmark is known at least as well as either was.
  const Matrix2 before = P.block<2, 2>(3, 3), after = filter.landmarkCovariance(0);
  EXPECT_GE((before - after).eigenvalues().real().minCoeff(), -1e-15);
}

// A twin with newer landmarks after it: the merge drops rows and columns from
// the middle of the state.
TEST(EkfSlam, MergingATwinFromTheMiddleIsTheConstrainedUpdateWithoutIt) {
  EkfSlam filter = builtFilter();
  int twin = -1;
  ASSERT_EQ(filter.augment(observation(1.76, 0.335), &twin), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(observation(2.6, -1.1)), FilterStatus::kOk);
  ASSERT_EQ(filter.augment(observation(3.4, 0.9)), FilterStatus::kOk);
  const int t = filter.slotOf(twin);
  ASSERT_EQ(t, 3);
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  const int n = filter.stateDim();
  MatrixXd H = MatrixXd::Zero(2, n);
  H.block<2, 2>(0, filter.landmarkIndex(0)).setIdentity();
  H.block<2, 2>(0, filter.landmarkIndex(t)) = -Matrix2::Identity();
  const MatrixXd K = P * H.transpose() * (H * P * H.transpose()).inverse();
  const VectorXd x_expected = x - K * (H * x);
  const MatrixXd P_expected = P - K * H * P;
  const int after_id = filter.landmarks()[t + 1].id;

  ASSERT_EQ(filter.mergeLandmarks(filter.landmarks()[0].id, twin, 9.21), FilterStatus::kOk);
  std::vector<int> keep;
  for (int i = 0; i < n; ++i) {
    if (i != filter.landmarkIndex(t) && i != filter.landmarkIndex(t) + 1) keep.push_back(i);
  }
  ASSERT_EQ(filter.stateDim(), n - 2);
  EXPECT_EQ(filter.slotOf(twin), -1);
  EXPECT_EQ(filter.slotOf(after_id), t);
  EXPECT_LT((filter.state() - x_expected(keep)).cwiseAbs().maxCoeff(), 1e-12);
  const MatrixXd P1 = filter.covariance();
  EXPECT_LT((P1 - P_expected(keep, keep)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(P1, P1.transpose()) << "P must be exactly symmetric";
  expectBlocksOfTheCovariance(filter);
  expectTextbookUpdate(filter, {1, 3, 4});
}

TEST(EkfSlam, DistinctLandmarksAreNotMergedAndNothingChanges) {
  EkfSlam filter = builtFilter();
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  const int a = filter.landmarks()[0].id, b = filter.landmarks()[1].id;
  EXPECT_EQ(filter.mergeLandmarks(a, b, 9.21), FilterStatus::kBadObservation);
  EXPECT_EQ(filter.mergeLandmarks(a, 12345, 9.21), FilterStatus::kUnknownLandmark);
  EXPECT_EQ(filter.mergeLandmarks(a, a, 9.21), FilterStatus::kUnknownLandmark);
  EXPECT_TRUE(filter.mergeDuplicates({a, b}, 9.21, 10.0).empty());
  EXPECT_EQ(filter.covariance(), P);
  EXPECT_EQ(filter.state(), x);
}

// With a bias allowance b the merge is the constrained update with R = b²I.
TEST(EkfSlam, MergingWithABiasAllowanceIsTheUpdateWithThatNoise) {
  EkfSlam filter = builtFilter();
  int twin = -1;
  ASSERT_EQ(filter.augment(observation(1.8, 0.32), &twin), FilterStatus::kOk);
  const MatrixXd P = filter.covariance();
  const VectorXd x = filter.state();
  const int n = filter.stateDim();
  MatrixXd H = MatrixXd::Zero(2, n);
  H.block<2, 2>(0, filter.landmarkIndex(0)).setIdentity();
  H.block<2, 2>(0, filter.landmarkIndex(filter.slotOf(twin))) = -Matrix2::Identity();
  const double b = 0.03;
  const MatrixXd S = H * P * H.transpose() + b * b * MatrixXd::Identity(2, 2);
  const MatrixXd K = P * H.transpose() * S.inverse();
  const VectorXd x_expected = x - K * (H * x);
  const MatrixXd P_expected = P - K * S * K.transpose();
  ASSERT_EQ(filter.mergeLandmarks(filter.landmarks()[0].id, twin, 9.21, b), FilterStatus::kOk);
  std::vector<int> keep;
  for (int i = 0; i < n - 2; ++i) keep.push_back(i);
  EXPECT_LT((filter.state() - x_expected(keep)).norm(), 1e-12);
  EXPECT_LT((filter.covariance() - P_expected(keep, keep)).norm(), 1e-12);
}

TEST(EkfSlam, MergeDuplicatesKeepsTheOlderLandmark) {
  EkfSlam filter = builtFilter();
  int twin = -1;
  ASSERT_EQ(filter.augment(observation(1.76, 0.335), &twin), FilterStatus::kOk);
  const int count = filter.landmarkCount();
  // Too far apart for max_distance: not even tested.
  EXPECT_TRUE(filter.mergeDuplicates({twin}, 9.21, 0.001).empty());
  const auto merged = filter.mergeDuplicates({twin}, 9.21, 0.5);
  ASSERT_EQ(merged.size(), 1u);
  EXPECT_EQ(merged[0].first, filter.landmarks()[0].id);
  EXPECT_EQ(merged[0].second, twin);
  EXPECT_EQ(filter.landmarkCount(), count - 1);
}

// First-estimates Jacobians: F's heading column from the predicted positions
// of consecutive steps, H at the landmark's first estimate; the predicted
// measurement itself still from the newest estimate.
TEST(EkfSlam, FirstEstimatesJacobiansUseThePriorPositionsAndFirstLandmarkEstimates) {
  FilterOptions options = testOptions();
  options.first_estimate_jacobians = true;
  EkfSlam filter(options, Pose2(0.5, -0.2, 0.3), Matrix3::Identity() * 0.01);
  int id = -1;
  ASSERT_EQ(filter.augment(observation(2.0, 0.4), &id), FilterStatus::kOk);
  const Vector2 first = filter.landmarkPosition(0);
  ASSERT_EQ(filter.predict(Pose2(), Pose2(0.3, 0.05, 0.1), 0.2), FilterStatus::kOk);
  const Pose2 predicted1 = filter.pose();
  ASSERT_EQ(filter.update({observation(1.8, 0.35)}, {{0, id}}), FilterStatus::kOk);
  const Pose2 corrected1 = filter.pose();
  ASSERT_GT((corrected1.translation() - predicted1.translation()).norm(), 1e-4);
  ASSERT_GT((filter.landmarkPosition(0) - first).norm(), 1e-4);
  ASSERT_EQ(filter.predict(Pose2(0.3, 0.05, 0.1), Pose2(0.6, 0.1, 0.2), 0.2), FilterStatus::kOk);
  const Pose2 predicted2 = filter.pose();
  const Matrix3& F = filter.lastMotionJacobian();
  EXPECT_NEAR(F(0, 2), -(predicted2.y - predicted1.y), 1e-12);
  EXPECT_NEAR(F(1, 2), predicted2.x - predicted1.x, 1e-12);
  EXPECT_GT(std::abs(F(0, 2) + (predicted2.y - corrected1.y)), 1e-6);  // not the textbook one

  EkfSlam::Prediction p;
  ASSERT_TRUE(filter.predictObservation(0, &p));
  RangeBearing z_newest, z_first;
  Matrix23 Hr;
  Matrix2 Hm;
  ASSERT_TRUE(predictPointObservation(filter.pose(), options.laser_pose, filter.landmarkPosition(0),
                                      &z_newest));
  ASSERT_TRUE(
      predictPointObservation(filter.pose(), options.laser_pose, first, &z_first, &Hr, &Hm));
  EXPECT_EQ(p.z.range, z_newest.range);
  EXPECT_EQ(p.z.bearing, z_newest.bearing);
  EXPECT_TRUE(p.H_robot.isApprox(Hr, 1e-14));
  EXPECT_TRUE(p.H_landmark.isApprox(Hm, 1e-14));
}

// The filter's state is a value: a snapshot restored into another filter
// (with line landmarks, after removals, so that the storage has spare
// capacity and moved entries) continues bit for bit as the original does.
TEST(EkfSlam, ARestoredSnapshotContinuesExactly) {
  EkfSlam original = builtFilter();
  LineObservation wall;
  wall.z = PolarLine{2.0, 0.3};
  wall.covariance << 1e-4, 0.0, 0.0, 1e-4;
  int line_id = -1;
  ASSERT_EQ(original.augmentLine(wall, LandmarkKind::kLine, &line_id), FilterStatus::kOk);
  ASSERT_EQ(original.augment(observation(2.5, -0.2)), FilterStatus::kOk);
  ASSERT_TRUE(original.removeLandmark(1));
  const FilterState snapshot = original.filterState();

  auto continueFrom = [&](EkfSlam* filter) {
    ASSERT_EQ(filter->predict(Pose2(), Pose2(0.2, -0.03, 0.05), 0.2), FilterStatus::kOk);
    ASSERT_EQ(filter->update({observation(1.7, 0.3)}, {{0, 0}}), FilterStatus::kOk);
    LineObservation seen = wall;
    seen.z = PolarLine{1.85, 0.26};
    ASSERT_EQ(filter->updateLines({seen}, {{0, line_id}}), FilterStatus::kOk);
    ASSERT_EQ(filter->augment(observation(2.2, 0.9)), FilterStatus::kOk);
  };
  continueFrom(&original);
  EkfSlam restored(testOptions());
  restored.restore(snapshot);
  continueFrom(&restored);
  ASSERT_EQ(restored.stateDim(), original.stateDim());
  EXPECT_EQ(restored.state(), original.state());
  EXPECT_EQ(restored.covariance(), original.covariance());
  ASSERT_EQ(restored.landmarkCount(), original.landmarkCount());
  for (int slot = 0; slot < original.landmarkCount(); ++slot) {
    EXPECT_EQ(restored.landmarks()[slot].id, original.landmarks()[slot].id);
    EXPECT_EQ(restored.landmarks()[slot].observations, original.landmarks()[slot].observations);
  }
  EXPECT_EQ(restored.step(), original.step());
}

TEST(EkfSlam, OptionsValidationNamesTheField) {
  FilterOptions options;
  EXPECT_EQ(options.validate(), "");
  options.max_step_translation = 0.0;
  EXPECT_NE(options.validate().find("max_step_translation"), std::string::npos);
  options = FilterOptions();
  options.motion_noise.rot_per_rot = std::nan("");
  EXPECT_NE(options.validate().find("rot_per_rot"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
