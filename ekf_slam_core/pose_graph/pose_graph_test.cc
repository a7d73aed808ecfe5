// Pose-graph optimiser on small graphs with known answers.
#include "ekf_slam_core/pose_graph/pose_graph.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "ekf_slam_core/testing/ceres_reference.h"
#include "ekf_slam_core/testing/numerical_jacobian.h"

namespace ekf_slam {
namespace {

using Eigen::VectorXd;
using testing::numericalJacobian;

Matrix3 informationOf(double sigma_translation, double sigma_rotation) {
  return Vector3(1.0 / (sigma_translation * sigma_translation),
                 1.0 / (sigma_translation * sigma_translation),
                 1.0 / (sigma_rotation * sigma_rotation))
      .asDiagonal();
}

PoseGraphEdge edge(int from, int to, const Pose2& z, const Matrix3& information,
                   bool robust = false) {
  PoseGraphEdge e;
  e.from = from;
  e.to = to;
  e.measurement = z;
  e.information = information;
  e.robust = robust;
  return e;
}

// Poses on a circle of radius 5 m, heading along the tangent.
std::vector<Pose2> circle(int count) {
  std::vector<Pose2> poses;
  for (int i = 0; i < count; ++i) {
    const double a = 2.0 * kPi * i / count;
    poses.emplace_back(5.0 * std::sin(a), 5.0 - 5.0 * std::cos(a), a);
  }
  return poses;
}

double largestError(const PoseGraph& graph, const std::vector<Pose2>& truth) {
  double worst = 0.0;
  for (int i = 0; i < graph.nodeCount(); ++i) {
    worst = std::max(worst, maxAbsDifference(graph.pose(i), truth[i]));
  }
  return worst;
}

class EdgeJacobians : public ::testing::TestWithParam<double> {};
// Headings near ±pi included: the error's angle must not jump there.
INSTANTIATE_TEST_SUITE_P(Headings, EdgeJacobians,
                         ::testing::Values(0.0, 0.7, -2.0, kPi - 1e-3, -kPi + 1e-3));

TEST_P(EdgeJacobians, MatchCentralDifferences) {
  const double heading = GetParam();
  const Pose2 from(0.4, -1.2, heading), to(2.1, 0.6, heading + 0.9);
  const Pose2 z(1.9, 1.6, 0.75);  // close to, not exactly, the relative pose
  Matrix3 J_from, J_to;
  edgeError(from, to, z, &J_from, &J_to);
  VectorXd both(6);
  both << from.vector(), to.vector();
  const auto f = [&z](const VectorXd& v) -> VectorXd {
    return edgeError(Pose2::fromVector(v.head<3>()), Pose2::fromVector(v.tail<3>()), z);
  };
  const Eigen::MatrixXd numerical = numericalJacobian(f, both, {2});
  EXPECT_LT((numerical.leftCols<3>() - J_from).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((numerical.rightCols<3>() - J_to).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(PoseGraph, SpreadsALoopErrorEvenlyOverEqualEdges) {
  // Along x: two steps of 1 m each and a loop edge saying 2.3 m, all with
  // the same information. The 0.3 m disagreement splits in three: 1.1, 2.2.
  PoseGraph graph;
  for (int i = 0; i < 3; ++i) graph.addNode(Pose2(i, 0.0, 0.0));
  const Matrix3 info = informationOf(0.1, 0.01);
  graph.addEdge(edge(0, 1, Pose2(1.0, 0, 0), info));
  graph.addEdge(edge(1, 2, Pose2(1.0, 0, 0), info));
  graph.addEdge(edge(0, 2, Pose2(2.3, 0, 0), info));
  const PoseGraphSummary summary = graph.optimize(PoseGraphOptions());
  EXPECT_TRUE(summary.converged());
  EXPECT_NEAR(graph.pose(1).x, 1.1, 1e-9);
  EXPECT_NEAR(graph.pose(2).x, 2.2, 1e-9);
  EXPECT_NEAR(graph.pose(2).y, 0.0, 1e-9);
  EXPECT_EQ(graph.pose(0).x, 0.0);  // node 0 is the fixed map frame
}

TEST(PoseGraph, ClosesADriftedLoopToTheTruth) {
  // Exact measurements around a circle and back to the start, the initial
  // estimate from odometry with 3 deg of heading drift per step.
  const std::vector<Pose2> truth = circle(40);
  PoseGraph graph;
  graph.addNode(truth[0]);
  const Matrix3 info = informationOf(0.05, 0.01);
  for (int i = 1; i < 40; ++i) {
    const Pose2 z = between(truth[i - 1], truth[i]);
    graph.addNode(compose(graph.pose(i - 1), compose(z, Pose2(0.0, 0.0, degToRad(3.0)))));
    graph.addEdge(edge(i - 1, i, z, info));
  }
  ASSERT_GT(largestError(graph, truth), 5.0);  // the loop is far from closed
  graph.addEdge(edge(39, 0, between(truth[39], truth[0]), info, /*robust=*/true));
  const PoseGraphSummary summary = graph.optimize(PoseGraphOptions());
  EXPECT_TRUE(summary.converged());
  EXPECT_LT(summary.final_cost, 1e-12);
  EXPECT_LT(largestError(graph, truth), 1e-6);
}

// A circle with noisy odometry and correct loop closures between laps plus
// one false loop that claims two opposite points of the circle coincide.
struct NoisyLoops {
  std::vector<Pose2> truth;
  PoseGraph graph;
  int false_edge = -1;
};

NoisyLoops noisyLoopsWithAFalseOne(bool robust_false_loop) {
  NoisyLoops out;
  const std::vector<Pose2> lap = circle(30);
  for (int k = 0; k < 60; ++k) out.truth.push_back(lap[k % 30]);  // two laps
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double sigma_t = 0.02, sigma_r = 0.005;
  const Matrix3 info = informationOf(sigma_t, sigma_r);
  out.graph.addNode(out.truth[0]);
  for (int i = 1; i < 60; ++i) {
    const Pose2 true_step = between(out.truth[i - 1], out.truth[i]);
    const Pose2 z =
        compose(true_step, Pose2(sigma_t * noise(rng), sigma_t * noise(rng), sigma_r * noise(rng)));
    out.graph.addNode(compose(out.graph.pose(i - 1), z));
    out.graph.addEdge(edge(i - 1, i, z, info));
  }
  for (int i = 30; i < 60; i += 3) {  // second lap sees the first
    out.graph.addEdge(edge(i - 30, i, Pose2(), info, /*robust=*/true));
  }
  out.false_edge = out.graph.addEdge(edge(5, 50, Pose2(), info, robust_false_loop));
  return out;
}

TEST(PoseGraph, CauchyKernelDownweightsAFalseLoop) {
  NoisyLoops robust = noisyLoopsWithAFalseOne(/*robust_false_loop=*/true);
  PoseGraphOptions options;
  options.max_iterations = 50;
  robust.graph.optimize(options);
  // The false edge joins points 10 m apart; the map stays within decimetres.
  EXPECT_LT(largestError(robust.graph, robust.truth), 0.25);
  EXPECT_LT(robust.graph.edgeWeight(robust.false_edge, options.robust_kernel_width), 1e-3);
  // The correct loops keep (almost) full weight.
  for (int k = 0; k < static_cast<int>(robust.graph.edges().size()); ++k) {
    if (robust.graph.edges()[k].robust && k != robust.false_edge) {
      EXPECT_GT(robust.graph.edgeWeight(k, options.robust_kernel_width), 0.5) << "edge " << k;
    }
  }

  // Without the kernel the same false edge bends the map by metres.
  NoisyLoops plain = noisyLoopsWithAFalseOne(/*robust_false_loop=*/false);
  plain.graph.optimize(options);
  EXPECT_GT(largestError(plain.graph, plain.truth), 1.0);
}

// Ceres (the reference, testing/ceres_reference.h) and the hand-written
// solver on the same noisy two-lap graph with its false loop, plus
// heading-only edges (information diag(0, 0, w), semi-definite: no Cholesky
// factor) between the laps: both reach the same minimum, and the false loop
// is down-weighted by both.
TEST(PoseGraph, CeresAndTheHandWrittenSolverReachTheSameMinimum) {
  PoseGraphOptions options;
  options.max_iterations = 100;
  NoisyLoops loops = noisyLoopsWithAFalseOne(/*robust_false_loop=*/true);
  for (int i = 31; i < 60; i += 3) {
    PoseGraphEdge heading;
    heading.from = i - 30;
    heading.to = i;
    heading.information = Vector3(0.0, 0.0, 1.0 / (0.01 * 0.01)).asDiagonal();
    heading.robust = true;
    loops.graph.addEdge(heading);
  }
  PoseGraphSummary reference;
  const PoseGraph by_ceres = solveWithCeres(loops.graph, options, 1e-10, &reference);
  const PoseGraphSummary summary = loops.graph.optimize(options);
  auto check = [&](const char* name, const PoseGraph& graph, const PoseGraphSummary& s) {
    EXPECT_TRUE(s.converged()) << name;
    EXPECT_LT(s.final_cost, s.initial_cost) << name;
    EXPECT_LT(largestError(graph, loops.truth), 0.25) << name;
    EXPECT_LT(graph.edgeWeight(loops.false_edge, options.robust_kernel_width), 1e-3) << name;
  };
  check("hand-written", loops.graph, summary);
  check("ceres", by_ceres, reference);
  for (int i = 0; i < loops.graph.nodeCount(); ++i) {
    const Pose2 d = between(loops.graph.pose(i), by_ceres.pose(i));
    EXPECT_LT(std::hypot(d.x, d.y), 1e-4) << "node " << i;
    EXPECT_LT(std::abs(d.theta), 1e-5) << "node " << i;
  }
}

// Random graphs far from their optimum: a random walk of 40–120 poses, its
// odometry noisy, 5–30 loop edges between random pairs (some robust, one
// in five false), started from the odometry with the heading drifted. The
// hand-written solver ends where Ceres does (the same cost to 10⁻⁶, every
// pose within 1 mm + 1 mrad: the robust kernels leave flat directions), and
// says it converged.
TEST(PoseGraph, MatchesCeresOnRandomGraphs) {
  for (int seed = 1; seed <= 12; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int count = 40 + static_cast<int>(80 * u(rng));
    std::vector<Pose2> truth = {Pose2()};
    for (int i = 1; i < count; ++i) {
      truth.push_back(compose(truth.back(), Pose2(0.5 + u(rng), 0.3 * n(rng), 0.6 * n(rng))));
    }
    PoseGraph graph;
    Pose2 start;
    graph.addNode(start);
    const Matrix3 motion_information = informationOf(0.05, 0.02);
    for (int i = 1; i < count; ++i) {
      const Pose2 z = compose(between(truth[i - 1], truth[i]),
                              Pose2(0.05 * n(rng), 0.05 * n(rng), 0.02 * n(rng) + 0.03));
      start = compose(start, z);
      graph.addNode(start);
      graph.addEdge(edge(i - 1, i, z, motion_information));
    }
    const int loops = 5 + static_cast<int>(25 * u(rng));
    for (int k = 0; k < loops; ++k) {
      const int a = static_cast<int>(u(rng) * (count - 5));
      const int b = a + 3 + static_cast<int>(u(rng) * (count - a - 3));
      const bool wrong = k % 5 == 4;
      const Pose2 z = wrong ? Pose2(3.0 * n(rng), 3.0 * n(rng), n(rng))
                            : compose(between(truth[a], truth[b]),
                                      Pose2(0.02 * n(rng), 0.02 * n(rng), 0.01 * n(rng)));
      graph.addEdge(edge(a, b, z, informationOf(0.05, 0.02), /*robust=*/wrong || k % 2 == 0));
    }
    PoseGraphOptions options;
    options.max_iterations = 500;
    options.convergence_step = 1e-9;
    PoseGraphSummary reference;
    const PoseGraph by_ceres = solveWithCeres(graph, options, 1e-14, &reference);
    const PoseGraphSummary summary = graph.optimize(options);
    EXPECT_TRUE(summary.converged()) << "seed " << seed << ": " << solveEndName(summary.end);
    EXPECT_NEAR(summary.final_cost, reference.final_cost, 1e-6 * reference.final_cost + 1e-9)
        << "seed " << seed;
    double largest = 0.0;
    for (int i = 0; i < count; ++i) {
      const Pose2 d = between(graph.pose(i), by_ceres.pose(i));
      largest = std::max(largest, std::hypot(d.x, d.y) + std::abs(d.theta));
    }
    EXPECT_LT(largest, 1e-3) << "seed " << seed;
  }
}

// A graph whose start is already its optimum to the last bit: no step
// lowers the cost. That is a converged solve (a step below the tolerance),
// and a solve where every damped step raises the cost is reported as
// stalled, never as converged.
TEST(PoseGraph, ReportsAStallAsAStall) {
  PoseGraph exact;
  exact.addNode(Pose2());
  exact.addNode(Pose2(1.0, 0.0, 0.0));
  exact.addEdge(edge(0, 1, Pose2(1.0, 0.0, 0.0), informationOf(0.1, 0.1)));
  EXPECT_TRUE(exact.optimize(PoseGraphOptions()).converged());

  // A cost that no step of the quadratic model can lower: a NaN edge.
  PoseGraph broken;
  broken.addNode(Pose2());
  broken.addNode(Pose2(1.0, 0.0, 0.0));
  broken.addEdge(edge(0, 1, Pose2(2.0, 0.0, 0.0), informationOf(0.1, 0.1)));
  PoseGraphEdge nan_edge = edge(0, 1, Pose2(1.0, 0.0, 0.0), informationOf(0.1, 0.1));
  nan_edge.information(0, 0) = std::numeric_limits<double>::quiet_NaN();
  broken.addEdge(nan_edge);
  const PoseGraphSummary summary = broken.optimize(PoseGraphOptions());
  EXPECT_FALSE(summary.converged());
  EXPECT_EQ(summary.end, SolveEnd::kStalled);
}

TEST(PoseGraphOptions, ValidateNamesTheBadField) {
  PoseGraphOptions options;
  EXPECT_EQ(options.validate(), "");
  options.robust_kernel_width = 0.0;
  EXPECT_NE(options.validate().find("robust_kernel_width"), std::string::npos);
  options = PoseGraphOptions();
  options.max_iterations = 0;
  EXPECT_NE(options.validate().find("max_iterations"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
