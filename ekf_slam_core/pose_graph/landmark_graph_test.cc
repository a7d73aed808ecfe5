#include "ekf_slam_core/pose_graph/landmark_graph.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "ekf_slam_core/testing/ceres_reference.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::numericalJacobian;

const Pose2 kLaser(0.12, -0.03, 0.05);

// e(x, m) as one vector function of the stacked (x, y, θ, m_x, m_y).
VectorXd observationErrorOf(const VectorXd& v, const RangeBearing& z) {
  Vector2 e;
  EXPECT_TRUE(observationError(Pose2(v(0), v(1), v(2)), kLaser, Vector2(v(3), v(4)), z, &e));
  return e;
}

void expectObservationJacobiansMatch(const Pose2& robot, const Vector2& landmark,
                                     const RangeBearing& z) {
  Vector2 e;
  Matrix23 J_robot;
  Matrix2 J_landmark;
  ASSERT_TRUE(observationError(robot, kLaser, landmark, z, &e, &J_robot, &J_landmark));
  VectorXd v(5);
  v << robot.x, robot.y, robot.theta, landmark.x(), landmark.y();
  const MatrixXd numeric =
      numericalJacobian([&](const VectorXd& p) { return observationErrorOf(p, z); }, v, {1});
  EXPECT_TRUE(numeric.leftCols<3>().isApprox(J_robot, 1e-6) ||
              (numeric.leftCols<3>() - J_robot).cwiseAbs().maxCoeff() < 1e-6)
      << "analytic\n"
      << J_robot << "\nnumeric\n"
      << numeric.leftCols<3>();
  EXPECT_LT((numeric.rightCols<2>() - J_landmark).cwiseAbs().maxCoeff(), 1e-6)
      << "analytic\n"
      << J_landmark << "\nnumeric\n"
      << numeric.rightCols<2>();
}

TEST(LandmarkGraph, ObservationJacobiansMatchCentralDifferences) {
  // Ordinary geometry, a landmark behind the sensor (bearing near ±π, both
  // sides), and one a few centimetres from the sensor.
  const Pose2 robot(1.0, -2.0, 0.7);
  const Pose2 sensor = compose(robot, kLaser);
  expectObservationJacobiansMatch(robot, Vector2(4.0, 1.0), {3.0, 0.4});
  for (const double bearing : {kPi - 1e-4, -kPi + 1e-4}) {
    const Vector2 behind =
        transformFrom(sensor, Vector2(2.0 * std::cos(bearing), 2.0 * std::sin(bearing)));
    // The measured bearing on the other side of ±π from the prediction: the
    // error must wrap, not jump by 2π.
    expectObservationJacobiansMatch(robot, behind, {2.0, -bearing});
  }
  const Vector2 close = transformFrom(sensor, Vector2(0.03, 0.02));
  expectObservationJacobiansMatch(robot, close, {0.04, 0.5});
}

TEST(LandmarkGraph, ObservationErrorWrapsTheBearing) {
  const Pose2 robot;
  const Pose2 sensor = compose(robot, kLaser);
  const Vector2 behind = transformFrom(sensor, Vector2(-2.0, 1e-3));  // bearing ≈ π − 5e-4
  Vector2 e;
  ASSERT_TRUE(observationError(robot, kLaser, behind, {2.0, -kPi + 5e-4}, &e));
  EXPECT_LT(std::abs(e(1)), 2e-3);
  EXPECT_FALSE(observationError(robot, kLaser, sensor.translation(), {1.0, 0.0}, &e));
}

TEST(LandmarkGraph, RelativePoseJacobiansWithOffsetsMatchCentralDifferences) {
  RelativePoseEdge edge;
  edge.from_offset = Pose2(0.3, -0.1, 0.4);
  edge.to_offset = Pose2(-0.2, 0.25, -1.1);
  edge.measurement = Pose2(2.0, 0.5, 3.0);  // near ±π: the heading error wraps
  const Pose2 from(1.0, 2.0, -0.3), to(2.5, 3.1, 2.9);
  Matrix3 J_from, J_to;
  relativePoseError(from, to, edge, &J_from, &J_to);
  VectorXd v(6);
  v << from.vector(), to.vector();
  const MatrixXd numeric = numericalJacobian(
      [&](const VectorXd& p) -> VectorXd {
        return relativePoseError(Pose2(p(0), p(1), p(2)), Pose2(p(3), p(4), p(5)), edge);
      },
      v, {2});
  EXPECT_LT((numeric.leftCols<3>() - J_from).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((numeric.rightCols<3>() - J_to).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(LandmarkGraph, RobustKernelsAgreeWithTheirWeights) {
  // ρ'(s) is the weight: check by central differences in s.
  for (RobustKernel k : {RobustKernel::kNone, RobustKernel::kHuber, RobustKernel::kCauchy}) {
    for (double s : {0.5, 4.0, 30.0, 400.0}) {
      const double h = 1e-5 * s;
      const double numeric = (robustCost(k, s + h, 3.0) - robustCost(k, s - h, 3.0)) / (2 * h);
      EXPECT_NEAR(robustWeight(k, s, 3.0), numeric, 1e-6);
    }
  }
  EXPECT_DOUBLE_EQ(robustCost(RobustKernel::kHuber, 4.0, 3.0), 4.0);  // inside: quadratic
}

// A small world: three poses on a line, two landmarks, exact measurements.
struct SmallWorld {
  std::vector<Pose2> poses = {Pose2(0, 0, 0), Pose2(1.0, 0.1, 0.2), Pose2(2.0, 0.4, 0.5)};
  std::vector<Vector2> landmarks = {Vector2(1.5, 2.0), Vector2(3.0, -1.0)};
};

LandmarkGraph buildGraph(const SmallWorld& truth, const std::vector<Pose2>& motion,
                         const std::vector<RangeBearing>& z, const std::vector<Pose2>& init_poses,
                         const std::vector<Vector2>& init_landmarks) {
  LandmarkGraph graph(kLaser);
  for (size_t i = 0; i < init_poses.size(); ++i) graph.addPose(init_poses[i], i == 0);
  for (const Vector2& m : init_landmarks) graph.addLandmark(m);
  for (size_t i = 1; i < truth.poses.size(); ++i) {
    RelativePoseEdge e;
    e.from = static_cast<int>(i) - 1;
    e.to = static_cast<int>(i);
    e.measurement = motion[i - 1];
    e.information = Vector3(400, 400, 2500).asDiagonal();
    graph.addEdge(e);
  }
  int k = 0;
  for (size_t i = 0; i < truth.poses.size(); ++i) {
    for (size_t j = 0; j < truth.landmarks.size(); ++j) {
      ObservationEdge e;
      e.pose = static_cast<int>(i);
      e.landmark = static_cast<int>(j);
      e.z = z[k++];
      e.information = Vector2(1.0 / 0.0004, 1.0 / 0.0001).asDiagonal();
      graph.addEdge(e);
    }
  }
  return graph;
}

// The world's odometry increments and every pose's reading of every landmark, exact.
bool exactMeasurements(const SmallWorld& truth, std::vector<Pose2>* motion,
                       std::vector<RangeBearing>* z) {
  for (size_t i = 1; i < truth.poses.size(); ++i) {
    motion->push_back(between(truth.poses[i - 1], truth.poses[i]));
  }
  for (const Pose2& x : truth.poses) {
    for (const Vector2& m : truth.landmarks) {
      RangeBearing r;
      if (!predictPointObservation(x, kLaser, m, &r)) return false;
      z->push_back(r);
    }
  }
  return true;
}

// Optimised from exact measurements, the graph ends at the truth, with H's
// pattern analysed once, or once more for each change of its edges.
void expectSolvedToTheTruth(LandmarkGraph graph, const SmallWorld& truth, double max_cost,
                            double tolerance, int symbolic_analyses) {
  const LandmarkGraphSummary summary = graph.optimize(LandmarkGraphOptions());
  EXPECT_GT(summary.iterations, 2);
  EXPECT_EQ(summary.symbolic_analyses, symbolic_analyses);
  EXPECT_TRUE(summary.converged());
  EXPECT_LT(summary.final_cost, max_cost);
  for (size_t i = 0; i < truth.poses.size(); ++i) {
    EXPECT_LT((graph.poses()[i].vector() - truth.poses[i].vector()).norm(), tolerance);
  }
  for (size_t j = 0; j < truth.landmarks.size(); ++j) {
    EXPECT_LT((graph.landmarks()[j] - truth.landmarks[j]).norm(), tolerance);
  }
}

// The small world's exact measurements, and its poses with the second one
// moved off the truth: the start of the solves below.
struct ExactProblem {
  SmallWorld truth;
  std::vector<Pose2> motion;
  std::vector<RangeBearing> z;
  std::vector<Pose2> poses;
  bool measured = false;
  ExactProblem() : poses(truth.poses), measured(exactMeasurements(truth, &motion, &z)) {
    poses[1] = Pose2(1.2, -0.1, 0.1);
  }
};

TEST(LandmarkGraph, RecoversTheTruthFromExactMeasurements) {
  ExactProblem p;
  ASSERT_TRUE(p.measured);
  p.poses[2] = Pose2(1.7, 0.7, 0.7);
  std::vector<Vector2> landmarks = {Vector2(1.0, 2.5), Vector2(3.4, -0.6)};
  expectSolvedToTheTruth(buildGraph(p.truth, p.motion, p.z, p.poses, landmarks), p.truth, 1e-16,
                         1e-8, /*symbolic_analyses=*/1);
}

// A landmark that starts on a laser has no observation error from that
// pose: the edge is left out of the first normal equations and enters once
// the landmark has moved, which changes the pattern of H. The solver must
// notice (a new pattern, analysed afresh) and still find the truth.
TEST(LandmarkGraph, AnEdgeThatEntersLaterChangesThePatternAndIsSolved) {
  const ExactProblem p;
  ASSERT_TRUE(p.measured);
  std::vector<Vector2> landmarks = {compose(p.poses[1], kLaser).translation(), Vector2(3.4, -0.6)};
  Vector2 e;
  ASSERT_FALSE(observationError(p.poses[1], kLaser, landmarks[0], p.z[2], &e));
  expectSolvedToTheTruth(buildGraph(p.truth, p.motion, p.z, p.poses, landmarks), p.truth, 1e-12,
                         1e-6, /*symbolic_analyses=*/2);
}

// Noisy measurements: the sparse LM optimum must be the stationary point of
// the dense problem: a dense Gauss–Newton on the stacked whitened residuals
// with numerical Jacobians, started from the sparse answer, does not move.
TEST(LandmarkGraph, MatchesADenseGaussNewtonSolve) {
  const SmallWorld truth;
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Pose2> motion;
  for (size_t i = 1; i < truth.poses.size(); ++i) {
    const Pose2 d = between(truth.poses[i - 1], truth.poses[i]);
    motion.push_back(Pose2(d.x + 0.05 * n(rng), d.y + 0.05 * n(rng), d.theta + 0.02 * n(rng)));
  }
  std::vector<RangeBearing> z;
  for (const Pose2& x : truth.poses) {
    for (const Vector2& m : truth.landmarks) {
      RangeBearing r;
      ASSERT_TRUE(predictPointObservation(x, kLaser, m, &r));
      z.push_back({r.range + 0.02 * n(rng), r.bearing + 0.01 * n(rng)});
    }
  }
  LandmarkGraph graph = buildGraph(truth, motion, z, truth.poses, truth.landmarks);
  graph.optimize(LandmarkGraphOptions());

  // Whitened residual of the whole problem over the free unknowns
  // (poses 1, 2 and both landmarks: 10 numbers).
  auto residual = [&](const VectorXd& v) -> VectorXd {
    std::vector<Pose2> x = {truth.poses[0], Pose2(v(0), v(1), v(2)), Pose2(v(3), v(4), v(5))};
    std::vector<Vector2> m = {Vector2(v(6), v(7)), Vector2(v(8), v(9))};
    VectorXd r(2 * 3 + 2 * 6);
    int row = 0;
    for (int i = 1; i < 3; ++i) {
      RelativePoseEdge e;
      e.measurement = motion[i - 1];
      const Vector3 err = relativePoseError(x[i - 1], x[i], e);
      r.segment<3>(row) = Vector3(20 * err(0), 20 * err(1), 50 * err(2));
      row += 3;
    }
    int k = 0;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 2; ++j) {
        Vector2 err;
        observationError(x[i], kLaser, m[j], z[k++], &err);
        r.segment<2>(row) = Vector2(err(0) / 0.02, err(1) / 0.01);
        row += 2;
      }
    }
    return r;
  };
  VectorXd v(10);
  v << graph.poses()[1].vector(), graph.poses()[2].vector(), graph.landmarks()[0],
      graph.landmarks()[1];
  const MatrixXd J = numericalJacobian(residual, v, {2, 5});
  const VectorXd step = (J.transpose() * J).ldlt().solve(-J.transpose() * residual(v));
  EXPECT_LT(step.cwiseAbs().maxCoeff(), 1e-7) << step.transpose();
  EXPECT_NEAR(graph.cost(3.0), residual(v).squaredNorm(), 1e-9);
}

// Ceres (the reference, testing/ceres_reference.h) on the exact problem
// ends at the truth too, and on the noisy one at the hand-written solver's
// optimum.
TEST(LandmarkGraph, CeresReachesTheSameOptimum) {
  ExactProblem p;
  ASSERT_TRUE(p.measured);
  const std::vector<Vector2> start = {Vector2(1.0, 2.5), Vector2(3.4, -0.6)};
  LandmarkGraphOptions options;
  LandmarkGraphSummary summary;
  const LandmarkGraph exact =
      solveWithCeres(buildGraph(p.truth, p.motion, p.z, p.poses, start), options, &summary);
  EXPECT_TRUE(summary.converged());
  EXPECT_LT(summary.final_cost, 1e-10);
  for (size_t i = 0; i < p.truth.poses.size(); ++i) {
    EXPECT_LT((exact.poses()[i].vector() - p.truth.poses[i].vector()).norm(), 1e-5);
  }
  EXPECT_EQ(exact.poses()[0].vector(), p.truth.poses[0].vector());  // fixed

  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<RangeBearing> noisy = p.z;
  for (RangeBearing& r : noisy) {
    r.range += 0.02 * n(rng);
    r.bearing += 0.01 * n(rng);
  }
  options.min_relative_decrease = 1e-12;
  LandmarkGraph by_hand = buildGraph(p.truth, p.motion, noisy, p.poses, start);
  const LandmarkGraph by_ceres = solveWithCeres(by_hand, options, &summary);
  EXPECT_TRUE(summary.converged());
  EXPECT_TRUE(by_hand.optimize(options).converged());
  EXPECT_NEAR(by_hand.cost(3.0), by_ceres.cost(3.0), 1e-6 * by_hand.cost(3.0));
  for (size_t i = 0; i < p.truth.poses.size(); ++i) {
    EXPECT_LT((by_hand.poses()[i].vector() - by_ceres.poses()[i].vector()).norm(), 1e-5);
  }
  for (size_t j = 0; j < p.truth.landmarks.size(); ++j) {
    EXPECT_LT((by_hand.landmarks()[j] - by_ceres.landmarks()[j]).norm(), 1e-5);
  }
}

TEST(LandmarkGraph, HuberKernelBoundsTheInfluenceOfAWrongObservation) {
  // Five poses see one landmark; one sighting is 1 m off. Without a kernel
  // it drags the landmark by decimetres; with Huber much less.
  auto solve = [](RobustKernel kernel) {
    LandmarkGraph graph(kLaser);
    const Vector2 landmark(3.0, 1.0);
    for (int i = 0; i < 5; ++i) graph.addPose(Pose2(0.2 * i, 0.0, 0.0), /*fixed=*/true);
    graph.addLandmark(Vector2(2.8, 1.2));
    for (int i = 0; i < 5; ++i) {
      RangeBearing z;
      predictPointObservation(graph.poses()[i], kLaser, landmark, &z);
      if (i == 4) z.range += 1.0;
      ObservationEdge e;
      e.pose = i;
      e.landmark = 0;
      e.z = z;
      e.information = Vector2(1.0 / 0.0004, 1.0 / 0.0001).asDiagonal();
      e.kernel = kernel;
      graph.addEdge(e);
    }
    graph.optimize(LandmarkGraphOptions());
    return (graph.landmarks()[0] - landmark).norm();
  };
  const double plain = solve(RobustKernel::kNone);
  const double huber = solve(RobustKernel::kHuber);
  EXPECT_GT(plain, 0.15);
  EXPECT_LT(huber, 0.3 * plain);
}

}  // namespace
}  // namespace ekf_slam
