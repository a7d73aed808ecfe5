// The pure helpers of the live nodes: covariance ellipse sizes, the rviz
// markers built from a filter (points and both kinds of line), and the
// conversions to this package's messages.
#include "ekf_slam_ros/slam_node/slam_messages.h"
#include "ekf_slam_ros/slam_node/processing_times.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <unordered_map>

#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

Matrix2 rotated(double sigma_major, double sigma_minor, double angle) {
  const Matrix2 r = Eigen::Rotation2Dd(angle).toRotationMatrix();
  return r * Vector2(sigma_major * sigma_major, sigma_minor * sigma_minor).asDiagonal() *
         r.transpose();
}

// The percentiles /diagnostics reports, from 0.1 ms bins.
TEST(ProcessingTimes, PercentilesFromTheBins) {
  ProcessingTimes times;
  EXPECT_EQ(times.percentile(50.0), 0.0);
  for (int i = 1; i <= 100; ++i) times.add(i * 1e-3);  // 1 … 100 ms
  times.add(20.0);                                     // beyond the last bin
  EXPECT_EQ(times.count(), 101);
  EXPECT_NEAR(times.percentile(50.0), 0.051, 1.5e-4);
  EXPECT_NEAR(times.percentile(99.0), 0.100, 1.5e-4);
  EXPECT_DOUBLE_EQ(times.max(), 20.0);
  EXPECT_NEAR(times.percentile(100.0), 10.0, 1e-9) << "the last bin holds the longer ones";
}

TEST(CovarianceEllipse, SemiAxesAreSqrtOfChiSquareTimesEigenvalues) {
  // 2-dof chi-square 95 % quantile: −2 ln(0.05) = 5.9915.
  const double k = -2.0 * std::log(0.05);
  const CovarianceEllipse e = covarianceEllipse(rotated(2.0, 0.5, 0.0), 0.95);
  EXPECT_NEAR(e.semi_major, std::sqrt(k) * 2.0, 1e-9);
  EXPECT_NEAR(e.semi_minor, std::sqrt(k) * 0.5, 1e-9);
  EXPECT_NEAR(std::abs(std::sin(e.angle)), 0.0, 1e-12);  // major axis along x

  const CovarianceEllipse tilted = covarianceEllipse(rotated(0.3, 0.1, 0.7), 0.95);
  EXPECT_NEAR(tilted.semi_major, std::sqrt(k) * 0.3, 1e-9);
  EXPECT_NEAR(tilted.semi_minor, std::sqrt(k) * 0.1, 1e-9);
  EXPECT_NEAR(std::sin(2.0 * (tilted.angle - 0.7)), 0.0, 1e-9);  // direction modulo π

  // 39.35 % (1-sigma in 2D): k = 1.
  EXPECT_NEAR(covarianceEllipse(rotated(2.0, 0.5, 0.0), 1.0 - std::exp(-0.5)).semi_major, 2.0,
              1e-6);
}

TEST(CovarianceEllipse, HoldsItsProbabilityOfSamples) {
  const Matrix2 c = rotated(0.8, 0.2, -1.1);
  const CovarianceEllipse e = covarianceEllipse(c, 0.95);
  const Eigen::LLT<Matrix2> llt(c);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  int inside = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Vector2 p = llt.matrixL() * Vector2(normal(rng), normal(rng));
    // Into the ellipse's axes.
    const double u = std::cos(e.angle) * p.x() + std::sin(e.angle) * p.y();
    const double v = -std::sin(e.angle) * p.x() + std::cos(e.angle) * p.y();
    if (u * u / (e.semi_major * e.semi_major) + v * v / (e.semi_minor * e.semi_minor) <= 1.0) {
      ++inside;
    }
  }
  EXPECT_NEAR(static_cast<double>(inside) / n, 0.95, 0.005);
}

TEST(CovarianceEllipse, DegenerateCovarianceGivesZeroAxisNotNaN) {
  Matrix2 c;
  c << 1.0, 1.0, 1.0, 1.0;  // rank 1
  const CovarianceEllipse e = covarianceEllipse(c, 0.95);
  EXPECT_NEAR(e.semi_minor, 0.0, 1e-6);
  EXPECT_TRUE(std::isfinite(e.semi_major));
}

EkfSlam filterWithLandmarks() {
  EkfSlam filter(FilterOptions{}, Pose2(0.5, -0.2, 0.1), Matrix3::Identity() * 1e-3);
  EXPECT_EQ(filter.addLandmark(4, Vector2(3.0, 1.0), rotated(0.2, 0.05, 0.3), 5),
            FilterStatus::kOk);
  EXPECT_EQ(filter.addLandmark(9, Vector2(-2.0, 4.0), rotated(0.1, 0.1, 0.0), 1),
            FilterStatus::kOk);
  return filter;
}

TEST(LandmarkMarkers, EllipsesAtTheMeansWithFullAxesLabelsAndTheRobot) {
  const EkfSlam filter = filterWithLandmarks();
  std_msgs::Header header;
  header.frame_id = "map";
  header.stamp = ros::Time(12.5);
  const visualization_msgs::MarkerArray markers =
      landmarkMarkers(filter, {}, nullptr, header, 0.95);
  ASSERT_FALSE(markers.markers.empty());
  EXPECT_EQ(markers.markers[0].action, visualization_msgs::Marker::DELETEALL);
  const double k = -2.0 * std::log(0.05);
  int ellipses = 0, labels = 0, robot = 0;
  for (const visualization_msgs::Marker& m : markers.markers) {
    if (m.action == visualization_msgs::Marker::DELETEALL) continue;
    EXPECT_EQ(m.header.stamp, header.stamp);
    EXPECT_EQ(m.header.frame_id, "map");
    if (m.ns == "landmark_ellipses") {
      ++ellipses;
      const int slot = filter.slotOf(m.id);
      ASSERT_GE(slot, 0);
      EXPECT_DOUBLE_EQ(m.pose.position.x, filter.landmarkPosition(slot).x());
      EXPECT_DOUBLE_EQ(m.pose.position.y, filter.landmarkPosition(slot).y());
      const double major = m.id == 4 ? 0.2 : 0.1, minor = m.id == 4 ? 0.05 : 0.1;
      EXPECT_NEAR(m.scale.x, 2.0 * std::sqrt(k) * major, 1e-9);  // full axis = 2 × semi-axis
      EXPECT_NEAR(m.scale.y, 2.0 * std::sqrt(k) * minor, 1e-9);
      if (m.id == 4) {
        EXPECT_NEAR(2.0 * std::atan2(m.pose.orientation.z, m.pose.orientation.w), 0.3, 1e-9);
      }
    } else if (m.ns == "landmark_ids") {
      ++labels;
      EXPECT_EQ(m.text, std::to_string(m.id));
    } else if (m.ns == "robot_ellipse") {
      ++robot;
      EXPECT_DOUBLE_EQ(m.pose.position.x, 0.5);
      EXPECT_NEAR(m.scale.x, 2.0 * std::sqrt(k * 1e-3), 1e-9);
    }
  }
  EXPECT_EQ(ellipses, 2);
  EXPECT_EQ(labels, 2);
  EXPECT_EQ(robot, 1);
}

TEST(Messages, LandmarkMapCarriesIdsMeansFullCovariancesAndTentativeFlag) {
  const EkfSlam filter = filterWithLandmarks();
  std_msgs::Header header;
  header.frame_id = "map";
  const LandmarkMapFile file = toLandmarkMapFile(filter, {}, "map");
  const LandmarkMap map = toLandmarkMapMessage(file, header);
  ASSERT_EQ(map.landmarks.size(), 2u);
  EXPECT_EQ(map.landmarks[0].id, 4);
  EXPECT_FALSE(map.landmarks[0].tentative);
  EXPECT_TRUE(map.landmarks[1].tentative);  // seen once
  const Matrix2 c = rotated(0.2, 0.05, 0.3);
  EXPECT_NEAR(map.landmarks[0].covariance[1], c(0, 1), 1e-15);
  EXPECT_NEAR(map.landmarks[0].covariance[2], c(1, 0), 1e-15);
  EXPECT_NEAR(map.landmarks[0].covariance[3], c(1, 1), 1e-15);
  EXPECT_TRUE(map.lines.empty() && map.line_angles.empty());
  ASSERT_EQ(file.landmarks.size(), 2u);
  EXPECT_EQ(file.landmarks[1].id, 9);
  EXPECT_EQ(file.landmarks[1].position, Vector2(-2.0, 4.0));
}

// filterWithLandmarks' points 4 and 9 and, with their support:
//   12: the wall x = 3 seen from y = -1 to 2, with a p–θ correlation;
//   16: a tentative (p, θ) line without support;
//   13: a θ-only line between points 4 and 9;
//   14: a θ-only line with point 4 alone;
//   15: a θ-only line without endpoints.
struct LineMap {
  EkfSlam filter = filterWithLandmarks();
  std::unordered_map<int, LineSupport> support;
  Matrix2 wall_covariance;

  LineMap() {
    wall_covariance << 0.01, 0.001, 0.001, 4e-4;
    EXPECT_EQ(filter.addLineLandmark(12, PolarLine{3.0, 0.0}, wall_covariance, 4),
              FilterStatus::kOk);
    EXPECT_EQ(filter.addLineLandmark(16, PolarLine{2.0, 1.0}, Matrix2::Identity() * 1e-3, 1),
              FilterStatus::kOk);
    for (int id : {13, 14, 15}) {
      EXPECT_EQ(filter.addLineAngleLandmark(id, 0.5 + 0.1 * id, 1e-3 * (id - 12), 3),
                FilterStatus::kOk);
    }
    support[12].s_min = -1.0;
    support[12].s_max = 2.0;
    support[13].endpoint_ids[0] = 4;
    support[13].endpoint_ids[1] = 9;
    support[14].endpoint_ids[1] = 4;
    support[15] = LineSupport{};
  }
};

Vector2 at(const geometry_msgs::Point& p) { return Vector2(p.x, p.y); }

TEST(LandmarkMarkers, LinesAreSegmentsOverTheirExtentWithTheirUncertainty) {
  const LineMap lines;
  const EkfSlam& filter = lines.filter;
  std_msgs::Header header;
  header.frame_id = "map";
  const visualization_msgs::MarkerArray markers =
      landmarkMarkers(filter, lines.support, nullptr, header, 0.95);
  const double k = 1.959963984540054;  // two-sided 95 %
  std::map<std::pair<std::string, int>, visualization_msgs::Marker> by_name;
  std::set<int> labelled;
  for (const visualization_msgs::Marker& m : markers.markers) {
    if (m.action == visualization_msgs::Marker::DELETEALL) continue;
    EXPECT_TRUE(by_name.emplace(std::make_pair(m.ns, m.id), m).second) << m.ns << " " << m.id;
    if (m.ns == "landmark_ids") labelled.insert(m.id);
  }
  EXPECT_EQ(labelled, (std::set<int>{4, 9, 12, 13, 14, 16}));  // 15 has no place to be drawn
  for (const auto& [name, m] : by_name) {
    EXPECT_NE(name.second, 15) << name.first;
    if (name.first == "landmark_ellipses") {
      EXPECT_TRUE(name.second == 4 || name.second == 9);
    }
  }

  // The wall x = 3 over y ∈ [-1, 2] …
  const visualization_msgs::Marker& wall = by_name.at({"line_landmarks", 12});
  ASSERT_EQ(wall.type, visualization_msgs::Marker::LINE_LIST);
  ASSERT_EQ(wall.points.size(), 2u);
  EXPECT_LT((at(wall.points[0]) - Vector2(3.0, -1.0)).norm(), 1e-12);
  EXPECT_LT((at(wall.points[1]) - Vector2(3.0, 2.0)).norm(), 1e-12);
  // … and its band: at every vertex, k σ across the wall, σ² = σ_p² − 2s σ_pθ + s² σ_θ².
  const visualization_msgs::Marker& band = by_name.at({"line_landmark_bands", 12});
  ASSERT_EQ(band.points.size(), 32u);  // 8 pieces a side
  const Matrix2& c = lines.wall_covariance;
  int left = 0, right = 0;
  for (const geometry_msgs::Point& p : band.points) {
    const double s = p.y;
    EXPECT_GE(s, -1.0 - 1e-12);
    EXPECT_LE(s, 2.0 + 1e-12);
    EXPECT_NEAR(std::abs(p.x - 3.0), k * std::sqrt(c(0, 0) - 2.0 * s * c(0, 1) + s * s * c(1, 1)),
                1e-12);
    (p.x > 3.0 ? right : left)++;
  }
  EXPECT_EQ(left, 16);
  EXPECT_EQ(right, 16);
  EXPECT_LT(band.scale.x, wall.scale.x);  // thin beside the segment

  // Without support: a kUnknownExtentLength stub centred on the foot point, grey (tentative).
  const visualization_msgs::Marker& stub = by_name.at({"line_landmarks", 16});
  const Vector2 foot = 2.0 * Vector2(std::cos(1.0), std::sin(1.0));
  EXPECT_NEAR((at(stub.points[1]) - at(stub.points[0])).norm(), kUnknownExtentLength, 1e-12);
  EXPECT_LT((0.5 * (at(stub.points[0]) + at(stub.points[1])) - foot).norm(), 1e-12);
  EXPECT_FLOAT_EQ(stub.color.r, stub.color.b);
  EXPECT_NE(wall.color.r, wall.color.b);

  // θ-only between its endpoints, its fan at ±k σ_θ through the midpoint.
  const Vector2 p4 = filter.landmarkPosition(filter.slotOf(4));
  const Vector2 p9 = filter.landmarkPosition(filter.slotOf(9));
  const visualization_msgs::Marker& between = by_name.at({"line_angle_landmarks", 13});
  ASSERT_EQ(between.points.size(), 2u);
  EXPECT_EQ(at(between.points[0]), p4);
  EXPECT_EQ(at(between.points[1]), p9);
  const visualization_msgs::Marker& fan = by_name.at({"line_angle_fans", 13});
  ASSERT_EQ(fan.points.size(), 4u);
  const double theta = 0.5 + 1.3, spread = k * std::sqrt(1e-3);
  for (int i = 0; i < 2; ++i) {
    const Vector2 a = at(fan.points[2 * i]), b = at(fan.points[2 * i + 1]);
    EXPECT_LT((0.5 * (a + b) - 0.5 * (p4 + p9)).norm(), 1e-12);
    EXPECT_NEAR((b - a).norm(), (p9 - p4).norm(), 1e-12);
    // The segment's normal direction is θ ± k σ_θ.
    const double normal = std::atan2(b.y() - a.y(), b.x() - a.x()) - 0.5 * kPi;
    EXPECT_NEAR(wrapAngle(normal - theta), i == 0 ? -spread : spread, 1e-12);
  }
  // One endpoint: a stub through it along the line's direction.
  const visualization_msgs::Marker& one = by_name.at({"line_angle_landmarks", 14});
  const Vector2 a = at(one.points[0]), b = at(one.points[1]);
  EXPECT_LT((0.5 * (a + b) - p4).norm(), 1e-12);
  EXPECT_NEAR((b - a).norm(), kUnknownExtentLength, 1e-12);
  EXPECT_NEAR(std::abs((b - a).normalized().dot(Vector2(std::cos(1.9), std::sin(1.9)))), 0.0,
              1e-12);
}

TEST(Messages, LandmarkMapCarriesEveryKindInItsOwnList) {
  const LineMap lines;
  std_msgs::Header header;
  header.frame_id = "map";
  const LandmarkMap map =
      toLandmarkMapMessage(toLandmarkMapFile(lines.filter, lines.support, "map"), header);
  ASSERT_EQ(map.landmarks.size(), 2u);  // the points, as before
  ASSERT_EQ(map.lines.size(), 2u);
  ASSERT_EQ(map.line_angles.size(), 3u);
  const LineLandmark& wall = map.lines[0];
  EXPECT_EQ(wall.id, 12);
  EXPECT_EQ(wall.p, 3.0);
  EXPECT_EQ(wall.theta, 0.0);
  EXPECT_EQ(wall.covariance[1], 0.001);
  EXPECT_EQ(wall.covariance[3], 4e-4);
  EXPECT_EQ(wall.observations, 4);
  EXPECT_FALSE(wall.tentative);
  EXPECT_TRUE(wall.extent_known);
  EXPECT_EQ(wall.s_min, -1.0);
  EXPECT_EQ(wall.s_max, 2.0);
  EXPECT_EQ(map.lines[1].id, 16);
  EXPECT_TRUE(map.lines[1].tentative);
  EXPECT_FALSE(map.lines[1].extent_known);
  const LineAngleLandmark& between = map.line_angles[0];
  EXPECT_EQ(between.id, 13);
  EXPECT_NEAR(between.theta, 1.8, 1e-15);
  EXPECT_NEAR(between.variance, 1e-3, 1e-18);
  EXPECT_EQ(between.endpoint_ids[0], 4);
  EXPECT_EQ(between.endpoint_ids[1], 9);
  EXPECT_EQ(map.line_angles[1].endpoint_ids[0], -1);
  EXPECT_EQ(map.line_angles[1].endpoint_ids[1], 4);
  EXPECT_EQ(map.line_angles[2].endpoint_ids[0], -1);
  EXPECT_EQ(map.line_angles[2].endpoint_ids[1], -1);
}

TEST(Messages, AssociationReportNamesDecisionsCandidatesAndIds) {
  FilterOptions options;
  EkfSlam filter(options, Pose2(), Matrix3::Identity() * 1e-4);
  ASSERT_EQ(filter.addLandmark(7, Vector2(2.0, 0.0), Matrix2::Identity() * 1e-3),
            FilterStatus::kOk);
  auto observation = [](double x, double y) {
    PointObservation z;
    z.z = {std::hypot(x, y), std::atan2(y, x)};
    z.covariance = Vector2(1e-4, 1e-5).asDiagonal();
    return z;
  };
  const std::vector<PointObservation> observations = {observation(2.01, 0.0),
                                                      observation(0.0, 5.0)};
  IterationReport iteration;
  observe(filter, AssociationOptions{}, observations, &iteration);
  std_msgs::Header header;
  header.frame_id = "laser";
  const AssociationReport report = toAssociationReport(observations, iteration, header);
  ASSERT_EQ(report.observations.size(), 2u);
  EXPECT_EQ(report.header.frame_id, "laser");
  EXPECT_EQ(report.observations[0].decision, "matched");
  EXPECT_EQ(report.observations[0].landmark_id, 7);
  ASSERT_FALSE(report.observations[0].candidates.empty());
  EXPECT_EQ(report.observations[0].candidates[0].landmark_id, 7);
  EXPECT_LT(report.observations[0].candidates[0].mahalanobis_sq, report.observations[0].gate);
  EXPECT_NEAR(report.observations[0].gate, -2.0 * std::log(0.01), 1e-6);  // χ²₂(0.99)
  EXPECT_EQ(report.observations[1].decision, "new");
  EXPECT_EQ(report.observations[1].landmark_id, 8);  // the next id after 7
  EXPECT_NEAR(report.observations[1].range, 5.0, 1e-12);
}

TEST(Messages, FeaturesOfASimulatedRoomKeepEveryPointAndLine) {
  sim::PolygonWorld room;
  room.addPolygon({Vector2(-2, -2), Vector2(4, -2), Vector2(4, 3), Vector2(-2, 3)});
  room.addBox(Vector2(2.0, 1.0), 0.6, 0.4);
  sim::SweepGeometry sweep;
  Scan scan;
  scan.ranges = sim::simulateRanges(room, Pose2(0, 0, 0.2), sweep);
  scan.angle_min = sweep.angle_min;
  scan.angle_increment = sweep.angle_increment;
  scan.range_max = sweep.max_range;
  const FeatureSet features = extractFeatures(scan, FeatureOptions{});
  ASSERT_TRUE(features.error.empty()) << features.error;
  ASSERT_GE(features.lines.size(), 3u);
  std_msgs::Header header;
  header.frame_id = "laser";
  header.stamp = ros::Time(3.25);
  const Features message = toFeaturesMessage(features, header);
  EXPECT_EQ(message.header.stamp, header.stamp);
  ASSERT_EQ(message.lines.size(), features.lines.size());
  ASSERT_EQ(message.points.size(), features.points_of_interest.size());
  for (size_t i = 0; i < message.lines.size(); ++i) {
    EXPECT_DOUBLE_EQ(message.lines[i].p, features.lines[i].p);
    EXPECT_DOUBLE_EQ(message.lines[i].covariance[1], features.lines[i].covariance(0, 1));
    EXPECT_DOUBLE_EQ(message.lines[i].end.y, features.lines[i].end.y());
  }
  int candidates = 0;
  for (size_t i = 0; i < message.points.size(); ++i) {
    EXPECT_EQ(message.points[i].landmark_candidate,
              features.points_of_interest[i].landmark_candidate);
    EXPECT_DOUBLE_EQ(message.points[i].range_bearing_covariance[3],
                     features.points_of_interest[i].range_bearing_covariance(1, 1));
    candidates += message.points[i].landmark_candidate;
  }
  EXPECT_GT(candidates, 0);

  // Back again (ekf_slam_node's features input): every value the filter uses
  // survives the round trip exactly.
  FeatureSet back;
  std::string error;
  ASSERT_TRUE(fromFeaturesMessage(message, &back, &error)) << error;
  ASSERT_EQ(back.points_of_interest.size(), features.points_of_interest.size());
  ASSERT_EQ(back.lines.size(), features.lines.size());
  for (size_t i = 0; i < back.points_of_interest.size(); ++i) {
    const PointFeature& a = features.points_of_interest[i];
    const PointFeature& b = back.points_of_interest[i];
    EXPECT_EQ(a.kind, b.kind);
    EXPECT_EQ(a.context, b.context);
    EXPECT_EQ(a.landmark_candidate, b.landmark_candidate);
    EXPECT_EQ(a.range, b.range);
    EXPECT_EQ(a.bearing, b.bearing);
    EXPECT_EQ(a.range_bearing_covariance, b.range_bearing_covariance);
    EXPECT_EQ(a.covariance, b.covariance);
  }
  for (size_t i = 0; i < back.lines.size(); ++i) {
    EXPECT_EQ(features.lines[i].covariance, back.lines[i].covariance);
    EXPECT_EQ(features.lines[i].end, back.lines[i].end);
  }
  EXPECT_EQ(validateFeatureSet(back), "");
  Features unknown = message;
  unknown.points.back().context = "behind_the_sofa";
  EXPECT_FALSE(fromFeaturesMessage(unknown, &back, &error));
  EXPECT_NE(error.find("behind_the_sofa"), std::string::npos) << error;

  const visualization_msgs::MarkerArray markers = featureMarkers(features, header);
  ASSERT_EQ(markers.markers.size(), 3u);
  EXPECT_EQ(markers.markers[0].points.size(), 2 * features.lines.size());
  EXPECT_EQ(static_cast<int>(markers.markers[1].points.size()), candidates);
}

// The pose graph in rviz: a node per key scan, a segment between
// consecutive ones, and each loop between the two key scans it joins.
TEST(PoseGraphMarkers, JoinTheKeyScansTheGraphJoins) {
  const std::vector<Pose2> keys = {
      {0.0, 0.0, 0.0}, {1.0, 0.0, 0.5}, {1.0, 1.0, 1.5}, {0.1, 0.9, 3.0}};
  std::vector<LoopLink> loops = {{0, 3, false}, {1, 3, true}, {0, 9, false}};
  std_msgs::Header header;
  header.frame_id = "map";
  header.stamp = ros::Time(12.5);
  const visualization_msgs::MarkerArray markers = poseGraphMarkers(keys, loops, header);
  std::map<std::string, visualization_msgs::Marker> by_ns;
  for (const visualization_msgs::Marker& m : markers.markers) {
    EXPECT_EQ(m.header.frame_id, "map");
    EXPECT_EQ(m.header.stamp, header.stamp);
    by_ns[m.ns] = m;
  }
  ASSERT_EQ(by_ns.size(), 4u);
  const auto at = [](const geometry_msgs::Point& p) { return Vector2(p.x, p.y); };
  const visualization_msgs::Marker& nodes = by_ns["pose_graph_nodes"];
  ASSERT_EQ(nodes.points.size(), keys.size());
  for (size_t k = 0; k < keys.size(); ++k) {
    EXPECT_EQ(at(nodes.points[k]), keys[k].translation());
  }
  const visualization_msgs::Marker& edges = by_ns["pose_graph_edges"];
  ASSERT_EQ(edges.points.size(), 6u);
  for (size_t k = 1; k < keys.size(); ++k) {
    EXPECT_EQ(at(edges.points[2 * (k - 1)]), keys[k - 1].translation());
    EXPECT_EQ(at(edges.points[2 * (k - 1) + 1]), keys[k].translation());
  }
  // The link to a key scan beyond the list is left out.
  const visualization_msgs::Marker& closed = by_ns["pose_graph_loops"];
  ASSERT_EQ(closed.points.size(), 2u);
  EXPECT_EQ(at(closed.points[0]), keys[0].translation());
  EXPECT_EQ(at(closed.points[1]), keys[3].translation());
  const visualization_msgs::Marker& heading = by_ns["pose_graph_heading_loops"];
  ASSERT_EQ(heading.points.size(), 2u);
  EXPECT_EQ(at(heading.points[0]), keys[1].translation());
  for (const auto& [ns, m] : by_ns) {
    EXPECT_EQ(m.action, visualization_msgs::Marker::ADD) << ns;
    EXPECT_GT(m.scale.x, 0.0) << ns;
    EXPECT_GT(m.color.a, 0.0) << ns;
  }

  // Before the first loop the loop lists are empty: sent as DELETEs.
  const visualization_msgs::MarkerArray early = poseGraphMarkers(keys, {}, header);
  for (const visualization_msgs::Marker& m : early.markers) {
    const bool loop_list = m.ns == "pose_graph_loops" || m.ns == "pose_graph_heading_loops";
    EXPECT_EQ(m.action,
              loop_list ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD)
        << m.ns;
  }
}

}  // namespace
}  // namespace ekf_slam
