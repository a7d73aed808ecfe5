// Line landmarks in the filter: the batch update against the dense EKF
// equations, the state kept in normal form, removal and re-anchoring with
// landmarks of every kind, and Monte Carlo NEES on the landmark simulator in
// a walled room, for (p, θ) lines and for θ-only lines with and without
// endpoint points.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <random>

#include "ekf_slam_core/filter/ekf_slam.h"
#include "ekf_slam_core/sim/landmark_simulator.h"
#include "ekf_slam_core/testing/monte_carlo_nees.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The walls around the simulator's default loop (a 10 m × 6 m rectangle)
// as map-frame normal forms, and their corners: wall i runs from corner i
// to corner i + 1.
const std::vector<PolarLine>& roomWalls() {
  static const std::vector<PolarLine> walls = {
      {3.0, -0.5 * kPi}, {13.0, 0.0}, {9.0, 0.5 * kPi}, {3.0, -kPi}};
  return walls;
}
const std::vector<Vector2>& roomCorners() {
  static const std::vector<Vector2> corners = {{-3, -3}, {13, -3}, {13, 9}, {-3, 9}};
  return corners;
}

Matrix2 lineNoise() {
  Matrix2 r = Matrix2::Zero();
  r(0, 0) = 0.02 * 0.02;
  r(1, 1) = 0.01 * 0.01;
  return r;
}

LineObservation noisyWall(const Pose2& truth, const Pose2& laser, const PolarLine& wall,
                          std::mt19937* rng) {
  PolarLine z;
  EXPECT_TRUE(predictLineObservation(truth, laser, wall, &z));
  std::normal_distribution<double> unit;
  LineObservation obs;
  obs.covariance = lineNoise();
  obs.z.p = z.p + 0.02 * unit(*rng);
  obs.z.theta = wrapAngle(z.theta + 0.01 * unit(*rng));
  return obs;
}

bool isSymmetricPositiveDefinite(const MatrixXd& P) {
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-12) return false;
  return Eigen::SelfAdjointEigenSolver<MatrixXd>(P).eigenvalues().minCoeff() > 0.0;
}

FilterOptions optionsFor(const sim::LandmarkSimOptions& sim_options) {
  FilterOptions options;
  options.laser_pose = sim_options.laser_pose;
  options.motion_noise = sim_options.odometry_noise;
  options.tentative_max_age = 0;
  return options;
}

// A filter holding points, one (p, θ) wall, one θ-only wall, with the
// robot moved so that everything is correlated.
struct MixedMap {
  EkfSlam filter;
  int line_id = -1, angle_id = -1;
  std::vector<int> corner_ids;
};

MixedMap mixedMap() {
  sim::LandmarkSimOptions sim_options;
  MixedMap map{EkfSlam(optionsFor(sim_options), Pose2(0.0, 0.0, 0.0), Matrix3::Identity() * 1e-4),
               -1,
               -1,
               {}};
  EkfSlam& filter = map.filter;
  const Pose2& laser = sim_options.laser_pose;
  std::mt19937 rng(7);
  // Corners 0 and 1 (the ends of wall 0) as points.
  for (int c = 0; c < 2; ++c) {
    const Vector2 d = transformTo(compose(filter.pose(), laser), roomCorners()[c]);
    PointObservation obs;
    obs.z = RangeBearing{d.norm(), std::atan2(d.y(), d.x())};
    obs.covariance = Matrix2(Eigen::Vector2d(4e-4, 1e-4).asDiagonal());
    int id = -1;
    EXPECT_EQ(filter.augment(obs, &id), FilterStatus::kOk);
    map.corner_ids.push_back(id);
  }
  EXPECT_EQ(filter.augmentLine(noisyWall(filter.pose(), laser, roomWalls()[1], &rng),
                               LandmarkKind::kLine, &map.line_id),
            FilterStatus::kOk);
  EXPECT_EQ(filter.augmentLine(noisyWall(filter.pose(), laser, roomWalls()[0], &rng),
                               LandmarkKind::kLineAngle, &map.angle_id),
            FilterStatus::kOk);
  EXPECT_EQ(filter.predict(Pose2(), Pose2(0.3, 0.05, 0.1), 0.2), FilterStatus::kOk);
  return map;
}

TEST(LineLandmarks, AugmentedLinesHoldTheirKindsIndicesAndAValidCovariance) {
  MixedMap map = mixedMap();
  const EkfSlam& filter = map.filter;
  ASSERT_EQ(filter.landmarkCount(), 4);
  EXPECT_EQ(filter.stateDim(), 3 + 2 + 2 + 2 + 1);
  const int line = filter.slotOf(map.line_id), angle = filter.slotOf(map.angle_id);
  EXPECT_EQ(filter.landmarkKind(line), LandmarkKind::kLine);
  EXPECT_EQ(filter.landmarkKind(angle), LandmarkKind::kLineAngle);
  EXPECT_EQ(filter.landmarkIndex(angle), 9);
  EXPECT_NEAR(filter.lineLandmark(line).p, 13.0, 0.1);
  EXPECT_NEAR(filter.lineLandmark(line).theta, 0.0, 0.05);
  EXPECT_NEAR(std::abs(wrapAngle(filter.lineAngle(angle) + 0.5 * kPi)), 0.0, 0.05);
  EXPECT_TRUE(isSymmetricPositiveDefinite(filter.covariance()));
  // Points only where points belong.
  EkfSlam::Prediction unused;
  EXPECT_FALSE(filter.predictObservation(line, &unused));
}

// The whole update (kLine, and kLineAngle with one and with two endpoints in
// one batch) against x + K ν, (I − K H) P with H stacked from the models.
TEST(LineLandmarks, BatchUpdateEqualsTheDenseEkfEquations) {
  sim::LandmarkSimOptions sim_options;
  const Pose2& laser = sim_options.laser_pose;
  for (int endpoints = 0; endpoints <= 2; ++endpoints) {
    MixedMap map = mixedMap();
    EkfSlam& filter = map.filter;
    const VectorXd x0 = filter.state();
    const MatrixXd P0 = filter.covariance();
    const int n = static_cast<int>(x0.size());
    std::mt19937 rng(11);
    const Pose2 truth(0.31, 0.04, 0.11);
    const std::vector<LineObservation> obs = {noisyWall(truth, laser, roomWalls()[1], &rng),
                                              noisyWall(truth, laser, roomWalls()[0], &rng)};
    LineMatch angle_match{1, map.angle_id};
    for (int e = 0; e < endpoints; ++e) angle_match.endpoint_ids[e] = map.corner_ids[e];
    const std::vector<LineMatch> matches = {{0, map.line_id}, angle_match};

    const int rows = endpoints == 0 ? 3 : 4;
    MatrixXd H = MatrixXd::Zero(rows, n);
    MatrixXd R = MatrixXd::Zero(rows, rows);
    VectorXd nu(rows);
    const int line = filter.slotOf(map.line_id), angle = filter.slotOf(map.angle_id);
    {
      PolarLine z_hat;
      Matrix23 Hr;
      Matrix2 Hl, J;
      Vector2 v;
      ASSERT_TRUE(predictLineObservation(filter.pose(), laser, filter.lineLandmark(line), &z_hat,
                                         &Hr, &Hl));
      ASSERT_TRUE(lineInnovation(obs[0].z, z_hat, &v, &J));
      H.block<2, 3>(0, 0) = -J * Hr;
      H.block<2, 2>(0, filter.landmarkIndex(line)) = -J * Hl;
      R.block<2, 2>(0, 0) = obs[0].covariance;
      nu.head<2>() = v;
    }
    const int a = filter.landmarkIndex(angle);
    const Vector2 m1 = filter.landmarkPosition(filter.slotOf(map.corner_ids[0]));
    const Vector2 m2 = filter.landmarkPosition(filter.slotOf(map.corner_ids[1]));
    const int i1 = filter.landmarkIndex(filter.slotOf(map.corner_ids[0]));
    const int i2 = filter.landmarkIndex(filter.slotOf(map.corner_ids[1]));
    if (endpoints == 0) {
      double theta = 0.0, H_angle = 0.0;
      RowVector3 Hr;
      ASSERT_TRUE(
          predictLineAngle(filter.pose(), laser, filter.lineAngle(angle), &theta, &Hr, &H_angle));
      H.block<1, 3>(2, 0) = Hr;
      H(2, a) = H_angle;
      R(2, 2) = obs[1].covariance(1, 1);
      nu(2) = lineAngleDifference(obs[1].z.theta, theta);
    } else {
      PolarLine z_hat;
      Matrix23 Hr;
      Matrix2 H1, H2 = Matrix2::Zero(), J;
      Vector2 Ha, v;
      if (endpoints == 1) {
        ASSERT_TRUE(predictLineFromAngleAndPoint(filter.pose(), laser, filter.lineAngle(angle), m1,
                                                 &z_hat, &Hr, &H1, &Ha));
      } else {
        ASSERT_TRUE(predictLineFromAngleAndEndpoints(filter.pose(), laser, filter.lineAngle(angle),
                                                     m1, m2, &z_hat, &Hr, &H1, &H2, &Ha));
      }
      ASSERT_TRUE(lineInnovation(obs[1].z, z_hat, &v, &J));
      H.block<2, 3>(2, 0) = -J * Hr;
      H.block<2, 1>(2, a) = -J * Ha;
      H.block<2, 2>(2, i1) = -J * H1;
      if (endpoints == 2) H.block<2, 2>(2, i2) = -J * H2;
      R.block<2, 2>(2, 2) = obs[1].covariance;
      nu.tail<2>() = v;
    }
    const MatrixXd S = H * P0 * H.transpose() + R;
    const MatrixXd K = P0 * H.transpose() * S.inverse();
    const VectorXd x_expected = x0 + K * nu;
    const MatrixXd P_expected = (MatrixXd::Identity(n, n) - K * H) * P0;

    // What association sees of each match is the update's linearisation.
    for (int i = 0; i < 2; ++i) {
      VectorXd innovation;
      MatrixXd S_i;
      ASSERT_EQ(filter.predictLineMatch(obs[i], matches[i], &innovation, &S_i), FilterStatus::kOk);
      const int r = i == 1 && endpoints == 0 ? 1 : 2;
      ASSERT_EQ(innovation.size(), r);
      EXPECT_LT((innovation - nu.segment(2 * i, r)).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((S_i - S.block(2 * i, 2 * i, r, r)).cwiseAbs().maxCoeff(), 1e-12);
    }
    std::vector<double> nis;
    ASSERT_EQ(filter.updateLines(obs, matches, &nis), FilterStatus::kOk) << endpoints;
    VectorXd dx = filter.state() - x_expected;
    for (int i : {2, a, filter.landmarkIndex(line) + 1}) dx(i) = wrapAngle(dx(i));
    EXPECT_LT(dx.cwiseAbs().maxCoeff(), 1e-10) << "endpoints " << endpoints;
    EXPECT_LT((filter.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-12)
        << "endpoints " << endpoints;
    ASSERT_EQ(nis.size(), 2u);
    EXPECT_NEAR(nis[0], nu.head<2>().dot(S.topLeftCorner(2, 2).ldlt().solve(nu.head<2>())), 1e-9);
    EXPECT_TRUE(isSymmetricPositiveDefinite(filter.covariance()));
  }
}

// With first-estimates Jacobians a line's H is taken at the landmark's
// estimate when it was created, its innovation at the current one.
TEST(LineLandmarks, FirstEstimateJacobiansLineariseLinesAtTheirFirstEstimate) {
  sim::LandmarkSimOptions sim_options;
  const Pose2& laser = sim_options.laser_pose;
  FilterOptions options = optionsFor(sim_options);
  options.first_estimate_jacobians = true;
  EkfSlam filter(options, Pose2(), Matrix3::Identity() * 1e-3);
  std::mt19937 rng(5);
  int id = -1;
  ASSERT_EQ(
      filter.augmentLine(noisyWall(Pose2(), laser, roomWalls()[1], &rng), LandmarkKind::kLine, &id),
      FilterStatus::kOk);
  const Vector2 first = filter.landmarks()[filter.slotOf(id)].first_estimate;
  const Pose2 truth(0.3, 0.05, 0.1);
  ASSERT_EQ(filter.predict(Pose2(), truth, 0.2), FilterStatus::kOk);
  const std::vector<LineObservation> obs = {noisyWall(truth, laser, roomWalls()[1], &rng)};
  ASSERT_EQ(filter.updateLines(obs, {{0, id}}), FilterStatus::kOk);
  const int slot = filter.slotOf(id);
  ASSERT_GT((filter.lineLandmark(slot).vector() - first).norm(), 1e-4);  // it has moved
  EXPECT_EQ(filter.landmarks()[slot].first_estimate, first);

  const Pose2 next(0.6, 0.1, 0.2);
  ASSERT_EQ(filter.predict(truth, next, 0.2), FilterStatus::kOk);
  const LineObservation seen = noisyWall(next, laser, roomWalls()[1], &rng);
  VectorXd innovation;
  MatrixXd S;
  ASSERT_EQ(filter.predictLineMatch(seen, {0, id}, &innovation, &S), FilterStatus::kOk);
  PolarLine z_now, z_first;
  Matrix23 Hr;
  Matrix2 Hl, J;
  Vector2 nu;
  ASSERT_TRUE(predictLineObservation(filter.pose(), laser, filter.lineLandmark(slot), &z_now));
  ASSERT_TRUE(lineInnovation(seen.z, z_now, &nu, &J));
  ASSERT_TRUE(predictLineObservation(filter.pose(), laser, PolarLine{first(0), first(1)}, &z_first,
                                     &Hr, &Hl));
  const int n = filter.stateDim();
  MatrixXd H = MatrixXd::Zero(2, n);
  H.leftCols<3>() = -J * Hr;
  H.block<2, 2>(0, filter.landmarkIndex(slot)) = -J * Hl;
  const MatrixXd S_expected = H * filter.covariance() * H.transpose() + seen.covariance;
  EXPECT_LT((innovation - nu).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((S - S_expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(LineLandmarks, BadMatchesAreRefusedAndTheStateIsUnchanged) {
  MixedMap map = mixedMap();
  EkfSlam& filter = map.filter;
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();
  std::mt19937 rng(3);
  sim::LandmarkSimOptions sim_options;
  LineObservation good = noisyWall(filter.pose(), sim_options.laser_pose, roomWalls()[1], &rng);
  LineObservation nan = good;
  nan.z.p = std::numeric_limits<double>::quiet_NaN();
  LineObservation singular = good;
  singular.covariance = Matrix2::Zero();
  LineObservation infinite = good;
  infinite.covariance(0, 0) = std::numeric_limits<double>::infinity();
  const std::vector<LineObservation> obs = {good, nan, singular, infinite};
  EXPECT_EQ(filter.updateLines(obs, {{1, map.line_id}}), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.updateLines(obs, {{2, map.line_id}}), FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.updateLines(obs, {{3, map.line_id}}), FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.updateLines(obs, {{0, map.corner_ids[0]}}), FilterStatus::kBadObservation)
      << "a point is not a line";
  EXPECT_EQ(filter.updateLines(obs, {{0, 999}}), FilterStatus::kUnknownLandmark);
  EXPECT_EQ(filter.updateLines(obs, {{0, map.line_id}, {0, map.line_id}}),
            FilterStatus::kBadObservation)
      << "one match per line";
  LineMatch to_a_line{0, map.angle_id};
  to_a_line.endpoint_ids[0] = map.line_id;
  EXPECT_EQ(filter.updateLines(obs, {to_a_line}), FilterStatus::kBadObservation)
      << "endpoints are points";
  EXPECT_EQ(filter.augmentLine(nan, LandmarkKind::kLine), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.augmentLine(singular, LandmarkKind::kLineAngle),
            FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.augmentLine(good, LandmarkKind::kPoint), FilterStatus::kBadObservation);
  EXPECT_EQ(filter.mergeLandmarks(map.line_id, map.corner_ids[0], 1e9),
            FilterStatus::kBadObservation);
  EXPECT_EQ(filter.state(), x0);
  EXPECT_EQ(filter.covariance(), P0);
  EXPECT_EQ(filter.landmarkCount(), 4);
}

// Removing landmarks of mixed sizes from the middle keeps exactly the
// remaining rows and columns; re-anchoring moves lines as rigid bodies.
TEST(LineLandmarks, RemovalAndReanchoringHandleEveryKind) {
  MixedMap map = mixedMap();
  EkfSlam& filter = map.filter;
  std::mt19937 rng(5);
  sim::LandmarkSimOptions sim_options;
  int second_angle = -1;
  ASSERT_EQ(
      filter.augmentLine(noisyWall(filter.pose(), sim_options.laser_pose, roomWalls()[2], &rng),
                         LandmarkKind::kLineAngle, &second_angle),
      FilterStatus::kOk);
  const VectorXd x0 = filter.state();
  const MatrixXd P0 = filter.covariance();
  // Keep: pose, corner 0, the θ-only wall 0, the second θ-only wall.
  std::vector<int> keep = {0, 1, 2, 3, 4, 9, 10};
  ASSERT_EQ(filter.removeLandmarks({map.corner_ids[1], map.line_id}), 2);
  ASSERT_EQ(filter.stateDim(), static_cast<int>(keep.size()));
  for (size_t r = 0; r < keep.size(); ++r) {
    EXPECT_EQ(filter.state()(r), x0(keep[r]));
    for (size_t c = 0; c < keep.size(); ++c) {
      EXPECT_EQ(filter.covariance()(r, c), P0(keep[r], keep[c])) << r << ", " << c;
    }
  }
  EXPECT_EQ(filter.landmarkIndex(filter.slotOf(second_angle)), 6);

  // Re-anchoring a (p, θ) line: the same line as the rigidly moved points.
  MixedMap moved = mixedMap();
  const int line = moved.filter.slotOf(moved.line_id);
  const PolarLine before = moved.filter.lineLandmark(line);
  const MatrixXd P_before = moved.filter.covariance();
  const double angle_before = moved.filter.lineAngle(moved.filter.slotOf(moved.angle_id));
  const Pose2 correction(-20.0, 1.5, 0.4);  // moves the origin across the line: p changes sign
  moved.filter.reanchor(Pose2(), {{moved.line_id, correction}, {moved.angle_id, correction}});
  const PolarLine after = moved.filter.lineLandmark(line);
  EXPECT_GE(after.p, 0.0);
  for (double t : {-3.0, 0.0, 4.0}) {
    const Vector2 n(std::cos(before.theta), std::sin(before.theta));
    const Vector2 on_line = before.p * n + t * Vector2(-n.y(), n.x());
    const Vector2 q = transformFrom(correction, on_line);
    EXPECT_NEAR(q.dot(Vector2(std::cos(after.theta), std::sin(after.theta))), after.p, 1e-9);
  }
  EXPECT_NEAR(
      wrapAngle(moved.filter.lineAngle(moved.filter.slotOf(moved.angle_id)) - angle_before - 0.4),
      0.0, 1e-12);
  // The line's covariance moves with the central-difference Jacobian of
  // the moved normal form; the direction's rows do not change.
  auto movedLine = [&](const Eigen::VectorXd& v) {
    const double theta = v(1) + correction.theta;
    const double p = v(0) + Vector2(std::cos(theta), std::sin(theta)).dot(correction.translation());
    return Eigen::VectorXd(p < 0.0 ? Vector2(-p, wrapAngle(theta + kPi)) : Vector2(p, theta));
  };
  Eigen::Matrix2d J;
  constexpr double h = 1e-6;
  for (int c = 0; c < 2; ++c) {
    Eigen::VectorXd plus = before.vector(), minus = before.vector();
    plus(c) += h;
    minus(c) -= h;
    Eigen::VectorXd d = movedLine(plus) - movedLine(minus);
    d(1) = wrapAngle(d(1));
    J.col(c) = d / (2.0 * h);
  }
  const int l = moved.filter.landmarkIndex(line);
  const MatrixXd P_after = moved.filter.covariance();
  EXPECT_LT((P_after.block<2, 2>(l, l) - J * P_before.block<2, 2>(l, l) * J.transpose())
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  EXPECT_LT((P_after.block<2, 3>(l, 0) - J * P_before.block<2, 3>(l, 0)).cwiseAbs().maxCoeff(),
            1e-9);
  const int d = moved.filter.landmarkIndex(moved.filter.slotOf(moved.angle_id));
  EXPECT_NEAR(P_after(d, d), P_before(d, d), 1e-15);
  EXPECT_TRUE(isSymmetricPositiveDefinite(moved.filter.covariance()));
}

// Line landmarks from a prior map (a saved one): kept as given, in normal
// form, with no correlation to the pose or the other landmarks, and
// corrected by the observations that follow.
TEST(LineLandmarks, PriorLinesKeepTheirIdsMeansAndCovariancesUncorrelated) {
  sim::LandmarkSimOptions sim_options;
  EkfSlam filter(optionsFor(sim_options), Pose2(1.0, 0.5, 0.2), Matrix3::Identity() * 1e-3);
  Matrix2 line_covariance;
  line_covariance << 4e-4, 1e-5, 1e-5, 1e-4;
  ASSERT_EQ(filter.addLandmark(4, Vector2(2.0, 1.0), Matrix2::Identity() * 1e-3),
            FilterStatus::kOk);
  ASSERT_EQ(filter.addLineLandmark(7, PolarLine{13.0, 0.0}, line_covariance, 5), FilterStatus::kOk);
  ASSERT_EQ(filter.addLineAngleLandmark(9, 0.5 * kPi, 2e-4, 3), FilterStatus::kOk);
  ASSERT_EQ(filter.stateDim(), 3 + 2 + 2 + 1);
  const int line = filter.slotOf(7), angle = filter.slotOf(9);
  EXPECT_EQ(filter.landmarkKind(line), LandmarkKind::kLine);
  EXPECT_EQ(filter.landmarkKind(angle), LandmarkKind::kLineAngle);
  EXPECT_EQ(filter.lineLandmark(line).p, 13.0);
  EXPECT_EQ(filter.lineLandmark(line).theta, 0.0);
  EXPECT_EQ(filter.landmarkCovariance(line), line_covariance);
  EXPECT_EQ(filter.lineAngle(angle), 0.5 * kPi);
  EXPECT_EQ(filter.lineAngleVariance(angle), 2e-4);
  EXPECT_EQ(filter.landmarks()[line].observations, 5);
  EXPECT_EQ(filter.landmarks()[angle].observations, 3);
  const MatrixXd P = filter.covariance();
  const int l = filter.landmarkIndex(line), a = filter.landmarkIndex(angle);
  EXPECT_EQ(P.block(l, 0, 2, l).norm(), 0.0);  // the pose and the point
  EXPECT_EQ(P.block(a, 0, 1, a).norm(), 0.0);  // the pose, the point and the line
  EXPECT_TRUE(isSymmetricPositiveDefinite(P));

  // p < 0 is the same line in normal form: (−p, θ + π), the p–θ covariance negated.
  ASSERT_EQ(filter.addLineLandmark(11, PolarLine{-2.0, 0.3}, line_covariance), FilterStatus::kOk);
  const PolarLine flipped = filter.lineLandmark(filter.slotOf(11));
  EXPECT_EQ(flipped.p, 2.0);
  EXPECT_NEAR(flipped.theta, 0.3 - kPi, 1e-15);
  Matrix2 flipped_covariance = line_covariance;
  flipped_covariance(0, 1) = flipped_covariance(1, 0) = -line_covariance(0, 1);
  EXPECT_EQ(filter.landmarkCovariance(filter.slotOf(11)), flipped_covariance);
  ASSERT_EQ(filter.addLineAngleLandmark(12, 4.0, 1e-4), FilterStatus::kOk);
  EXPECT_NEAR(filter.lineAngle(filter.slotOf(12)), 4.0 - 2.0 * kPi, 1e-15);

  // Refusals leave the state alone.
  const VectorXd x = filter.state();
  Matrix2 indefinite;
  indefinite << 1e-4, 1e-3, 1e-3, 1e-4;
  EXPECT_EQ(filter.addLineLandmark(7, PolarLine{1.0, 0.0}, line_covariance),
            FilterStatus::kDuplicateLandmark);
  EXPECT_EQ(filter.addLineAngleLandmark(4, 0.0, 1e-4), FilterStatus::kDuplicateLandmark);
  EXPECT_EQ(filter.addLineLandmark(20, PolarLine{NAN, 0.0}, line_covariance),
            FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.addLineLandmark(20, PolarLine{1.0, 0.0}, indefinite),
            FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.addLineLandmark(20, PolarLine{1.0, 0.0}, Matrix2::Identity() * 1e300),
            FilterStatus::kUnrepresentablePrior);
  EXPECT_EQ(filter.addLineLandmark(20, PolarLine{1.0, 0.0}, Matrix2::Identity() * 20.0),
            FilterStatus::kUnrepresentablePrior);  // σ_θ beyond π
  EXPECT_EQ(filter.addLineAngleLandmark(20, INFINITY, 1e-4), FilterStatus::kNonFiniteInput);
  EXPECT_EQ(filter.addLineAngleLandmark(20, 0.0, 0.0), FilterStatus::kSingularInnovation);
  EXPECT_EQ(filter.addLineAngleLandmark(20, 0.0, 20.0), FilterStatus::kUnrepresentablePrior);
  EXPECT_EQ(filter.state(), x);

  // An observation of the prior wall corrects it and correlates it with the pose.
  std::mt19937 rng(3);
  std::vector<LineObservation> z = {
      noisyWall(filter.pose(), sim_options.laser_pose, roomWalls()[1], &rng),
      noisyWall(filter.pose(), sim_options.laser_pose, roomWalls()[2], &rng)};
  LineMatch to_line, to_angle;
  to_line.observation = 0;
  to_line.landmark_id = 7;
  to_angle.observation = 1;
  to_angle.landmark_id = 9;
  ASSERT_EQ(filter.updateLines(z, {to_line, to_angle}), FilterStatus::kOk);
  EXPECT_LT(filter.landmarkCovariance(filter.slotOf(7))(0, 0), line_covariance(0, 0));
  EXPECT_LT(filter.lineAngleVariance(filter.slotOf(9)), 2e-4);
  EXPECT_GT(filter.covariance().block(filter.landmarkIndex(filter.slotOf(7)), 0, 2, 3).norm(), 0.0);
  EXPECT_TRUE(isSymmetricPositiveDefinite(filter.covariance()));
  EXPECT_EQ(filter.landmarks()[filter.slotOf(7)].observations, 6);
}

enum class LineVariant { kPTheta, kThetaWithEndpoints, kThetaAlone };

// One run on the landmark simulator in the walled room with known
// association; the pose NEES of every step.
std::vector<double> neesOfRun(unsigned seed, LineVariant variant) {
  sim::LandmarkSimOptions sim_options;
  sim_options.seed = seed;
  sim_options.landmarks = roomCorners();  // the walls' endpoints: all the points there are
  sim_options.max_range = 12.0;
  sim_options.field_of_view = 2.0 * kPi;
  sim::LandmarkSimulator sim(sim_options);
  EkfSlam filter(optionsFor(sim_options), sim.current().true_pose);
  std::mt19937 rng(seed * 7919u + 1u);
  std::vector<int> point_id(roomCorners().size(), -1), wall_id(roomWalls().size(), -1);
  const LandmarkKind kind =
      variant == LineVariant::kPTheta ? LandmarkKind::kLine : LandmarkKind::kLineAngle;
  std::vector<double> nees;
  Pose2 odom = sim.current().odometry;
  auto observe = [&](const sim::SimStep& s) {
    std::vector<PointMatch> point_matches;
    std::vector<int> fresh;
    for (size_t i = 0; i < s.observations.size(); ++i) {
      const int id = point_id[s.true_landmark[i]];
      if (id >= 0) {
        point_matches.push_back({static_cast<int>(i), id});
      } else {
        fresh.push_back(static_cast<int>(i));
      }
    }
    EXPECT_EQ(filter.update(s.observations, point_matches), FilterStatus::kOk);
    for (int i : fresh) filter.augment(s.observations[i], &point_id[s.true_landmark[i]]);
    std::vector<LineObservation> lines;
    std::vector<LineMatch> line_matches;
    for (size_t w = 0; w < roomWalls().size(); ++w) {
      lines.push_back(noisyWall(s.true_pose, sim_options.laser_pose, roomWalls()[w], &rng));
      if (wall_id[w] < 0) {
        EXPECT_EQ(filter.augmentLine(lines.back(), kind, &wall_id[w]), FilterStatus::kOk);
        continue;
      }
      LineMatch match{static_cast<int>(w), wall_id[w]};
      if (variant == LineVariant::kThetaWithEndpoints) {
        match.endpoint_ids[0] = point_id[w];
        match.endpoint_ids[1] = point_id[(w + 1) % roomCorners().size()];
      }
      line_matches.push_back(match);
    }
    EXPECT_EQ(filter.updateLines(lines, line_matches), FilterStatus::kOk);
  };
  observe(sim.current());
  while (sim.next()) {
    const sim::SimStep& s = sim.current();
    EXPECT_EQ(filter.predict(odom, s.odometry, sim_options.dt), FilterStatus::kOk);
    odom = s.odometry;
    observe(s);
    nees.push_back(filter.poseNees(s.true_pose));
  }
  return nees;
}

class LineConsistency : public ::testing::TestWithParam<LineVariant> {};
INSTANTIATE_TEST_SUITE_P(Variants, LineConsistency,
                         ::testing::Values(LineVariant::kPTheta, LineVariant::kThetaWithEndpoints,
                                           LineVariant::kThetaAlone),
                         [](const ::testing::TestParamInfo<LineVariant>& info) {
                           switch (info.param) {
                             case LineVariant::kPTheta:
                               return "PTheta";
                             case LineVariant::kThetaWithEndpoints:
                               return "ThetaWithEndpoints";
                             case LineVariant::kThetaAlone:
                               return "ThetaAlone";
                           }
                           return "unknown";
                         });

TEST_P(LineConsistency, MonteCarloAveragePoseNeesIsInsideTheChiSquareBand) {
  constexpr int kRuns = 30;
  std::vector<std::vector<double>> runs;
  for (int r = 0; r < kRuns; ++r) runs.push_back(neesOfRun(200 + r, GetParam()));
  const testing::NeesSummary nees = testing::summariseNees(runs, 3);
  ASSERT_GT(nees.steps, 100u);
  RecordProperty("average_nees", std::to_string(nees.average));
  EXPECT_GE(nees.average, nees.band.lower);
  EXPECT_LE(nees.average, nees.band.upper);
  EXPECT_GE(nees.fraction_inside, 0.85);
}

}  // namespace
}  // namespace ekf_slam
