#include "ekf_slam_core/pose_graph/graph_io.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>

namespace ekf_slam {
namespace {

class GraphIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir[] = "/tmp/graph_ioXXXXXX";
    ASSERT_NE(::mkdtemp(dir), nullptr);
    dir_ = dir;
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }

  // Values whose decimal forms are long (no round numbers), so that a
  // short format would lose bits.
  double value() { return std::uniform_real_distribution<double>(-3.0, 3.0)(random_); }
  Pose2 pose() {
    Pose2 p;
    p.x = value();
    p.y = value();
    p.theta = value();
    return p;
  }
  Matrix3 information() {
    const Matrix3 a = Matrix3::Random();
    const double v = value();
    return a * a.transpose() + Matrix3::Identity() * (1.0 + v * v);  // positive definite
  }

  std::string dir_;
  std::mt19937 random_{7};
};

void expectSame(const Pose2& a, const Pose2& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.theta, b.theta);
}

TEST_F(GraphIoTest, PoseGraphRoundTripsBitForBit) {
  PoseGraph graph;
  for (int i = 0; i < 6; ++i) graph.addNode(pose());
  for (int i = 0; i < 8; ++i) {
    PoseGraphEdge e;
    e.from = i % 6;
    e.to = (i * 5 + 1) % 6;
    e.measurement = pose();
    e.information = information();
    e.robust = i % 2 == 0;
    e.active = i != 3;
    graph.addEdge(e);
  }
  PoseGraphOptions options;
  options.max_iterations = 17;
  options.convergence_step = 1.0 / 3.0;
  options.robust_kernel_width = std::sqrt(2.0);
  options.initial_lambda = 1e-7 / 3.0;
  ASSERT_EQ(savePoseGraph(path("graph.txt"), graph, options), "");

  PoseGraph loaded;
  PoseGraphOptions loaded_options;
  ASSERT_EQ(loadPoseGraph(path("graph.txt"), &loaded, &loaded_options), "");
  EXPECT_EQ(loaded_options.max_iterations, 17);
  EXPECT_EQ(loaded_options.convergence_step, options.convergence_step);
  EXPECT_EQ(loaded_options.robust_kernel_width, options.robust_kernel_width);
  EXPECT_EQ(loaded_options.initial_lambda, options.initial_lambda);
  ASSERT_EQ(loaded.nodeCount(), graph.nodeCount());
  for (int i = 0; i < graph.nodeCount(); ++i) expectSame(loaded.pose(i), graph.pose(i));
  ASSERT_EQ(loaded.edges().size(), graph.edges().size());
  for (size_t k = 0; k < graph.edges().size(); ++k) {
    const PoseGraphEdge &a = graph.edges()[k], &b = loaded.edges()[k];
    EXPECT_EQ(a.from, b.from);
    EXPECT_EQ(a.to, b.to);
    expectSame(a.measurement, b.measurement);
    EXPECT_TRUE(a.information == b.information);
    EXPECT_EQ(a.robust, b.robust);
    EXPECT_EQ(a.active, b.active);
  }
  // The same problem: the same solution, bit for bit.
  graph.optimize(options);
  loaded.optimize(loaded_options);
  for (int i = 0; i < graph.nodeCount(); ++i) expectSame(loaded.pose(i), graph.pose(i));
}

TEST_F(GraphIoTest, LandmarkGraphRoundTripsBitForBit) {
  LandmarkGraph graph(pose());
  for (int i = 0; i < 4; ++i) graph.addPose(pose(), i == 0);
  for (int j = 0; j < 3; ++j) graph.addLandmark(Vector2(value() * 3.0, value() * 3.0));
  const RobustKernel kernels[] = {RobustKernel::kNone, RobustKernel::kHuber, RobustKernel::kCauchy};
  for (int i = 0; i < 3; ++i) {
    RelativePoseEdge e;
    e.from = i;
    e.to = i + 1;
    e.from_offset = pose();
    e.to_offset = pose();
    e.measurement = pose();
    e.information = information();
    e.kernel = kernels[i];
    graph.addEdge(e);
  }
  PosePriorEdge prior;
  prior.pose = 1;
  prior.mean = pose();
  prior.information = information();
  graph.addEdge(prior);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 3; ++j) {
      ObservationEdge e;
      e.pose = i;
      e.landmark = j;
      e.z.range = 2.0 + value();
      e.z.bearing = value();
      e.information = information().topLeftCorner<2, 2>();
      e.kernel = kernels[(i + j) % 3];
      graph.addEdge(e);
    }
  }
  LandmarkGraphOptions options;
  options.max_iterations = 9;
  options.convergence_step = 1.0 / 7.0;
  options.min_relative_decrease = 1e-6 / 3.0;
  options.initial_lambda = 1.0 / 11.0;
  options.kernel_width = std::sqrt(5.0);
  ASSERT_EQ(saveLandmarkGraph(path("graph.txt"), graph, options), "");

  LandmarkGraph loaded;
  LandmarkGraphOptions loaded_options;
  ASSERT_EQ(loadLandmarkGraph(path("graph.txt"), &loaded, &loaded_options), "");
  EXPECT_EQ(loaded_options.max_iterations, 9);
  EXPECT_EQ(loaded_options.convergence_step, options.convergence_step);
  EXPECT_EQ(loaded_options.min_relative_decrease, options.min_relative_decrease);
  EXPECT_EQ(loaded_options.initial_lambda, options.initial_lambda);
  EXPECT_EQ(loaded_options.kernel_width, options.kernel_width);
  expectSame(loaded.laserPose(), graph.laserPose());
  ASSERT_EQ(loaded.poseCount(), graph.poseCount());
  for (int i = 0; i < graph.poseCount(); ++i) {
    expectSame(loaded.poses()[i], graph.poses()[i]);
    EXPECT_EQ(loaded.isFixed(i), graph.isFixed(i));
  }
  ASSERT_EQ(loaded.landmarkCount(), graph.landmarkCount());
  for (int j = 0; j < graph.landmarkCount(); ++j) {
    EXPECT_TRUE(loaded.landmarks()[j] == graph.landmarks()[j]);
  }
  ASSERT_EQ(loaded.relativeEdges().size(), graph.relativeEdges().size());
  for (size_t k = 0; k < graph.relativeEdges().size(); ++k) {
    const RelativePoseEdge &a = graph.relativeEdges()[k], &b = loaded.relativeEdges()[k];
    EXPECT_EQ(a.from, b.from);
    EXPECT_EQ(a.to, b.to);
    expectSame(a.from_offset, b.from_offset);
    expectSame(a.to_offset, b.to_offset);
    expectSame(a.measurement, b.measurement);
    EXPECT_TRUE(a.information == b.information);
    EXPECT_EQ(a.kernel, b.kernel);
  }
  ASSERT_EQ(loaded.priorEdges().size(), 1u);
  EXPECT_EQ(loaded.priorEdges()[0].pose, 1);
  expectSame(loaded.priorEdges()[0].mean, prior.mean);
  EXPECT_TRUE(loaded.priorEdges()[0].information == prior.information);
  ASSERT_EQ(loaded.observationEdges().size(), graph.observationEdges().size());
  for (size_t k = 0; k < graph.observationEdges().size(); ++k) {
    const ObservationEdge &a = graph.observationEdges()[k], &b = loaded.observationEdges()[k];
    EXPECT_EQ(a.pose, b.pose);
    EXPECT_EQ(a.landmark, b.landmark);
    EXPECT_EQ(a.z.range, b.z.range);
    EXPECT_EQ(a.z.bearing, b.z.bearing);
    EXPECT_TRUE(a.information == b.information);
    EXPECT_EQ(a.kernel, b.kernel);
  }
  EXPECT_EQ(loaded.cost(options.kernel_width), graph.cost(options.kernel_width));
  graph.optimize(options);
  loaded.optimize(loaded_options);
  for (int i = 0; i < graph.poseCount(); ++i) expectSame(loaded.poses()[i], graph.poses()[i]);
}

TEST_F(GraphIoTest, ScanAnchorsRoundTripAndPlaceScans) {
  std::vector<ScanAnchor> anchors;
  for (int k = 0; k < 5; ++k) anchors.push_back({1e9 + k / 3.0, k - 1, pose()});
  ASSERT_EQ(saveScanAnchors(path("scans.txt"), anchors), "");
  std::vector<ScanAnchor> loaded;
  ASSERT_EQ(loadScanAnchors(path("scans.txt"), &loaded), "");
  ASSERT_EQ(loaded.size(), anchors.size());
  for (size_t k = 0; k < anchors.size(); ++k) {
    EXPECT_EQ(loaded[k].stamp, anchors[k].stamp);
    EXPECT_EQ(loaded[k].node, anchors[k].node);
    expectSame(loaded[k].offset, anchors[k].offset);
  }
  const std::vector<Pose2> nodes = {pose(), pose(), pose()};  // node 3 is missing
  const std::vector<StampedPose> placed = anchoredScanPoses(loaded, nodes);
  ASSERT_EQ(placed.size(), anchors.size());
  expectSame(placed[0].pose, anchors[0].offset);  // node −1
  expectSame(placed[1].pose, compose(nodes[0], anchors[1].offset));
  expectSame(placed[3].pose, compose(nodes[2], anchors[3].offset));
  expectSame(placed[4].pose, anchors[4].offset);  // beyond the nodes
}

TEST_F(GraphIoTest, ReportsTheLineOfABadRecord) {
  std::ofstream(path("bad.txt")) << "# comment\n"
                                 << "POSE_GRAPH_OPTIONS 20 1e-6 3 1e-6\n"
                                 << "NODE 0 0 0 0\n"
                                 << "NODE 1 1 0\n";
  PoseGraph graph;
  graph.addNode(Pose2(1.0, 2.0, 0.5));
  const std::string error = loadPoseGraph(path("bad.txt"), &graph, nullptr);
  EXPECT_NE(error.find("bad.txt:4:"), std::string::npos) << error;
  EXPECT_EQ(graph.nodeCount(), 1);  // untouched
  EXPECT_NE(loadPoseGraph(path("missing.txt"), &graph, nullptr), "");

  std::ofstream(path("edge.txt")) << "POSE_GRAPH_OPTIONS 20 1e-6 3 1e-6\nNODE 0 0 0 0\n"
                                  << "EDGE 0 1 0 0 0 1 0 0 0 1 0 0 0 1 0 1\n";
  EXPECT_NE(loadPoseGraph(path("edge.txt"), &graph, nullptr).find("unknown node"),
            std::string::npos);
  std::ofstream(path("kernel.txt"))
      << "LANDMARK_GRAPH_OPTIONS 100 1e-6 1e-6 1e-6 3\nLASER 0 0 0\nPOSE 0 0 0 0 1\n"
      << "LANDMARK 0 1 1\nOBSERVATION 0 0 1.4 0.7 1 0 0 1 tukey\n";
  LandmarkGraph landmarks;
  EXPECT_NE(loadLandmarkGraph(path("kernel.txt"), &landmarks, nullptr).find(":5:"),
            std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
