#include "ekf_slam_core/features/clustering.h"

#include <gtest/gtest.h>

#include <limits>

#include "ekf_slam_core/features/split_and_merge.h"

namespace ekf_slam {
namespace {

Scan scanOf(std::vector<double> ranges, double angle_min, double increment) {
  Scan scan;
  scan.ranges = std::move(ranges);
  scan.angle_min = angle_min;
  scan.angle_increment = increment;
  scan.range_min = 0.02;
  scan.range_max = 80.0;
  return scan;
}

// Ranges of a straight wall x cos θ + y sin θ = p for the given beams.
std::vector<double> wall(double p, double theta, double angle_min, double increment, int count) {
  std::vector<double> ranges(count);
  for (int i = 0; i < count; ++i) ranges[i] = p / std::cos(angle_min + i * increment - theta);
  return ranges;
}

TEST(Clustering, SkipsInvalidReadingsAndKeepsBeamIndices) {
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  const Scan scan = scanOf({1.0, nan, inf, -inf, 81.83, 2.0}, 0.0, 0.1);
  const std::vector<ScanPoint> points = scanToPoints(scan);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0].beam, 0);
  EXPECT_EQ(points[1].beam, 5);
  EXPECT_NEAR(points[1].xy.x(), 2.0 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(points[1].xy.y(), 2.0 * std::sin(0.5), 1e-12);
}

TEST(Clustering, EmptyAndAllInvalidGiveNoClusters) {
  FeatureOptions options;
  EXPECT_TRUE(clusterPoints({}, options).empty());
  const Scan scan = scanOf(std::vector<double>(50, std::nan("")), 0.0, 0.01);
  EXPECT_TRUE(clusterPoints(scanToPoints(scan), options).empty());
}

TEST(Clustering, AlternatingRangesGiveSinglePointClusters) {
  std::vector<double> ranges;
  for (int i = 0; i < 20; ++i) ranges.push_back(i % 2 == 0 ? 1.0 : 5.0);
  const Scan scan = scanOf(ranges, -0.2, 0.02);
  const std::vector<IndexSpan> clusters = clusterPoints(scanToPoints(scan), FeatureOptions());
  ASSERT_EQ(clusters.size(), 20u);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(clusters[i].first, i);
    EXPECT_EQ(clusters[i].last, i);
  }
}

TEST(Clustering, NanInsideAWallDoesNotSplitItButALongGapDoes) {
  std::vector<double> ranges = wall(3.0, 0.2, -0.5, 0.01, 100);
  ranges[40] = std::nan("");
  ranges[41] = std::numeric_limits<double>::infinity();
  FeatureOptions options;
  EXPECT_EQ(clusterPoints(scanToPoints(scanOf(ranges, -0.5, 0.01)), options).size(), 1u);
  ranges[42] = 81.91;  // three invalid beams in a row > cluster_max_invalid_beams = 2
  EXPECT_EQ(clusterPoints(scanToPoints(scanOf(ranges, -0.5, 0.01)), options).size(), 2u);
  options.cluster_max_invalid_beams = 3;
  EXPECT_EQ(clusterPoints(scanToPoints(scanOf(ranges, -0.5, 0.01)), options).size(), 1u);
}

// A wall at 7 m seen obliquely with 1° beams: neighbours lie 0.2–0.5 m apart.
// The thesis's fixed hc = 0.1 m shreds it; the adaptive threshold keeps it.
TEST(Clustering, AdaptiveThresholdKeepsAFarObliqueWallWhereFixedHcFails) {
  const double increment = degToRad(1.0);
  const std::vector<double> ranges = wall(5.0, 0.0, 0.6, increment, 15);
  const Scan scan = scanOf(ranges, 0.6, increment);
  const std::vector<ScanPoint> points = scanToPoints(scan);
  FeatureOptions options;
  options.cluster_mode = ClusterMode::kAdaptive;
  EXPECT_EQ(clusterPoints(points, options).size(), 1u);
  options.cluster_mode = ClusterMode::kFixed;
  EXPECT_GT(clusterPoints(points, options).size(), 10u);
  // And the adaptive threshold still separates a box 0.5 m in front of a wall
  // at 2 m.
  std::vector<double> box_ranges = wall(2.0, 0.0, -0.3, increment, 35);
  for (int i = 15; i < 20; ++i) box_ranges[i] -= 0.5;
  options.cluster_mode = ClusterMode::kAdaptive;
  EXPECT_EQ(clusterPoints(scanToPoints(scanOf(box_ranges, -0.3, increment)), options).size(), 3u);
}

TEST(SplitAndMerge, SplitsAnLShapeAtItsCornerAndKeepsAStraightWallWhole) {
  // Two walls meeting at (3, 1): x = 3 for y < 1 and y = 1 for x < 3.
  const double increment = degToRad(0.5);
  std::vector<double> ranges;
  for (int i = 0; i < 120; ++i) {
    const double bearing = -0.6 + i * increment;
    const double to_x_wall = 3.0 / std::cos(bearing);
    const double to_y_wall = std::sin(bearing) > 0 ? 1.0 / std::sin(bearing) : 1e9;
    ranges.push_back(std::min(to_x_wall, to_y_wall));
  }
  const std::vector<ScanPoint> points = scanToPoints(scanOf(ranges, -0.6, increment));
  FeatureOptions options;
  const std::vector<IndexSpan> clusters = clusterPoints(points, options);
  ASSERT_EQ(clusters.size(), 1u);
  const std::vector<IndexSpan> pieces = splitAndMerge(points, clusters[0], options);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].first, 0);
  EXPECT_EQ(pieces[0].last, pieces[1].first);
  EXPECT_EQ(pieces[1].last, 119);
  EXPECT_LT((points[pieces[0].last].xy - Vector2(3.0, 1.0)).norm(), 0.05);

  const std::vector<ScanPoint> straight =
      scanToPoints(scanOf(wall(2.0, 0.3, -1.0, increment, 200), -1.0, increment));
  EXPECT_EQ(splitAndMerge(straight, {0, 199}, options).size(), 1u);
  EXPECT_EQ(splitAndMerge(straight, {5, 6}, options).size(), 1u);  // too short to split
}

}  // namespace
}  // namespace ekf_slam
